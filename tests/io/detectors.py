"""Stand-in detectors for a keypoint process (:mod:`mocap.io.keypoint_process`): module-level,
so that a child process unpickles them, and deterministic in the image alone (as MediaPipe's
image mode is)."""
from __future__ import annotations

import os
import signal
import time

import numpy as np

from mocap.io.keypoints import Keypoints


class BrightestPixel:
    """Joints spread about the image's brightest pixel, scaled by its mean brightness.

    ``fail_on``: ``detect`` calls (counted from 1) that raise; ``die_on``: the call on which the
    process kills itself (SIGKILL), as an out-of-memory kill would; ``stop_on``: the call on which
    it stops itself (SIGSTOP); ``hang_on``: the call that never returns (it sleeps); ``broken``:
    the constructor raises (as a missing MediaPipe does)."""

    def __init__(self, fail_on: tuple[int, ...] = (), die_on: int | None = None, broken: bool = False,
                 stop_on: int | None = None, hang_on: int | None = None) -> None:
        if broken:
            raise ValueError("the stand-in detector cannot open")
        self.fail_on, self.die_on, self.calls = fail_on, die_on, 0
        self.stop_on, self.hang_on = stop_on, hang_on

    def detect(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.calls += 1
        if self.calls == self.die_on:
            os.kill(os.getpid(), signal.SIGKILL)
        if self.calls == self.stop_on:
            os.kill(os.getpid(), signal.SIGSTOP)
        if self.calls == self.hang_on:
            time.sleep(3600)
        if self.calls in self.fail_on:
            raise RuntimeError(f"the detector failed on its call {self.calls}")
        h, w = image.shape[:2]
        grey = image.mean(axis=2)
        row, col = np.unravel_index(int(np.argmax(grey)), grey.shape)
        spread = np.linspace(-0.2, 0.2, 10)[:, None] * np.array([w, h]) * (0.5 + image.mean() / 510)
        uv = np.clip(np.array([col + 0.5, row + 0.5]) + spread, 0.5, [w - 0.5, h - 0.5])
        confidence = np.full(10, 0.9)
        confidence[1] = 0.0                              # the neck: absent, as MediaPipe gives it
        return uv, confidence


def to_keypoints(result, height: int, width: int) -> Keypoints:
    """``convert`` of a keypoint process running :class:`BrightestPixel`."""
    uv, confidence = result
    return Keypoints(uv, confidence)


class InProcess:
    """:class:`BrightestPixel` as a keypoint source in this process (the reference)."""

    def __init__(self) -> None:
        self.detector = BrightestPixel()

    def keypoints(self, frame_index, image) -> Keypoints:
        return to_keypoints(self.detector.detect(image), *image.shape[:2])
