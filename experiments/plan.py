"""Which units a sweep runs, and which unit each figure reads (one place for both).

The same :class:`~experiments.config.SweepConfig` gives the same :class:`RunSpec` objects to
the sweep (to run them) and to the figures (to find their result files), so a figure never
guesses a file name. Identical settings needed by two figures are one unit (e.g. the 50/50
policy at 200 evaluations is the grid cell 100 x 100). With ``SweepConfig.gradient`` the grid
and Fig. 4's two-step runs get a twin with the gradient step on (a third policy beside the
region and the edge step: the gradient step takes its share of each edge budget).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from experiments.config import SweepConfig
from experiments.units import DataSpec, RunSpec
from mocap.track import split_budget

#: Motion-capture clip suffixes picked up from ``--motion-dir`` (AMC needs its ASF beside it).
CLIP_SUFFIXES: tuple[str, ...] = (".bvh", ".amc")


def find_clips(motion_dir: str | Path) -> tuple[str, ...]:
    """Motion-capture clips in a folder (``*.bvh``, ``*.amc``), sorted, as absolute paths (links kept).

    Raises
    ------
    ValueError
        If the folder does not exist or holds no clip.
    """
    folder = Path(motion_dir)
    if not folder.is_dir():
        raise ValueError(f"motion folder {folder} does not exist")
    clips = sorted(os.path.abspath(p) for p in folder.iterdir() if p.suffix.lower() in CLIP_SUFFIXES)
    if not clips:
        raise ValueError(f"motion folder {folder} holds no .bvh or .amc clip")
    return tuple(clips)


def data_spec(config: SweepConfig, actor: str, *, motion: str | None = None, size=None) -> DataSpec:
    """The sequence of ``actor`` (driven by ``motion`` when given) under ``config``."""
    w, h = config.size if size is None else size
    frames = config.frames if motion is None else config.motion_frames
    return DataSpec(actor, motion, frames, config.seed, w, h)


def grid_specs(config: SweepConfig, data: DataSpec, region_budgets=None, edge_budgets=None, *,
               gradient: bool = False) -> dict:
    """Figs. 9-12: ``{(R, E): RunSpec}`` over the region x edge budgets.

    With ``gradient`` the gradient-step twin of the grid (the gradient step taking its share of
    each cell's E; cells where that share is 0 are the simplex-only units themselves).
    """
    rs = config.region_budgets if region_budgets is None else region_budgets
    es = config.edge_budgets if edge_budgets is None else edge_budgets
    return {(r, e): RunSpec(data, r, e, ftol=config.ftol, gradient=gradient) for r in rs for e in es}


def convergence_specs(config: SweepConfig, data: DataSpec, *, gradient: bool = False) -> dict:
    """Figs. 4 and 6: region-only and two-step runs, converged and limited.

    Keys: ``region_converged``, ``region_limited`` (edge budget 0); ``both_converged``,
    ``both_limited`` (the same budget for each step, edge step from the region step's final
    simplex); ``both_converged_fresh``, ``both_limited_fresh`` (edge step from a large fresh
    simplex, as before the paper's section 4.2 fix: a fully converged region simplex has
    collapsed, and an edge step started from it cannot move). All use ``converged_ftol`` so
    that only the budget differs. With ``gradient`` the same runs with the gradient step on
    (region-only runs, and runs whose edge budget leaves the step no evaluation, are unchanged).
    """
    big, small, tol, g = config.converged_budget, config.limited_budget, config.converged_ftol, gradient
    return {"region_converged": RunSpec(data, big, 0, ftol=tol), "region_limited": RunSpec(data, small, 0, ftol=tol),
            "both_converged": RunSpec(data, big, big, ftol=tol, gradient=g),
            "both_limited": RunSpec(data, small, small, ftol=tol, gradient=g),
            "both_converged_fresh": RunSpec(data, big, big, edge_start="fresh", ftol=tol, gradient=g),
            "both_limited_fresh": RunSpec(data, small, small, edge_start="fresh", ftol=tol, gradient=g)}


def handoff_specs(config: SweepConfig, data: DataSpec) -> dict:
    """Fig. 8: ``{(E, start): RunSpec}`` at ``handoff_total`` evaluations, both edge starts."""
    total = config.handoff_total
    return {(e, start): RunSpec(data, total - e, e, edge_start=start, ftol=config.ftol)
            for e in config.handoff_edge_budgets for start in ("region_simplex", "fresh")}


def policy_specs(config: SweepConfig, data: DataSpec) -> dict:
    """Accuracy vs time: ``{(policy, total): RunSpec}``."""
    out = {}
    for policy in config.policies:
        for total in config.policy_totals:
            r, e = split_budget(total, policy)
            out[(policy, total)] = RunSpec(data, r, e, ftol=config.ftol)
    return out


def timing_specs(config: SweepConfig, data: DataSpec) -> dict:
    """Table 1: ``{total: RunSpec}`` with a 50/50 split, prepared afresh and run alone."""
    return {t: RunSpec(data, *split_budget(t, "1:1"), ftol=config.ftol, kind="timing") for t in config.table1_totals}


@dataclass(frozen=True)
class Plan:
    """Everything one sweep runs, in order (figure sequence first)."""

    data: tuple[DataSpec, ...]
    runs: tuple[RunSpec, ...]
    timing: tuple[RunSpec, ...]
    clips: tuple[str, ...]


def ordered_sequences(config: SweepConfig) -> tuple[str, ...]:
    """``config.sequences`` with the figure sequence first."""
    return (config.figure_sequence,) + tuple(s for s in config.sequences if s != config.figure_sequence)


def clip_specs(config: SweepConfig, clips) -> tuple[DataSpec, ...]:
    """Clip-driven sequences: every actor of ``motion_actors`` with every clip."""
    return tuple(data_spec(config, actor, motion=clip) for clip in clips for actor in config.motion_actors)


def make_plan(config: SweepConfig, clips=()) -> Plan:
    """All units of a sweep, duplicates removed, in the order they are submitted."""
    runs: dict[tuple, RunSpec] = {}

    def add(specs) -> None:
        for spec in specs:
            runs.setdefault((spec.data.key, spec.key), spec)

    data = []
    for name in ordered_sequences(config):
        d = data_spec(config, name)
        data.append(d)
        add(grid_specs(config, d).values())
        add(convergence_specs(config, d).values())
        add(handoff_specs(config, d).values())
        add(policy_specs(config, d).values())
        if config.gradient:
            add(grid_specs(config, d, gradient=True).values())
            specs = convergence_specs(config, d, gradient=True)
            add(specs[k] for k in ("both_converged_fresh", "both_limited_fresh"))     # the runs Fig. 4 draws
    for d in clip_specs(config, clips):
        data.append(d)
        add(grid_specs(config, d, config.motion_budgets, config.motion_budgets).values())
    timing = []
    for name in config.timing_sequences:
        d = data_spec(config, name)
        if d not in data:
            data.append(d)
        timing.extend(timing_specs(config, d).values())
    return Plan(tuple(data), tuple(runs.values()), tuple(timing), tuple(clips))
