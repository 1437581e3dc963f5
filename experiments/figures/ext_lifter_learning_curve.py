"""The lifter's learning curve: training steps against held-out subjects' coverage at M = 1 and M = 10.

From the run files of ``python -m experiments.lifter_learning_curve``: one panel per M (the top
hypothesis; the best of ten), one colour per held-out subject. A run's measurements along the
way are a thin line (its cosine schedule unfinished there); its end, what a lifter trained for
that budget gives, a filled marker joined to the other runs' ends.
"""
from __future__ import annotations

from pathlib import Path

from experiments.style import new_figure, placeholder, save, style_context

_COLOURS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00")
_MEASURES = (("top1", "top hypothesis (M = 1)"), ("best_of_10", "best of 10 (M = 10)"))


def main(runs: list[dict], out: str | Path, name: str = "ext_lifter_learning_curve") -> list[Path]:
    """Draw the figure.

    Parameters
    ----------
    runs : list of dict
        Run records (``budget``, ``hold_out``, ``points``: ``step`` and per held-out subject
        ``top1`` / ``best_of_10`` shares 0-1), as :func:`experiments.lifter_learning_curve.read_runs` gives.
    out : str or Path
        Output folder.
    """
    with style_context():
        fig = new_figure(7.0, 3.0)
        axes = [fig.add_subplot(1, 2, i + 1) for i in range(2)]
        subjects = sorted({s for r in runs for s in r.get("hold_out", [])})
        for ax, (key, title) in zip(axes, _MEASURES):
            if not runs:
                placeholder(ax, "no runs")
                continue
            for colour, s in zip(_COLOURS * 4, subjects):
                ends = []
                for r in runs:
                    pts = [p for p in r["points"] if s in p]
                    if not pts:
                        continue
                    ax.plot([p["step"] for p in pts], [100.0 * p[s][key] for p in pts], "-", color=colour,
                            lw=0.7, alpha=0.6)
                    if r.get("finished"):
                        ends.append((r["budget"], 100.0 * pts[-1][s][key]))
                if ends:
                    ax.plot(*zip(*ends), "o-", color=colour, ms=5, label=f"subject {s} held out (run ends)")
            ax.set_title(title, fontsize=8)
            ax.set_xlabel("training steps (batch 256)")
            ax.set_ylabel("held-out poses within 100 mm (%)")
            ax.set_xlim(left=0)
            if ax.get_legend_handles_labels()[1]:
                ax.legend(fontsize=6, loc="lower right")
        return save(fig, out, name)
