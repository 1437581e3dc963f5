"""Fig. 11: failures of the non-overlapping ratio vs region and edge budgets (figure sequence as a surface, all sequences as a heat map)."""
from __future__ import annotations

from pathlib import Path

from experiments.figures._common import surface_figure
from experiments.results import Results

NAME = "fig11"
STAT = "fail_F"
TITLE = "Fig. 11 — failures of the non-overlapping ratio vs region and edge budgets"


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``fig11.png`` and ``fig11.pdf`` into ``out`` from the results folder ``results``."""
    return surface_figure(results, out, NAME, STAT, TITLE)
