"""Fig. 9: mean residual of the non-overlapping ratio F vs region and edge budgets (figure sequence as a surface, all sequences as a heat map)."""
from __future__ import annotations

from pathlib import Path

from experiments.figures._common import surface_figure
from experiments.results import Results

NAME = "fig9"
STAT = "mean_F"
TITLE = "Fig. 9 — mean residual of the non-overlapping ratio F vs region and edge budgets"


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``fig9.png`` and ``fig9.pdf`` into ``out`` from the results folder ``results``."""
    return surface_figure(results, out, NAME, STAT, TITLE)
