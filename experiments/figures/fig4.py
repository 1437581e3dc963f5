"""Fig. 4: residual per frame at convergence vs limited to a few evaluations, for both costs.

Left: F per frame of region-only runs, converged (black) vs limited to ``limited_budget``
evaluations (grey). Right: mean edge distance per frame of two-step runs, each step converged
(black) vs each step limited to ``limited_budget`` evaluations (grey); the edge step starts
from a fresh simplex here (a fully converged region simplex has collapsed and would leave the
edge step nothing to do, see Fig. 6). Figure sequence. When the sweep ran with the gradient
step (``SweepConfig.gradient``), the right panel also shows the same two-step runs with the
gradient step on (dashed; it takes its share of each edge budget, and none of a budget too small
to leave it one, so the limited run is drawn only where it differs).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from experiments.figures._common import as_results
from experiments.plan import convergence_specs
from experiments.results import Results
from experiments.style import BLACK, GREY, new_figure, placeholder, save, style_context

NAME = "fig4"


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``fig4.png`` and ``fig4.pdf`` into ``out``."""
    res = as_results(results)
    cfg = res.config
    specs = convergence_specs(cfg, res.data(cfg.figure_sequence))
    gradient_specs = convergence_specs(cfg, res.data(cfg.figure_sequence), gradient=True)
    panels = (("region_converged", "region_limited", "region_residual", "non-overlapping ratio F",
               "region step only (F)"),
              ("both_converged_fresh", "both_limited_fresh", "edge_residual", "mean edge distance (px)",
               "region then edge step from a fresh simplex (edge distance)"))
    with style_context():
        fig = new_figure(10.0, 3.4)
        for k, (conv, lim, field, ylabel, title) in enumerate(panels):
            ax = fig.add_subplot(1, 2, k + 1)
            uc, ul = res.unit(specs[conv]), res.unit(specs[lim])
            if uc is None or ul is None:
                placeholder(ax, f"no results for {title}")
                continue
            ax.plot(ul["frame"], ul[field], color=GREY, label=f"limited to {cfg.limited_budget} evaluations per step "
                    f"(mean {np.nanmean(ul[field]):.3g})")
            ax.plot(uc["frame"], uc[field], color=BLACK, label=f"converged (≤{cfg.converged_budget}, "
                    f"ftol {cfg.converged_ftol:g}; mean {np.nanmean(uc[field]):.3g})")
            if cfg.gradient and conv.startswith("both"):
                _draw_gradient_twins(ax, res, gradient_specs[conv], gradient_specs[lim], field)
            ax.set_xlabel("frame")
            ax.set_ylabel(ylabel)
            ax.set_title(title)
            ax.legend(loc="upper left")
        fig.suptitle(f"Fig. 4 — effect of a limited number of evaluations on the residual ({cfg.figure_sequence})")
        return save(fig, out, NAME)


def _draw_gradient_twins(ax, res: Results, converged, limited, field: str) -> None:
    """The gradient-step runs beside the simplex ones (dashed), those that differ from them."""
    for spec, color, what in ((limited, GREY, "limited"), (converged, BLACK, "converged")):
        u = res.unit(spec) if spec.gradient else None
        if u is not None:
            ax.plot(u["frame"], u[field], color=color, linestyle="--",
                    label=f"{what}, with the gradient step (mean {np.nanmean(u[field]):.3g})")
