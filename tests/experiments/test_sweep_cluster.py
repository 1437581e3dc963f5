"""The sweep on a real Dask cluster: a scheduler and workers as separate processes, one worker killed.

Every process is started here on 127.0.0.1 (free ports chosen by the system, announced through a
scheduler file) and stopped at the end, also when the test fails.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from experiments.plan import make_plan
from experiments.units import load_unit

from tests.conftest import REPO_ROOT

distributed = pytest.importorskip("distributed")

#: Seconds to wait for the cluster to come up and for the sweep to finish.
STARTUP_S, SWEEP_S = 120, 600


def dask_command(*args: str) -> list[str]:
    """``dask ...`` run by this interpreter (the ``dask`` script of its environment)."""
    return [sys.executable, "-c", "import sys; from dask.__main__ import main; sys.exit(main())", *args]


def wait_for(condition, timeout: float, what: str, processes=()) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        for p in processes:
            assert p.poll() is None, f"{what}: a process ended early ({p.args[-1]})"
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)


@pytest.mark.slow
def test_sweep_survives_a_killed_worker_and_computes_every_unit_once(tiny_results, tiny_config, tmp_path):
    config = tiny_config.with_changes({"sequences": ("gestures-2",), "timing_sequences": ("gestures-2",)})
    config.to_json(tmp_path / "tiny.json")
    plan = make_plan(config)
    n_units = len(plan.runs) + len(plan.timing)
    scheduler_file, out = tmp_path / "scheduler.json", tmp_path / "results"
    # the workers import this checkout's experiments and mocap, not an installed copy
    env = {**os.environ, "PYTHONPATH": str(REPO_ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    logs = {name: open(tmp_path / f"{name}.log", "w") for name in ("scheduler", "worker-a", "worker-b")}
    processes: dict[str, subprocess.Popen] = {}
    try:
        processes["scheduler"] = subprocess.Popen(
            dask_command("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                         "--scheduler-file", str(scheduler_file)),
            cwd=tmp_path, env=env, stdout=logs["scheduler"], stderr=subprocess.STDOUT)
        wait_for(scheduler_file.exists, STARTUP_S, "the scheduler file", processes.values())
        time.sleep(0.2)                          # (written whole: read it once it has settled)
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        for name in ("worker-a", "worker-b"):
            processes[name] = subprocess.Popen(
                dask_command("worker", address, "--host", "127.0.0.1", "--nworkers", "1", "--nthreads", "1",
                             "--no-nanny", "--no-dashboard", "--memory-limit", "0", "--name", name),
                cwd=REPO_ROOT, env=env, stdout=logs[name], stderr=subprocess.STDOUT)
        wait_for(lambda: all("Registered to" in (tmp_path / f"{n}.log").read_text() for n in ("worker-a", "worker-b")),
                 STARTUP_S, "the workers", processes.values())

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
    finally:
        for p in processes.values():
            if p.poll() is None:
                p.kill()
                p.wait(timeout=30)
        for log in logs.values():
            log.close()
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
