"""``python -m mocap bench [--json] [--quick]``."""
from __future__ import annotations

import argparse


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("bench", help="time every stage at every resolution (one core)",
                              description=__doc__)
    p.add_argument("--json", action="store_true", help="print one JSON object (docs/design.md section 6)")
    p.add_argument("--quick", action="store_true", help="few runs per stage (a smoke test, not a measurement)")
    p.add_argument("--no-llvmpipe", action="store_true", help="skip the OpenGL (Mesa llvmpipe) comparison")
    p.add_argument("--groups", nargs="+", default=None, metavar="GROUP",
                   help="stage groups to run: render (render and cost evaluations), imaging (prepare_*), "
                        "frame (frame_100, frame_500: the paper's method; frame_beam: the default tracker; frame_beam_keypoints: "
                        "the same given keypoints), "
                        "lifter (lifter: one frame's keypoints to the lifter's hypotheses), "
                        "video (video_640x480: the own-video path end to end); default all")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from mocap.bench import print_result, run_benchmark
    from mocap.bench import GROUPS
    groups = tuple(args.groups) if args.groups else GROUPS
    unknown = set(groups) - set(GROUPS)
    if unknown:
        raise ValueError(f"unknown benchmark group(s) {', '.join(sorted(unknown))}; known: {', '.join(GROUPS)}")
    result = run_benchmark(quick=args.quick, with_llvmpipe=not args.no_llvmpipe, stages=groups)
    print_result(result, args.json)
    return 0
