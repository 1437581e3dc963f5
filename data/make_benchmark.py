"""Regenerate the synthetic benchmark set into ``data/cache/`` (git-ignored).

    python data/make_benchmark.py [--seed S] [--size WxH] [--frames N] [--only NAME ...] [--out DIR]

The same as ``python -m mocap.synth.datasets`` with this folder's ``cache`` as default output;
``--default`` rewrites the bundled ``data/default`` sequence. See ``data/README.md``.
"""
import sys
from pathlib import Path

from mocap.synth.datasets import main

if __name__ == "__main__":
    sys.exit(main(default_out=Path(__file__).resolve().parent / "cache"))
