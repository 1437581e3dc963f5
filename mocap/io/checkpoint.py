"""A journal and the exact state that goes with it, for resuming after a crash bit for bit.

A run appends rows to a journal (``poses.csv``) and, after each step, saves a checkpoint: the
state its computation continues from (named arrays, saved generically with ``np.savez``), the
next input index, and the journal's length in bytes at that moment. The checkpoint is written
atomically after the rows are on disk, so whatever instant the process dies at, the saved
checkpoint describes a prefix of the journal: resuming truncates the journal to the recorded
length (dropping rows written after the checkpoint, and a partial last line) and continues from
the saved state. A step interrupted between its rows and its checkpoint is simply done again.
"""
from __future__ import annotations

import io
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.io.files import write_bytes_atomic

__all__ = ["Checkpoint", "cut_journal", "read_checkpoint", "synced_length", "truncate_journal", "write_checkpoint"]

#: Prefix of the bookkeeping arrays in the checkpoint file (the state's names must not use it).
_META = "checkpoint__"


@dataclass
class Checkpoint:
    """What a resumed run continues from.

    Attributes
    ----------
    state : dict of str to ndarray
        Exact state (e.g. :meth:`mocap.track.Tracker.state`).
    next_index : int
        First input (frame) not yet given to the computation.
    journal_bytes : int
        Length of the journal, in bytes, that goes with ``state``.
    """

    state: dict[str, np.ndarray]
    next_index: int
    journal_bytes: int


def write_checkpoint(path: str | Path, state: dict[str, np.ndarray], next_index: int, journal: str | Path) -> None:
    """Save ``state`` with the current length of ``journal`` (0 if it does not exist), atomically,
    after syncing the journal to disk (so the checkpoint never describes rows a power cut loses)."""
    size = synced_length(journal)
    if any(k.startswith(_META) for k in state):
        raise ValueError(f"state names must not start with {_META!r}")
    buf = io.BytesIO()
    np.savez(buf, **{f"{_META}next_index": np.int64(next_index), f"{_META}journal_bytes": np.int64(size)},
             **{k: np.asarray(v) for k, v in state.items()})
    write_bytes_atomic(path, buf.getvalue())


def synced_length(journal: str | Path) -> int:
    """The length in bytes of ``journal`` (0 if it does not exist) once it is on disk (synced):
    what a checkpoint records of a journal (:func:`write_checkpoint`; a second journal's length
    can go in its state, cut back with :func:`cut_journal`)."""
    import os

    journal = Path(journal)
    if not journal.exists():
        return 0
    with journal.open("rb") as fh:
        os.fsync(fh.fileno())
        return os.fstat(fh.fileno()).st_size


def read_checkpoint(path: str | Path) -> Checkpoint | None:
    """The checkpoint saved at ``path``, or None if there is none.

    Raises
    ------
    ValueError
        If the file is not a checkpoint (damaged or foreign).
    """
    path = Path(path)
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
        next_index = int(arrays.pop(f"{_META}next_index"))
        size = int(arrays.pop(f"{_META}journal_bytes"))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise ValueError(f"{path} is not a readable checkpoint ({type(exc).__name__}); start afresh "
                         "with --overwrite") from None
    return Checkpoint(arrays, next_index, size)


def truncate_journal(journal: str | Path, checkpoint: Checkpoint | None) -> None:
    """Cut ``journal`` back to the length ``checkpoint`` records (remove it when there is none).

    Raises
    ------
    ValueError
        If the journal is shorter than the checkpoint says (it was edited or replaced).
    """
    cut_journal(journal, 0 if checkpoint is None else checkpoint.journal_bytes)


def cut_journal(journal: str | Path, size: int) -> None:
    """Cut ``journal`` back to ``size`` bytes (remove it for 0): :func:`truncate_journal` for
    a length kept elsewhere (:func:`synced_length`).

    Raises
    ------
    ValueError
        If the journal is shorter than ``size`` (it was edited or replaced).
    """
    journal = Path(journal)
    actual = journal.stat().st_size if journal.exists() else 0
    if actual < size:
        raise ValueError(f"{journal} is shorter ({actual} bytes) than its saved state says ({size} bytes): "
                         "it was changed after the run; start afresh with --overwrite")
    if size == 0:
        journal.unlink(missing_ok=True)
    elif actual > size:
        with journal.open("r+b") as fh:
            fh.truncate(size)
