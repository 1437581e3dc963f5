"""2D keypoints detected beside the caller, frames ahead of the one who asks for them.

A detector (MediaPipe Pose, :mod:`mocap.io.mediapipe_keypoints`) costs about as much per frame
as the tracker. :class:`KeypointPipeline` wraps any :class:`~mocap.io.keypoints.KeypointSource`:
frames are handed in as they are decoded (:meth:`KeypointPipeline.submit`) and detected in that
order while the caller prepares them; their keypoints are taken in the same order
(:meth:`KeypointPipeline.take`). Where the detector works:

* a source that works ahead itself (``submit``/``take``/``pending``/``depth``: a detector in a
  process of its own, :class:`~mocap.io.keypoint_process.KeypointProcess`) is handed the frames
  directly, no thread of this process between;
* any other source is called on a thread of its own (:class:`mocap.io.prefetch.Ahead`, the
  one thread helper), with the same frames in the same order as a sequential run calls it.

Either way the keypoints (and everything after them) are those of a sequential run, whenever
the frames arrive.

At most ``depth`` frames are in the pipeline at once (submitted and not yet taken): the memory it
holds is bounded; submitting one more is an error (take first). An error of the detector is
raised by :meth:`~KeypointPipeline.take` of its frame. A crash leaves nothing behind: the frames
are in memory only.
"""
from __future__ import annotations

import collections
import queue

import numpy as np

from mocap.io.keypoints import KeypointSource, Keypoints
from mocap.io.prefetch import Ahead

__all__ = ["DETECT_AHEAD", "KeypointPipeline"]

#: Frames a run's detector may be ahead of the frames taken.
DETECT_AHEAD = 3
_STOP = object()


def works_ahead(source) -> bool:
    """Whether ``source`` takes frames ahead itself (``submit``, ``take``, ``pending``, ``depth``)."""
    return all(hasattr(source, name) for name in ("submit", "take", "pending", "depth"))


class KeypointPipeline:
    """A :class:`~mocap.io.keypoints.KeypointSource` working ahead of its caller (see the module).

    Parameters
    ----------
    source : KeypointSource
        Called on the pipeline's thread only, until :meth:`close` (a source that works ahead
        itself is handed the frames instead, and not closed here).
    depth : int
        Frames submitted and not yet taken, at most (>= 1; at most the source's own ``depth``).

    Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, source: KeypointSource, depth: int = DETECT_AHEAD, *, name: str = "mocap-detector") -> None:
        if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
            raise ValueError(f"depth must be a positive integer, got {depth!r}")
        self.source, self.depth = source, depth
        self._order: collections.deque[int] = collections.deque()     # submitted, not taken, oldest first
        self._closed = False
        if works_ahead(source):
            if depth > source.depth:
                raise ValueError(f"depth {depth} is more than the source's own ({source.depth})")
            self._inbox = self._results = None
            return
        self._inbox: queue.SimpleQueue = queue.SimpleQueue()
        self._results = Ahead(self._detections, depth, name=name)

    def _detections(self):
        """On the pipeline's thread: each submitted frame's ``(index, ok, keypoints or error)``."""
        while (item := self._inbox.get()) is not _STOP:
            index, image = item
            try:
                yield index, True, self.source.keypoints(index, image)
            except Exception as exc:        # handed to the caller, raised by take()
                yield index, False, exc

    def submit(self, index: int, image: np.ndarray | None) -> None:
        """Hand frame ``index`` (input size, uint8 RGB) to the detector (ValueError when
        ``depth`` frames are in the pipeline: take one first)."""
        if self._closed:
            raise ValueError("the keypoint pipeline is closed")
        index = int(index)
        if index in self._order:
            raise ValueError(f"frame {index} is already in the keypoint pipeline")
        if len(self._order) == self.depth:
            raise ValueError(f"{self.depth} frames are in the keypoint pipeline already: take one first")
        if self._inbox is None:
            self.source.submit(index, image)
        else:
            self._inbox.put((index, image))
        self._order.append(index)

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
        self._order.popleft()
        if self._results is None:
            return self.source.take(index)
        try:
            done, ok, result = next(self._results).item
        except StopIteration:
            raise RuntimeError("the keypoint detector's thread ended") from None
        if done != index:
            raise RuntimeError(f"the keypoint detector answered frame {done} for frame {index}")
        if not ok:
            raise result
        return result

    def close(self) -> None:
        """Stop the thread (frames not taken are dropped; safe to call twice). A source that
        works ahead itself keeps its frames in flight: its owner closes it."""
        if self._closed:
            return
        self._closed = True
        if self._results is not None:
            self._inbox.put(_STOP)
            self._results.close()
        elif self._order:       # frames in flight: taken and dropped, so the source can be asked again
            for index in list(self._order):
                try:
                    self.source.take(index)
                except Exception:       # (the run stops on its own error; this frame's is not the news)
                    pass
        self._order.clear()

    def __enter__(self) -> "KeypointPipeline":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
