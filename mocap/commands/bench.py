"""``python -m mocap bench [--json] [--quick]``."""
from __future__ import annotations

import argparse


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("bench", help="time every stage at every resolution (one core)",
                              description=__doc__)
    p.add_argument("--json", action="store_true", help="print one JSON object (DESIGN.md section 6)")
    p.add_argument("--quick", action="store_true", help="few runs per stage (a smoke test, not a measurement)")
    p.add_argument("--no-llvmpipe", action="store_true", help="skip the OpenGL (Mesa llvmpipe) comparison")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from mocap.bench import print_result, run_benchmark
    result = run_benchmark(quick=args.quick, with_llvmpipe=not args.no_llvmpipe)
    print_result(result, args.json)
    return 0
