"""Beyond the paper: the actors driven by motion-capture clips (``--motion-dir``), coarser grid.

Top rows: MPJPE over ``motion_budgets`` for every actor (row) and clip (column). Bottom row:
MPJPE, mean edge distance and mean F averaged over every clip-driven sequence (heat maps,
red frame: minimum; a colour bar with an arrow is clipped at the 95th percentile).
"""
from __future__ import annotations

from pathlib import Path

from experiments.figures._common import as_results, heatmap
from experiments.results import STATS, Results
from experiments.style import new_figure, placeholder, save, style_context
from experiments.units import clip_name

NAME = "ext_clips"
MEAN_COLUMNS = ("mpjpe", "mean_D", "mean_F")


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
        actors = list(dict.fromkeys(d.actor for d in datas))
        clips = list(dict.fromkeys(d.motion for d in datas))
        cols = max(len(clips), len(MEAN_COLUMNS))
        fig = new_figure(3.0 * cols, 2.7 * (len(actors) + 1) + 0.5)
        for i, actor in enumerate(actors):
            for j, clip in enumerate(clips):
                ax = fig.add_subplot(len(actors) + 1, cols, i * cols + j + 1)
                group = [d for d in datas if d.actor == actor and d.motion == clip]
                rs, es, z = res.mean_surface(group, "mpjpe", b, b)
                heatmap(ax, rs, es, z, "MPJPE (mm)", fig=fig)
                ax.set_title(f"{actor}\n+ {clip_name(clip)}", fontsize=8)
        for j, stat in enumerate(MEAN_COLUMNS):
            ax = fig.add_subplot(len(actors) + 1, cols, len(actors) * cols + j + 1)
            rs, es, z = res.mean_surface(datas, stat, b, b)
            heatmap(ax, rs, es, z, STATS[stat][0], fig=fig)
            ax.set_title(f"mean over {len(datas)} clip-driven sequences:\n{STATS[stat][0]}", fontsize=8)
        fig.suptitle("Beyond the paper — actors driven by CMU motion-capture clips (top: MPJPE in mm per actor and clip)")
        return save(fig, out, NAME)
