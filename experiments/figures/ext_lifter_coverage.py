"""The lifter's coverage against the number of hypotheses M.

One line per measure of ``python -m experiments.lifter_coverage`` (its ``results.json``): oracle
keypoints on an unseen benchmark seed, MediaPipe's landmarks on the same seed's rendered frames,
and the CMU subjects held out in turn; the share of frames on which one of the first M
hypotheses is within 100 mm of the truth (joints about the neck), M = 1, 2, 5, 10. Left: all
frames of each measure; right: each sequence of the oracle measure.
"""
from __future__ import annotations

from pathlib import Path

from experiments.style import new_figure, placeholder, save, style_context

_LABELS = {"oracle": "oracle 2D + 2 px (benchmark seed {seed})", "mediapipe": "MediaPipe 2D (benchmark seed {seed})",
           "loso": "CMU subject held out (oracle 2D + 2 px)"}


def _curve(summary: dict) -> tuple[list[int], list[float]]:
    ms = sorted(int(k.split("_")[-1]) for k in summary if k.startswith("coverage_at_"))
    return ms, [100.0 * summary[f"coverage_at_{m}"] for m in ms]


def main(results: dict, out: str | Path, name: str = "ext_lifter_coverage") -> list[Path]:
    """Draw the figure.

    Parameters
    ----------
    results : dict
        ``results.json`` of :mod:`experiments.lifter_coverage`: measures ``oracle``, ``mediapipe``,
        ``loso``, each with ``all`` (``coverage_at_M`` shares 0-1) and, for the first two,
        ``sequences`` (the same per sequence).
    out : str or Path
        Output folder.
    """
    with style_context():
        fig = new_figure(7.0, 3.0)
        left, right = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
        measures = [k for k in _LABELS if k in results]
        if not measures:
            placeholder(left, "no coverage results")
        for key in measures:
            ms, cov = _curve(results[key]["all"])
            label = _LABELS[key].format(seed=results[key].get("seed", "?"))
            if key == "loso" and "hidden" in results[key]:
                label += f"; {'x'.join(map(str, results[key]['hidden']))}, {results[key]['steps']} steps"
            left.plot(ms, cov, "o-", ms=4, label=label)
        if "oracle" in results:
            for seq, summary in results["oracle"]["sequences"].items():
                ms, cov = _curve(summary)
                right.plot(ms, cov, "o-", ms=3, label=seq)
            right.set_title(f"oracle 2D, seed {results['oracle'].get('seed', '?')}, per sequence", fontsize=8)
        else:
            placeholder(right, "no oracle results")
        for ax in (left, right):
            ax.axhline(95.0, color="0.6", lw=0.8, ls="--")
            ax.set_xscale("log")
            ax.set_xticks([1, 2, 5, 10])
            ax.set_xticklabels(["1", "2", "5", "10"])
            ax.set_xlabel("hypotheses M")
            ax.set_ylabel("frames within 100 mm (%)")
            ax.set_ylim(0.0, 100.0)
            if ax.get_legend_handles_labels()[1]:
                ax.legend(fontsize=6, loc="lower right")
        return save(fig, out, name)
