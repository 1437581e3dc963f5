"""The sweep on a real Dask cluster: a scheduler and workers as separate processes, one worker killed.

Every process is started here on 127.0.0.1 and stopped at the end, also when the test fails
(:func:`tests.dask_cluster.local_cluster`).
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from experiments.plan import make_plan
from experiments.units import load_unit

from tests.conftest import REPO_ROOT
from tests.dask_cluster import local_cluster, cluster_env, wait_for

distributed = pytest.importorskip("distributed")

#: Seconds to wait for the sweep to finish.
SWEEP_S = 600


@pytest.mark.slow
def test_sweep_survives_a_killed_worker_and_computes_every_unit_once(tiny_results, tiny_config, tmp_path):
    config = tiny_config.with_changes({"sequences": ("gestures-2",), "timing_sequences": ("gestures-2",)})
    config.to_json(tmp_path / "tiny.json")
    plan = make_plan(config)
    n_units = len(plan.runs) + len(plan.timing)
    out = tmp_path / "results"
    env = cluster_env()
    with local_cluster(tmp_path, {"worker-a": {}, "worker-b": {}}) as (address, processes):
        sweep = subprocess.Popen([sys.executable, "-m", "experiments.sweep", "--config", str(tmp_path / "tiny.json"),
                                  "--out", str(out), "--scheduler", address, "--no-table2", "--no-progress"],
                                 cwd=REPO_ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        processes["sweep"] = sweep
        units = lambda: sorted((out / "units").rglob("*.npz")) if (out / "units").is_dir() else []
        # kill a worker in the middle: some units are done, and the worker is running one
        wait_for(lambda: len(units()) >= 2, SWEEP_S, "the first units", processes.values())
        with distributed.Client(address, timeout=30) as client:
            worker_b = next(a for a, w in client.scheduler_info()["workers"].items() if w["name"] == "worker-b")
            wait_for(lambda: any("run_unit" in str(k) for k in client.processing([worker_b])[worker_b]), SWEEP_S,
                     "worker-b to run a unit", processes.values())
            os.kill(processes["worker-b"].pid, signal.SIGKILL)
        assert len(units()) < n_units, "the sweep ended before a worker could be killed"
        processes["worker-b"].wait(timeout=30)
        stdout, stderr = sweep.communicate(timeout=SWEEP_S)
        assert sweep.returncode == 0, stderr
    assert processes["worker-b"].returncode == -signal.SIGKILL
    assert f"{n_units} units computed, 0 already there, 0 left, 0 failed" in stdout
    log = json.loads((out / "sweep.json").read_text())["invocations"]
    assert len(log) == 1 and log[0]["computed"] == n_units and log[0]["errors"] == []
    assert log[0]["backend"] == f"dask {address}"
    expected = sorted(spec.path(out) for spec in plan.runs + plan.timing)
    assert units() == expected                        # every unit once, nothing else
    for spec in plan.runs:                            # the same numbers as the local processes' run
        a, b = load_unit(spec.path(tiny_results)), load_unit(spec.path(out))
        for name in ("poses", "region_residual", "edge_residual", "evaluations"):
            np.testing.assert_array_equal(a[name], b[name])
