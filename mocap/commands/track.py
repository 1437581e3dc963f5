"""``python -m mocap track VIDEO [--background IMG | --background-frames A:B | --no-background]
[--calibration JSON] [--hfov DEG] [--height M] [--work-width PX] [--keypoints auto|mediapipe|none|FILE]
[--out DIR]``, or
``python -m mocap track --camera N``

VIDEO is a video file, a folder of images, or a sequence folder (``frames/``, and its
``background.png``/``calibration.json``/``ground_truth.csv`` are used when not given).

With nothing else given, everything is found from the video (docs/own-video.md): a
background estimated from the clip when the person moves enough (else a colour-only
foreground), an automatic calibration on the first frame with a face, a working resolution
near 160 pixels wide, and 2D keypoints from MediaPipe Pose where its optional extra
``keypoints`` is installed (``--keypoints auto``; the output says which). ``--camera N`` tracks webcam N live (Ctrl-C stops and keeps what was
tracked).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from mocap.commands._common import (add_background_options, add_camera_options, add_keypoints_option, add_run_options,
                                    add_tracker_options, own_video_options, print_summary)


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("track", help="track a video with a calibrated body model", description=__doc__,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("video", type=Path, nargs="?", help="video file, image folder or sequence folder")
    cam = p.add_mutually_exclusive_group()
    cam.add_argument("--camera", type=int, default=None, metavar="N", help="track webcam N live instead of a file")
    cam.add_argument("--camera-device", default=None, metavar="NAME",
                     help="track a capture device by its ffmpeg name (/dev/video2, video=NAME on Windows), or a "
                          "video file streamed as a live camera (a rehearsal)")
    add_background_options(p)
    p.add_argument("--calibration", type=Path, default=None, help="calibration.json (python -m mocap calibrate)")
    add_camera_options(p, "the person's height in metres: fixes the absolute scale (else default adult proportions)")
    p.add_argument("--show", action="store_true", help="show the overlay live in a window (needs a display)")
    add_keypoints_option(p, "as a further cue")
    p.add_argument("--out", type=Path, default=Path("mocap-track"), help="output folder (default ./mocap-track)")
    p.add_argument("--ground-truth", type=Path, default=None, help="ground_truth.csv for accuracy metrics")
    add_run_options(p, "first frame to track (default 0); the calibration's initial pose is the pose there",
                    "track a video whose frames do not all decode (they are listed in run.json) instead of stopping")
    add_tracker_options(p)
    p.set_defaults(run=run)


def print_setup(account) -> None:
    """What the set-up found (:func:`mocap.run.track`'s ``on_setup``: a
    :class:`mocap.run.accounts.SetupAccount`)."""
    print(f"working resolution {account.working_width}x{account.working_height} "
          f"(input {account.input_width}x{account.input_height} reduced {account.working_factor}x)")
    background, calibration = account.background, account.calibration
    print(f"background: {background.mode} ({background.reason})")
    if account.keypoints is not None:
        print(f"keypoints: {account.keypoints}")
    if calibration.source == "automatic":
        height = account.height_m
        print(f"calibration: automatic on frame {calibration.frame}, person at {calibration.depth_m:.2f} m "
              f"(hfov {account.hfov_deg:g} deg" + (f", height {height:g} m)" if height else
                                                   ", default adult size: scale unknown)"))


def run(args: argparse.Namespace) -> int:
    import mocap.run
    from mocap.io.frames import CameraSource

    live = args.camera is not None or args.camera_device is not None
    if (args.video is None) == (not live):
        raise ValueError("give a VIDEO or --camera N (not both)")
    chosen = own_video_options(args)
    if live:
        if args.background_frames is not None:
            raise ValueError("--background-frames needs a video file")
        source = CameraSource.open(args.camera) if args.camera is not None else \
            CameraSource.from_device(args.camera_device)
    else:
        source = args.video
    summary = mocap.run.track(source, args.out, chosen, on_setup=print_setup)
    print_summary(summary)
    return 0
