"""Every table and figure of the paper's experimental section, and ours beyond it.

One module per output, each with ``main(results, out)`` writing ``<name>.png`` and
``<name>.pdf`` (tables also ``<name>.md``) from a results folder of
:mod:`experiments.sweep`. ``python -m experiments.figures`` runs them all.
"""
from __future__ import annotations

import importlib
from pathlib import Path

#: Module names, i.e. output names, in order: the paper's, then ours (``ext_*``).
FIGURES: tuple[str, ...] = ("table1", "table2", "fig4", "fig6", "fig8", "fig9", "fig10", "fig11", "fig12",
                            "ext_mpjpe", "ext_gt_failures", "ext_policies", "ext_thresholds", "ext_sequences",
                            "ext_clips")


def make_all(results, out: str | Path, names=FIGURES, *, progress: bool = False) -> list[Path]:
    """Run the ``main`` of every figure module in ``names``.

    Parameters
    ----------
    results : Results or str or Path
        Results folder (or a loaded :class:`~experiments.results.Results`, shared by all).
    out : str or Path
        Output folder.
    names : sequence of str
        Subset of :data:`FIGURES`.

    Returns
    -------
    list of Path
        Files written.
    """
    from tqdm import tqdm

    from experiments.figures._common import as_results

    unknown = [n for n in names if n not in FIGURES]
    if unknown:
        raise ValueError(f"unknown figure(s) {', '.join(unknown)}; known: {', '.join(FIGURES)}")
    res = as_results(results)
    written = []
    for name in tqdm(names, desc="figures", unit="figure", disable=not progress):
        written += importlib.import_module(f"experiments.figures.{name}").main(res, out)
    return written
