"""``python -m mocap calibrate VIDEO [--background IMG | --background-frames A:B | --no-background]
[--hfov DEG] [--height M] [--keypoints auto|mediapipe|none|FILE] [--out JSON]``: automatic calibration of
body proportions and initial pose (with ``--keypoints``, the calibration frame's 2D keypoints
pull the model's joints onto them: shoulder width and place, head, arms).

With ``--background`` (or a sequence folder's ``background.png``) the paper's set-up: the actor
stands roughly neutral on frame ``--frame`` (default 0) against the empty scene. Otherwise the
own-video path of ``track`` (docs/own-video.md): background as given, estimated from the video
or none, and the first usable frame of a real person (a face seeds colours, position and
depth). The calibration is written at the video's input resolution.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from mocap.commands._common import (add_allow_damaged_option, add_background_options, add_camera_options,
                                    add_keypoints_option, own_video_options)


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("calibrate", help="fit body dimensions and initial pose to a frame",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("video", type=Path, help="video file, image folder or sequence folder")
    add_background_options(p)
    p.add_argument("--out", type=Path, default=Path("calibration.json"), help="output JSON (default ./calibration.json)")
    p.add_argument("--frame", type=int, default=None,
                   help="frame to calibrate on against --background (default 0); without a background image the "
                        "first usable frame is found")
    add_camera_options(p, "the person's height in metres: fixes the absolute scale")
    add_keypoints_option(p, "of the calibration frame")
    add_allow_damaged_option(p, "calibrate on a video whose frames do not all decode instead of stopping")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from mocap.calibrate import Calibration, auto_calibrate
    from mocap.io.video import read_image
    from mocap.render import Camera
    from mocap.run.options import RunChoices
    from mocap.run.setup import SetupRequest, find_setup
    from mocap.run.tracking import RunInput

    # the background and the keypoints as track chooses them (given, the sequence folder's own, frames, none or auto)
    chosen = own_video_options(args)
    opened = RunInput.open(args.video, chosen)
    with RunChoices.of(chosen, opened.sequence_background) as choices:    # its detector's process ends with it
        keypoints = choices.keypoint_source
        print(f"keypoints: {choices.keypoints_line}")
        source, background = opened.frames, opened.background
        source.damaged_frames(args.allow_damaged)
        if background is not None and args.height is None:
            index = args.frame or 0
            frame = next(source.frames(index, index + 1), None)
            if frame is None:
                raise ValueError(f"{source.name} has no frame {index}")
            camera = Camera.default(frame.shape[1], frame.shape[0], hfov_deg=args.hfov)
            found = None if keypoints is None else keypoints.keypoints(index, frame)    # input size = camera size
            calibration = auto_calibrate(frame, read_image(background), camera, keypoints=found)
            how = f"frame {index} against the background image"
        else:
            if args.frame is not None:
                raise ValueError("--frame needs --background IMG (without one the first usable frame is found)")
            request = SetupRequest(background_mode=choices.background_mode,
                                   background_image=read_image(background) if background is not None else None,
                                   background_frames=args.background_frames, hfov_deg=args.hfov, height_m=args.height,
                                   keypoints=keypoints)
            setup = find_setup(source, request).setup
            camera = setup.calibration.camera.enlarged(setup.factor, source.width, source.height)
            calibration = Calibration(setup.calibration.dims, setup.calibration.initial_pose, camera)
            note = setup.record
            how = f"frame {note.calibration.frame}, background {note.background_mode} ({note.background.reason})"
    calibration.to_json(args.out)
    q = calibration.initial_pose
    print(f"calibration written to {args.out} ({how}): actor at {q[2]:.2f} m, torso "
          f"{calibration.dims['torso'].length:.2f} x {calibration.dims['torso'].width:.2f} m, colour classes "
          f"{', '.join(calibration.class_names)}, hairline "
          + ("none" if calibration.dims.hairline is None else f"{calibration.dims.hairline:+.2f} (half head lengths)"))
    return 0
