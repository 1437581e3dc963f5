"""The outputs of a tracking run (docs/design.md section 4): ``poses.csv`` rows, and at the end
``poses.bvh``, ``residuals.png``, ``overlay.mp4`` and ``run.json``.

:mod:`mocap.pipeline` runs the tracker and hands every decided frame to :func:`frame_row`
(appended to the journal) and to an :class:`OverlayWriter`; :func:`finish_run` writes the
rest. The overlay has one drawer, :func:`draw_pose`, whether it is written as frames come
(a fresh run) or redrawn at the end from ``poses.csv`` (a resumed run): both look the same.

What a crash leaves behind: rows already appended (the journal, :mod:`mocap.io.checkpoint`),
possibly a hidden ``.overlay.tmp.mp4``; every other output is written atomically, so it is
either the previous session's or absent.
"""
from __future__ import annotations

import io
import json
import os
import platform
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.body.skeleton import JOINT_NAMES
from mocap.files import write_bytes_atomic, write_text_atomic
from mocap.io.pose_table import PoseTable
from mocap.io.video_check import format_frames

__all__ = ["EXTRA_COLUMNS", "PIXEL_COLUMNS", "RunSummary", "OverlayWriter", "draw_pose", "finish_run",
           "frame_row", "joint_pixels", "versions"]

#: Per-frame columns of ``poses.csv`` after the pose and joint columns.
EXTRA_COLUMNS = ("region_residual", "edge_residual", "edge_residual_after_region", "failed", "empty", "hypothesis",
                 "score", "origin", "evaluations", "region_iterations",
                 "edge_iterations", "ms_prepare", "ms_region", "ms_edge", "ms_beam", "ms_proposals", "ms_total")
#: Names of the 2D keypoint columns of ``poses.csv`` (input-video pixels).
PIXEL_COLUMNS = tuple(f"{j}_{a}" for j in JOINT_NAMES for a in "uv")


@dataclass
class RunSummary:
    """What a tracking run did (:func:`mocap.pipeline.track_video`)."""

    out_dir: Path
    frames: int
    resumed_from: int
    fps: float
    metrics: dict | None
    failures: int
    damaged_frames: tuple[int, ...] = ()
    empty_frames: int = 0
    dark_frames: int = 0
    setup: dict | None = None


def joint_pixels(joints: np.ndarray, camera, work_factor: int = 1) -> np.ndarray:
    """Joints projected into the input video's pixels.

    Parameters
    ----------
    joints : ndarray, shape (..., J, 3), metres
        Camera coordinates.
    camera : Camera
        The working-resolution camera.
    work_factor : int
        Input pixels per working pixel (:mod:`mocap.imaging.resample`).

    Returns
    -------
    ndarray, shape (..., J, 2), float64, input pixels ``(u right, v down)``
        NaN for joints at or behind the camera.
    """
    joints = np.asarray(joints, dtype=np.float64)
    z = joints[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(z > 0, camera.fx * joints[..., 0] / z + camera.cx, np.nan)
        v = np.where(z > 0, camera.fy * joints[..., 1] / z + camera.cy, np.nan)
    return work_factor * np.stack([u, v], axis=-1)


def frame_row(result, camera=None, work_factor: int = 1, dark: bool | None = None,
              time_s: float | None = None, segment: int | None = None) -> PoseTable:
    """One ``poses.csv`` row of a decided frame (:class:`mocap.track.FrameResult`): its
    ``time_s`` (seconds from the first frame, the frame's own timestamp), pose, joints, the
    joints' input pixels (with ``camera``), :data:`EXTRA_COLUMNS`, ``dark`` and ``segment``
    (the person: ``run.json`` ``segments``)."""
    t = result.timings_ms
    extra = {} if time_s is None else {"time_s": [time_s]}
    if camera is not None:
        uv = joint_pixels(result.joints, camera, work_factor).reshape(-1)
        extra.update({name: [value] for name, value in zip(PIXEL_COLUMNS, uv)})
    extra |= {"region_residual": [result.region_residual], "edge_residual": [result.edge_residual],
              "edge_residual_after_region": [result.edge_residual_after_region],
              "failed": np.array([int(result.failed)]), "empty": np.array([int(result.empty)]),
              "hypothesis": np.array([result.hypothesis]), "score": [result.score],
              "origin": np.array([result.origin]),
              "evaluations": np.array([result.evaluations]),
              "region_iterations": np.array([result.region_iterations]),
              "edge_iterations": np.array([result.edge_iterations]), "ms_prepare": [t.get("prepare", 0.0)],
              "ms_region": [t.get("region", 0.0)], "ms_edge": [t.get("edge", 0.0)],
              "ms_beam": [t.get("beam", 0.0)], "ms_proposals": [t.get("proposals", 0.0)],
              "ms_total": [t.get("total", 0.0)]}
    if dark is not None:
        extra["dark"] = np.array([int(dark)])
    if segment is not None:
        extra["segment"] = np.array([int(segment)])
    return PoseTable([result.frame], result.pose[None], result.joints[None],
                     {k: np.asarray(v) for k, v in extra.items()})


def versions() -> dict:
    """Versions of Python and the libraries the results depend on."""
    import numba
    import scipy
    import skimage

    import mocap
    return {"python": platform.python_version(), "mocap": mocap.__version__, "numpy": np.__version__,
            "numba": numba.__version__, "scipy": scipy.__version__, "scikit-image": skimage.__version__}


def draw_pose(frame: np.ndarray, pose: np.ndarray, model, camera) -> np.ndarray:
    """The overlay picture: ``frame`` (working size, uint8 RGB, shape (h, w, 3)) with the model
    in ``pose`` (shape (23,), radians and metres) rendered by ``camera`` blended in, its classes
    in their named colours (:func:`mocap.io.overlay.draw_model`)."""
    from mocap.io.overlay import draw_model
    from mocap.render import render

    r = render(pose, model, camera)
    return draw_model(frame, r.labels, r.edges, model.n_classes, class_names=model.class_names)


class OverlayWriter:
    """The overlay as frames come: written to ``overlay.mp4`` (``write``; moved into place by
    :meth:`close`), and shown in a window when asked and a display exists."""

    def __init__(self, out_dir: Path, fps: float, model, camera, *, show: bool = False, write: bool = True) -> None:
        from mocap.io.video import VideoWriter

        self.model, self.camera = model, camera
        self.path, self.tmp = Path(out_dir) / "overlay.mp4", Path(out_dir) / ".overlay.tmp.mp4"
        self.video = VideoWriter(self.tmp, fps) if write else None
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
        """Add a working-size frame, with the model in ``pose`` drawn (the frame alone for None);
        ``model`` replaces the body model from now on (a new person's)."""
        if model is not None:
            self.model = model
        picture = frame if pose is None else draw_pose(frame, pose, self.model, self.camera)
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


def redraw_overlay(out_dir: Path, frames, table: PoseTable, models: list, camera, fps: float) -> None:
    """``overlay.mp4`` drawn afresh from ``poses.csv``: ``frames`` are ``(index, working-size
    frame)`` pairs from frame 0 (frames without a row are shown as they are); ``models`` are
    the body models of the segments (column ``segment``, 0 without it)."""
    segment = table.extra.get("segment", np.zeros(len(table)))
    rows = {int(f): (p, int(s)) for f, p, s in zip(table.frames, table.poses, segment)}
    writer = OverlayWriter(out_dir, fps, models[0], camera)
    try:
        for index, frame in frames:
            pose, person = rows.get(index, (None, 0))
            writer.update(frame, pose, models[person])
    finally:
        writer.close()


def residual_plot(path: Path, table: PoseTable, tracker: dict) -> None:
    """Both residuals per frame with their failure thresholds and the failed frames."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f, d, failed = table.extra["region_residual"], table.extra["edge_residual"], table.extra["failed"] > 0
    fig, axes = plt.subplots(2, 1, figsize=(8, 4.5), sharex=True, constrained_layout=True)
    for ax, values, thr, name in ((axes[0], f, tracker["region_failure_threshold"], "non-overlapping ratio F"),
                                  (axes[1], d, tracker["edge_failure_threshold_px"], "mean edge distance (px)")):
        ax.plot(table.frames, values, color="0.2", lw=1)
        ax.axhline(thr, color="tab:red", ls="--", lw=0.8, label=f"failure threshold {thr:g}")
        if failed.any():
            ax.plot(table.frames[failed], values[failed], "o", color="tab:red", ms=3, label="failed frames")
        ax.set_ylabel(name)
        ax.legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("frame")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    write_bytes_atomic(path, buf.getvalue())


def finish_run(out_dir: Path, table: PoseTable, settings: dict, *, calibration, camera, ground_truth: PoseTable | None,
               fps: float, start: int, wall_s: float, damaged: list[int], colour_frame: int | None,
               overlay_frames=None, models: list | None = None, extra_run: dict | None = None) -> RunSummary:
    """Write ``poses.bvh``, ``residuals.png``, ``run.json`` (and ``overlay.mp4`` redrawn from
    ``overlay_frames`` when given, see :func:`redraw_overlay`) of a run whose journal is
    ``table``; its summary."""
    from mocap.io.bvh import write_bvh

    extra = table.extra
    # frames per second: the first frame of a session also loads the compiled kernels, leave it out
    ms_total = extra["ms_total"][1:] if len(table) > 1 else extra["ms_total"]
    timings = {k[3:]: {"mean": float(np.mean(extra[k])), "std": float(np.std(extra[k])),
                       "median": float(np.median(extra[k]))} for k in extra if k.startswith("ms_")}
    tracked = len(table)
    metrics = None
    if ground_truth is not None:
        from mocap import metrics as mx
        index = {int(f): i for i, f in enumerate(ground_truth.frames)}
        rows = [index[int(f)] for f in table.frames if int(f) in index]
        if len(rows) != tracked:
            raise ValueError("ground truth lacks some tracked frames")
        metrics = mx.summary(table.poses, ground_truth.poses[rows], table.joints, ground_truth.joints[rows], camera)
        metrics["fps"] = float(1e3 / np.mean(ms_total))
    failures = int(extra["failed"].sum())
    run = {"status": "finished", "settings": settings, "versions": versions(), "frames": tracked,
           "resumed_from_frame": start, "wall_seconds_this_session": wall_s,
           "fps": float(1e3 / np.mean(ms_total)), "timings_ms": timings,
           "failures": failures, "empty_frames": int(extra["empty"].sum()),
           "units": {"positions": "metres", "angles_in_csv": "degrees", "residual_edge": "pixels",
                     "time_s": "seconds from the first frame (the frame's own timestamp)"}}
    if metrics is not None:
        run["metrics"] = metrics
    run["colour_model_frame"] = colour_frame
    if damaged:
        run["damaged_frames"] = damaged
        run["damaged_frames_text"] = format_frames(damaged)
    run |= extra_run or {}
    write_bvh(out_dir / "poses.bvh", table.poses, calibration.dims, fps)
    residual_plot(out_dir / "residuals.png", table, settings["tracker"])
    if overlay_frames is not None:
        redraw_overlay(out_dir, overlay_frames, table, models, camera, fps)
    if "dark" in extra:
        run["dark_frames"] = int(extra["dark"].sum())
    write_text_atomic(out_dir / "run.json", json.dumps(run, indent=2))
    return RunSummary(out_dir, tracked, start, run["fps"], metrics, failures, tuple(damaged), run["empty_frames"],
                      run.get("dark_frames", 0), settings.get("own_video"))
