"""Work ahead on a thread, the one helper of the run's threads (:class:`Ahead`): the items of an
iterator made on a thread of their own while the caller works on the ones before. Two ways to
keep them:

* :func:`prefetch`: every item, in order, at most ``depth`` waiting (decoding and image
  processing ahead of the tracker; the keypoint pipeline's detector,
  :class:`mocap.io.keypoint_pipeline.KeypointPipeline`).
* :func:`newest`: the newest item only, for a live source whose delay must not grow.

The memory it holds is bounded (``depth`` items, or one). Nothing polls: the reader and the
caller wait on one condition, which every item, every take and the stop wake. An error in the
reader comes out of the caller's loop as it was raised, after the items made before it; when
the caller stops early (a ``break``, an error, Ctrl-C) the reader stops and closes its iterator
(ending an ffmpeg process). A crash leaves nothing behind: the items are in memory only.
"""
from __future__ import annotations

import collections
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import TypeVar

__all__ = ["Ahead", "Arrival", "newest", "prefetch"]

T = TypeVar("T")
#: Seconds the caller waits, once it stops, for the reader thread to end.
_JOIN_S = 5.0


@dataclass(frozen=True)
class Arrival:
    """An item of :class:`Ahead`: ``position`` counts every item the iterator gave (taken or
    dropped) from 0, ``time_s`` is when it came (``time.perf_counter``, seconds)."""

    position: int
    time_s: float
    item: object


class Ahead(Iterator[Arrival]):
    """The items of ``make()``, made on a thread of their own (started at once), as :class:`Arrival`.

    Parameters
    ----------
    make : callable
        Returns the iterable; called on the reader thread (a generator starts there).
    depth : int
        Items waiting at most (>= 1); with ``drop``, 1.
    drop : bool
        Keep only the newest item: the reader never waits, an item not taken yet is dropped when
        the next comes (the gaps in :attr:`Arrival.position`).
    name : str
        The thread's name.

    Iterating gives the arrivals in order (with ``drop``, the newest each time), waiting for one
    when none is new; :meth:`close` (or the end of the items, or an error) stops the reader.
    """

    def __init__(self, make: Callable[[], Iterable[T]], depth: int, *, drop: bool = False,
                 name: str = "reader") -> None:
        if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
            raise ValueError(f"depth must be a positive integer, got {depth!r}")
        self.make, self.depth, self.drop = make, 1 if drop else depth, drop
        self._waiting: collections.deque[Arrival] = collections.deque()
        self._changed = threading.Condition()
        self._done, self._error, self._stop = False, None, False
        self._thread = threading.Thread(target=self._read, name=name, daemon=True)
        self._thread.start()

    def _read(self) -> None:
        """The reader thread."""
        iterator, changed, waiting = None, self._changed, self._waiting
        try:
            iterator = iter(self.make())
            for position, item in enumerate(iterator):
                arrival = Arrival(position, time.perf_counter(), item)
                with changed:
                    while len(waiting) == self.depth and not self.drop and not self._stop:
                        changed.wait()
                    if self._stop:
                        break
                    if self.drop:
                        waiting.clear()             # an item not taken yet is dropped
                    waiting.append(arrival)
                    changed.notify_all()
        except BaseException as exc:        # handed to the caller, raised there
            self._error = exc
        finally:
            with changed:
                self._done = True
                changed.notify_all()
            close = getattr(iterator, "close", None)
            if close is not None:
                close()

    def __next__(self) -> Arrival:
        with self._changed:
            while not self._waiting and not self._done:
                self._changed.wait()
            if self._waiting:
                arrival = self._waiting.popleft()
                self._changed.notify_all()
                return arrival
            error, self._error = self._error, None
        self.close()
        if error is not None:
            raise error
        raise StopIteration

    def close(self) -> None:
        """Stop the reader (it closes its iterator) and wait for it (safe to call twice)."""
        with self._changed:
            self._stop = True
            self._changed.notify_all()
        if self._thread is not threading.current_thread():
            self._thread.join(timeout=_JOIN_S)

    def __del__(self) -> None:
        if getattr(self, "_thread", None) is not None and not self._stop:
            self.close()


def prefetch(make: Callable[[], Iterable[T]], depth: int = 4, *, name: str = "reader") -> Iterator[T]:
    """The items of ``make()``, in order, made on a thread of their own ``depth`` items ahead
    (:class:`Ahead`).

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
    arrivals = Ahead(make, depth, name=name)
    try:
        for arrival in arrivals:
            yield arrival.item
    finally:
        arrivals.close()



def newest(make: Callable[[], Iterable[T]], *, name: str = "grabber") -> Iterator[Arrival]:
    """The items of ``make()`` read on a thread of their own as fast as they come, of which the
    caller gets the newest each time it asks (waiting for one when none is new): the items it
    was too slow for are dropped, so what it gets is never more than one item old (a live
    camera's frames: the delay does not grow when the tracker is slower than the camera).

    Memory: one item waits at most. An error in the reader comes out of the caller's loop; when
    the caller stops, the reader stops and closes its iterator. Dropped items are the gaps in
    :attr:`Arrival.position` (:class:`Ahead` with ``drop``).
    """
    return Ahead(make, 1, drop=True, name=name)
