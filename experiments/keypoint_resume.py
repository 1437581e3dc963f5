"""``python -m experiments.keypoint_resume``: what an exact resume with MediaPipe keypoints costs.

MediaPipe Pose's video mode carries state from frame to frame (the region it tracks the person
in, its landmark smoothing), so a run resumed at frame ``k`` with a fresh detector gets other
keypoints from ``k`` on than the uninterrupted run (issue 35). The ways out, measured here on a
synthetic clip (``gestures-3``, ``--frames`` frames of ``--seed``, at its 160x120 input size,
as ``track --keypoints mediapipe`` runs the detector):

* ``video``: the uninterrupted video mode (the reference), per-frame milliseconds;
* ``image``: image mode (``static_image_mode``: no state; every frame detected afresh);
* ``refeed-N``: a fresh video-mode detector fed the ``N`` frames before each resume point, then
  the 25 frames from it: are they the reference's, bit for bit? (``N = k``: a replay from the
  start);
* for each: whether a second detector of the same mode gives the same keypoints, bit for bit;
  PCK@0.5 (half the reference's shoulder width) against the video mode, and the mean
  pixel distance to the ground truth's projected joints (shoulders, elbows, wrists; MediaPipe's
  other joints are defined apart from the model's);
* with ``--clip VIDEO``: the same two modes on the first ``--clip-frames`` frames of a real
  clip instead of the synthetic one (no ground truth: PCK against the video mode only);
* with ``--track``: the tracker's accuracy (``run.json`` ``metrics``) on the clip with each
  mode's keypoints (given as a keypoint file, so that only the keypoints differ).

Prints one JSON object.
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

JOINTS = ("r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist")


def detect(frames, image_mode: bool) -> tuple[np.ndarray, float]:
    """Keypoints (frames, 10, 2) input pixels and the median ms per frame."""
    from mocap.io.mediapipe_keypoints import MediaPipeKeypoints

    with MediaPipeKeypoints(image_mode=image_mode) as detector:
        uv = np.stack([detector.keypoints(i, f).uv for i, f in enumerate(frames)])
        return uv, float(np.median(detector.milliseconds))


def refed(frames, first: int, resume: int, frames_after: int) -> np.ndarray:
    """Video-mode keypoints of ``resume .. resume + frames_after - 1`` from a detector fed
    ``first .. resume - 1`` before them."""
    from mocap.io.mediapipe_keypoints import MediaPipeKeypoints

    with MediaPipeKeypoints() as detector:
        for i in range(first, resume):
            detector.keypoints(i, frames[i])
        return np.stack([detector.keypoints(i, frames[i]).uv for i in range(resume, resume + frames_after)])


def tracked_with_each_mode(seq: Path, frames, work: Path) -> dict:
    """``run.json`` ``metrics`` of ``track`` on ``seq`` with each mode's keypoints (a file each)."""
    from mocap.io.keypoints import write_keypoints
    from mocap.io.mediapipe_keypoints import MediaPipeKeypoints
    from mocap.run import OwnVideoOptions, files, track

    out = {}
    for name, image_mode in (("video", False), ("image", True)):
        with MediaPipeKeypoints(image_mode=image_mode) as detector:
            write_keypoints(work / f"{name}.csv", {i: detector.keypoints(i, f) for i, f in enumerate(frames)})
        summary = track(seq, work / name, OwnVideoOptions(keypoints=str(work / f"{name}.csv"), overlay=False),
                        progress=False)
        metrics = json.loads((work / name / files.RUN_JSON).read_text())["metrics"]
        out[name] = {k: round(metrics[k], 4) for k in ("mpjpe_mm", "pa_mpjpe_mm", "failure_rate")}
        out[name]["frames"] = summary.frames
    return out


def compare_on_clip(clip: Path, count: int) -> dict:
    """Video and image mode on the first ``count`` frames of ``clip``: ms, joints found, PCK
    (0.5 and 0.1 of the video mode's shoulder width) and the median pixel distance to the video mode."""
    from mocap.body.skeleton import JOINT_NAMES
    from mocap.io.video import iter_frames
    from mocap.metrics import pck_2d

    frames = [frame for _, frame in zip(range(count), iter_frames(clip))]
    out = {"clip": str(clip), "frames": len(frames), "size": list(frames[0].shape[1::-1])}
    uv = {}
    for name, image_mode in (("video", False), ("image", True)):
        uv[name], ms = detect(frames, image_mode)
        out[name] = {"median_ms": round(ms, 2), "found": round(float(np.isfinite(uv[name][:, :, 0]).mean()), 4)}
    ref = uv["video"]
    width = np.linalg.norm(ref[:, JOINT_NAMES.index("r_shoulder")] - ref[:, JOINT_NAMES.index("l_shoulder")], axis=1)
    out["image"].update(pck_vs_video=round(pck_2d(uv["image"], ref, width), 4),
                        pck_0_1_vs_video=round(pck_2d(uv["image"], ref, width, 0.1), 4),
                        median_px_to_video=round(float(np.nanmedian(np.linalg.norm(uv["image"] - ref, axis=2))), 2))
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.keypoint_resume", description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--seed", type=int, default=41)
    parser.add_argument("--resume-at", type=int, nargs="+", default=[50, 100, 175, 250])
    parser.add_argument("--refeed", type=int, nargs="+", default=[0, 5, 25])
    parser.add_argument("--track", action="store_true", help="also track the clip with each mode's keypoints")
    parser.add_argument("--clip", type=Path, default=None, help="a real clip: compare the two modes on it only")
    parser.add_argument("--clip-frames", type=int, default=65)
    args = parser.parse_args(argv)

    from mocap.body.skeleton import JOINT_NAMES
    from mocap.io.pose_table import PoseTable
    from mocap.io.video import iter_frames
    from mocap.metrics import pck_2d
    from mocap.render.calibration import Calibration
    from mocap.synth.sequence import generate_sequence

    if args.clip is not None:
        print(json.dumps(compare_on_clip(args.clip, args.clip_frames), indent=1))
        return 0
    with tempfile.TemporaryDirectory() as work:
        seq = generate_sequence("gestures-3", Path(work) / "seq", frames=args.frames, seed=args.seed, progress=False)
        frames = list(iter_frames(seq / "frames"))
        camera = Calibration.from_json(seq / "calibration.json").camera
        truth = camera.project(PoseTable.read(seq / "ground_truth.csv").joints)
        tracked = tracked_with_each_mode(seq, frames, Path(work)) if args.track else None
    picked = [JOINT_NAMES.index(j) for j in JOINTS]
    result = {"frames": len(frames), "seed": args.seed, "size": list(frames[0].shape[1::-1])}
    reference, ref_ms = None, None
    started = time.perf_counter()
    runs = {}
    for name, image_mode in (("video", False), ("image", True)):
        started = time.perf_counter()
        uv, ms = detect(frames, image_mode)
        runs[name] = uv
        result[name] = {"median_ms": round(ms, 2), "wall_s": round(time.perf_counter() - started, 2),
                        "repeat_identical": bool(np.array_equal(detect(frames, image_mode)[0], uv, equal_nan=True))}
    reference = runs["video"]
    shoulders = np.linalg.norm(reference[:, JOINT_NAMES.index("r_shoulder")]
                               - reference[:, JOINT_NAMES.index("l_shoulder")], axis=1)
    for name, uv in runs.items():
        error = np.linalg.norm(uv[:, picked] - truth[:, picked], axis=2)
        result[name].update(pck_vs_video=round(pck_2d(uv, reference, shoulders), 4),
                            detected=round(float(np.isfinite(uv[:, picked, 0]).mean()), 4),
                            px_to_truth=round(float(np.nanmean(error)), 3))
    after = 25
    for n in args.refeed:
        rows = {}
        for k in args.resume_at:
            got = refed(frames, k - n, k, after)
            want = reference[k:k + after]
            same = np.array_equal(got, want, equal_nan=True)
            rows[str(k)] = {"identical": bool(same), "max_px": round(float(np.nanmax(np.abs(got - want))), 4)}
        result[f"refeed-{n}"] = rows
    rows = {}
    for k in args.resume_at:
        started = time.perf_counter()
        got = refed(frames, 0, k, after)
        rows[str(k)] = {"identical": bool(np.array_equal(got, reference[k:k + after], equal_nan=True)),
                        "wall_s": round(time.perf_counter() - started, 2)}
    result["replay"] = rows
    if tracked is not None:
        result["tracked"] = tracked
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
