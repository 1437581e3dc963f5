"""The hand-size cue against depth mirrors (issue 46): does perspective tell the truth from its mirrors?

Left: pooled share of (truth, distinct exact mirror) pairs on which the hand cue rates the truth
better, against the detector's noise per coordinate at the input size (``points``: the three hand
points' mean distance; ``span``: the palm's width and the hand's length), for the seeds the
weights are chosen on and the unseen seed, beside the prior and the tracker's score (which do not
depend on the hand's noise); the dotted lines mark MediaPipe's two measured levels. Middle: the
``points`` cue's share by how far the mirror moves the hand in depth, at each level. Right: the
tracker's score plus ``w`` times the cue (at MediaPipe's image-mode level) against ``w``, on both
groups of seeds. Not one of the sweep's figures: it takes the summary of
:func:`experiments.hand_size.summarise` (the figure reads the data alone).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from experiments.style import new_figure, placeholder, save, style_context


def main(summary: dict, out: str | Path, name: str = "ext_hand_size") -> list[Path]:
    """Draw the figure.

    Parameters
    ----------
    summary : dict
        :func:`experiments.hand_size.summarise`'s result.
    out : str or Path
        Output folder.
    """
    groups = summary.get("groups", {})
    settings = summary.get("settings", {})
    levels = settings.get("noise_px", [])
    with style_context():
        fig = new_figure(11.0, 3.4)
        left, middle, right = (fig.add_subplot(1, 3, k) for k in (1, 2, 3))
        if not groups or not levels:
            for ax in (left, middle, right):
                placeholder(ax, "no pairs")
            return save(fig, out, name)
        if "stage" in summary:
            fig.suptitle(f"stage: {summary['stage']}", fontsize=8)
        styles = {"fit": "-", "unseen": "--"}
        for g, data in groups.items():
            seeds = (",".join(map(str, settings.get("fit_seeds", []))) if g == "fit"
                     else str(settings.get("unseen_seed", "?")))
            p = data["pooled"]
            for cue, colour in (("points", "C0"), ("span", "C1")):
                left.plot(levels, [100.0 * v for v in p[cue]], styles.get(g, "-"), color=colour, marker="o", ms=3,
                          label=f"{cue}, seeds {seeds} ({p['pairs']} pairs)")
            for cue, colour in (("prior", "C2"), ("score", "C3")):
                if not math.isnan(p.get(cue, math.nan)):
                    left.axhline(100.0 * p[cue], color=colour, ls=styles.get(g, "-"), lw=0.8,
                                 label=f"{cue} alone, seeds {seeds}")
        for key in ("mediapipe_sigma_px", "mediapipe_json_sigma_px"):
            if key in settings:
                left.axvline(settings[key], color="k", ls=":", lw=0.6)
        left.set_xlabel("detector noise per coordinate (px at the input size)")
        left.set_ylabel("pairs with the truth better (%)")
        left.set_ylim(40, 101)
        left.legend(fontsize=5, loc="lower left")

        data = groups.get("fit") or next(iter(groups.values()))
        bins = data["per_depth"]
        x = np.arange(len(bins))
        width = 0.8 / len(levels)
        for k, level in enumerate(levels):
            values = [100.0 * b["points"][k] if b.get("pairs") else 0.0 for b in bins]
            middle.bar(x + (k - (len(levels) - 1) / 2) * width, values, width, label=f"σ = {level:g} px")
        middle.set_xticks(x, [f"{100 * b['low_m']:.0f}-{100 * b['high_m']:.0f}\n{b.get('pairs', 0)}" for b in bins],
                          fontsize=6)
        middle.set_xlabel("hand's depth change (cm), pairs")
        middle.set_ylabel("points cue: truth better (%)")
        middle.set_ylim(0, 118)
        middle.set_yticks(range(0, 101, 20))
        middle.axhline(50, color="k", lw=0.5, ls=":")
        middle.legend(fontsize=5, ncol=3, loc="upper center")

        weights = summary.get("combine_weights", [])
        rows = [r for r in summary.get("combined", []) if r["base"] == "score" and r["cue"] == "points"]
        if not rows or not weights:
            placeholder(right, "no score measured")
        else:
            target = settings.get("mediapipe_sigma_px", levels[-1])
            row = min(rows, key=lambda r: abs(r["noise_px"] - target))
            xw = np.arange(len(weights))
            right.plot(xw, [100.0 * v for v in row["fit_curve"]], "-o", ms=3, label="seeds fitted on")
            if "unseen_curve" in row:
                right.plot(xw, [100.0 * v for v in row["unseen_curve"]], "--o", ms=3, label="unseen seed")
            right.set_xticks(xw, [f"{w:g}" for w in weights], fontsize=6)
            right.set_xlabel(f"w (score units per px), points cue at σ = {row['noise_px']:g} px")
            right.set_ylabel("score + w · cue: truth better (%)")
            right.legend(fontsize=6)
        return save(fig, out, name)
