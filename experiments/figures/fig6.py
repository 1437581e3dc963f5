"""Fig. 6: edge residual per frame after the region step (grey) vs after the edge step (black).

Both steps iterated to convergence, the edge step from a fresh simplex around the region
result (the paper's section 4.1, before its small-simplex hand-off of section 4.2). Left: the
figure sequence, frame by frame. Right: every sequence's mean after the region step, after
the edge step from a fresh simplex, and after the edge step handed the region step's final
simplex (which, fully converged, has collapsed: the edge step then barely moves).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from experiments.figures._common import as_results
from experiments.plan import convergence_specs
from experiments.results import Results
from experiments.style import BLACK, GREY, new_figure, placeholder, save, style_context

NAME = "fig6"


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``fig6.png`` and ``fig6.pdf`` into ``out``."""
    res = as_results(results)
    cfg = res.config
    with style_context():
        fig = new_figure(10.0, 3.4)
        ax = fig.add_subplot(1, 2, 1)
        u = res.unit(convergence_specs(cfg, res.data(cfg.figure_sequence))["both_converged_fresh"])
        if u is None:
            placeholder(ax, "no converged run")
        else:
            after_region, after_edge = u["edge_residual_after_region"], u["edge_residual"]
            better = np.count_nonzero(after_edge < after_region)
            ax.plot(u["frame"], after_region, color=GREY, label=f"after region step (mean {np.nanmean(after_region):.3f} px)")
            ax.plot(u["frame"], after_edge, color=BLACK, label=f"after edge step (mean {np.nanmean(after_edge):.3f} px)")
            ax.set_xlabel("frame")
            ax.set_ylabel("mean edge distance (px)")
            ax.set_title(f"{cfg.figure_sequence}: edge step lowers it on {better} of {u['frame'].size} frames")
            ax.legend(loc="upper left")
        ax = fig.add_subplot(1, 2, 2)
        names, before, after, handed = [], [], [], []
        for name in res.sequences:
            specs = convergence_specs(cfg, res.data(name))
            u, h = res.unit(specs["both_converged_fresh"]), res.unit(specs["both_converged"])
            if u is not None:
                names.append(name)
                before.append(np.nanmean(u["edge_residual_after_region"]))
                after.append(np.nanmean(u["edge_residual"]))
                handed.append(np.nanmean(h["edge_residual"]) if h is not None else np.nan)
        if names:
            x = np.arange(len(names))
            ax.bar(x - 0.27, before, 0.27, color=GREY, label="after region step")
            ax.bar(x, after, 0.27, color=BLACK, label="after edge step (fresh simplex)")
            ax.bar(x + 0.27, handed, 0.27, color="#0072B2", label="after edge step handed the converged\nregion simplex (separate run)")
            ax.set_xticks(x, names, rotation=20)
            ax.set_ylabel("mean edge distance (px)")
            ax.set_title("every sequence (mean over frames)")
            ax.legend(loc="upper left")
        else:
            placeholder(ax, "no converged runs")
        fig.suptitle(f"Fig. 6 — residual edge distance after the region step vs after the edge step "
                     f"(both converged, ≤{cfg.converged_budget} evaluations each, ftol {cfg.converged_ftol:g})")
        return save(fig, out, NAME)
