"""``python -m experiments.lifter_coverage``: how often the lifter's hypotheses contain the truth.

Coverage at M: the share of frames on which one of the lifter's first M hypotheses (most
probable first, :meth:`mocap.track.lifter.Lifter.lift`) is within :data:`COVERED_MM` of the
truth (mean joint distance, joints about the neck, :func:`mocap.metrics.root_relative_mpjpe`),
for M in :data:`M_VALUES`. Three measures:

* ``--oracle``: oracle keypoints (the true joints projected plus sigma = 2 px,
  :func:`experiments.keypoints.oracle_keypoints`) on the six benchmark sequences at full length
  for a generator seed (:func:`mocap.synth.setup_sequence` and
  :func:`mocap.synth.sequence_poses` give exactly the ground truth that
  :func:`mocap.synth.datasets.make_benchmark` writes; no frame needs rendering for this), each
  sequence's own body and camera;
* ``--mediapipe``: MediaPipe Pose's 2D landmarks (:class:`mocap.io.mediapipe_keypoints.MediaPipeKeypoints`,
  on the frames enlarged 4x as :mod:`experiments.peers` does; landmarks with visibility under 0.5
  missing; no neck) on the rendered benchmark of that seed (``make_benchmark``);
* ``--loso``: each CMU training subject held out in turn: a lifter trained on the others
  (:data:`LOSO_HIDDEN`, :data:`LOSO_STEPS`: a smaller budget than the shipped model's) and
  queried with projections of the held-out subject's poses (random heading, body and place
  before the benchmark's camera, 160x120, 60 degrees; oracle noise 2 px).

Writes ``results.json`` in ``--out`` (default ``experiments/lifter_coverage``), merged with
what is there (each measure replaces its own entry), and the figure
(:mod:`experiments.figures.ext_lifter_coverage`).
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from experiments import EXPERIMENTS_DIR

#: Hypotheses counted.
M_VALUES = (1, 2, 5, 10)
#: A frame is covered when a hypothesis is this close (mm).
COVERED_MM = 100.0
#: Leave-one-subject-out budget per fold.
LOSO_HIDDEN = (256, 256, 256)
LOSO_STEPS = 1500
#: Poses per held-out subject queried (drawn evenly).
LOSO_QUERIES = 1500
OUT = EXPERIMENTS_DIR / "lifter_coverage"


def hypothesis_errors(lifter, keypoints_uv, visible, camera, model, truth) -> np.ndarray:
    """Root-relative MPJPE (mm) of every hypothesis of each frame, most probable first.

    Parameters
    ----------
    keypoints_uv : ndarray, shape (n, 10, 2), pixels
    visible : ndarray of bool, shape (n, 10)
    camera : Camera or list of Camera (one per frame)
    model : BodyModel or list of BodyModel (one per frame)
    truth : ndarray, shape (n, 10, 3), metres

    Returns
    -------
    ndarray, shape (n, K), millimetres; NaN rows where too few joints were visible.
    """
    from mocap.metrics import root_relative_mpjpe
    from mocap.track.lifter import MIN_VISIBLE

    n = len(keypoints_uv)
    out = np.full((n, lifter.n_hypotheses), np.nan)
    for i in range(n):
        if visible[i].sum() < MIN_VISIBLE:
            continue
        cam = camera[i] if isinstance(camera, list) else camera
        body = model[i] if isinstance(model, list) else model
        lifted = lifter.lift(keypoints_uv[i], visible[i], cam, body)
        truth_k = np.repeat(truth[i][None], len(lifted), axis=0)
        out[i] = root_relative_mpjpe(lifted.joints, truth_k, per_frame=True)
    return out


def coverage(errors: np.ndarray) -> dict:
    """Coverage at each M of :data:`M_VALUES` (share of all frames; a frame without hypotheses is
    not covered) and the median best-of-K error (mm)."""
    out = {}
    for m in M_VALUES:
        best = np.nanmin(np.where(np.isnan(errors[:, :m]), np.inf, errors[:, :m]), axis=1)
        out[f"coverage_at_{m}"] = float(np.mean(best <= COVERED_MM))
    best = np.min(np.where(np.isnan(errors), np.inf, errors), axis=1)
    out["median_best_mm"] = float(np.median(best))
    out["median_top1_mm"] = float(np.nanmedian(errors[:, 0]))
    out["frames"] = int(len(errors))
    out["lifted_frames"] = int(np.isfinite(errors[:, 0]).sum())
    return out


def _summary(rows: dict[str, np.ndarray]) -> dict:
    return {"sequences": {name: coverage(e) for name, e in rows.items()},
            "all": coverage(np.concatenate(list(rows.values())))}


def oracle_measure(lifter, seed: int, sigma_px: float = 2.0) -> dict:
    """Coverage with oracle keypoints on the six sequences of ``seed`` at full length."""
    from experiments.keypoints import oracle_keypoints
    from mocap.body.model import BodyModel
    from mocap.synth import SEQUENCE_NAMES, setup_sequence
    from mocap.synth.sequence import sequence_poses

    rows = {}
    for name in SEQUENCE_NAMES:
        setup = setup_sequence(name, seed=seed)
        poses, _ = sequence_poses(setup)
        model = BodyModel.build(setup.actor.dims)
        truth = np.stack([model.joint_positions(q) for q in poses])
        kps = oracle_keypoints(truth, setup.camera, sigma_px, seed)
        uv = np.stack([k.uv for k in kps])
        rows[name] = hypothesis_errors(lifter, uv, np.ones(uv.shape[:2], bool), setup.camera, model, truth)
        print(f"oracle seed {seed} {name}: {coverage(rows[name])}", file=sys.stderr)
    return {"seed": seed, "sigma_px": sigma_px, **_summary(rows)}


def mediapipe_measure(lifter, seed: int, work: Path) -> dict:
    """Coverage with MediaPipe's landmarks on the rendered benchmark of ``seed`` (written to
    ``work``, or read from there when its six sequences are complete)."""
    from skimage.transform import rescale

    from mocap.io.mediapipe_keypoints import MediaPipeKeypoints
    from mocap.io.pose_table import PoseTable
    from mocap.io.video import iter_frames
    from mocap.render.calibration import Calibration
    from mocap.synth.datasets import make_benchmark

    rows = {}
    from mocap.synth import SEQUENCE_NAMES

    folders = [work / name for name in SEQUENCE_NAMES]
    if not all((f / "meta.json").is_file() and json.loads((f / "meta.json").read_text()).get("seed") == seed
               for f in folders):
        folders = make_benchmark(work, seed=seed, progress=False)
    for seq in folders:
        calibration = Calibration.from_json(seq / "calibration.json")
        truth = PoseTable.read(seq / "ground_truth.csv").joints
        uv, vis = [], []
        with MediaPipeKeypoints() as detector:
            for i, frame in enumerate(iter_frames(seq / "frames")):
                big = (rescale(frame, 4, order=1, channel_axis=-1) * 255).round().astype(np.uint8)
                kp = detector.keypoints(i, big).scaled(0.25, 0.25)
                uv.append(np.nan_to_num(kp.uv))
                vis.append(kp.present & (kp.confidence >= 0.5))
        rows[seq.name] = hypothesis_errors(lifter, np.array(uv), np.array(vis), calibration.camera,
                                           calibration.body_model(), truth)
        print(f"mediapipe seed {seed} {seq.name}: {coverage(rows[seq.name])}", file=sys.stderr)
    return {"seed": seed, **_summary(rows)}


@dataclass(frozen=True)
class HeldOutQueries:
    """Projections of a held-out subject's poses (see the module docstring, ``--loso``).

    Attributes
    ----------
    uv : ndarray, shape (n, 10, 2), pixels (oracle 2D + 2 px)
    camera : Camera (160x120, the benchmark's)
    models : list of BodyModel, one per query (8 random bodies in turn)
    truth : ndarray, shape (n, 10, 3), metres, camera coordinates
    """

    uv: np.ndarray
    camera: object
    models: list
    truth: np.ndarray


def held_out_queries(held: np.ndarray, subject: str, seed: int = 0, queries: int = LOSO_QUERIES) -> HeldOutQueries:
    """``queries`` of a held-out subject's poses ``held`` (n, 23), drawn evenly, each given a random
    heading, place before the camera and body (random generator seeded by ``seed`` and the subject)."""
    from experiments.keypoints import oracle_keypoints
    from mocap.body.model import BodyModel
    from mocap.body.pose import PARAMETER_INDEX
    from mocap.render.camera import Camera
    from mocap.synth.actor import random_dimensions

    held = np.asarray(held, dtype=np.float64)
    camera = Camera.default(160, 120)
    rng = np.random.default_rng([seed, 7, int(subject)])
    pick = held[np.linspace(0, len(held) - 1, min(queries, len(held))).astype(int)].copy()
    n = len(pick)
    z = rng.uniform(1.3, 2.6, n)
    pick[:, PARAMETER_INDEX["root_z"]] = z
    pick[:, PARAMETER_INDEX["root_y"]] = z * rng.uniform(0.27, 0.39, n)
    pick[:, PARAMETER_INDEX["root_x"]] = z * rng.uniform(-0.15, 0.15, n)
    pick[:, PARAMETER_INDEX["chest_yaw"]] = rng.uniform(-np.pi, np.pi, n)
    bodies = [BodyModel.build(random_dimensions(rng)) for _ in range(8)]
    models = [bodies[i % len(bodies)] for i in range(n)]
    truth = np.stack([m.joint_positions(q) for m, q in zip(models, pick)])
    uv = np.stack([k.uv for k in oracle_keypoints(truth, camera, 2.0, seed)])
    return HeldOutQueries(uv, camera, models, truth)


def held_out_errors(lifter, q: HeldOutQueries) -> np.ndarray:
    """:func:`hypothesis_errors` of ``lifter`` on :func:`held_out_queries`' projections, (n, K) mm."""
    return hypothesis_errors(lifter, q.uv, np.ones(q.uv.shape[:2], bool), q.camera, q.models, q.truth)


def loso_measure(train_dir: Path, seed: int = 0, hidden=LOSO_HIDDEN, steps: int = LOSO_STEPS,
                 queries: int = LOSO_QUERIES) -> dict:
    """Leave-one-subject-out coverage (see the module docstring)."""
    from experiments.fit_lifter import BATCH, KeypointNoise, export_weights, train, training_poses
    from mocap.track.lifter import Lifter

    poses, subjects = training_poses(train_dir)
    noise = KeypointNoise.read()
    rows, walls = {}, {}
    for subject in np.unique(subjects):
        started = time.perf_counter()
        net = train(poses[subjects != subject], seed=seed, hidden=hidden, steps=steps, batch=BATCH, noise=noise,
                    progress=False)
        lifter = Lifter(export_weights(net))
        walls[str(subject)] = round(time.perf_counter() - started, 1)
        rows[str(subject)] = held_out_errors(lifter, held_out_queries(poses[subjects == subject], subject, seed, queries))
        print(f"held out {subject}: {coverage(rows[str(subject)])} ({walls[str(subject)]:.0f} s)", file=sys.stderr)
    summary = _summary(rows)
    return {"hidden": list(hidden), "steps": steps, "queries_per_subject": queries, "wall_s": walls,
            "subjects": summary.pop("sequences"), **summary}


def main(argv=None) -> int:
    from experiments.fit_pose_prior import TRAIN_DIR
    from mocap.io.files import write_json
    from mocap.track.lifter import Lifter

    p = argparse.ArgumentParser(prog="python -m experiments.lifter_coverage", description=__doc__.split("\n\n")[0])
    p.add_argument("--lifter", type=Path, default=None, help="lifter file (default: the shipped one)")
    p.add_argument("--seed", type=int, default=23, help="benchmark generator seed (default 23, never used before)")
    p.add_argument("--oracle", action="store_true")
    p.add_argument("--mediapipe", action="store_true")
    p.add_argument("--loso", action="store_true")
    p.add_argument("--benchmark", type=Path, default=None,
                   help="folder for the rendered benchmark of --mediapipe (kept; reused when complete)")
    p.add_argument("--train", type=Path, default=TRAIN_DIR)
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(argv)
    if not (args.oracle or args.mediapipe or args.loso):
        print("error: choose at least one of --oracle, --mediapipe, --loso", file=sys.stderr)
        return 2
    try:
        lifter = Lifter.load(args.lifter)
    except (ValueError, FileNotFoundError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "results.json"
    results = json.loads(path.read_text()) if path.exists() else {}
    results["lifter"] = {"sha256": lifter.checksum, "provenance": lifter.provenance.get("command", "")}
    if args.oracle:
        results["oracle"] = oracle_measure(lifter, args.seed)
        write_json(path, results)
    if args.mediapipe:
        if args.benchmark is not None:
            results["mediapipe"] = mediapipe_measure(lifter, args.seed, args.benchmark)
        else:
            with tempfile.TemporaryDirectory() as tmp:
                results["mediapipe"] = mediapipe_measure(lifter, args.seed, Path(tmp))
        write_json(path, results)
    if args.loso:
        results["loso"] = loso_measure(args.train)
        write_json(path, results)
    from experiments.figures import ext_lifter_coverage

    ext_lifter_coverage.main(results, args.out)
    for key in ("oracle", "mediapipe", "loso"):
        if key in results:
            a = results[key]["all"]
            print(f"{key}: " + ", ".join(f"M={m} {100 * a[f'coverage_at_{m}']:.0f} %" for m in M_VALUES)
                  + f" (median best {a['median_best_mm']:.0f} mm, top-1 {a['median_top1_mm']:.0f} mm)")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
