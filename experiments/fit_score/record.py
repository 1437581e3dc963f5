"""``python -m experiments.fit_score record``: track benchmark sequences and record every frame's candidates.

Tracks benchmark sequences (:func:`experiments.ambiguity.benchmark_sequence`: full length,
160x120, true calibration) with the oracle's 2D keypoints (projected truth plus ``--sigma-px`` of
noise, :func:`experiments.keypoints.oracle_keypoints`) and a tracker configuration (default: the
defaults), and writes every frame's candidates (:attr:`mocap.track.Tracker.scored`) with each
term's value before its weight (:meth:`mocap.track.ScoredCandidate.values`: the motion term from
the previous frame's best-path hypothesis) and their error against the truth: MPJPE about the
neck and in the camera, millimetres. One ``.npz`` per (sequence, seed) under ``--out``, written
atomically (a crash leaves the finished sequences; a second run skips them); also each
candidate's joints, the truth, the lifter's hypotheses and the decided poses. ``--no-keypoints``
tracks the silhouette alone; ``--max-frames`` records only each sequence's first frames.
"""
from __future__ import annotations

import argparse
import io
import json
import math
import sys
from pathlib import Path

import numpy as np

from experiments import RESULTS_DIR
from experiments.fit_score.candidates import K_SAVED, TERMS, record_path

#: Default seeds recorded.
SEEDS = "0,1"


def record_sequence(sequence: str, seed: int, out: Path, config, sigma_px: float | None, data_root: Path,
                    max_frames: int | None = None) -> Path:
    """Track one sequence with oracle keypoints (``sigma_px`` None: without keypoints) and write its
    candidates (see the module); ``max_frames``: only its first frames."""
    from experiments.ambiguity import benchmark_sequence
    from experiments.keypoints import oracle_keypoints
    from mocap.io.files import write_bytes_atomic
    from mocap.metrics import mpjpe, root_relative_mpjpe
    from mocap.track import Tracker

    loaded, prepared = benchmark_sequence(sequence, data_root, seed)
    prepared = prepared[:max_frames]
    camera = loaded.calibration.camera
    truth = loaded.ground_truth.joints
    keypoints = ([None] * len(prepared) if sigma_px is None
                 else oracle_keypoints(truth[: len(prepared)], camera, sigma_px, seed))
    tracker = Tracker(loaded.model, camera, config, loaded.calibration.initial_pose)
    rows: dict[str, list] = {k: [] for k in ("frame", "features", "error_mm", "camera_error_mm", "origin", "joints")}
    lifter_best, results, lifted_joints, lifted_p = [], [], [], []
    for i, frame in enumerate(prepared):
        results += tracker.push(i, frame, keypoints[i])
        scored = tracker.scored
        if scored:
            joints = np.array([c.joints for c in scored])
            t = np.repeat(truth[i:i + 1], len(scored), axis=0)
            rows["frame"] += [i] * len(scored)
            rows["features"] += [c.values(previous=0) for c in scored]
            rows["error_mm"] += list(root_relative_mpjpe(joints, t, per_frame=True))
            rows["camera_error_mm"] += list(mpjpe(joints, t, per_frame=True))
            rows["origin"] += [c.origin for c in scored]
            rows["joints"] += list(joints)
        lifted = tracker.lifted
        lifted_joints.append(np.full((K_SAVED, 10, 3), np.nan) if lifted is None else lifted.joints[:K_SAVED])
        lifted_p.append(np.full(K_SAVED, np.nan) if lifted is None else lifted.probabilities[:K_SAVED])
        lifter_best.append(math.inf if lifted is None else float(np.min(root_relative_mpjpe(
            lifted.joints, np.repeat(truth[i:i + 1], len(lifted), axis=0), per_frame=True))))
    results += tracker.finish()
    tracked = np.array([r.joints for r in results])
    buffer = io.BytesIO()
    np.savez_compressed(buffer, frame=np.array(rows["frame"], dtype=np.int64),
                        features=np.array(rows["features"], dtype=np.float64).reshape(-1, len(TERMS)),
                        error_mm=np.array(rows["error_mm"]), camera_error_mm=np.array(rows["camera_error_mm"]),
                        origin=np.array(rows["origin"], dtype=str), lifter_best_mm=np.array(lifter_best),
                        joints=np.array(rows["joints"], dtype=np.float64).reshape(-1, 10, 3),
                        truth=truth[: len(prepared)], lifted_joints=np.array(lifted_joints),
                        lifted_probabilities=np.array(lifted_p),
                        tracked_joints=tracked, tracked_poses=np.array([r.pose for r in results]),
                        tracked_error_mm=root_relative_mpjpe(tracked, truth[: len(tracked)], per_frame=True),
                        tracked_camera_error_mm=mpjpe(tracked, truth[: len(tracked)], per_frame=True),
                        config=np.array(json.dumps(config.to_dict(), sort_keys=True)), sigma_px=np.array(np.nan if sigma_px is None else sigma_px))
    path = record_path(out, sequence, seed)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bytes_atomic(path, buffer.getvalue())
    return path


def add_parser(sub) -> argparse.ArgumentParser:
    r = sub.add_parser("record", help="track sequences with oracle keypoints and record every frame's candidates")
    r.add_argument("--sigma-px", type=float, default=2.0, help="the oracle keypoints' noise (pixels)")
    r.add_argument("--no-keypoints", action="store_true", help="track without keypoints (the silhouette only)")
    r.add_argument("--config-file", type=Path, help="TrackerConfig JSON to record with (default: the defaults)")
    r.add_argument("--max-frames", type=int, help="only the first frames of each sequence (a smoke test)")
    r.add_argument("--data", type=Path, default=RESULTS_DIR / "tracking",
                   help="where the generated sequences are (made there when missing)")
    return r


def run(args, sequences: list[str], seeds: list[int]) -> int:
    """The subcommand: every (seed, sequence) not yet recorded."""
    from mocap.track import TrackerConfig

    if args.max_frames is not None and args.max_frames < 1:
        print(f"error: --max-frames must be at least 1, got {args.max_frames}", file=sys.stderr)
        return 2
    config = TrackerConfig.from_json(args.config_file) if args.config_file else TrackerConfig()
    for seed in seeds:
        for sequence in sequences:
            if record_path(args.out, sequence, seed).is_file():
                continue
            print(f"recording {sequence} seed {seed}", flush=True)
            record_sequence(sequence, seed, args.out, config, None if args.no_keypoints else args.sigma_px, args.data,
                            args.max_frames)
    return 0
