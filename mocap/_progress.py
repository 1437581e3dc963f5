"""Progress that says when Numba compiles.

The first run of a fresh checkout (or the first after an edit of a compiled source,
:mod:`mocap._numba`) compiles the kernels it calls: tens of seconds in which a bar would show
one very slow step and nothing else. Numba fires a ``numba:compile`` event around every real
compilation, never when a kernel is loaded from the on-disk cache; the bar and the notice here
listen to it, so they say "compiling" exactly while it happens, on whichever thread.
"""
from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from numba.core import event
from tqdm import tqdm

__all__ = ["COMPILING_NOTE", "ProgressBar", "compiling_announced"]

#: What a progress bar's label says while Numba compiles.
COMPILING_NOTE = "compiling, first run only"
_COMPILE_EVENT = "numba:compile"


class _CompileListener(event.Listener):
    """Calls ``started`` when the outermost compilation starts and ``ended`` when it ends
    (a kernel compiles the kernels it calls inside its own event)."""

    def __init__(self, started: Callable[[], None], ended: Callable[[], None]) -> None:
        self._started, self._ended = started, ended
        self._depth = 0
        self._lock = threading.Lock()

    def on_start(self, ev) -> None:
        with self._lock:
            self._depth += 1
            first = self._depth == 1
        if first:
            self._started()

    def on_end(self, ev) -> None:
        with self._lock:
            self._depth -= 1
            last = self._depth == 0
        if last:
            self._ended()


class ProgressBar(tqdm):
    """A tqdm bar whose label reads ``"<desc> (compiling, first run only)"`` while Numba compiles
    (and ``desc`` again after). Takes tqdm's arguments; ``desc`` is required."""

    def __init__(self, *args, desc: str, **tqdm_arguments) -> None:
        super().__init__(*args, desc=desc, **tqdm_arguments)
        self._label = desc
        self._listener = _CompileListener(lambda: self.set_description(f"{desc} ({COMPILING_NOTE})"),
                                          lambda: self.set_description(desc))
        event.register(_COMPILE_EVENT, self._listener)

    def close(self) -> None:
        """Close the bar and stop listening (safe to call twice)."""
        listener = self.__dict__.pop("_listener", None)
        if listener is not None:
            event.unregister(_COMPILE_EVENT, listener)
        super().close()


@contextmanager
def compiling_announced(show: bool = True, what: str = "the kernels") -> Iterator[None]:
    """Within the block, the first compilation prints one line to stderr (through
    ``tqdm.write``, so that bars stay whole): ``compiling <what> (first run only: later runs
    load them from the cache)``. Nothing when ``show`` is false or nothing compiles."""
    if not show:
        yield
        return
    said = []

    def started() -> None:
        if not said:
            said.append(True)
            tqdm.write(f"compiling {what} (first run only: later runs load them from the cache)", file=sys.stderr)

    listener = _CompileListener(started, lambda: None)
    event.register(_COMPILE_EVENT, listener)
    try:
        yield
    finally:
        event.unregister(_COMPILE_EVENT, listener)
