"""``python -m experiments.figures [--results DIR] [--out DIR] [--only NAME,...]``."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from experiments import RESULTS_DIR
from experiments.figures import FIGURES, make_all


def main(argv=None) -> int:
    """Regenerate every table and figure from stored results; exit 2 on bad input."""
    p = argparse.ArgumentParser(prog="python -m experiments.figures",
                                description="Regenerate the paper's tables and figures (PNG + PDF) from sweep results.")
    p.add_argument("--results", type=Path, default=RESULTS_DIR / "full", help="results folder (default: %(default)s)")
    p.add_argument("--out", type=Path, help="output folder (default: RESULTS/figures)")
    p.add_argument("--only", help=f"comma-separated subset of: {', '.join(FIGURES)}")
    p.add_argument("--no-progress", action="store_true")
    args = p.parse_args(argv)
    names = tuple(n.strip() for n in args.only.split(",") if n.strip()) if args.only else FIGURES
    out = args.out or args.results / "figures"
    try:
        written = make_all(args.results, out, names, progress=not args.no_progress)
    except ValueError as exc:
        print(f"experiments.figures: error: {exc}", file=sys.stderr)
        return 2
    print(f"{len(written)} files written to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
