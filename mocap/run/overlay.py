"""``overlay.mp4``: the projected model drawn over the input's own frames (paper Fig. 1), with
the fitted skeleton seen from the side and from above in two insets, at the input's resolution
up to :data:`OVERLAY_MAX_WIDTH` pixels wide (a wider input is reduced by the integer factor
that brings it under: :func:`overlay_factor`).

The overlay has one drawer, :class:`mocap.imaging.visual.ModelDrawer` (its compiled kernel and
its argument checks sit there), whether it is written as frames come (:class:`OverlayWriter`, a
fresh run) or redrawn at the end from ``poses.csv`` (:func:`redraw_overlay`, a resumed run):
both look the same.

What a crash leaves behind: a hidden ``.overlay.tmp.mp4`` at most; ``overlay.mp4`` is moved
into place when finished.
"""
from __future__ import annotations

import math
import os
import platform
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.imaging.resample import downscale
from mocap.imaging.visual import ModelDrawer
from mocap.io.pose_table import PoseTable
from mocap.render.camera import Camera
from mocap.run import files

__all__ = ["OVERLAY_MAX_WIDTH", "OVERLAY_PRESET", "OverlayGeometry", "OverlayWriter", "overlay_factor",
           "redraw_overlay"]

#: Widest overlay, pixels: a wider input is reduced by an integer factor.
OVERLAY_MAX_WIDTH = 1280
#: x264 preset of ``overlay.mp4``: half the encoding CPU of x264's default (``medium``) at the
#: same quality setting and about the same size (640x480, 2026-11-26: 11.5 against 24.3 ms a frame).
OVERLAY_PRESET = "veryfast"


def overlay_factor(width: int) -> int:
    """Integer reduction of an input ``width`` (pixels) to at most :data:`OVERLAY_MAX_WIDTH`."""
    return max(1, math.ceil(width / OVERLAY_MAX_WIDTH))


@dataclass(frozen=True)
class OverlayGeometry:
    """Where the overlay is drawn: the input frames reduced by ``factor``, seen by ``camera``.

    Attributes
    ----------
    factor : int
        Input pixels per overlay pixel (:func:`overlay_factor`).
    camera : Camera
        The camera at the overlay's size.
    """

    factor: int
    camera: Camera

    @classmethod
    def of(cls, working: Camera, work_factor: int, width: int, height: int) -> "OverlayGeometry":
        """The overlay of ``width`` x ``height`` input frames tracked with the ``working`` camera
        (the input reduced ``work_factor`` times)."""
        factor = overlay_factor(width)
        if factor == work_factor:
            return cls(factor, working)
        return cls(factor, working.enlarged(work_factor, width, height).working(width, height, factor))

    def frame(self, frame: np.ndarray) -> np.ndarray:
        """An input frame at the overlay's size."""
        return downscale(frame, self.factor)


class OverlayWriter:
    """The overlay as frames come: written to ``overlay.mp4`` (``write``; moved into place by
    :meth:`close`), and shown in a window when asked and a display exists.

    Written without a window, each picture is drawn on a thread of its own (the compiled drawer
    lets go of the interpreter lock), at most :data:`DRAWS_AHEAD` pictures behind the caller,
    and the pictures go to the video in order: the tracker's thread does not wait for the
    drawing. With a window, a picture is drawn and shown at once."""

    #: Pictures that may wait for the drawing thread before :meth:`update` waits.
    DRAWS_AHEAD = 2

    def __init__(self, out_dir: Path, fps: float, model, camera: Camera, *, show: bool = False,
                 write: bool = True) -> None:
        from mocap.io.video import VideoWriter

        self.model, self.camera = model, camera
        self.drawer: ModelDrawer | None = None
        self.path, self.tmp = Path(out_dir) / files.OVERLAY_MP4, Path(out_dir) / files.OVERLAY_TMP
        self.video = VideoWriter(self.tmp, fps, preset=OVERLAY_PRESET) if write else None
        self.figure = self.image = None
        self.pending: deque[Future | np.ndarray] = deque()      # pictures (or their drawing) in frame order
        self.drawing: ThreadPoolExecutor | None = None
        if show and (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or platform.system() != "Linux"):
            import matplotlib.pyplot as plt
            plt.ion()
            self.figure, ax = plt.subplots(num="mocap track")
            ax.set_axis_off()
            self.plt = plt
        elif show:
            print("no display: the live view is not shown (overlay.mp4 is written)")
        if self.video is not None and self.figure is None:
            self.drawing = ThreadPoolExecutor(max_workers=1, thread_name_prefix="overlay-draw")

    def update(self, frame: np.ndarray, pose: np.ndarray | None, model=None) -> None:
        """Add a frame at the overlay's size (``camera``'s; not changed, and not to be changed
        by the caller after), with the model in ``pose`` drawn (the frame alone for None);
        ``model`` replaces the body model from now on (a new person's)."""
        if model is not None:
            self.model = model
        if pose is not None and (self.drawer is None or self.drawer.model is not self.model):
            self.drawer = ModelDrawer(self.model, self.camera)
        if self.drawing is not None:
            self.pending.append(frame if pose is None else self.drawing.submit(self.drawer.draw, frame, pose))
            self._write_drawn(self.DRAWS_AHEAD)
            return
        if self.video is None and self.figure is None:
            return
        picture = frame if pose is None else self.drawer.draw(frame, pose)
        if self.video is not None:
            self.video.write(picture)
        if self.figure is not None:
            if self.image is None:
                self.image = self.figure.axes[0].imshow(picture)
            else:
                self.image.set_data(picture)
            self.plt.pause(0.001)

    def _write_drawn(self, ahead: int) -> None:
        """Pictures to the video in order: those drawn, and the oldest until at most ``ahead``
        wait (a drawing's error is raised here)."""
        while self.pending and (len(self.pending) > ahead or not isinstance(self.pending[0], Future)
                                or self.pending[0].done()):
            item = self.pending.popleft()
            self.video.write(item.result() if isinstance(item, Future) else item)

    def close(self) -> None:
        """Finish the video (the pictures still drawn first; moved into place when it has
        frames) and the window."""
        try:
            if self.drawing is not None and self.video is not None:
                self._write_drawn(0)
        finally:
            if self.drawing is not None:
                self.drawing.shutdown(wait=True, cancel_futures=True)
                self.drawing = None
            self.pending.clear()
            if self.video is not None:
                self.video.close()
                if self.video.frames:
                    os.replace(self.tmp, self.path)
                self.video = None
            if self.figure is not None:
                self.plt.close(self.figure)


def redraw_overlay(out_dir: Path, frames, table: PoseTable, models: list, geometry: OverlayGeometry,
                   fps: float) -> None:
    """``overlay.mp4`` drawn afresh from ``poses.csv``: ``frames`` are ``(index, input-size
    frame)`` pairs from frame 0 (frames without a row are shown as they are); ``models`` are
    the body models of the segments (column ``segment``, 0 without it)."""
    segment = table.extra.get("segment", np.zeros(len(table)))
    rows = {int(f): (p, int(s)) for f, p, s in zip(table.frames, table.poses, segment)}
    writer = OverlayWriter(out_dir, fps, models[0], geometry.camera)
    try:
        for index, frame in frames:
            pose, person = rows.get(index, (None, 0))
            writer.update(geometry.frame(frame), pose, models[person])
    finally:
        writer.close()
