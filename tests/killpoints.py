"""``python -m tests.killpoints MODE N -- CLI ARGS...``: the mocap CLI, stopped at a chosen point.

Test helper for crash-exact resume and the output-folder lock. It wraps the two writes of a
tracking run — a ``poses.csv`` row (:meth:`mocap.io.pose_table.PoseTable.append_to`) and the
checkpoint (:func:`mocap.io.checkpoint.write_checkpoint`, as :mod:`mocap.run.journal` calls it) — and at the ``N``-th one (1-based, counted in
this process) does what ``MODE`` says:

``after-row``    SIGKILL itself right after the row is on disk, before the checkpoint
``mid-row``      write the first half of the row's line, then SIGKILL itself
``after-state``  SIGKILL itself right after the checkpoint
``pause``        after the checkpoint, create the file ``$KILLPOINTS_PAUSED`` and wait until
                 it has been removed (another run can then meet the held lock)
``stop``         after the checkpoint, unless the file ``$KILLPOINTS_PAUSED`` exists already
                 (once per test, whichever process gets there first), create it holding the
                 run's output folder and stop itself with SIGSTOP (a hung process: alive,
                 holding its lock, never answering)

The checkpoint interval is :data:`CHECKPOINT_EVERY` frames (instead of the run's default), so
that the kill points of a short clip fall on every position inside an interval.

SIGKILL cannot be caught: nothing of the run's own clean-up happens, as with ``kill -9``.
:func:`install` does the same inside any process (the track-many cluster test starts a Dask
worker with it); as a Dask preload (``dask worker --preload tests.killpoints``, :func:`dask_setup`)
it reaches the worker's own process also under a nanny, with ``$KILLPOINTS_MODE`` and
``$KILLPOINTS_N``.
"""
from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path


#: Frames between checkpoints in the killed runs.
CHECKPOINT_EVERY = 3


def install(mode: str, n: int) -> None:
    """Wrap the run's two writes in this process so that the ``n``-th one does what ``mode`` says,
    and checkpoint every :data:`CHECKPOINT_EVERY` frames (also before starting something else
    than the CLI, e.g. a Dask worker)."""
    if mode not in ("after-row", "mid-row", "after-state", "pause", "stop"):
        raise SystemExit(f"unknown mode {mode!r}")
    import mocap.run.journal as run
    from mocap.io.pose_table import PoseTable

    counts = {"row": 0, "state": 0}
    append_to, write_checkpoint = PoseTable.append_to, run.write_checkpoint

    def die() -> None:
        os.kill(os.getpid(), signal.SIGKILL)

    def append_and_maybe_die(self, path, *, sync: bool = True) -> None:
        counts["row"] += 1
        if mode == "mid-row" and counts["row"] == n:
            line = self.to_csv_text().split("\n")[1]
            with open(path, "a") as fh:
                fh.write(line[: len(line) // 2])
                fh.flush()
                os.fsync(fh.fileno())
            die()
        append_to(self, path, sync=sync)
        if mode == "after-row" and counts["row"] == n:
            die()

    def checkpoint_and_maybe_die(*args) -> None:
        write_checkpoint(*args)
        counts["state"] += 1
        if counts["state"] == n and mode == "after-state":
            die()
        if counts["state"] == n and mode == "stop":
            try:
                fd = os.open(os.environ["KILLPOINTS_PAUSED"], os.O_WRONLY | os.O_CREAT | os.O_EXCL)
            except FileExistsError:
                return
            os.write(fd, str(Path(args[0]).parent).encode())
            os.close(fd)
            os.kill(os.getpid(), signal.SIGSTOP)
        if counts["state"] == n and mode == "pause":
            flag = Path(os.environ["KILLPOINTS_PAUSED"])
            flag.touch()
            while flag.exists():
                time.sleep(0.05)

    PoseTable.append_to = append_and_maybe_die
    run.write_checkpoint = checkpoint_and_maybe_die
    run.CHECKPOINT_EVERY = CHECKPOINT_EVERY


def dask_setup(worker) -> None:
    """Dask preload hook (``dask worker --preload tests.killpoints``): :func:`install` with
    ``$KILLPOINTS_MODE`` and ``$KILLPOINTS_N`` in the worker's process."""
    install(os.environ["KILLPOINTS_MODE"], int(os.environ["KILLPOINTS_N"]))


def main(argv: list[str]) -> int:
    mode, n, sep, *cli_args = argv
    if sep != "--":
        raise SystemExit(f"usage: MODE N -- CLI ARGS (got {argv})")
    install(mode, int(n))
    from mocap.cli import main as cli_main
    return cli_main(cli_args)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
