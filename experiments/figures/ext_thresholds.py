"""Beyond the paper: the residual distributions behind the failure thresholds.

Every frame of every grid run of every named sequence: F (left) and mean edge distance
(right) against that frame's MPJPE, with the failure thresholds of the sweep drawn. A useful
image threshold separates the frames that are wrong in 3D (MPJPE above its threshold).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from experiments.figures._common import as_results
from experiments.plan import grid_specs
from experiments.results import Results
from experiments.style import new_figure, placeholder, save, style_context

NAME = "ext_thresholds"


def pooled(res: Results) -> dict:
    """Per-frame F, edge distance and MPJPE pooled over every stored grid unit of every sequence."""
    keys = ("region_residual", "edge_residual", "mpjpe_mm")
    parts = {k: [] for k in keys}
    for name in res.sequences:
        for spec in grid_specs(res.config, res.data(name)).values():
            u = res.unit(spec)
            if u is not None:
                for k in keys:
                    parts[k].append(u[k])
    return {k: np.concatenate(v) if v else np.empty(0) for k, v in parts.items()}


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``ext_thresholds.png`` and ``ext_thresholds.pdf`` into ``out``."""
    res = as_results(results)
    t = res.thresholds()
    data = pooled(res)
    with style_context():
        fig = new_figure(10.0, 3.8)
        for k, (key, thr, label) in enumerate((("region_residual", t["F"], "F"),
                                               ("edge_residual", t["D"], "mean edge distance (px)"))):
            ax = fig.add_subplot(1, 2, k + 1)
            x, y = data[key], data["mpjpe_mm"]
            ok = np.isfinite(x) & np.isfinite(y)
            if not ok.any():
                placeholder(ax, "no grid results")
                continue
            x, y = x[ok], y[ok]
            ax.hexbin(x, np.clip(y, 1, None), gridsize=45, bins="log", cmap="Greys", yscale="log")
            ax.axvline(thr, color="r", lw=1)
            ax.axhline(t["mpjpe"], color="b", lw=1, ls="--")
            above = x > thr
            bad = y > t["mpjpe"]
            prec = 100.0 * np.count_nonzero(above & bad) / max(1, np.count_nonzero(above))
            rec = 100.0 * np.count_nonzero(above & bad) / max(1, np.count_nonzero(bad))
            ax.set_xlabel(label)
            ax.set_ylabel("MPJPE of the frame (mm, log)")
            ax.set_title(f"threshold {thr:g} (red): {100 * above.mean():.1f}% of frames above;\n"
                         f"of them {prec:.0f}% have MPJPE > {t['mpjpe']:g} mm (blue); they catch {rec:.0f}% of those")
        fig.suptitle(f"Beyond the paper — failure thresholds against ground truth ({data['mpjpe_mm'].size} frames "
                     "of every grid run)")
        return save(fig, out, NAME)
