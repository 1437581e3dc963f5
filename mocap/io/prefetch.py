"""Work ahead on a thread: the items of an iterator made by a reader thread while the caller
works on the ones before (decoding and image processing ahead of the tracker); and
:func:`newest`, the newest item only, for a live source whose delay must not grow.

At most ``depth`` finished items wait in between, so the memory it holds is bounded. An error
in the reader comes out of the caller's loop as it was raised; when the caller stops early
(a ``break``, an error, Ctrl-C) the reader stops and closes its iterator (ending an ffmpeg
process). A crash leaves nothing behind: the items are in memory only.
"""
from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import TypeVar

__all__ = ["Arrival", "newest", "prefetch"]

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


@dataclass(frozen=True)
class Arrival:
    """An item of :func:`newest`: ``position`` counts every item the iterator gave (taken or
    dropped) from 0, ``time_s`` is when it came (``time.perf_counter``, seconds)."""

    position: int
    time_s: float
    item: object


def newest(make: Callable[[], Iterable[T]], *, name: str = "grabber") -> Iterator[Arrival]:
    """The items of ``make()`` read on a thread of their own as fast as they come, of which the
    caller gets the newest each time it asks (waiting for one when none is new): the items it
    was too slow for are dropped, so what it gets is never more than one item old (a live
    camera's frames: the delay does not grow when the tracker is slower than the camera).

    Memory: one item waits at most. An error in the reader comes out of the caller's loop; when
    the caller stops, the reader stops and closes its iterator. Dropped items are the gaps in
    :attr:`Arrival.position`.
    """
    slot: list[Arrival] = []
    state = {"done": False, "error": None}
    changed = threading.Condition()
    stop = threading.Event()

    def read() -> None:
        iterator = None
        try:
            iterator = iter(make())
            for position, item in enumerate(iterator):
                arrival = Arrival(position, time.perf_counter(), item)
                with changed:
                    slot[:] = [arrival]             # an item not taken yet is dropped
                    changed.notify_all()
                if stop.is_set():
                    break
        except BaseException as exc:        # handed to the caller, raised there
            state["error"] = exc
        finally:
            with changed:
                state["done"] = True
                changed.notify_all()
            close = getattr(iterator, "close", None)
            if close is not None:
                close()

    thread = threading.Thread(target=read, name=name, daemon=True)
    thread.start()
    try:
        while True:
            with changed:
                while not slot and not state["done"]:
                    changed.wait(timeout=_POLL_S)
                if slot:
                    arrival = slot.pop()
                elif state["error"] is not None:
                    raise state["error"]
                else:
                    return
            yield arrival
    finally:
        stop.set()
        thread.join(timeout=5.0)
