"""The command line of ``python -m experiments.fit_score``: one subcommand per module of the package.

Every subcommand takes ``--seeds`` (its module's ``SEEDS`` by default), ``--sequences`` (the six
benchmark sequences) and ``--out`` (where the records are), and is run by its module's ``run``.
"""
from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

from experiments import RESULTS_DIR

#: The subcommands' modules, by name (each has ``SEEDS``, ``add_parser(sub)`` and ``run(args, sequences, seeds)``;
#: imported by name: the package's ``decompose`` is the function).
SUBCOMMANDS = {name: importlib.import_module(f"experiments.fit_score.{name}")
               for name in ("record", "fit", "decompose", "decode", "depth")}


def main(argv=None) -> int:
    """Parse ``argv`` (default ``sys.argv[1:]``) and run the subcommand; returns the exit status."""
    from experiments.fit_score import __doc__ as doc
    from mocap.synth import SEQUENCE_NAMES

    p = argparse.ArgumentParser(prog="python -m experiments.fit_score", description=doc.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    for module in SUBCOMMANDS.values():
        q = module.add_parser(sub)
        q.add_argument("--seeds", default=module.SEEDS)
        q.add_argument("--sequences", default=",".join(SEQUENCE_NAMES))
        q.add_argument("--out", type=Path, default=RESULTS_DIR / "fit_score")
    args = p.parse_args(argv)
    try:
        seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    except ValueError:
        seeds = []
    sequences = [s for s in args.sequences.split(",") if s]
    if not seeds or not sequences or any(s not in SEQUENCE_NAMES for s in sequences):
        print(f"error: need seeds and sequences of {', '.join(SEQUENCE_NAMES)}", file=sys.stderr)
        return 2
    return SUBCOMMANDS[args.command].run(args, sequences, seeds)
