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


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The argument parser with every available sub-command, or with sub-command ``only`` (its
    module name, e.g. ``track_many``) alone: a command line that names its command imports no
    other command's module (``synth`` alone imports scipy.interpolate and scipy.optimize)."""
    parser = argparse.ArgumentParser(
        prog="python -m mocap",
        description="Markerless monocular 3D upper-body motion capture on the CPU.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS if only is None else (only,):
        module_name = f"mocap.commands.{name}"
        if importlib.util.find_spec(module_name) is None:
            continue
        importlib.import_module(module_name).add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the process exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    named = argv[0].replace("-", "_") if argv and "_" not in argv[0] else None    # the CLI spells track-many
    parser = build_parser(named if named in COMMANDS else None)
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
