"""Beyond the paper: accuracy vs time per frame for the split policies.

Policies (``policies`` of the sweep): the paper's ``auto`` (all evaluations to the region
step below 200, else 50/50), 50/50, all-region, all-edge, at each of ``policy_totals``.
Left: MPJPE against measured time per frame; middle: ground-truth failures vs total
evaluations; right: mean edge distance vs total. Means over all sequences.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from experiments.config import POLICY_LABELS
from experiments.figures._common import as_results, threshold_text
from experiments.analysis import policy_summary
from experiments.results import Results
from experiments.style import POLICY_COLOURS, new_figure, save, style_context

NAME = "ext_policies"


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``ext_policies.png`` and ``ext_policies.pdf`` into ``out``."""
    res = as_results(results)
    cfg = res.config
    table = {p: {k: np.asarray(v) for k, v in row.items()} for p, row in policy_summary(res).items()}
    totals = np.array(cfg.policy_totals)
    with style_context():
        fig = new_figure(11.0, 3.6)
        ax1, ax2, ax3 = (fig.add_subplot(1, 3, k) for k in (1, 2, 3))
        for policy, row in table.items():
            c = POLICY_COLOURS.get(policy, None)
            label = POLICY_LABELS.get(policy, policy)
            style = dict(ls="--", marker="s", ms=5, mfc="none", zorder=5, lw=1.6) if policy == "auto" else \
                dict(ls="-", marker="o", ms=3)
            ax1.plot(row["ms_median"], row["mpjpe"], color=c, label=label, **style)
            for t, x, y in zip(totals, row["ms_median"], row["mpjpe"]):
                if policy == "1:1" and np.isfinite(x):
                    ax1.annotate(str(t), (x, y), fontsize=6, xytext=(2, 3), textcoords="offset points")
            ax2.plot(totals, row["fail_gt"], color=c, label=label, **style)
            ax3.plot(totals, row["mpjpe"], color=c, label=label, **style)
        ax1.set_xlabel("median time per frame (ms, measured during the sweep)")
        ax1.set_ylabel("MPJPE (mm)")
        ax1.set_title("accuracy vs time (labels: evaluations, 50/50)")
        ax2.set_xlabel("evaluations per frame")
        ax2.set_ylabel("ground-truth failures (% of frames)")
        ax2.set_title(threshold_text(res, "fail_gt"))
        ax3.set_xlabel("evaluations per frame")
        ax3.set_ylabel("MPJPE (mm)")
        ax3.set_title("accuracy vs evaluations")
        for ax in (ax2, ax3):
            ax.axvline(200, color="k", lw=0.6, ls=":")
        ax1.legend()
        fig.suptitle(f"Beyond the paper — split policies, mean over {len(res.sequences)} sequences "
                     "(dotted: the paper's 200-evaluation switch)")
        return save(fig, out, NAME)
