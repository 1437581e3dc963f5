"""Hashes of what the tracker decides, to check that a speed change leaves it byte-identical (issue 41).

``python -m experiments.identical_poses [--sequences gestures-1 arms-crossing] [--frames 40]``

For each synthetic sequence (seed 0, 160x120, true calibration) the default tracker is pushed
every frame (:meth:`mocap.track.Tracker.push`, then ``finish``) without keypoints and with the
oracle keypoints (:func:`experiments.keypoints.oracle_keypoints`); prints one JSON object per
run: the SHA-256 of the decided poses, joints, residuals, scores and evaluation counts (float
bytes as they are). Run it in two trees (e.g. a baseline ``git worktree``) and compare the lines.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import tempfile

import numpy as np


def run(name: str, frames: int, keypoints: bool) -> dict:
    from mocap.body.mesh import resolution_for_image
    from mocap.calibrate import Calibration, colour_model_from_pose
    from mocap.imaging import prepare_frame
    from mocap.io.pose_table import PoseTable
    from mocap.io.sequence import find_sequence
    from mocap.io.video import iter_frames, read_image
    from mocap.synth import generate_sequence
    from mocap.track import Tracker, TrackerConfig

    from experiments.keypoints import oracle_keypoints

    with tempfile.TemporaryDirectory() as tmp:
        seq = find_sequence(generate_sequence(name, tmp, frames=frames, seed=0, progress=False))
        calibration = Calibration.from_json(seq.calibration)
        camera = calibration.camera
        model = calibration.body_model(resolution_for_image(*camera.shape[::-1]))
        images = list(iter_frames(seq.frames))
        background = read_image(seq.background)
        colour = colour_model_from_pose(images[0], background, model, camera, calibration.initial_pose)
        model = model.with_class_names(colour.names)
        given = (oracle_keypoints(PoseTable.read(seq.ground_truth).joints, camera) if keypoints
                 else [None] * len(images))
        tracker = Tracker(model, camera, TrackerConfig(), calibration.initial_pose)
        results = []
        for i, frame in enumerate(images):
            results += tracker.push(i, prepare_frame(frame, background, colour), given[i])
        results += tracker.finish()
    digest = hashlib.sha256()
    for r in sorted(results, key=lambda r: r.frame):
        digest.update(np.asarray(r.pose, np.float64).tobytes())
        digest.update(np.asarray(r.joints, np.float64).tobytes())
        digest.update(np.array([r.region_residual, r.edge_residual, r.edge_residual_after_region, r.score,
                                r.evaluations, r.hypothesis], np.float64).tobytes())
    return {"sequence": name, "frames": len(results), "keypoints": keypoints, "sha256": digest.hexdigest(),
            "evaluations": int(sum(r.evaluations for r in results))}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sequences", nargs="+", default=["gestures-1", "arms-crossing"])
    p.add_argument("--frames", type=int, default=40)
    args = p.parse_args(argv)
    for name in args.sequences:
        for keypoints in (False, True):
            print(json.dumps(run(name, args.frames, keypoints)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
