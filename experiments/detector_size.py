"""How large a frame MediaPipe Pose must see (issue 44, item 2): ``python -m experiments.detector_size``.

``python -m experiments.detector_size [--sizes 160x120 320x240] [--sides 0 320 480 640 960]
[--frames 80] [--only synthetic|cmu] [--out DIR]``

On renders with ground truth, at each input size, MediaPipe Pose (the run's detector,
:class:`mocap.io.mediapipe_pose.PoseLandmarks`, image mode) is handed each frame enlarged to a
longer side of at least each of ``--sides`` pixels (0: as it is; an integer factor, bilinear:
:func:`enlarged`), and its arm joints (shoulders, elbows, wrists, as
:func:`mocap.io.mediapipe_keypoints.keypoints_of_landmarks` makes them) are compared with the
truth's projection, in input pixels:

- ``found``: share of frames where it found a person;
- ``swapped``: share of those frames where its arms fit the truth better with left and right
  exchanged (the person's left arm labelled right: :func:`experiments.peers.label_swapped`);
- ``error_px``: median over the found frames and the six joints of the distance to the truth,
  each frame under its better labelling (so a swap does not count twice), and ``error_pct`` the
  same as a percentage of the image width;
- ``ms``: median detection time per frame (wall clock, this machine as loaded).

Clips: the four synthetic sequences of ``experiments.peers`` (seed ``--seed``, 80 frames), and
with ``--only cmu`` or by default the CMU-driven clips of ``experiments.peers --only cmu``
(subject 14's trials, each in one of those sequences' settings; ``../shared/data/mocap/train``,
skipped with a line when absent). Writes ``OUT/results.json`` and ``OUT/detector_size.md``
(default ``experiments/results/detector_size``); a clip's rows are kept in ``OUT/rows/`` as it
ends, and the same command skips those (resume).

Measured on 2026-11-28 (docs/research-log.md): no side paid. MediaPipe crops the person's box
from the frame it is given and resamples it to its landmark model's input itself, so a frame
enlarged beforehand brings no detail, only another interpolation; the run's detector is handed
the input frame as it is.
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from experiments import RESULTS_DIR
from experiments.peers import ARM_JOINTS, CMU_SCENES, CMU_TRIALS, OTHER_SIDE, SYNTHETIC, label_swapped

#: Default longer sides (pixels) the frames are enlarged to (0: as they are).
SIDES = (0, 320, 480, 640, 960)


def enlargement(height: int, width: int, side: int) -> int:
    """The least integer factor bringing the longer of ``width`` x ``height`` to ``side``
    pixels (1 for a frame that large already, and for ``side`` 0)."""
    return max(1, -(-side // max(height, width)))


def enlarged(image: np.ndarray, side: int) -> np.ndarray:
    """``image`` (H, W, 3) uint8 enlarged by :func:`enlargement`'s factor, bilinear (OpenCV,
    which comes with MediaPipe), pixel centres kept: a point at ``(u, v)`` is at ``(k u, k v)``,
    so MediaPipe's normalised landmarks are the same in both."""
    factor = enlargement(image.shape[0], image.shape[1], side)
    if factor == 1:
        return image
    import cv2

    return cv2.resize(image, (image.shape[1] * factor, image.shape[0] * factor), interpolation=cv2.INTER_LINEAR)


def measure(frames: list[np.ndarray], truth_uv: np.ndarray, side: int) -> dict:
    """MediaPipe on ``frames`` (each (H, W, 3) uint8) enlarged to a longer side of ``side``
    pixels (0: as they are), against ``truth_uv`` (N, 6, 2) input pixels: the row's figures."""
    from mocap.body.skeleton import JOINT_NAMES
    from mocap.io.mediapipe_keypoints import keypoints_of_landmarks
    from mocap.io.mediapipe_pose import PoseLandmarks

    index = [JOINT_NAMES.index(j) for j in ARM_JOINTS]
    pose = PoseLandmarks(image_mode=True)
    detected, ms = [], []
    try:
        for frame in frames:
            t0 = time.perf_counter()
            landmarks = pose.detect(enlarged(frame, side))
            ms.append(1e3 * (time.perf_counter() - t0))
            keypoints = keypoints_of_landmarks(landmarks, *frame.shape[:2])    # normalised: input pixels
            uv = keypoints.uv[index].copy()
            uv[~keypoints.present[index]] = np.nan
            detected.append(uv)
    finally:
        pose.close()
    detected = np.asarray(detected, dtype=np.float64)
    found = np.isfinite(detected).all(axis=(1, 2))
    swapped = label_swapped(detected, truth_uv)
    better = np.where(swapped[:, None, None], detected[:, OTHER_SIDE], detected)
    errors = np.linalg.norm(better - truth_uv, axis=2)[found]
    width = frames[0].shape[1]
    error = float(np.median(errors)) if errors.size else float("nan")
    return {"side": side, "found": float(found.mean()), "swapped": float(swapped[found].mean()) if found.any() else
            float("nan"), "error_px": error, "error_pct": 100.0 * error / width, "ms": float(np.median(ms))}


def clips(only: str | None, train: Path, seed: int, frames: int) -> list[tuple[str, str, Path | None]]:
    """``(clip name, scene, motion file or None)`` of the material."""
    out = []
    if only in (None, "synthetic"):
        out += [(name, name, None) for name in SYNTHETIC]
    if only in (None, "cmu"):
        if not train.is_dir():
            print(f"no CMU training folder {train}: the CMU-driven clips are skipped", file=sys.stderr)
        else:
            trials = CMU_TRIALS["14"]
            out += [(f"cmu_{t}", CMU_SCENES[k % len(CMU_SCENES)], train / f"cmu_{t}.amc") for k, t in enumerate(trials)]
    return out


def clip_rows(name: str, scene: str, motion: Path | None, size: tuple[int, int], sides, work: Path, seed: int,
              frames: int) -> list[dict]:
    """Every side's row of one clip rendered at ``size`` (width, height)."""
    from mocap.body.skeleton import JOINT_NAMES
    from mocap.calibrate import Calibration
    from mocap.io.pose_table import PoseTable
    from mocap.io.video import iter_frames
    from mocap.synth import generate_sequence

    seq = generate_sequence(scene, work / f"{name}-{size[0]}x{size[1]}", frames=frames, seed=seed, size=size,
                            motion=motion, progress=False)
    camera = Calibration.from_json(seq / "calibration.json").camera
    joints = PoseTable.read(seq / "ground_truth.csv").joints[:, [JOINT_NAMES.index(j) for j in ARM_JOINTS]]
    truth_uv = camera.project(joints.reshape(-1, 3)).reshape(len(joints), len(ARM_JOINTS), 2)
    images = list(iter_frames(seq / "frames"))[: len(truth_uv)]
    return [{"clip": name, "size": f"{size[0]}x{size[1]}", "frames": len(images),
             **measure(images, truth_uv[: len(images)], side)} for side in sides]


def markdown(rows: list[dict]) -> str:
    """One table: per input size and side, the clips' figures and their medians."""
    lines = ["| input | enlarged to | clip | found | label swapped | arm joints' error px (% of width) | ms |",
             "|---|---|---|---:|---:|---:|---:|"]
    for size in sorted({r["size"] for r in rows}, key=lambda s: int(s.split("x")[0])):
        for side in sorted({r["side"] for r in rows}):
            group = [r for r in rows if r["size"] == size and r["side"] == side]
            for r in group + [{"clip": "**median**", **{k: statistics.median(g[k] for g in group)
                                                         for k in ("found", "swapped", "error_px", "error_pct", "ms")}}]:
                lines.append(f"| {size} | {side or 'as is'} | {r['clip']} | {100 * r['found']:.0f} % | "
                             f"{100 * r['swapped']:.0f} % | {r['error_px']:.1f} ({r['error_pct']:.1f} %) | {r['ms']:.0f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.detector_size", description=__doc__.splitlines()[0])
    p.add_argument("--sizes", nargs="+", default=["160x120", "320x240"], help="input sizes WxH (default 160x120 320x240)")
    p.add_argument("--sides", nargs="+", type=int, default=list(SIDES),
                   help="longer sides (pixels) the frames are enlarged to; 0: as they are")
    p.add_argument("--frames", type=int, default=80)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--only", choices=("synthetic", "cmu"), default=None)
    p.add_argument("--train", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap" / "train")
    p.add_argument("--out", type=Path, default=RESULTS_DIR / "detector_size")
    args = p.parse_args(argv)
    try:
        sizes = [tuple(int(v) for v in s.lower().split("x")) for s in args.sizes]
        if any(len(s) != 2 or min(s) < 1 for s in sizes) or args.frames < 1 or min(args.sides) < 0:
            raise ValueError
    except ValueError:
        print("error: --sizes takes WxH sizes, --frames a positive integer, --sides non-negative integers",
              file=sys.stderr)
        return 2
    from mocap.io.mediapipe_keypoints import available
    if not available():
        print("error: MediaPipe is not installed (pip install 'mocap[keypoints]')", file=sys.stderr)
        return 2
    (args.out / "rows").mkdir(parents=True, exist_ok=True)
    rows = []
    for name, scene, motion in clips(args.only, args.train, args.seed, args.frames):
        for size in sizes:
            kept = args.out / "rows" / f"{name}-{size[0]}x{size[1]}-s{args.seed}-f{args.frames}.json"
            if kept.is_file():
                done = json.loads(kept.read_text())
                if sorted(r["side"] for r in done) == sorted(args.sides):
                    rows += done
                    continue
            done = clip_rows(name, scene, motion, size, args.sides, args.out / "work", args.seed, args.frames)
            kept.write_text(json.dumps(done, indent=1))
            rows += done
            print(f"{name} at {size[0]}x{size[1]}: " + ", ".join(
                f"{r['side'] or 'as is'}: found {100 * r['found']:.0f} %, swapped {100 * r['swapped']:.0f} %, "
                f"{r['error_px']:.1f} px" for r in done), file=sys.stderr)
    (args.out / "results.json").write_text(json.dumps({"rows": rows, "command": " ".join(
        ["python -m experiments.detector_size", *(sys.argv[1:] if argv is None else argv)])}, indent=1))
    table = markdown(rows)
    (args.out / "detector_size.md").write_text(table)
    print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
