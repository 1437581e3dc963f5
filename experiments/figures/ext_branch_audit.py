"""The branch audit: which cues tell a pose from its depth mirrors (issue 39).

Left: pooled over every sequence and seed, per cue the share of (truth, distinct alternative)
pairs on which the cue rates the truth better, per stage (the exact mirrors unrefined, both after
the equal refinement, the refined truth against its own exact mirrors: ``leader``) and for the
leader's differences summed over the lag's window. Right: per sequence (and pooled), the share of
frames on which the tracker's region + edge sum, its whole score and the logistic combination
(where fitted) rate the truth better than every alternative, beside the ambiguity floor (frames
with an alternative that no single cue separates), in the leader stage (else the refined one). Not one of the sweep's figures: it takes the summary of
:func:`experiments.branch_audit.summarise`.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from experiments.style import new_figure, placeholder, save, style_context


def main(summary: dict, out: str | Path, name: str = "ext_branch_audit") -> list[Path]:
    """Draw the figure.

    Parameters
    ----------
    summary : dict
        :func:`experiments.branch_audit.summarise`'s result.
    out : str or Path
        Output folder.
    """
    pooled = summary.get("pooled", {})
    with style_context():
        fig = new_figure(9.0, 3.4)
        left, right = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
        if not pooled or not pooled.get("refined", {}).get("pairs"):
            placeholder(left, "no pairs")
            placeholder(right, "no pairs")
            return save(fig, out, name)
        bars = [(pooled[st]["pair_truth_better"], st) for st in summary["stages"]]
        columns = list(bars[0][0])          # the cues in the summary's order: the figure reads the data alone
        x = np.arange(len(columns))
        if "leader" in summary["stages"]:
            bars.append((pooled["leader"]["window_truth_better"], f"leader, {summary['settings']['window']}-frame sums"))
        width = 0.8 / len(bars)
        for k, (shares, label) in enumerate(bars):
            values = [100.0 * shares.get(c, math.nan) for c in columns]
            left.bar(x + (k - (len(bars) - 1) / 2) * width, [0.0 if math.isnan(v) else v for v in values], width,
                     label=label)
        left.set_xticks(x, columns, rotation=35, ha="right")
        left.set_ylabel("pairs with the truth better (%)")
        left.set_ylim(0, 100)
        left.axhline(50, color="k", lw=0.5, ls=":")
        left.legend(fontsize=6)
        left.set_title(f"{pooled['refined']['pairs']} pairs, {summary.get('evaluations', '?')} evaluations each",
                       fontsize=8)
        stage = "leader" if "leader" in summary["stages"] else "refined"
        groups = list(summary["per_sequence"]) + ["pooled"]
        rates = [summary["per_sequence"][g][stage] if g != "pooled" else pooled[stage] for g in groups]
        series = [("region_edge", "region + edge"), ("score", "score"), ("logistic", "logistic (held-out seeds)"),
                  ("floor", "ambiguity floor")]
        y = np.arange(len(groups))
        for k, (key, label) in enumerate(series):
            v = [100.0 * r.get(key, math.nan) for r in rates]
            right.barh(y + (k - 1.5) * 0.2, [0.0 if math.isnan(a) else a for a in v], 0.2, label=label)
        right.set_yticks(y, groups)
        right.invert_yaxis()
        right.set_xlabel(f"frames with the truth better than every alternative (%), {stage}")
        right.set_xlim(0, 100)
        right.legend(fontsize=6, loc="lower right")
        return save(fig, out, name)
