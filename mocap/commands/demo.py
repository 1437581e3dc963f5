"""``python -m mocap demo [--out DIR]``: track the bundled default sequence (``data/default``),
write every output and print accuracy against its ground truth and frames per second."""
from __future__ import annotations

import argparse
from pathlib import Path

from mocap.commands._common import add_tracker_options, own_video_options, print_summary


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("demo", help="track the bundled default sequence and report accuracy and speed",
                              description=__doc__)
    p.add_argument("--out", type=Path, default=Path("mocap-demo"), help="output folder (default ./mocap-demo)")
    p.add_argument("--auto-calibrate", action="store_true",
                   help="calibrate automatically from the first frame instead of using the true calibration")
    add_tracker_options(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    import dataclasses

    import mocap.run
    from mocap.run import files
    from mocap.calibrate import Calibration, auto_calibrate
    from mocap.io.sequence import find_sequence
    from mocap.io.video import iter_frames, read_image
    from mocap.synth.datasets import default_sequence

    root = default_sequence(args.out / "sequence")
    seq = find_sequence(root)
    calibration = None              # the sequence's own
    if args.auto_calibrate:
        first = next(iter_frames(seq.frames, 0, 1))
        found = auto_calibrate(first, read_image(seq.background), Calibration.from_json(seq.calibration).camera)
        args.out.mkdir(parents=True, exist_ok=True)
        calibration = str(args.out / files.CALIBRATION_JSON)
        found.to_json(calibration)
    print(f"tracking {root} ({'automatic' if args.auto_calibrate else 'true'} calibration)")
    # the paper's setting: no keypoints, so that the demo's figures are the same on every install
    options = dataclasses.replace(own_video_options(args), calibration=calibration, keypoints="none")
    summary = mocap.run.track(root, args.out, options)
    print_summary(summary)
    return 0
