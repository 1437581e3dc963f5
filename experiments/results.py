"""Reading stored sweep results: units, per-unit statistics, surfaces over the budget grid.

Statistics (:data:`STATS`) reduce one unit's per-frame arrays to a number; failures compare
residuals with the thresholds of the results' :class:`~experiments.config.SweepConfig`. A unit
that is not (yet) in the results folder gives NaN, so figures of a partial sweep show holes
instead of failing.
"""
from __future__ import annotations

import json
import math
from pathlib import Path
from types import MappingProxyType

import numpy as np

from experiments.config import SweepConfig
from experiments.plan import data_spec, grid_specs
from experiments.sweep import CONFIG_FILE, SWEEP_FILE, TABLE2_FILE
from experiments.units import DataSpec, RunSpec, clip_name, load_unit

#: Statistic name -> (label with unit, short description).
STATS = MappingProxyType({
    "mean_F": ("mean F", "mean non-overlapping ratio F over frames"),
    "mean_D": ("mean edge distance (px)", "mean of the per-frame mean edge distance, pixels"),
    "fail_F": ("failures of F (frames)", "frames whose F exceeds the region threshold"),
    "fail_D": ("failures of edge distance (frames)", "frames whose edge distance exceeds the edge threshold"),
    "mpjpe": ("MPJPE (mm)", "mean per-joint position error against ground truth, mm"),
    "pa_mpjpe": ("PA-MPJPE (mm)", "MPJPE after Procrustes alignment, mm"),
    "angle": ("joint-angle error (deg)", "mean absolute joint-angle error, degrees"),
    "fail_gt": ("ground-truth failures (frames)", "frames whose MPJPE exceeds the ground-truth threshold"),
    "ms_total": ("time per frame (ms)", "mean time per frame, image processing included, ms"),
    "ms_median": ("median time per frame (ms)", "median time per frame, image processing included, ms"),
    "ms_registration": ("registration time per frame (ms)", "mean time of region + edge steps per frame, ms"),
    "frames": ("frames", "frames tracked"),
})


class Results:
    """A results folder written by :func:`experiments.sweep.run_sweep`.

    Parameters
    ----------
    root : str or Path
        The results folder.

    Raises
    ------
    ValueError
        If ``root`` holds no sweep results (no ``config.json``).
    """

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        if not (self.root / CONFIG_FILE).is_file():
            raise ValueError(f"{self.root} holds no sweep results ({CONFIG_FILE} missing); "
                             "run python -m experiments.sweep first")
        self.config = SweepConfig.from_json(self.root / CONFIG_FILE)
        log_path = self.root / SWEEP_FILE
        self.log = json.loads(log_path.read_text()) if log_path.is_file() else {"invocations": [], "clips": []}
        self._units: dict[Path, dict | None] = {}

    # ------------------------------------------------------------------ what is there
    @property
    def sequences(self) -> tuple[str, ...]:
        return self.config.sequences

    @property
    def clips(self) -> tuple[str, ...]:
        """Motion clips of the sweep (absolute paths as given to ``--motion-dir``)."""
        return tuple(self.log.get("clips", ()))

    def data(self, name: str) -> DataSpec:
        """The data spec of a named sequence."""
        return data_spec(self.config, name)

    def clip_data(self) -> list[DataSpec]:
        """Data specs of the clip-driven sequences."""
        return [data_spec(self.config, a, motion=c) for c in self.clips for a in self.config.motion_actors]

    def unit(self, spec: RunSpec) -> dict | None:
        """The stored result of ``spec`` (see :func:`experiments.units.load_unit`), or None."""
        path = spec.path(self.root)
        if path not in self._units:
            self._units[path] = load_unit(path) if path.is_file() else None
        return self._units[path]

    def table2(self) -> dict | None:
        path = self.root / TABLE2_FILE
        return json.loads(path.read_text()) if path.is_file() else None

    def wall_time_s(self) -> float:
        """Seconds over every invocation of the sweep in this folder."""
        return float(sum(i.get("wall_s", 0.0) for i in self.log.get("invocations", [])))

    # ------------------------------------------------------------------ statistics
    def thresholds(self) -> dict:
        c = self.config
        return {"F": c.figure_failure_f, "D": c.figure_failure_edge_px, "mpjpe": c.mpjpe_failure_mm}

    def stat(self, spec: RunSpec, name: str) -> float:
        """Statistic ``name`` (:data:`STATS`) of one unit; NaN if it is not stored."""
        u = self.unit(spec)
        return math.nan if u is None else unit_stat(u, name, self.thresholds())

    def surface(self, data: DataSpec, name: str, region_budgets=None, edge_budgets=None, *, gradient: bool = False):
        """Statistic over the budget grid of one sequence (with ``gradient``: its gradient-step twin).

        Returns
        -------
        (region_budgets, edge_budgets, values)
            ``values[i, j]`` at region budget ``i``, edge budget ``j`` (NaN where missing).
        """
        rs = tuple(self.config.region_budgets if region_budgets is None else region_budgets)
        es = tuple(self.config.edge_budgets if edge_budgets is None else edge_budgets)
        specs = grid_specs(self.config, data, rs, es, gradient=gradient)
        z = np.array([[self.stat(specs[(r, e)], name) for e in es] for r in rs])
        return np.array(rs), np.array(es), z

    def mean_surface(self, datas, name: str, region_budgets=None, edge_budgets=None, *, gradient: bool = False):
        """Mean of :meth:`surface` over several sequences (failures: percent of frames)."""
        zs, frames = [], []
        rs = es = None
        for d in datas:
            rs, es, z = self.surface(d, name, region_budgets, edge_budgets, gradient=gradient)
            zs.append(z)
            frames.append(self.surface(d, "frames", region_budgets, edge_budgets, gradient=gradient)[2])
        if not zs:
            raise ValueError("no sequences given")
        z, n = np.array(zs), np.array(frames)
        if name.startswith("fail_"):
            return rs, es, 100.0 * np.nansum(z, axis=0) / np.nansum(np.where(np.isnan(z), np.nan, n), axis=0)
        return rs, es, np.nanmean(z, axis=0) if np.isfinite(z).any() else np.full(z.shape[1:], np.nan)


def unit_stat(unit: dict, name: str, thresholds: dict) -> float:
    """Reduce one unit's per-frame arrays to statistic ``name`` (:data:`STATS`)."""
    if name == "mean_F":
        return float(np.nanmean(unit["region_residual"]))
    if name == "mean_D":
        return float(np.nanmean(unit["edge_residual"]))
    if name == "fail_F":
        return float(np.count_nonzero(unit["region_residual"] > thresholds["F"]))
    if name == "fail_D":
        return float(np.count_nonzero(unit["edge_residual"] > thresholds["D"]))
    if name == "mpjpe":
        return float(np.mean(unit["mpjpe_mm"]))
    if name == "pa_mpjpe":
        return float(np.mean(unit["pa_mpjpe_mm"]))
    if name == "angle":
        return float(np.mean(unit["angle_error_deg"]))
    if name == "fail_gt":
        return float(np.count_nonzero(unit["mpjpe_mm"] > thresholds["mpjpe"]))
    if name == "ms_total":
        return float(np.mean(unit["ms_total"]))
    if name == "ms_median":
        return float(np.median(unit["ms_total"]))
    if name == "ms_registration":
        return float(np.mean(unit["ms_region"] + unit["ms_edge"]))
    if name == "frames":
        return float(unit["frame"].size)
    raise ValueError(f"unknown statistic {name!r}; known: {', '.join(STATS)}")


def short_name(data: DataSpec) -> str:
    """Readable sequence name (clip-driven: ``actor + clip``)."""
    return data.actor if data.motion is None else f"{data.actor} + {clip_name(data.motion)}"
