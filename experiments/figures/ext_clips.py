"""Beyond the paper: the actors driven by motion-capture clips (``--motion-dir``), coarser grid.

One row per clip-driven sequence: MPJPE and mean edge distance over ``motion_budgets``
(heat maps, red frame: minimum); the last row is the mean over clips.
"""
from __future__ import annotations

from pathlib import Path

from experiments.figures._common import as_results, heatmap
from experiments.results import STATS, Results, short_name
from experiments.style import new_figure, placeholder, save, style_context

NAME = "ext_clips"
COLUMNS = ("mpjpe", "mean_D", "mean_F")


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``ext_clips.png`` and ``ext_clips.pdf`` into ``out``."""
    res = as_results(results)
    datas = res.clip_data()
    b = res.config.motion_budgets
    with style_context():
        if not datas:
            fig = new_figure(6.0, 2.0)
            placeholder(fig.add_subplot(1, 1, 1), "no clip-driven sequences in these results (sweep without --motion-dir)")
            return save(fig, out, NAME)
        rows = [(short_name(d), [d]) for d in datas] + [(f"mean over {len(datas)} clips", datas)]
        fig = new_figure(12.0, 2.5 * len(rows) + 0.6)
        for i, (title, group) in enumerate(rows):
            for j, stat in enumerate(COLUMNS):
                ax = fig.add_subplot(len(rows), len(COLUMNS), i * len(COLUMNS) + j + 1)
                rs, es, z = res.mean_surface(group, stat, b, b)
                heatmap(ax, rs, es, z, STATS[stat][0], fig=fig)
                ax.set_title(f"{title}: {STATS[stat][0]}")
        fig.suptitle("Beyond the paper — actors driven by CMU motion-capture clips")
        return save(fig, out, NAME)
