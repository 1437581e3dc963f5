"""``python -m mocap track VIDEO [--background IMG | --background-frames A:B | --no-background]
[--calibration JSON] [--hfov DEG] [--height M] [--work-width PX] [--out DIR]``, or
``python -m mocap track --camera N``

VIDEO is a video file, a folder of images, or a sequence folder (``frames/``, and its
``background.png``/``calibration.json``/``ground_truth.csv`` are used when not given).

With nothing else given, everything is found from the video (docs/own-video.md): a
background estimated from the clip when the person moves enough (else a colour-only
foreground), an automatic calibration on the first frame with a face, a working resolution
near 160 pixels wide. ``--camera N`` tracks webcam N live (Ctrl-C stops and keeps what was
tracked).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from mocap.commands._common import add_tracker_options, print_summary, tracker_config
from mocap.commands._common import add_background_options


def add_parser(subparsers) -> None:
    from mocap.imaging.resample import DEFAULT_WORK_WIDTH
    from mocap.render.camera import DEFAULT_HFOV_DEG

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
    p.add_argument("--hfov", type=float, default=DEFAULT_HFOV_DEG, metavar="DEG",
                   help=f"camera horizontal field of view without a calibration (default {DEFAULT_HFOV_DEG:g}, a webcam)")
    p.add_argument("--height", type=float, default=None, metavar="M",
                   help="the person's height in metres: fixes the absolute scale (else default adult proportions)")
    p.add_argument("--work-width", type=int, default=None, metavar="PX",
                   help=f"working width: frames are reduced by the integer factor that brings them nearest to it "
                        f"(default: the tracker chooses, near {DEFAULT_WORK_WIDTH} or less for a person close to "
                        "the camera; see docs/own-video.md)")
    p.add_argument("--show", action="store_true", help="show the overlay live in a window (needs a display)")
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


def _background_mode(args, sequence_background) -> str:
    if args.background is not None or sequence_background is not None:
        return "image"
    if args.background_frames is not None:
        return "frames"
    return "none" if args.no_background else "auto"


def run(args: argparse.Namespace) -> int:
    from mocap.calibrate import Calibration
    from mocap.imaging.resample import working_factor
    from mocap.io.frames import CameraSource, VideoSource
    from mocap.io.sequence import find_sequence
    from mocap.io.video import read_image
    from mocap.own_video import setup_own_video
    from mocap.pipeline import track_video

    live = args.camera is not None or args.camera_device is not None
    if (args.video is None) == (not live):
        raise ValueError("give a VIDEO or --camera N (not both)")
    if live:
        if args.background_frames is not None:
            raise ValueError("--background-frames needs a video file")
        seq = None
        source = CameraSource.open(args.camera) if args.camera is not None else \
            CameraSource.from_device(args.camera_device)
    else:
        seq = find_sequence(args.video)
        source = VideoSource(seq.frames)
    seq_background = seq.background if seq is not None and not args.no_background and \
        args.background_frames is None else None
    background = args.background or seq_background
    calibration = args.calibration or (seq.calibration if seq is not None else None)
    for what, path in (("background", background), ("calibration", calibration)):
        if path is not None and not Path(path).is_file():
            raise FileNotFoundError(f"{what} file not found: {path}")
    factor = None if args.work_width is None else working_factor(source.width, source.height, args.work_width)
    given = None
    if calibration is not None:
        given = Calibration.from_json(calibration)
        cam = given.camera
        factor = factor or working_factor(source.width, source.height)
        if cam.shape == (source.height, source.width) and factor > 1:
            from dataclasses import replace
            given = replace(given, camera=type(cam)(source.width // factor, source.height // factor, cam.fx / factor,
                                                    cam.fy / factor, cam.cx / factor, cam.cy / factor))
        elif cam.shape != (source.height // factor, source.width // factor):
            raise ValueError(f"frames are {source.width}x{source.height} but the calibration's camera is "
                             f"{cam.width}x{cam.height}: calibrate for this video (python -m mocap calibrate)")
    mode = _background_mode(args, seq_background)
    setup, consumed = setup_own_video(
        source, factor, background_mode=mode, background_image=read_image(background) if background else None,
        background_frames=args.background_frames, calibration=given, hfov_deg=args.hfov, height_m=args.height)
    if source.live:
        source.hold(consumed)
    bg_note = setup.record["background"]
    cal_note = setup.record["calibration"]
    factor = setup.factor
    print(f"working resolution {setup.calibration.camera.width}x{setup.calibration.camera.height} "
          f"(input {source.width}x{source.height} reduced {factor}x)")
    print(f"background: {bg_note['mode']} ({bg_note['reason']})")
    if cal_note["from"] == "automatic":
        print(f"calibration: automatic on frame {cal_note['frame']}, person at {cal_note['depth_m']:.2f} m "
              f"(hfov {args.hfov:g} deg" + (f", height {args.height:g} m)" if args.height else
                                             ", default adult size: scale unknown)"))
    fps = (seq.fps(source.fps or 25.0) if seq is not None and seq.meta is not None else source.fps) or 25.0
    summary = track_video(source, setup.background, setup.calibration, args.out, tracker_config(args),
                          colour=args.colour, ground_truth=args.ground_truth or (seq.ground_truth if seq else None),
                          fps=fps, max_frames=args.max_frames, overwrite=args.overwrite,
                          imaging=setup.imaging, write_overlay=not args.no_overlay, work_factor=factor,
                          colour_model=setup.colour_model,
                          scene=setup.scene, setup_record=setup.record, show=args.show,
                          allow_damaged=args.allow_damaged, start_frame=args.start)
    print_summary(summary)
    return 0
