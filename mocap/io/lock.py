"""One writer per output folder: an OS file lock held for the whole run.

The lock is ``fcntl.flock`` on ``<folder>/.lock``: the kernel releases it when the holder's
file descriptor is closed, which also happens when the process dies (even by ``kill -9``), so
a lock left by a dead process is never in the way — the file stays, the lock does not. The file
records the holder's process id and host for the message a second writer gets.
"""
from __future__ import annotations

import fcntl
import functools
import inspect
import os
import socket
from pathlib import Path

__all__ = ["LOCK_FILE", "FolderInUseError", "FolderLock", "one_writer"]

#: Name of the lock file inside a locked folder.
LOCK_FILE = ".lock"


class FolderInUseError(OSError):
    """Another process holds the folder's lock."""


class FolderLock:
    """Exclusive lock on a folder (created if missing), as a context manager.

    Parameters
    ----------
    folder : str or Path

    Raises
    ------
    FolderInUseError
        On entering, if another process (or another lock in this one) holds the folder.
    """

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.path = self.folder / LOCK_FILE
        self._fd: int | None = None

    def acquire(self) -> FolderLock:
        """Take the lock at once or raise :class:`FolderInUseError` (never waits)."""
        self.folder.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 200, 0).decode("utf-8", "replace").strip() or "another process"
            os.close(fd)
            raise FolderInUseError(f"{self.folder} is in use by another run ({holder}); wait for it to "
                                   "finish or choose another output folder") from None
        except BaseException:
            os.close(fd)
            raise
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode(), 0)
        self._fd = fd
        return self

    def release(self) -> None:
        """Give the lock up (safe to call twice). The lock file stays: removing it would let a
        third process lock a new file while a second still waits on the old one."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(self, *exc_info: object) -> None:
        self.release()


def one_writer(argument: str):
    """Decorator: hold a :class:`FolderLock` on the folder passed as ``argument`` while the
    function runs (taken before anything else, released on any exit)."""
    def decorate(fn):
        signature = inspect.signature(fn)

        @functools.wraps(fn)
        def locked(*args, **kwargs):
            folder = signature.bind(*args, **kwargs).arguments[argument]
            with FolderLock(folder):
                return fn(*args, **kwargs)
        return locked
    return decorate
