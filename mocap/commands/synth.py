"""``python -m mocap synth NAME [--out DIR] [--frames N] [--seed S] [--size WxH] [--motion FILE]``.

Writes a synthetic benchmark sequence with ground truth (docs/design.md sections 3-4); see
:func:`mocap.synth.generate_sequence`.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from mocap.synth.sequence import FRAME_FORMATS, SEQUENCES, SEQUENCE_NAMES, generate_sequence, parse_size


def _names_help() -> str:
    return "; ".join(f"{n}: {SEQUENCES[n].description} ({SEQUENCES[n].frames} frames)" for n in SEQUENCE_NAMES)


def add_parser(subparsers) -> None:
    """Register the ``synth`` sub-command."""
    p = subparsers.add_parser(
        "synth", help="write a synthetic benchmark sequence with ground truth",
        description="Write a synthetic sequence folder: frames, background.png, calibration.json, "
                    "ground_truth.csv, meta.json. Sequences: " + _names_help())
    p.add_argument("name", metavar="NAME", help=f"sequence: {', '.join(SEQUENCE_NAMES)}")
    p.add_argument("--out", metavar="DIR", default=None, help="output folder (default: out/synth/NAME)")
    p.add_argument("--frames", metavar="N", type=int, default=None,
                   help="number of frames (default: the sequence's own, or the whole --motion clip)")
    p.add_argument("--seed", metavar="S", type=int, default=0, help="random seed (default 0); same seed, same bytes")
    p.add_argument("--size", metavar="WxH", default="160x120", help="image size in pixels (default 160x120)")
    p.add_argument("--motion", metavar="FILE", default=None,
                   help="drive the actor with a motion-capture clip (.bvh, or .amc with its .asf beside it)")
    p.add_argument("--format", dest="frame_format", choices=FRAME_FORMATS, default="png",
                   help="frame files: png (default) or jpg (the camera's JPEG streams: same pixels, smaller)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Generate the sequence; prints where it went and how long it took."""
    if args.name not in SEQUENCES:
        raise ValueError(f"unknown sequence {args.name!r}; choose one of: {', '.join(SEQUENCE_NAMES)}")
    size = parse_size(args.size)
    out = Path(args.out) if args.out is not None else Path("out") / "synth" / args.name
    start = time.perf_counter()
    folder = generate_sequence(args.name, out, frames=args.frames, seed=args.seed, size=size,
                               motion=args.motion, frame_format=args.frame_format)
    n = len(list((folder / "frames").iterdir()))
    print(f"wrote {n} frames of {args.name} ({size[0]}x{size[1]}, seed {args.seed}) to {folder} "
          f"in {time.perf_counter() - start:.1f} s")
    return 0
