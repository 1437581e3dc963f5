"""Fig. 8: edge residual vs edge-step budget, region-simplex hand-off (black) vs large fresh simplex (grey).

The total per frame is fixed (``handoff_total``); the edge step gets the abscissa, the region
step the rest. Left: the figure sequence (the paper's plot); middle: mean over all sequences;
right: the same runs against ground truth (MPJPE).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from experiments.figures._common import as_results
from experiments.plan import handoff_specs
from experiments.results import Results
from experiments.style import BLACK, GREY, new_figure, save, style_context

NAME = "fig8"
LABELS = {"region_simplex": "edge step starts from the region step's final simplex",
          "fresh": "edge step starts from a large fresh simplex"}


def curves(res: Results, names, stat: str) -> dict:
    """``{start: (edge budgets, mean of stat over the sequences in names)}``."""
    cfg = res.config
    out = {}
    for start in ("region_simplex", "fresh"):
        es = np.array(cfg.handoff_edge_budgets)
        vals = np.array([[res.stat(handoff_specs(cfg, res.data(n))[(e, start)], stat) for e in es] for n in names])
        with np.errstate(all="ignore"):
            out[start] = (es, np.nanmean(vals, axis=0) if np.isfinite(vals).any() else np.full(es.size, np.nan))
    return out


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``fig8.png`` and ``fig8.pdf`` into ``out``."""
    res = as_results(results)
    cfg = res.config
    panels = (([cfg.figure_sequence], "mean_D", "mean edge distance (px)", cfg.figure_sequence),
              (list(res.sequences), "mean_D", "mean edge distance (px)", f"mean over {len(res.sequences)} sequences"),
              (list(res.sequences), "mpjpe", "MPJPE (mm)", f"ground truth, mean over {len(res.sequences)} sequences"))
    with style_context():
        fig = new_figure(11.0, 3.4)
        for k, (names, stat, ylabel, title) in enumerate(panels):
            ax = fig.add_subplot(1, 3, k + 1)
            for start, (es, v) in curves(res, names, stat).items():
                ax.plot(es, v, "o-", ms=3, color=BLACK if start == "region_simplex" else GREY,
                        label=LABELS[start] if k == 0 else None)
            ax.set_xlabel(f"edge-step evaluations (region step: {cfg.handoff_total} minus these)")
            ax.set_ylabel(ylabel)
            ax.set_title(title)
        fig.legend(loc="outside lower center", ncol=2)
        fig.suptitle(f"Fig. 8 — residual edge distance vs edge-step budget at {cfg.handoff_total} evaluations per frame")
        return save(fig, out, NAME)
