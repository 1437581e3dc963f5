"""Command-line interface: ``python -m mocap COMMAND ...``.

Each command lives in its own module under :mod:`mocap.commands` exposing
``add_parser(subparsers)`` (which sets ``run`` as the parser default). Bad input ends the
program with a one-line reason on standard error and exit status 2.
"""
from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys

#: Sub-commands in the order ``--help`` lists them.
COMMANDS: tuple[str, ...] = ("demo", "track", "track_many", "calibrate", "segment", "synth", "bench")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every available sub-command."""
    parser = argparse.ArgumentParser(
        prog="python -m mocap",
        description="Markerless monocular 3D upper-body motion capture on the CPU.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        module_name = f"mocap.commands.{name}"
        if importlib.util.find_spec(module_name) is None:
            continue
        importlib.import_module(module_name).add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the process exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        status = args.run(args)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted: finished work was kept; run the same command again to resume",
              file=sys.stderr)
        return 130
    return int(status or 0)
