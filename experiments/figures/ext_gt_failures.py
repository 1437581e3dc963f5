"""Beyond the paper: ground-truth failures (MPJPE) vs region and edge budgets (figure sequence as a surface, all sequences as a heat map)."""
from __future__ import annotations

from pathlib import Path

from experiments.figures._common import surface_figure
from experiments.results import Results

NAME = "ext_gt_failures"
STAT = "fail_gt"
TITLE = "Beyond the paper — ground-truth failures (MPJPE) vs region and edge budgets"


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``ext_gt_failures.png`` and ``ext_gt_failures.pdf`` into ``out`` from the results folder ``results``."""
    return surface_figure(results, out, NAME, STAT, TITLE)
