"""The proposal stage's budget: accuracy against cost evaluations per frame.

One point per tracker configuration of ``python -m experiments.tracking`` (summaries as
:func:`experiments.tracking.summarise` writes them): the mean cost evaluations per frame it
used (all hypotheses, proposals and refinements) against its median MPJPE over the sequences
(left) and its share of frames over 100 mm (right), each point labelled with the
configuration's name. Not one of the sweep's figures: it takes the tracking summaries.
"""
from __future__ import annotations

import math
from pathlib import Path

from experiments.style import new_figure, placeholder, save, style_context
from mocap.metrics import DEFAULT_FAILURE_MM


def main(summaries: dict[str, dict], out: str | Path, name: str = "ext_proposal_budget") -> list[Path]:
    """Draw the figure.

    Parameters
    ----------
    summaries : dict of str to dict
        Per configuration name: ``evaluations_per_frame``, ``median_mpjpe_mm`` (mm) and
        ``failure_rate`` (0-1). Configurations without a measured evaluation count are left out.
    out : str or Path
        Output folder.
    """
    points = {k: s for k, s in summaries.items() if math.isfinite(s.get("evaluations_per_frame", math.nan))}
    with style_context():
        fig = new_figure(7.0, 3.0)
        left, right = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
        if not points:
            placeholder(left, "no tracking results")
        for ax, key, scale, label in ((left, "median_mpjpe_mm", 1.0, "median MPJPE (mm)"),
                                      (right, "failure_rate", 100.0, f"frames over {DEFAULT_FAILURE_MM:g} mm (%)")):
            for config, s in points.items():
                ax.plot(s["evaluations_per_frame"], scale * s[key], "o", ms=4, color="C0")
                ax.annotate(config, (s["evaluations_per_frame"], scale * s[key]), fontsize=6,
                            xytext=(3, 3), textcoords="offset points")
            ax.set_xlabel("cost evaluations per frame")
            ax.set_ylabel(label)
            ax.set_ylim(bottom=0.0)
        return save(fig, out, name)
