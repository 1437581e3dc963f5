"""``python -m mocap track VIDEO --background IMG --calibration JSON [--iterations N] [--split auto|R:E] [--out DIR]``

VIDEO is a video file, a folder of images, or a sequence folder (``frames/``, and its
``background.png``/``calibration.json``/``ground_truth.csv`` are used when not given).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from mocap.commands._common import add_tracker_options, print_summary, tracker_config


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("track", help="track a video with a calibrated body model", description=__doc__,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("video", type=Path, help="video file, image folder or sequence folder")
    p.add_argument("--background", type=Path, default=None, help="image of the empty scene")
    p.add_argument("--calibration", type=Path, default=None, help="calibration.json (python -m mocap calibrate)")
    p.add_argument("--out", type=Path, default=Path("mocap-track"), help="output folder (default ./mocap-track)")
    p.add_argument("--colour", choices=("calibration", "face"), default="calibration",
                   help="learn colours inside the calibrated model (default) or from the detected face")
    p.add_argument("--ground-truth", type=Path, default=None, help="ground_truth.csv for accuracy metrics")
    p.add_argument("--start", type=int, default=0, metavar="N",
                   help="first frame to track (default 0); the calibration's initial pose is the pose there")
    p.add_argument("--allow-damaged", action="store_true",
                   help="track a video whose frames do not all decode (they are listed in run.json) instead of stopping")
    add_tracker_options(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from mocap.calibrate import Calibration
    from mocap.io.sequence import find_sequence
    from mocap.run import track_video

    seq = find_sequence(args.video)
    background = args.background or seq.background
    calibration = args.calibration or seq.calibration
    if background is None:
        raise ValueError("no background image: pass --background IMG (an image of the empty scene)")
    if calibration is None:
        raise ValueError("no calibration: pass --calibration JSON (make one with python -m mocap calibrate)")
    for what, path in (("background", background), ("calibration", calibration)):
        if not Path(path).is_file():
            raise FileNotFoundError(f"{what} file not found: {path}")
    summary = track_video(seq.frames, background, Calibration.from_json(calibration), args.out, tracker_config(args),
                          colour=args.colour, ground_truth=args.ground_truth or seq.ground_truth, fps=seq.fps(),
                          max_frames=args.max_frames, overwrite=args.overwrite, write_overlay=not args.no_overlay,
                          allow_damaged=args.allow_damaged, start_frame=args.start)
    print_summary(summary)
    return 0
