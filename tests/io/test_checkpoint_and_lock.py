"""The checkpoint that pairs a journal with its exact state, and the output-folder lock."""
from __future__ import annotations

import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from mocap.io.checkpoint import read_checkpoint, truncate_journal, write_checkpoint
from mocap.io.lock import LOCK_FILE, FolderInUseError, FolderLock


def test_checkpoint_round_trip_is_exact(tmp_path):
    journal = tmp_path / "poses.csv"
    journal.write_text("header\nrow 0\nrow 1\n")
    rng = np.random.default_rng(0)
    state = {"history": rng.normal(size=(2, 23)), "last_good": rng.normal(size=23), "beam": np.arange(6).reshape(2, 3)}
    write_checkpoint(tmp_path / "state.npz", state, 7, journal)
    got = read_checkpoint(tmp_path / "state.npz")
    assert got.next_index == 7 and got.journal_bytes == len("header\nrow 0\nrow 1\n")
    assert set(got.state) == set(state)
    for name, value in state.items():
        assert got.state[name].dtype == value.dtype
        np.testing.assert_array_equal(got.state[name], value)
    assert read_checkpoint(tmp_path / "missing.npz") is None
    with pytest.raises(ValueError, match="must not start with"):
        write_checkpoint(tmp_path / "s.npz", {"checkpoint__next_index": np.zeros(1)}, 0, journal)


def test_journal_is_cut_back_to_its_checkpoint(tmp_path):
    journal = tmp_path / "poses.csv"
    journal.write_text("header\nrow 0\n")
    write_checkpoint(tmp_path / "state.npz", {}, 1, journal)
    with journal.open("a") as fh:
        fh.write("row 1\nrow 2 (half")                        # written after the checkpoint
    truncate_journal(journal, read_checkpoint(tmp_path / "state.npz"))
    assert journal.read_text() == "header\nrow 0\n"
    journal.write_text("head")                               # shorter than the checkpoint says
    with pytest.raises(ValueError, match="shorter .4 bytes. than its saved state says .13 bytes."):
        truncate_journal(journal, read_checkpoint(tmp_path / "state.npz"))
    truncate_journal(journal, None)                          # no checkpoint: nothing to keep
    assert not journal.exists()
    (tmp_path / "state.npz").write_bytes(b"PK\x03\x04 not a zip")
    with pytest.raises(ValueError, match="not a readable checkpoint"):
        read_checkpoint(tmp_path / "state.npz")


def test_lock_is_exclusive_and_a_dead_holder_does_not_keep_it(tmp_path):
    folder = tmp_path / "out"
    holder = subprocess.run(
        [sys.executable, "-c", "import os, signal, sys; from mocap.io.lock import FolderLock; "
         f"FolderLock({str(folder)!r}).acquire(); os.kill(os.getpid(), signal.SIGKILL)"],
        capture_output=True, text=True, timeout=60)
    assert holder.returncode == -signal.SIGKILL, holder.stderr
    assert (folder / LOCK_FILE).read_text().startswith("pid ")          # its lock file is still there
    with FolderLock(folder):                                            # but not its lock
        with pytest.raises(FolderInUseError, match=f"in use by another run .pid {os.getpid()} on "):
            FolderLock(folder).acquire()
        waiting = subprocess.run([sys.executable, "-c", f"from mocap.io.lock import FolderLock; "
                                  f"FolderLock({str(folder)!r}).acquire()"], capture_output=True, text=True,
                                 timeout=60)
        assert waiting.returncode != 0 and "FolderInUseError" in waiting.stderr
    FolderLock(folder).acquire().release()
