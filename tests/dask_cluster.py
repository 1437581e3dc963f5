"""A real Dask cluster on 127.0.0.1 for a test: a scheduler and named single-threaded workers,
each a separate process (free ports chosen by the system, announced through a scheduler file),
all stopped when the test ends, also when it fails."""
from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from tests.conftest import REPO_ROOT

#: Seconds to wait for the cluster to come up.
STARTUP_S = 120


def dask_command(*args: str, prelude: str = "") -> list[str]:
    """``dask ...`` run by this interpreter (the ``dask`` script of its environment), after the
    Python statements ``prelude``."""
    return [sys.executable, "-c", f"{prelude}import sys; from dask.__main__ import main; sys.exit(main())", *args]


def wait_for(condition, timeout: float, what: str, processes=()) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        for p in processes:
            assert p.poll() is None, f"{what}: a process ended early ({p.args[-1]})"
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)


def cluster_env() -> dict[str, str]:
    """The environment of the test's processes: they import this checkout, not an installed copy."""
    return {**os.environ, "PYTHONPATH": str(REPO_ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}


@contextlib.contextmanager
def local_cluster(folder: Path, workers: dict[str, dict]):
    """Start a scheduler and the ``workers`` (name -> ``{"prelude": STATEMENTS, "env": {...}}``,
    both optional) with their logs in ``folder``; yield ``(address, processes)``, ``processes``
    a dict name -> Popen to which the test may add its own; kill whatever still runs at the end."""
    scheduler_file = folder / "scheduler.json"
    env = cluster_env()
    logs = {name: open(folder / f"{name}.log", "w") for name in ("scheduler", *workers)}
    processes: dict[str, subprocess.Popen] = {}
    try:
        processes["scheduler"] = subprocess.Popen(
            dask_command("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                         "--scheduler-file", str(scheduler_file)),
            cwd=folder, env=env, stdout=logs["scheduler"], stderr=subprocess.STDOUT)
        wait_for(scheduler_file.exists, STARTUP_S, "the scheduler file", processes.values())
        time.sleep(0.2)                          # (written whole: read it once it has settled)
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        for name, extra in workers.items():
            processes[name] = subprocess.Popen(
                dask_command("worker", address, "--host", "127.0.0.1", "--nworkers", "1", "--nthreads", "1",
                             "--no-nanny", "--no-dashboard", "--memory-limit", "0", "--name", name,
                             prelude=extra.get("prelude", "")),
                cwd=REPO_ROOT, env={**env, **extra.get("env", {})}, stdout=logs[name], stderr=subprocess.STDOUT)
        wait_for(lambda: all("Registered to" in (folder / f"{n}.log").read_text() for n in workers),
                 STARTUP_S, "the workers", processes.values())
        yield address, processes
    finally:
        for p in processes.values():
            if p.poll() is None:
                p.kill()
                p.wait(timeout=30)
        for log in logs.values():
            log.close()
