"""``python -m mocap calibrate VIDEO --background IMG [--out JSON]``: automatic first-frame
calibration of body proportions and initial pose (the actor should stand roughly neutral,
facing the camera, arms away from the body)."""
from __future__ import annotations

import argparse
from pathlib import Path


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("calibrate", help="fit body dimensions and initial pose to the first frame",
                              description=__doc__)
    p.add_argument("video", type=Path, help="video file, image folder or sequence folder")
    p.add_argument("--background", type=Path, default=None, help="image of the empty scene")
    p.add_argument("--out", type=Path, default=Path("calibration.json"), help="output JSON (default ./calibration.json)")
    p.add_argument("--frame", type=int, default=0, help="frame to calibrate on (default 0)")
    p.add_argument("--hfov", type=float, default=60.0, help="camera horizontal field of view, degrees (default 60)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from mocap.calibrate import auto_calibrate
    from mocap.io.sequence import find_sequence
    from mocap.io.video import iter_frames, read_image
    from mocap.render import Camera

    seq = find_sequence(args.video)
    background = args.background or seq.background
    if background is None:
        raise ValueError("no background image: pass --background IMG (an image of the empty scene)")
    frame = next(iter_frames(seq.frames, args.frame, args.frame + 1), None)
    if frame is None:
        raise ValueError(f"{seq.frames} has no frame {args.frame}")
    camera = Camera.default(frame.shape[1], frame.shape[0], hfov_deg=args.hfov)
    calibration = auto_calibrate(frame, read_image(background), camera)
    calibration.to_json(args.out)
    q = calibration.initial_pose
    print(f"calibration written to {args.out}: actor at {q[2]:.2f} m, torso "
          f"{calibration.dims['torso'].length:.2f} x {calibration.dims['torso'].width:.2f} m, colour classes "
          f"{', '.join(calibration.class_names)}, hairline "
          + ("none" if calibration.dims.hairline is None else f"{calibration.dims.hairline:+.2f} (half head lengths)"))
    return 0
