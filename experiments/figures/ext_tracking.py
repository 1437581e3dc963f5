"""Tracking ablation: share of frames under each 3D error, per tracker configuration.

Reads the per-frame errors that ``python -m experiments.tracking`` stores (one file per
configuration, sequence and seed under ``results/tracking/units``) and draws, for each
configuration, the cumulative share of frames (all sequences and seeds pooled) whose MPJPE is
at most a given value, with the 100 mm failure line. Not one of the sweep's figures: it takes
the tracking results folder.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from experiments.style import new_figure, placeholder, save, style_context
from mocap.metrics import DEFAULT_FAILURE_MM

#: Largest error drawn, millimetres.
MAX_MM = 400.0


def main(per_frame: dict[str, np.ndarray], out: str | Path, name: str = "ext_tracking") -> list[Path]:
    """Draw the figure.

    Parameters
    ----------
    per_frame : dict of str to ndarray of shape (n,), millimetres
        Per-frame MPJPE of each configuration (pooled over sequences and seeds).
    out : str or Path
        Output folder.
    """
    with style_context():
        fig = new_figure(6.0, 3.4)
        ax = fig.add_subplot()
        if not per_frame:
            placeholder(ax, "no tracking results")
        grid = np.linspace(0.0, MAX_MM, 401)
        for label, errors in per_frame.items():
            errors = np.sort(np.asarray(errors, dtype=np.float64))
            share = np.searchsorted(errors, grid, side="right") / max(len(errors), 1)
            ax.plot(grid, 100.0 * share, lw=1.6 if label == "default" else 1.0,
                    label=f"{label} ({100.0 * np.mean(errors > DEFAULT_FAILURE_MM):.0f} % > {DEFAULT_FAILURE_MM:g} mm)")
        ax.axvline(DEFAULT_FAILURE_MM, color="0.5", ls="--", lw=0.8)
        ax.set_xlabel("MPJPE of a frame (mm)")
        ax.set_ylabel("frames at or under it (%)")
        ax.set_xlim(0.0, MAX_MM)
        ax.set_ylim(0.0, 100.0)
        ax.legend(loc="lower right", fontsize=7)
        return save(fig, out, name)
