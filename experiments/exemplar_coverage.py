"""``python -m experiments.exemplar_coverage``: how often an exemplar proposal is near the truth.

Queries the shipped exemplar source (:class:`mocap.track.exemplars.ExemplarSource`) with the
image side's label image of every frame of the six benchmark sequences (full length, 160x120,
true calibration, ``--seed``) and counts the frames on which at least one of the first M
proposals (the M/2 nearest exemplars, each followed by its turn) is within 100 mm of the truth,
joints about the neck (:func:`mocap.metrics.root_relative_mpjpe`: the posture, wherever the
placement puts the root). The leading pose handed to the source is the true one (the source
reads only its depth and heading, which do not change the posture). Also reported: the share
caught by the exemplars alone (without their turns), the share when the turns are re-posed
towards the hands' camera rays (:func:`mocap.body.jumps.torso_flip`, 6 ms each, instead of the
source's :func:`~mocap.body.jumps.turned_mirror`), and the time of one query (descriptor, PCA
and neighbour search) and of the whole ``propose`` (with the placements), per frame (medians).
About 10 minutes on one core (the re-posed turns take most of it).

The generated sequences are kept under ``--out`` (default
``experiments/results/exemplar_coverage``) and reused.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from experiments import RESULTS_DIR
from experiments.units import DataSpec, load_prepared, load_sequence, prepare_data
from mocap.body.jumps import torso_flip
from mocap.metrics import DEFAULT_FAILURE_MM, root_relative_mpjpe
from mocap.synth import SEQUENCE_NAMES, SEQUENCES
from mocap.track.exemplars import ExemplarSource
from mocap.track.proposals import ProposalContext

#: Proposals per frame counted (the first M of each frame's list).
PROPOSAL_COUNTS = (10, 20, 40)
SIZE = (160, 120)


def measure(sequence: str, source: ExemplarSource, root: Path, seed: int,
            counts: tuple[int, ...] = PROPOSAL_COUNTS) -> dict:
    """Coverage of one benchmark sequence (see the module).

    Returns
    -------
    dict
        ``frames``; ``covered[M]`` (share of frames with one of the first M proposals within
        100 mm); ``covered_without_turns[M]``; ``best_mm`` (per frame, the nearest of all
        proposals, mm); ``query_ms`` and ``propose_ms`` (medians per frame).
    """
    folder = prepare_data(DataSpec(sequence, None, SEQUENCES[sequence].frames, seed, *SIZE), str(root))
    loaded, prepared = load_sequence(folder), load_prepared(folder)
    model, camera = loaded.model, loaded.calibration.camera
    truth_poses, truth_joints = loaded.ground_truth.poses, loaded.ground_truth.joints
    source = source.with_neighbours(max(counts) // 2)
    distances, reposed, query_ms, propose_ms = [], [], [], []
    for i, frame in enumerate(prepared):
        started = time.perf_counter()
        source.nearest(frame.labels, model.class_names)
        query_ms.append(1e3 * (time.perf_counter() - started))
        started = time.perf_counter()
        proposals = source.propose(frame, ProposalContext(model, camera, truth_poses[i]))
        propose_ms.append(1e3 * (time.perf_counter() - started))
        joints = np.stack([model.joint_positions(p.pose) for p in proposals])
        truth = np.repeat(truth_joints[i:i + 1], len(joints), axis=0)
        distances.append(root_relative_mpjpe(joints, truth, per_frame=True))
        # the turns re-posed towards the hands' camera rays (torso_flip) instead, for comparison
        flipped = np.stack([model.joint_positions(torso_flip(p.pose, model.skeleton)) for p in proposals[::2]])
        reposed.append(root_relative_mpjpe(flipped, truth[::2], per_frame=True))
    d = np.array(distances)                     # (frames, proposals): exemplar, its turn, next exemplar, ...
    d_reposed = d.copy()
    d_reposed[:, 1::2] = np.array(reposed)
    return {"sequence": sequence, "frames": len(d),
            "covered": {m: float((d[:, :m].min(axis=1) <= DEFAULT_FAILURE_MM).mean()) for m in counts},
            "covered_without_turns": {m: float((d[:, :m:2].min(axis=1) <= DEFAULT_FAILURE_MM).mean()) for m in counts},
            "covered_reposed_turns": {m: float((d_reposed[:, :m].min(axis=1) <= DEFAULT_FAILURE_MM).mean())
                                      for m in counts},
            "best_mm": d.min(axis=1).tolist(),
            "query_ms": float(np.median(query_ms)), "propose_ms": float(np.median(propose_ms))}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.exemplar_coverage", description=__doc__.split("\n\n")[0])
    p.add_argument("--seed", type=int, default=11, help="benchmark seed (never one the proposer was tuned on)")
    p.add_argument("--sequences", default=",".join(SEQUENCE_NAMES))
    p.add_argument("--out", type=Path, default=RESULTS_DIR / "exemplar_coverage")
    args = p.parse_args(argv)
    names = [s.strip() for s in args.sequences.split(",") if s.strip()]
    unknown = [s for s in names if s not in SEQUENCES]
    if unknown or not names:
        print(f"error: unknown sequence(s) {', '.join(unknown) or '(none given)'}; choose from "
              f"{', '.join(SEQUENCE_NAMES)}", file=sys.stderr)
        return 2
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    started = time.perf_counter()
    source = ExemplarSource.default()
    load_s = time.perf_counter() - started
    rows = [measure(name, source, args.out, args.seed) for name in names]
    head = " | ".join(f"M={m}" for m in PROPOSAL_COUNTS)
    print(f"| sequence | frames | {head} | M=40 without turns | M=40 turns re-posed | query ms | propose ms |")
    print("|---" * (6 + len(PROPOSAL_COUNTS)) + "|")
    for r in rows:
        print(f"| {r['sequence']} | {r['frames']} | " + " | ".join(f"{100 * r['covered'][m]:.1f} %" for m in PROPOSAL_COUNTS)
              + f" | {100 * r['covered_without_turns'][max(PROPOSAL_COUNTS)]:.1f} % | "
              f"{100 * r['covered_reposed_turns'][max(PROPOSAL_COUNTS)]:.1f} % | {r['query_ms']:.1f} | "
              f"{r['propose_ms']:.1f} |")
    n = sum(r["frames"] for r in rows)
    pooled = {m: sum(r["covered"][m] * r["frames"] for r in rows) / n for m in PROPOSAL_COUNTS}
    alone, reposed = (sum(r[key][max(PROPOSAL_COUNTS)] * r["frames"] for r in rows) / n
                      for key in ("covered_without_turns", "covered_reposed_turns"))
    print(f"| all (pooled) | {n} | " + " | ".join(f"{100 * pooled[m]:.1f} %" for m in PROPOSAL_COUNTS)
          + f" | {100 * alone:.1f} % | {100 * reposed:.1f} % | | |")
    print(f"seed {args.seed}; {source.n_exemplars} exemplars loaded in {load_s:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
