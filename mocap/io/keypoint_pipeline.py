"""2D keypoints detected on a thread of their own, frames ahead of the one who asks for them.

A detector (MediaPipe Pose, :mod:`mocap.io.mediapipe_keypoints`) costs about as much per frame
as the tracker. :class:`KeypointPipeline` wraps any :class:`~mocap.io.keypoints.KeypointSource`:
frames are handed in as they are decoded (:meth:`KeypointPipeline.submit`) and detected on the
pipeline's thread in that order (MediaPipe's video mode needs the frames' order; MediaPipe's
graph releases the GIL while it works), while the caller prepares them; their keypoints are
taken in the same order (:meth:`KeypointPipeline.take`). The source's ``keypoints`` is called
with the same frames in the same order as a sequential run calls it, so the keypoints (and
everything after them) are the same, whenever the frames arrive.

At most ``depth`` frames are in the pipeline at once (submitted and not yet taken): a caller
that gets ahead waits, so the memory it holds is bounded. An error of the detector is raised by
:meth:`~KeypointPipeline.take` of its frame. A crash leaves nothing behind: the frames are in
memory only.
"""
from __future__ import annotations

import collections
import queue
import threading

import numpy as np

from mocap.io.keypoints import KeypointSource, Keypoints

__all__ = ["DETECT_AHEAD", "KeypointPipeline"]

#: Frames a run's detector may be ahead of the frames taken.
DETECT_AHEAD = 3
#: Seconds the detector thread waits for a frame between looks at whether it must stop.
_POLL_S = 0.1
_STOP = object()


class KeypointPipeline:
    """A :class:`~mocap.io.keypoints.KeypointSource` run on its own thread (see the module).

    Parameters
    ----------
    source : KeypointSource
        Called on the pipeline's thread only, until :meth:`close`.
    depth : int
        Frames submitted and not yet taken, at most (>= 1).

    Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, source: KeypointSource, depth: int = DETECT_AHEAD, *, name: str = "mocap-detector") -> None:
        if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
            raise ValueError(f"depth must be a positive integer, got {depth!r}")
        self.source, self.depth = source, depth
        self._slots = threading.Semaphore(depth)
        self._inbox: queue.Queue = queue.Queue()
        self._done: dict[int, tuple[bool, object]] = {}
        self._ready = threading.Condition()
        self._order: collections.deque[int] = collections.deque()     # submitted, not taken, oldest first
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._detect, name=name, daemon=True)
        self._thread.start()

    def _detect(self) -> None:
        while not self._stop.is_set():
            try:
                item = self._inbox.get(timeout=_POLL_S)
            except queue.Empty:
                continue
            if item is _STOP:
                return
            index, image = item
            try:
                result = (True, self.source.keypoints(index, image))
            except BaseException as exc:        # handed to the caller, raised by take()
                result = (False, exc)
            with self._ready:
                self._done[index] = result
                self._ready.notify_all()

    def submit(self, index: int, image: np.ndarray | None) -> None:
        """Hand frame ``index`` (input size, uint8 RGB) to the detector; waits while ``depth``
        frames are in the pipeline."""
        if self._stop.is_set():
            raise ValueError("the keypoint pipeline is closed")
        index = int(index)
        if index in self._order:
            raise ValueError(f"frame {index} is already in the keypoint pipeline")
        self._slots.acquire()
        self._order.append(index)
        self._inbox.put((index, image))

    @property
    def pending(self) -> int:
        """Frames submitted and not yet taken."""
        return len(self._order)

    def take(self, index: int) -> Keypoints:
        """The keypoints of frame ``index``, the oldest frame submitted and not taken (waiting for
        the detector); the detector's error on it is raised here."""
        index = int(index)
        if not self._order or self._order[0] != index:
            raise ValueError(f"frame {index} is not the next frame of the keypoint pipeline "
                             f"(next: {self._order[0] if self._order else None})")
        with self._ready:
            while index not in self._done:
                if not self._thread.is_alive():
                    raise RuntimeError("the keypoint detector's thread ended")
                self._ready.wait(timeout=_POLL_S)
            ok, result = self._done.pop(index)
        self._order.popleft()
        self._slots.release()
        if not ok:
            raise result
        return result

    def keypoints(self, frame_index: int, image: np.ndarray | None) -> Keypoints:
        """As a :class:`~mocap.io.keypoints.KeypointSource`: the frame's keypoints, submitted
        now unless it is the next one in the pipeline."""
        if not self._order or self._order[0] != int(frame_index):
            self.submit(frame_index, image)
        return self.take(frame_index)

    def close(self) -> None:
        """Stop the thread (frames not taken are dropped; safe to call twice)."""
        if self._stop.is_set():
            return
        self._inbox.put(_STOP)
        self._stop.set()
        self._thread.join(timeout=30.0)

    def __enter__(self) -> "KeypointPipeline":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
