"""``overlay.mp4``: the projected model drawn over the input's own frames (paper Fig. 1), at the
input's resolution up to :data:`OVERLAY_MAX_WIDTH` pixels wide (a wider input is reduced by the
integer factor that brings it under: :func:`overlay_factor`).

The overlay has one drawer, :class:`ModelDrawer`, whether it is written as frames come
(:class:`OverlayWriter`, a fresh run) or redrawn at the end from ``poses.csv``
(:func:`redraw_overlay`, a resumed run): both look the same.

What a crash leaves behind: a hidden ``.overlay.tmp.mp4`` at most; ``overlay.mp4`` is moved
into place when finished.
"""
from __future__ import annotations

import math
import os
import platform
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.imaging.resample import downscale
from mocap.imaging.visual import blend_into_box, blend_table, draw_model_box, label_palette
from mocap.io.pose_table import PoseTable
from mocap.render.camera import Camera
from mocap.run import files

__all__ = ["EDGE_COLOUR", "OVERLAY_MAX_WIDTH", "ModelDrawer", "OverlayGeometry", "OverlayWriter", "draw_model",
           "redraw_overlay"]

#: RGB colour of the model's occluding edges.
EDGE_COLOUR = np.array([255, 255, 0], np.uint8)
#: Widest overlay, pixels: a wider input is reduced by an integer factor.
OVERLAY_MAX_WIDTH = 1280
#: x264 preset of ``overlay.mp4``: half the encoding CPU of x264's default (``medium``) at the
#: same quality setting and about the same size (640x480, 2026-11-26: 11.5 against 24.3 ms a frame).
OVERLAY_PRESET = "veryfast"


def draw_model(frame: np.ndarray, labels: np.ndarray, edges: np.ndarray, n_classes: int = 2, *,
               alpha: float = 0.35, class_names: tuple[str, ...] | None = None) -> np.ndarray:
    """The frame with the model's coloured silhouette blended in and its occluding edges drawn
    (compiled, in the model's box: :func:`mocap.imaging.visual.blend_into_box`).

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3), uint8
    labels : ndarray, shape (H, W), uint8
        Rendered class labels (colours of :func:`mocap.imaging.visual.label_palette`).
    edges : ndarray, shape (H, W), bool
        Rendered occluding edges (yellow).
    n_classes : int
    alpha : float
        Opacity of the silhouette colours.
    class_names : tuple of str, optional
        The ``n_classes`` class names, for the colours of named classes (hair, lower body).

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
    """
    if frame.ndim != 3 or frame.shape[:2] != labels.shape or labels.shape != edges.shape:
        raise ValueError(f"frame {frame.shape}, labels {labels.shape} and edges {edges.shape} must match")
    out = np.array(frame, dtype=np.uint8, order="C")
    # only the model's box is looked at: at the input's resolution it is a small part of the frame
    rows = np.flatnonzero(labels.any(axis=1) | edges.any(axis=1))
    if rows.size == 0:
        return out
    cols = np.flatnonzero(labels[rows[0]:rows[-1] + 1].any(axis=0) | edges[rows[0]:rows[-1] + 1].any(axis=0))
    box = np.array([cols[0], rows[0], cols[-1], rows[-1]], np.int64)
    blend_into_box(out, out, np.ascontiguousarray(labels, np.uint8).ravel(), _IDENTITY,
                   np.ascontiguousarray(edges, np.bool_).ravel(), labels.shape[1], box,
                   label_palette(n_classes, class_names), blend_table(alpha), EDGE_COLOUR)
    return out


#: Label of each label value (:func:`draw_model` draws label images, not part ids).
_IDENTITY = np.arange(256, dtype=np.uint8)


class ModelDrawer:
    """The overlay's drawer for one body model and camera: the model in a pose rendered into
    buffers of its own (reused from frame to frame) and drawn into the frame in its box by the
    compiled :func:`mocap.imaging.visual.draw_model_box` — the picture of :func:`draw_model` on
    :func:`mocap.render.render`'s labels and edges, bit for bit.

    Parameters
    ----------
    model : BodyModel
    camera : Camera
        At the frames' size.
    alpha : float
        Opacity of the silhouette colours.
    """

    def __init__(self, model, camera: Camera, *, alpha: float = 0.35) -> None:
        from mocap.render.rasterize import Buffers, Scene

        self.model, self.camera = model, camera
        self.scene, self.buffers = Scene.of(model, camera), Buffers.of(model, camera)
        self.marks = np.zeros(camera.width * camera.height, np.bool_)
        self.lut = np.zeros(256, np.uint8)          # part id (part + 1) -> label; 0 background
        self.lut[1:len(model.part_label) + 1] = model.part_label
        self.palette = label_palette(model.n_classes, model.class_names)
        self.table = blend_table(alpha)

    def draw(self, frame: np.ndarray, pose: np.ndarray) -> np.ndarray:
        """``frame`` (uint8 RGB, shape (h, w, 3), the camera's size; not changed) with the model in
        ``pose`` (shape (23,), radians and metres) drawn: a new array."""
        from mocap.body.pose import check_pose
        from mocap.render.rasterize import EDGE_DEPTH_GAP_M

        if frame.shape != (self.camera.height, self.camera.width, 3) or frame.dtype != np.uint8:
            raise ValueError(f"the frame must be uint8 ({self.camera.height}, {self.camera.width}, 3), got "
                             f"{frame.dtype} {frame.shape}")
        out = np.array(frame, order="C")
        draw_model_box(out, check_pose(pose), self.scene, self.buffers, self.marks, self.lut, EDGE_DEPTH_GAP_M,
                       self.palette, self.table, EDGE_COLOUR)
        return out


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
    :meth:`close`), and shown in a window when asked and a display exists."""

    def __init__(self, out_dir: Path, fps: float, model, camera: Camera, *, show: bool = False,
                 write: bool = True) -> None:
        from mocap.io.video import VideoWriter

        self.model, self.camera = model, camera
        self.drawer: ModelDrawer | None = None
        self.path, self.tmp = Path(out_dir) / files.OVERLAY_MP4, Path(out_dir) / files.OVERLAY_TMP
        self.video = VideoWriter(self.tmp, fps, preset=OVERLAY_PRESET) if write else None
        self.figure = self.image = None
        if show and (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or platform.system() != "Linux"):
            import matplotlib.pyplot as plt
            plt.ion()
            self.figure, ax = plt.subplots(num="mocap track")
            ax.set_axis_off()
            self.plt = plt
        elif show:
            print("no display: the live view is not shown (overlay.mp4 is written)")

    def update(self, frame: np.ndarray, pose: np.ndarray | None, model=None) -> None:
        """Add a frame at the overlay's size (``camera``'s), with the model in ``pose`` drawn (the
        frame alone for None); ``model`` replaces the body model from now on (a new person's)."""
        if model is not None:
            self.model = model
        if pose is None:
            picture = frame
        else:
            if self.drawer is None or self.drawer.model is not self.model:
                self.drawer = ModelDrawer(self.model, self.camera)
            picture = self.drawer.draw(frame, pose)
        if self.video is not None:
            self.video.write(picture)
        if self.figure is not None:
            if self.image is None:
                self.image = self.figure.axes[0].imshow(picture)
            else:
                self.image.set_data(picture)
            self.plt.pause(0.001)

    def close(self) -> None:
        """Finish the video (moved into place when it has frames) and the window."""
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
