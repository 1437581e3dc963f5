"""Beyond the paper: MPJPE against ground truth vs region and edge budgets (figure sequence as a surface, all sequences as a heat map)."""
from __future__ import annotations

from pathlib import Path

from experiments.figures._common import surface_figure
from experiments.results import Results

NAME = "ext_mpjpe"
STAT = "mpjpe"
TITLE = "Beyond the paper — MPJPE against ground truth vs region and edge budgets"


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``ext_mpjpe.png`` and ``ext_mpjpe.pdf`` into ``out`` from the results folder ``results``."""
    return surface_figure(results, out, NAME, STAT, TITLE)
