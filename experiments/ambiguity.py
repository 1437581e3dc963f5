"""``python -m experiments.ambiguity``: how much of the 3D error is the monocular depth flip?

Tracks each synthetic sequence (full length, 160x120, true calibration) with a tracker
configuration and measures, against ground truth:

* ``mpjpe_mm`` and ``failure_rate`` (frames over 100 mm), as ``python -m mocap track`` does;
* ``reprojection_px``: the same joints' error in the image, which the costs can see;
* ``flip_oracle_mpjpe_mm`` and ``flip_oracle_failure_rate``: the error left when, per frame and
  per arm, an oracle that knows the truth picks the best of the four depth reflections of the
  tracked arm (upper arm and forearm each mirrored or not about the plane through their proximal
  joint that faces the camera). The four project to nearly the same silhouette and edges, so
  this is the error that choosing the right depth branch could remove, and what is left is not
  a branch error. The oracle is applied after tracking (the tracker is not fed its choice), so
  it is a bound on the flip's share, not a tracker.

Results go to ``--out`` (default ``experiments/results/ambiguity``): the generated sequences
(reused, as by :mod:`experiments.sweep`) and one JSON file per sequence and configuration
(written atomically; a second run reuses them). A Markdown table is printed.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

from experiments import RESULTS_DIR
from experiments.units import DataSpec, load_prepared, load_sequence, prepare_data
from mocap.body import JOINT_NAMES
from mocap.io.jsonfile import read_json, write_json
from mocap.metrics import DEFAULT_FAILURE_MM, failure_rate, mpjpe, reprojection_error
from mocap.synth import SEQUENCE_NAMES, SEQUENCES
from mocap.track import Tracker, TrackerConfig, track_prepared

#: Image size of the benchmark (pixels).
SIZE = (160, 120)
#: Joints of one arm, proximal to distal; the upper arm turns about the shoulder, the forearm
#: (with the hand) about the elbow.
ARM_JOINTS = {side: tuple(JOINT_NAMES.index(f"{side}_{j}") for j in ("shoulder", "elbow", "wrist", "hand"))
              for side in "rl"}


def reflect_in_depth(points: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """Mirror points about the plane through ``pivot`` whose normal is the camera ray to it.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres, camera coordinates
    pivot : ndarray, shape (3,), metres

    Returns
    -------
    ndarray, shape (n, 3)
        Points the same distance from the plane on its other side: under a pinhole camera they
        project close to the originals (exactly for a very distant camera).
    """
    normal = pivot / np.linalg.norm(pivot)
    return points - 2.0 * ((points - pivot) @ normal)[:, None] * normal[None, :]


def flip_oracle(joints: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Tracked joints with each arm replaced by its depth reflection nearest to the truth.

    Parameters
    ----------
    joints, truth : ndarray, shape (frames, joints, 3), metres

    Returns
    -------
    ndarray, shape (frames, joints, 3)
        Per frame and arm, the best (summed joint distance to ``truth``) of: the arm as tracked,
        the forearm mirrored about the elbow, the whole arm mirrored about the shoulder, and both.
    """
    out = joints.copy()
    for f in range(joints.shape[0]):
        for idx in ARM_JOINTS.values():
            arm, true_arm = joints[f, idx], truth[f, idx]
            best, best_err = arm, np.inf
            for mirror_upper in (False, True):
                a = arm.copy()
                if mirror_upper:
                    a[1:] = reflect_in_depth(a[1:], a[0])
                for mirror_fore in (False, True):
                    b = a.copy()
                    if mirror_fore:
                        b[2:] = reflect_in_depth(b[2:], b[1])
                    err = np.linalg.norm(b - true_arm, axis=1).sum()
                    if err < best_err:
                        best, best_err = b, err
            out[f, idx] = best
    return out


def measure(sequence: str, config: TrackerConfig, root: Path, seed: int = 0) -> dict:
    """Track one benchmark sequence with ``config`` and measure its errors (see the module)."""
    spec = DataSpec(sequence, None, SEQUENCES[sequence].frames, seed, *SIZE)
    folder = prepare_data(spec, str(root))
    loaded = load_sequence(folder)
    prepared = load_prepared(folder)
    camera = loaded.calibration.camera
    results = track_prepared(prepared, Tracker(loaded.model, camera, config, loaded.calibration.initial_pose))
    joints = np.array([r.joints for r in results])
    truth = loaded.ground_truth.joints[: len(joints)]
    oracle = flip_oracle(joints, truth)
    return {"sequence": sequence, "frames": len(joints),
            "mpjpe_mm": mpjpe(joints, truth), "failure_rate": failure_rate(joints, truth),
            "reprojection_px": reprojection_error(joints, truth, camera),
            "flip_oracle_mpjpe_mm": mpjpe(oracle, truth), "flip_oracle_failure_rate": failure_rate(oracle, truth),
            "flip_oracle_reprojection_px": reprojection_error(oracle, truth, camera)}


def config_key(config: TrackerConfig) -> str:
    """Short stable name of a tracker configuration (for result file names)."""
    text = json.dumps(config.to_dict(), sort_keys=True)
    return hashlib.sha1(text.encode()).hexdigest()[:10]


def table(rows: list[dict]) -> str:
    """Markdown table of :func:`measure` results, with the medians over the sequences."""
    cols = ("mpjpe_mm", "failure_rate", "reprojection_px", "flip_oracle_mpjpe_mm", "flip_oracle_failure_rate")
    head = ("sequence", "MPJPE mm", f"frames > {DEFAULT_FAILURE_MM:g} mm", "reproj. px", "flip oracle MPJPE mm",
            f"flip oracle > {DEFAULT_FAILURE_MM:g} mm")
    fmt = lambda c, v: f"{100 * v:.0f} %" if "rate" in c else (f"{v:.1f}" if "px" in c else f"{v:.0f}")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        lines.append("| " + " | ".join([r["sequence"]] + [fmt(c, r[c]) for c in cols]) + " |")
    lines.append("| **median** | " + " | ".join(fmt(c, float(np.median([r[c] for r in rows]))) for c in cols) + " |")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m experiments.ambiguity", description=__doc__.split("\n\n")[0])
    p.add_argument("--sequences", default=",".join(SEQUENCE_NAMES),
                   help="comma-separated benchmark sequences (default: all six)")
    p.add_argument("--evaluations", type=int, default=None, help="cost evaluations per frame (default: the config's)")
    p.add_argument("--config", type=Path, default=None, help="TrackerConfig JSON (default: the tracker's defaults)")
    p.add_argument("--out", type=Path, default=RESULTS_DIR / "ambiguity", help="results folder")
    p.add_argument("--seed", type=int, default=0, help="sequence generator seed")
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    names = tuple(s for s in args.sequences.split(",") if s)
    unknown = [s for s in names if s not in SEQUENCES]
    if unknown or not names:
        print(f"error: unknown sequence(s) {unknown}; choose from {', '.join(SEQUENCE_NAMES)}", file=sys.stderr)
        return 2
    config = TrackerConfig.from_json(args.config) if args.config is not None else TrackerConfig()
    if args.evaluations is not None:
        config = TrackerConfig.from_dict({**config.to_dict(), "evaluations": args.evaluations})
    key = config_key(config)
    rows = []
    for name in names:
        path = args.out / "units" / f"{name}-s{args.seed}-{key}.json"
        if path.is_file():
            rows.append(read_json(path)["result"])
            continue
        print(f"tracking {name} ...", file=sys.stderr, flush=True)
        row = measure(name, config, args.out, args.seed)
        write_json(path, {"config": config.to_dict(), "result": row})
        rows.append(row)
    print(f"configuration {key} ({config.evaluations} evaluations per frame)\n")
    print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
