"""Helpers shared by the figure modules: loading results, surfaces, heat maps, captions."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from experiments.results import STATS, Results
from experiments.style import CMAP, new_figure, placeholder, save, style_context

__all__ = ["as_results", "heatmap", "save", "style_context", "surface_figure", "surface3d", "threshold_text"]


def as_results(results: Results | str | Path) -> Results:
    """Accept a :class:`~experiments.results.Results` or the path of a results folder."""
    return results if isinstance(results, Results) else Results(results)


def threshold_text(results: Results, stat: str) -> str:
    """The failure threshold a statistic uses, as text ('' for statistics without one)."""
    t = results.thresholds()
    return {"fail_F": f"failure: F > {t['F']:g}", "fail_D": f"failure: edge distance > {t['D']:g} px",
            "fail_gt": f"failure: MPJPE > {t['mpjpe']:g} mm"}.get(stat, "")


def _fmt(v: float, integers: bool = False) -> str:
    """A cell value: integers as such, otherwise 3 significant digits or so."""
    if not np.isfinite(v):
        return "–"
    if integers or abs(v) >= 100:
        return f"{v:.0f}"
    return f"{v:.1f}" if abs(v) >= 10 else f"{v:.2f}"


def surface3d(ax, rs, es, z, zlabel: str) -> None:
    """The paper's 3D surface: region budget on x, edge budget on y."""
    if not np.isfinite(z).any():
        placeholder(ax, "no results")
        return
    X, Y = np.meshgrid(rs, es, indexing="ij")
    zz = np.ma.masked_invalid(z)
    ax.plot_surface(X, Y, zz, cmap=CMAP, edgecolor="k", linewidth=0.25, alpha=0.95, antialiased=True)
    ax.set_xlabel("region-step evaluations")
    ax.set_ylabel("edge-step evaluations")
    ax.set_zlabel(zlabel)
    ax.view_init(elev=28, azim=-128)
    ax.xaxis.labelpad = ax.yaxis.labelpad = 2
    ax.tick_params(pad=0)


def heatmap(ax, rs, es, z, label: str, *, annotate: bool = True, fig=None, lower_is_better: bool = True) -> None:
    """Heat map with values: region budget on x, edge budget on y; the best cell framed."""
    if not np.isfinite(z).any():
        placeholder(ax, "no results")
        return
    vmin, vmax = float(np.nanmin(z)), float(np.nanmax(z))
    high = float(np.nanpercentile(z, 95))
    clipped = vmax - vmin > 2.0 * (high - vmin) > 0          # a few outliers would wash out the rest
    if clipped:
        vmax = high
    im = ax.imshow(np.ma.masked_invalid(z.T), origin="lower", cmap=CMAP, aspect="auto", vmin=vmin, vmax=vmax)
    ax.set_xticks(range(len(rs)), [str(r) for r in rs])
    ax.set_yticks(range(len(es)), [str(e) for e in es])
    ax.set_xlabel("region-step evaluations")
    ax.set_ylabel("edge-step evaluations")
    ax.grid(False)
    if annotate:
        finite = z[np.isfinite(z)]
        integers = bool(np.all(finite == np.round(finite)))
        lo, hi = vmin, vmax
        for i in range(len(rs)):
            for j in range(len(es)):
                v = z[i, j]
                bright = np.isfinite(v) and hi > lo and min(v - lo, hi - lo) / (hi - lo) > 0.6
                ax.text(i, j, _fmt(v, integers), ha="center", va="center", fontsize=6, color="k" if bright else "w")
    best = np.nanargmin(z) if lower_is_better else np.nanargmax(z)
    i, j = np.unravel_index(best, z.shape)
    ax.add_patch(_frame((i, j)))
    if fig is not None:
        fig.colorbar(im, ax=ax, label=label + (" (clipped)" if clipped else ""), shrink=0.9,
                     extend="max" if clipped else "neither")


def _frame(cell):
    from matplotlib.patches import Rectangle
    return Rectangle((cell[0] - 0.5, cell[1] - 0.5), 1, 1, fill=False, edgecolor="red", linewidth=1.5)


def surface_figure(results: Results | str | Path, out: str | Path, name: str, stat: str, title: str) -> list[Path]:
    """A Figs. 9-12 style figure: the figure sequence's 3D surface and all sequences' heat map.

    Left: statistic ``stat`` over region x edge budgets on ``figure_sequence`` (the paper's
    sequence 2), as the paper's surfaces. Right: the same over all sequences (mean; failures
    as percent of all frames), with values; the red frame marks the minimum. When the sweep ran
    with the gradient step (``SweepConfig.gradient``) a second row shows the same with the
    gradient step taking its share of each edge budget (each row on its own colour scale).
    """
    res = as_results(results)
    cfg = res.config
    label, _ = STATS[stat]
    thr = threshold_text(res, stat)
    rows = ((False, "simplex"), (True, "with the gradient step")) if cfg.gradient else ((False, ""),)
    mean_label = (label.replace("(frames)", "(% of frames)") if stat.startswith("fail_") else label)
    with style_context():
        fig = new_figure(10.0, 4.3 * len(rows))
        for k, (gradient, row_name) in enumerate(rows):
            ax3 = fig.add_subplot(len(rows), 2, 2 * k + 1, projection="3d")
            ax2 = fig.add_subplot(len(rows), 2, 2 * k + 2)
            figure_data = res.data(cfg.figure_sequence)
            rs, es, z = res.surface(figure_data, stat, gradient=gradient)
            n = (int(np.nanmax(res.surface(figure_data, "frames", gradient=gradient)[2]))
                 if np.isfinite(z).any() else 0)
            surface3d(ax3, rs, es, z, label)
            prefix = f"{row_name}: " if row_name else ""
            ax3.set_title(f"{prefix}{cfg.figure_sequence} ({n} frames)" + (f"\n{thr}" if thr else ""))
            rs, es, zm = res.mean_surface([res.data(s) for s in res.sequences], stat, gradient=gradient)
            heatmap(ax2, rs, es, zm, mean_label, fig=fig)
            ax2.set_title(f"{prefix}all {len(res.sequences)} sequences "
                          f"({'percent of frames' if stat.startswith('fail_') else 'mean'})"
                          + (f"; {thr}" if thr else "") + "; red: minimum")
        fig.suptitle(title + (" — simplex (top) and gradient step (bottom)" if cfg.gradient else ""))
        return save(fig, out, name)
