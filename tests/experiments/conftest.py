"""A tiny sweep shared by the experiment tests (2x2 grid, a few frames, two sequences)."""
from __future__ import annotations

import pytest

from experiments.config import SweepConfig
from experiments.sweep import run_sweep

#: Small enough to run in seconds, but with every kind of unit the figures need.
TINY = SweepConfig(sequences=("gestures-2", "turning"), frames=3, region_budgets=(0, 30), edge_budgets=(0, 30),
                   converged_budget=60, limited_budget=10, handoff_total=40, handoff_edge_budgets=(0, 20, 40),
                   policy_totals=(20, 200), timing_sequences=("gestures-2",), table1_totals=(20, 40),
                   table2_sizes=((160, 120), (192, 144)), table2_frames=1, table2_min_runs=3, table2_min_seconds=0.01,
                   motion_frames=3, motion_budgets=(0, 20))


@pytest.fixture(scope="session")
def tiny_config() -> SweepConfig:
    return TINY


@pytest.fixture(scope="session")
def tiny_results(tmp_path_factory):
    """Results folder of the tiny sweep, run in this process (``workers=0``): the suite's own
    workers keep both cores busy, so two more processes only added their start and kernel
    loading (117 s against about 12 s; the local process pool is tested by test_sweep.py's
    ``--workers 1`` run, Dask by test_sweep_cluster.py)."""
    out = tmp_path_factory.mktemp("tiny") / "results"
    summary = run_sweep(TINY, out, workers=0, progress=False)
    assert not summary.errors, summary.errors
    return out
