"""Beyond the paper: Figs. 9, 10 and the MPJPE surface for every sequence (the paper: "similar results").

Rows: sequences; columns: mean F, mean edge distance, MPJPE over region x edge budgets (heat
maps, red frame: minimum).
"""
from __future__ import annotations

from pathlib import Path

from experiments.figures._common import as_results, heatmap
from experiments.results import STATS, Results
from experiments.style import new_figure, save, style_context

NAME = "ext_sequences"
COLUMNS = ("mean_F", "mean_D", "mpjpe")


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``ext_sequences.png`` and ``ext_sequences.pdf`` into ``out``."""
    res = as_results(results)
    names = res.sequences
    with style_context():
        fig = new_figure(12.0, 2.6 * len(names) + 0.6)
        for i, name in enumerate(names):
            for j, stat in enumerate(COLUMNS):
                ax = fig.add_subplot(len(names), len(COLUMNS), i * len(COLUMNS) + j + 1)
                rs, es, z = res.surface(res.data(name), stat)
                heatmap(ax, rs, es, z, STATS[stat][0], fig=fig, annotate=True)
                ax.set_title(f"{name}: {STATS[stat][0]}")
        fig.suptitle("Beyond the paper — every sequence over region x edge budgets")
        return save(fig, out, NAME)
