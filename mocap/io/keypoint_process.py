"""A keypoint detector in a child process of its own (MediaPipe Pose: :mod:`mocap.io.mediapipe_keypoints`).

A detector such as MediaPipe holds Python's interpreter lock for much of its work (its import,
its graph, its result's conversion), so on a thread it slows the tracker beside it. In a process
of its own it takes a core of its own: :class:`KeypointProcess` starts the child at once (its
import overlaps whatever the caller does next), hands it frames through shared memory
(:mod:`multiprocessing.shared_memory`: one slot per frame in flight, the frame copied in once)
and a socket pair that carries only small messages (``(index, slot, shape)`` out; the
detector's small result and its milliseconds back), and takes the results in the order the
frames went (:meth:`KeypointProcess.submit`, :meth:`KeypointProcess.take`; or
:meth:`KeypointProcess.keypoints`, one frame there and back). The child builds its detector with
``make()`` (pickled: a class or a module-level function) and calls its ``detect(image)`` on each
frame; the parent turns what comes back into :class:`~mocap.io.keypoints.Keypoints` with
``convert``. The child imports only this module, NumPy and what ``make`` needs.

What can go wrong, and what it leaves behind:

* The detector raises on a frame: :meth:`~KeypointProcess.take` of that frame raises the same
  error; the child goes on.
* ``make()`` raises (MediaPipe not installed): the first :meth:`~KeypointProcess.take` raises it.
* The child dies (killed, out of memory): :meth:`~KeypointProcess.take` (or
  :meth:`~KeypointProcess.submit`) raises :class:`DetectorEnded`, one line saying so, and the
  run stops there (its journal and checkpoint are kept: the same command resumes it, exactly).
* The child hangs: stopped (SIGSTOP, or a debugger's), or silent for ``hung_after_s`` seconds
  while a frame waits (a deadlock, a detector that never returns): :meth:`~KeypointProcess.take`
  kills it and raises :class:`DetectorHung` (a :class:`DetectorEnded`), one line saying which,
  and the run stops there as above; the same command resumes it exactly. A stopped child is
  seen by its state (Linux's ``/proc``), at once, whatever the machine's speed; the time-out is
  the fallback for a child that runs but never answers.
* The parent dies, even by SIGKILL: the child's socket closes, its next read ends, and it exits
  (no orphan); the shared memory is unlinked by the parent's resource tracker, which ends too.
* Ctrl-C: the child ignores SIGINT (the terminal sends it to both), the parent decides.

The child is a plain subprocess, not a :mod:`multiprocessing` one: a Dask nanny's worker
(``track-many``) is a daemonic process, which may not have multiprocessing children. POSIX only
(the socket is passed by its file descriptor).
"""
from __future__ import annotations

import collections
import pickle
import signal
import socket
import subprocess
import sys
import time
import weakref
from collections.abc import Callable
from multiprocessing.connection import Connection
from multiprocessing import shared_memory
from pathlib import Path

import numpy as np

__all__ = ["DetectorEnded", "DetectorHung", "KeypointProcess", "HUNG_AFTER_S"]

#: Seconds :meth:`KeypointProcess.close` waits for the child to end before killing it.
_CLOSE_WAIT_S = 10.0
#: Default seconds a frame (or the detector's start) may wait for the child's answer before it
#: counts as hung: MediaPipe's start (its import and graph) takes 2-4 s on an idle core, a frame
#: 20-40 ms; this leaves room for a machine loaded many times over.
HUNG_AFTER_S = 120.0
#: Seconds between two looks at the child's state while :meth:`KeypointProcess.take` waits.
_LOOK_EVERY_S = 0.25


class DetectorEnded(ValueError):
    """The detector's process ended while the run needed it (one line: which frame, how)."""


class DetectorHung(DetectorEnded):
    """The detector's process was stopped, or answered nothing for too long: it was killed (one
    line: which frame, how)."""


class KeypointProcess:
    """A keypoint source whose detector runs in a child process (see the module).

    Parameters
    ----------
    make : callable
        Picklable (a class or module-level function); called in the child, returns the detector:
        an object with ``detect(image)`` (image: (H, W, 3) uint8) returning something picklable
        and, optionally, ``close()``.
    convert : callable
        ``convert(result, height, width)``: a :class:`~mocap.io.keypoints.Keypoints` of what
        ``detect`` returned on a frame of that size (called in the parent).
    depth : int
        Frames in flight at most (submitted, not yet taken; >= 1): the shared memory slots.
    description : str
        What ``run.json`` ``settings.keypoints`` says of the source.
    hung_after_s : float, seconds
        How long :meth:`take` waits for one answer of a running child before it counts as hung
        (:data:`HUNG_AFTER_S`); a stopped child counts at once.

    Attributes
    ----------
    milliseconds : list of float
        The child's wall-clock time of each frame's ``detect``.
    pid : int
        The child's process id.
    """

    def __init__(self, make: Callable[[], object], convert: Callable, *, depth: int = 3,
                 description: str = "a keypoint detector in its own process",
                 hung_after_s: float = HUNG_AFTER_S) -> None:
        if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
            raise ValueError(f"depth must be a positive integer, got {depth!r}")
        if isinstance(hung_after_s, bool) or not isinstance(hung_after_s, (int, float)) or not hung_after_s > 0:
            raise ValueError(f"hung_after_s must be a positive number of seconds, got {hung_after_s!r}")
        self.convert, self.depth, self.description = convert, depth, description
        self.hung_after_s = float(hung_after_s)
        self.milliseconds: list[float] = []
        self._order: collections.deque[tuple[int, int, int]] = collections.deque()   # (index, height, width)
        self._slots: list[shared_memory.SharedMemory | None] = [None] * depth
        self._sent = 0                      # frames sent so far: frame s goes to slot s % depth
        self._ready = False
        self._closed = False
        ours, theirs = socket.socketpair()
        root = str(Path(__file__).resolve().parents[2])       # where this mocap is imported from
        code = (f"import sys; sys.path.insert(0, {root!r}); "
                f"from mocap.io.keypoint_process import serve; serve({theirs.fileno()})")
        with theirs:
            self._process = subprocess.Popen([sys.executable, "-c", code], pass_fds=(theirs.fileno(),),
                                             stdin=subprocess.DEVNULL)
        self.pid = self._process.pid
        self._conn = Connection(ours.detach())
        self._finalizer = weakref.finalize(self, _end, self._process, self._conn, self._slots)
        try:
            self._conn.send(list(sys.path))
            self._conn.send(make)
        except OSError:
            pass                # it ended already: said by the first take()

    @property
    def pending(self) -> int:
        """Frames submitted and not yet taken."""
        return len(self._order)

    def submit(self, index: int, image: np.ndarray) -> None:
        """Hand frame ``index`` (RGB uint8, (H, W, 3)) to the child; ValueError when ``depth``
        frames are in flight or the source is closed."""
        if self._closed:
            raise ValueError("the keypoint process is closed")
        if len(self._order) == self.depth:
            raise ValueError(f"{self.depth} frames are in the keypoint process already: take one first")
        image = np.ascontiguousarray(image)
        if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise ValueError(f"the keypoint process needs an RGB uint8 frame (H, W, 3), got {image.shape} "
                             f"{image.dtype}")
        slot = self._sent % self.depth
        memory = self._slots[slot]
        if memory is None or memory.size < image.nbytes:
            if memory is not None:
                memory.close()
                memory.unlink()
            memory = self._slots[slot] = shared_memory.SharedMemory(create=True, size=image.nbytes)
        np.ndarray(image.shape, np.uint8, buffer=memory.buf)[...] = image
        try:
            self._conn.send((int(index), slot, memory.name, image.shape))
        except OSError:
            raise self._ended(int(index)) from None
        self._sent += 1
        self._order.append((int(index), image.shape[0], image.shape[1]))

    def take(self, index: int):
        """The keypoints of frame ``index``, the oldest submitted and not taken (waiting for
        the child); the detector's error on it is raised here, :class:`DetectorEnded` if the
        child has ended."""
        index = int(index)
        if not self._order or self._order[0][0] != index:
            raise ValueError(f"frame {index} is not the next frame of the keypoint process "
                             f"(next: {self._order[0][0] if self._order else None})")
        self._wait_ready(index)
        done, ok, result, milliseconds = self._receive(index)
        _, height, width = self._order.popleft()
        if done != index:
            raise RuntimeError(f"the keypoint process answered frame {done} for frame {index}")
        if not ok:
            raise result
        self.milliseconds.append(milliseconds)
        return self.convert(result, height, width)

    def keypoints(self, frame_index: int, image: np.ndarray):
        """As a :class:`~mocap.io.keypoints.KeypointSource`: one frame there and back (none may
        be in flight)."""
        if self._order:
            raise ValueError(f"{len(self._order)} frames are in the keypoint process: take them first")
        self.submit(frame_index, image)
        return self.take(frame_index)

    def _wait_ready(self, index: int) -> None:
        """The child's first word: its detector made, or why not (raised)."""
        if self._ready:
            return
        ok, error = self._receive(index)
        if not ok:
            self.close()
            raise error
        self._ready = True

    def _receive(self, index: int):
        """The child's next message, waited for while it runs: :class:`DetectorEnded` if it
        ends, :class:`DetectorHung` (the child killed) if it is stopped or silent for
        :attr:`hung_after_s`."""
        waited_since = time.monotonic()
        while True:
            try:
                if self._conn.poll(_LOOK_EVERY_S):
                    return self._conn.recv()
            except (EOFError, OSError):
                raise self._ended(index) from None
            if self._process.poll() is not None:
                raise self._ended(index)
            if _stopped(self._process.pid):
                raise self._hung(index, "was stopped (SIGSTOP)")
            if time.monotonic() - waited_since > self.hung_after_s:
                raise self._hung(index, f"answered nothing for {self.hung_after_s:g} s")

    def _hung(self, index: int, how: str) -> DetectorHung:
        self._process.kill()              # a stopped process dies of SIGKILL too
        self._process.wait()
        self.close()
        return DetectorHung(f"the keypoint detector's process {how} before frame {index}'s keypoints and was "
                            "killed: the run stops here (its frames so far are kept; the same command resumes it)")

    def _ended(self, index: int) -> DetectorEnded:
        try:
            code = self._process.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            code = None
        if code is not None and code < 0:
            how = f"was killed by signal {-code} ({signal.Signals(-code).name})"
        else:
            how = f"exited with code {code}" if code is not None else "closed its pipe"
        self.close()
        return DetectorEnded(f"the keypoint detector's process {how} before frame {index}'s keypoints: the run "
                             "stops here (its frames so far are kept; the same command resumes it)")

    def close(self) -> None:
        """End the child (it finishes the frame it is on) and free the shared memory; safe to
        call twice (and done at the interpreter's exit for a source never closed)."""
        self._closed = True
        self._order.clear()
        self._finalizer()

    def __enter__(self) -> "KeypointProcess":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _end(process: subprocess.Popen, conn: Connection, slots: list) -> None:
    """Tell the child to stop, wait for it (kill it after :data:`_CLOSE_WAIT_S`), free the memory."""
    try:
        conn.send(None)
    except OSError:
        pass
    conn.close()
    try:
        process.wait(timeout=_CLOSE_WAIT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
    for k, memory in enumerate(slots):
        if memory is not None:
            memory.close()
            memory.unlink()
            slots[k] = None


def _stopped(pid: int) -> bool:
    """Process ``pid`` is stopped by a signal or a tracer (its ``/proc`` state ``T`` or ``t``;
    False where there is no ``/proc``: the time-out alone then tells a hang)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state in ("T", "t")


def _attach(name: str) -> shared_memory.SharedMemory:
    """The parent's shared memory ``name``, attached without registering it with a resource
    tracker of the child's own (Python < 3.13 registers every attachment, and the child's
    tracker would unlink the parent's memory when the child ends: bpo-39959)."""
    if sys.version_info >= (3, 13):
        return shared_memory.SharedMemory(name=name, track=False)
    from multiprocessing import resource_tracker

    register = resource_tracker.register
    resource_tracker.register = lambda *args: None
    try:
        return shared_memory.SharedMemory(name=name)
    finally:
        resource_tracker.register = register


def serve(fd: int) -> None:
    """The child's life: build the detector, then detect each frame the socket ``fd`` names
    until told to stop (None) or the socket closes (the parent is gone)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    conn = Connection(fd)
    try:
        sys.path[:] = conn.recv()
        make = conn.recv()
    except (EOFError, OSError):
        return
    try:
        detector = make()
    except Exception as exc:        # handed to the parent, raised by its first take()
        _send(conn, (False, exc))
        return
    if not _send(conn, (True, None)):
        return
    import os
    os.nice(int(os.environ.get("MOCAP_DETECTOR_NICE", "0")))
    attached: dict[int, shared_memory.SharedMemory] = {}
    try:
        while True:
            try:
                message = conn.recv()
            except (EOFError, OSError):
                return
            if message is None:
                return
            index, slot, name, shape = message
            if slot not in attached or attached[slot].name != name:
                if slot in attached:
                    attached[slot].close()
                attached[slot] = _attach(name)
            image = np.ndarray(shape, np.uint8, buffer=attached[slot].buf)
            started = time.perf_counter()
            try:
                answer = (index, True, detector.detect(image), 1e3 * (time.perf_counter() - started))
            except Exception as exc:        # handed to the parent, raised by take() of this frame
                answer = (index, False, exc, 1e3 * (time.perf_counter() - started))
            del image
            if not _send(conn, answer):
                return
    finally:
        for memory in attached.values():
            memory.close()
        close = getattr(detector, "close", None)
        if close is not None:
            close()


def _send(conn: Connection, message: tuple) -> bool:
    """Send ``message`` (an error in it that does not pickle goes as a RuntimeError of its
    text); False when the parent is gone."""
    try:
        data = pickle.dumps(message)
    except Exception:       # an unpicklable error: its text
        data = pickle.dumps(tuple(RuntimeError(str(part)) if isinstance(part, BaseException) else part
                                  for part in message))
    try:
        conn.send_bytes(data)
    except OSError:
        return False
    return True
