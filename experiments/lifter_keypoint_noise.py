"""``python -m experiments.lifter_keypoint_noise``: measure MediaPipe Pose's keypoints against the model's joints.

The lifter (:mod:`mocap.track.lifter`, trained by :mod:`experiments.fit_lifter`) must take a
detector's keypoints, whose joints are not the model's: MediaPipe's shoulder landmark sits
higher and further out than the model's shoulder joint, its "head" (the ears' midpoint) is not
the model's head centre, and it has no neck. This measures, per joint, the mean offset and the
spread of MediaPipe's 2D landmarks (:class:`mocap.io.mediapipe_keypoints.MediaPipeKeypoints`)
about the true projected joints, in units of the keypoints' scale (the RMS distance of the ten
true joints from their mean, the lifter's normalisation), and how often each joint is missed.

Frames: the toolkit's synthetic sensor (:func:`mocap.synth.generate_sequence`, 160x120, each of the
six sequences' actors and scenes with generator seeds :data:`SEEDS` that no benchmark uses)
driven by CMU *training* trials (one per subject, :data:`FRAMES` frames each) — never the
benchmark's procedural motion. MediaPipe sees the frames enlarged 4x (it does not find people at
160x120), as in :mod:`experiments.peers`. Robust statistics: the median offset and 1.4826 times
the median absolute deviation about it (a gross miss, e.g. left and right swapped, would
otherwise inflate the spread of every frame); the share of gross misses (over 1.0 of the scale)
is reported apart.

Writes ``experiments/lifter_keypoint_noise.json`` (read by :mod:`experiments.fit_lifter`).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from experiments import EXPERIMENTS_DIR
from experiments.fit_pose_prior import TRAIN_DIR
from mocap.body.skeleton import JOINT_NAMES

#: One CMU training trial per subject (file stems) drives one synthetic sequence each.
TRIALS = ("cmu_02_05", "cmu_05_02", "cmu_14_05", "cmu_17_10", "cmu_49_09", "cmu_127_02")
#: Generator seeds of the sequences' actors and scenes (no benchmark uses them).
SEEDS = (1000, 1001, 1002, 1003, 1004, 1005)
#: Frames per sequence (25 frames per second).
FRAMES = 100
#: Enlargement of the frames for MediaPipe.
UPSCALE = 4
#: A landmark further than this (in units of the scale) from the joint is a gross miss.
GROSS = 1.0
#: Confidence under which a landmark counts as missing (MediaPipe's visibility).
MIN_CONFIDENCE = 0.5
OUT = EXPERIMENTS_DIR / "lifter_keypoint_noise.json"


def measure(train_dir: Path, work: Path, progress: bool = True) -> dict:
    """Residuals of MediaPipe's keypoints; see the module docstring. Returns the JSON's content."""
    from skimage.transform import rescale
    from tqdm import tqdm

    from mocap.io.mediapipe_keypoints import MediaPipeKeypoints
    from mocap.io.pose_table import PoseTable
    from mocap.io.video import iter_frames
    from mocap.render.calibration import Calibration
    from mocap.synth import SEQUENCE_NAMES, generate_sequence

    residuals, missing, found = [], [], 0
    total = 0
    available = {p.stem for p in train_dir.glob("*.amc")}
    trials = [t for t in TRIALS if t in available]
    if not trials:
        raise FileNotFoundError(f"none of the trials {TRIALS} in {train_dir}")
    for name, seed, trial in tqdm(list(zip(SEQUENCE_NAMES, SEEDS, trials)), desc="sequences", disable=not progress):
        seq = generate_sequence(name, work / name, frames=FRAMES, seed=seed, motion=train_dir / f"{trial}.amc",
                                progress=False)
        truth = PoseTable.read(seq / "ground_truth.csv").joints
        camera = Calibration.from_json(seq / "calibration.json").camera
        with MediaPipeKeypoints() as detector:
            for i, frame in enumerate(iter_frames(seq / "frames")):
                total += 1
                big = (rescale(frame, UPSCALE, order=1, channel_axis=-1) * 255).round().astype(np.uint8)
                kp = detector.keypoints(i, big).scaled(1.0 / UPSCALE, 1.0 / UPSCALE)
                uv_true = camera.project(truth[i])
                scale = np.sqrt(np.mean(np.sum((uv_true - uv_true.mean(axis=0)) ** 2, axis=1)))
                present = kp.present & (kp.confidence >= MIN_CONFIDENCE)
                missing.append(~present)
                if present.any():
                    found += 1
                residuals.append(np.where(present[:, None], (kp.uv - uv_true) / scale, np.nan))
    r = np.array(residuals)                       # (frames, 10, 2)
    miss = np.array(missing)
    joints = {}
    for j, name in enumerate(JOINT_NAMES):
        rj = r[:, j][np.isfinite(r[:, j]).all(axis=1)]
        if len(rj) < 10:
            joints[name] = {"offset": [0.0, 0.0], "sigma": 0.0, "missing": 1.0, "frames": int(len(rj))}
            continue
        offset = np.median(rj, axis=0)
        dist = np.linalg.norm(rj - offset, axis=1)
        mad = np.median(np.abs(rj - offset), axis=0)
        joints[name] = {"offset": [round(float(v), 4) for v in offset],
                        "sigma": round(float(1.4826 * mad.mean()), 4),
                        "missing": round(float(miss[:, j].mean()), 4),
                        "gross": round(float((dist > GROSS).mean()), 4),
                        "mean": [round(float(v), 4) for v in rj.mean(axis=0)],
                        "std": [round(float(v), 4) for v in rj.std(axis=0)],
                        "frames": int(len(rj))}
    return {"what": "MediaPipe Pose 2D landmarks minus the model's projected joints, in units of the ten true "
                    "joints' RMS distance from their mean (u right, v down); offset = median, sigma = 1.4826 MAD "
                    "per coordinate, missing = share of frames without the joint (visibility < "
                    f"{MIN_CONFIDENCE}), gross = share of residuals over {GROSS}",
            "command": "python -m experiments.lifter_keypoint_noise", "trials": trials, "seeds": list(SEEDS),
            "frames": total, "frames_found": found, "upscale": UPSCALE, "joints": joints}


def main(argv=None) -> int:
    from mocap.io.jsonfile import write_json

    p = argparse.ArgumentParser(prog="python -m experiments.lifter_keypoint_noise",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("--train", type=Path, default=TRAIN_DIR, help="folder of CMU .asf/.amc trials")
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(argv)
    if not args.train.is_dir():
        print(f"error: no training folder {args.train}", file=sys.stderr)
        return 2
    try:
        import mediapipe  # noqa: F401
    except ImportError:
        print("error: needs MediaPipe Pose, the optional extra 'keypoints'", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        result = measure(args.train, Path(tmp))
    write_json(args.out, result)
    for name, j in result["joints"].items():
        print(f"{name:11s} offset {j['offset']} sigma {j['sigma']:.3f} missing {j['missing']:.2f} "
              f"gross {j.get('gross', float('nan')):.3f}")
    print(f"wrote {args.out} ({result['frames']} frames, {result['frames_found']} with a person)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
