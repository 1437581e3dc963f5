"""Experiments of the paper (sections 4-5) on the synthetic benchmark, and past it with ground truth.

* ``python -m experiments.sweep`` runs the tracker over the region x edge budget grid and the
  runs behind every figure (:mod:`experiments.sweep`, :mod:`experiments.units`), writing one
  result file per finished unit under ``experiments/results/<name>`` (resumable);
* ``python -m experiments.figures`` regenerates every table and figure from stored results
  (:mod:`experiments.figures`);
* ``python -m experiments.report`` writes ``experiments/REPORT.md`` beside the paper's claims
  (:mod:`experiments.report`).

Only the public API of :mod:`mocap` is used.
"""
from __future__ import annotations

from pathlib import Path

#: Folder of this package; default result and report folders are relative to it.
EXPERIMENTS_DIR: Path = Path(__file__).resolve().parent
#: Default parent folder of sweep results (git-ignored).
RESULTS_DIR: Path = EXPERIMENTS_DIR / "results"

__all__ = ["EXPERIMENTS_DIR", "RESULTS_DIR"]
