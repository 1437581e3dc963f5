"""Work ahead on a thread: the items of an iterator made by a reader thread while the caller
works on the ones before (decoding and image processing ahead of the tracker).

At most ``depth`` finished items wait in between, so the memory it holds is bounded. An error
in the reader comes out of the caller's loop as it was raised; when the caller stops early
(a ``break``, an error, Ctrl-C) the reader stops and closes its iterator (ending an ffmpeg
process). A crash leaves nothing behind: the items are in memory only.
"""
from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Iterable, Iterator
from typing import TypeVar

__all__ = ["prefetch"]

T = TypeVar("T")
_DONE = object()
#: Seconds a waiting reader sleeps between looks at whether the caller has stopped.
_POLL_S = 0.1


def prefetch(make: Callable[[], Iterable[T]], depth: int = 4, *, name: str = "reader") -> Iterator[T]:
    """The items of ``make()``, produced on a thread of their own ``depth`` items ahead.

    Parameters
    ----------
    make : callable
        Returns the iterable; called on the reader thread (a generator starts there).
    depth : int
        Items made ahead at most (>= 1).
    name : str
        The thread's name.

    Yields
    ------
    The items of ``make()``, in order.
    """
    if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        raise ValueError(f"depth must be a positive integer, got {depth!r}")
    items: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def put(item) -> bool:
        while not stop.is_set():
            try:
                items.put(item, timeout=_POLL_S)
                return True
            except queue.Full:
                continue
        return False

    def read() -> None:
        iterator = None
        try:
            iterator = iter(make())
            for item in iterator:
                if not put((True, item)):
                    break
            put((True, _DONE))
        except BaseException as exc:        # handed to the caller, raised there
            put((False, exc))
        finally:
            close = getattr(iterator, "close", None)
            if close is not None:
                close()

    thread = threading.Thread(target=read, name=name, daemon=True)
    thread.start()
    try:
        while True:
            ok, item = items.get()
            if not ok:
                raise item
            if item is _DONE:
                return
            yield item
    finally:
        stop.set()
        thread.join(timeout=5.0)
