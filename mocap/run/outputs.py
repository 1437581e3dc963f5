"""The outputs of a tracking run (docs/design.md section 4): ``poses.csv`` rows, and at the end
``poses.bvh``, ``residuals.png`` and ``run.json``.

:mod:`mocap.run.loop` runs the tracker and hands every decided frame to :func:`frame_row`
(appended to the journal) and to the overlay (:mod:`mocap.run.overlay`); :func:`finish_run`
writes the rest from a :class:`FinishedRun`, ``run.json`` once.

What a crash leaves behind: rows already appended (the journal, :mod:`mocap.run.journal`),
possibly a hidden ``.overlay.tmp.mp4``; every other output is written atomically, so it is
either the previous session's or absent.
"""
from __future__ import annotations

import io
import json
import platform
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.body.skeleton import JOINT_NAMES
from mocap.calibrate import Calibration
from mocap.io.files import write_bytes_atomic, write_text_atomic
from mocap.io.pose_table import PoseTable
from mocap.io.video_check import format_frames
from mocap.render.camera import Camera
from mocap.run import files
from mocap.run.accounts import SetupAccount
from mocap.track.config import EDGE_FAILURE_THRESHOLD_PX, REGION_FAILURE_THRESHOLD

__all__ = ["EXTRA_COLUMNS", "PIXEL_COLUMNS", "FinishedRun", "RunSummary", "finish_run", "frame_row",
           "joint_pixels", "versions"]

#: Per-frame columns of ``poses.csv`` after the pose and joint columns.
EXTRA_COLUMNS = ("region_residual", "edge_residual", "keypoint_residual", "edge_residual_after_region", "smoothed_mm",
                 "failed", "empty", "hypothesis",
                 "score", "origin", "labels_swapped", "evaluations", "region_iterations",
                 "edge_iterations", "ms_prepare", "ms_region", "ms_edge", "ms_beam", "ms_proposals", "ms_total")
#: Names of the 2D keypoint columns of ``poses.csv`` (input-video pixels).
PIXEL_COLUMNS = tuple(f"{j}_{a}" for j in JOINT_NAMES for a in "uv")


@dataclass(kw_only=True)
class RunSummary:
    """What a tracking run did (:func:`mocap.run.track`), or a finished run's ``run.json`` as
    read back (:meth:`read`).

    Attributes
    ----------
    out_dir : Path
    frames : int
        Rows of ``poses.csv``.
    resumed_from : int
        The frame this session started from.
    fps : float, frames per second
        The session's rate by the wall clock (``run.json`` ``fps``: :func:`mocap.run.loop.session_fps`).
    metrics : dict or None
        Accuracy against the ground truth (``run.json`` ``metrics``).
    failures : int
        Frames marked failed.
    damaged_frames : tuple of int
        Frames that did not decode cleanly.
    empty_frames, dark_frames : int
        Frames with nobody in view, very dark frames.
    wall_s : float, seconds
        The time of the session that finished the run (``run.json`` ``wall_seconds_this_session``).
    setup : SetupAccount or None
        How the set-up was found (``run.json`` ``settings.own_video``; from :func:`mocap.run.track`
        with the input and working sizes).
    advice : str or None
        One line on what to try when most frames failed (:func:`mocap.run.advice.what_to_try`).
    """

    out_dir: Path
    frames: int
    resumed_from: int
    fps: float
    metrics: dict | None
    failures: int
    damaged_frames: tuple[int, ...] = ()
    empty_frames: int = 0
    dark_frames: int = 0
    wall_s: float = 0.0
    setup: SetupAccount | None = None
    advice: str | None = None

    @classmethod
    def read(cls, out_dir: str | Path) -> "RunSummary | None":
        """The summary of the finished run in ``out_dir`` from its ``run.json``; None where there
        is none, an unreadable one, an unfinished run or one of another version (``advice`` is
        not kept: None)."""
        out_dir = Path(out_dir)
        try:
            record = json.loads((out_dir / files.RUN_JSON).read_text())
        except (OSError, ValueError):
            return None
        if not isinstance(record, dict) or record.get("status") != "finished":
            return None
        try:
            return cls(out_dir=out_dir, frames=record["frames"], resumed_from=record["resumed_from_frame"],
                       fps=record["fps"], metrics=record.get("metrics"), failures=record["failures"],
                       damaged_frames=tuple(record.get("damaged_frames", ())), empty_frames=record["empty_frames"],
                       dark_frames=record.get("dark_frames", 0), wall_s=record["wall_seconds_this_session"],
                       setup=SetupAccount.from_settings(record["settings"]))
        except (KeyError, TypeError, AttributeError):          # a run.json of another version
            return None


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
              "keypoint_residual": [result.keypoint_residual],
              "edge_residual_after_region": [result.edge_residual_after_region], "smoothed_mm": [result.smoothed_mm],
              "failed": np.array([int(result.failed)]), "empty": np.array([int(result.empty)]),
              "hypothesis": np.array([result.hypothesis]), "score": [result.score],
              "origin": np.array([result.origin]), "labels_swapped": np.array([int(result.labels_swapped)]),
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


def residual_plot(path: Path, table: PoseTable) -> None:
    """Both residuals per frame with their failure thresholds and the failed frames.

    Drawn on a bare :class:`matplotlib.figure.Figure` with fixed margins: no pyplot (its import)
    and no constrained layout, which together were about half of this plot's time, all of it at
    the end of a run (2026-11-27)."""
    from matplotlib.figure import Figure

    f, d, failed = table.extra["region_residual"], table.extra["edge_residual"], table.extra["failed"] > 0
    fig = Figure(figsize=(8, 4.5))
    fig.subplots_adjust(left=0.09, right=0.98, bottom=0.11, top=0.98, hspace=0.08)
    axes = fig.subplots(2, 1, sharex=True)
    for ax, values, thr, name in ((axes[0], f, REGION_FAILURE_THRESHOLD, "non-overlapping ratio F"),
                                  (axes[1], d, EDGE_FAILURE_THRESHOLD_PX, "mean edge distance (px)")):
        ax.plot(table.frames, values, color="0.2", lw=1)
        ax.axhline(thr, color="tab:red", ls="--", lw=0.8, label=f"failure threshold {thr:g}")
        if failed.any():
            ax.plot(table.frames[failed], values[failed], "o", color="tab:red", ms=3, label="failed frames")
        ax.set_ylabel(name)
        ax.legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("frame")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    write_bytes_atomic(path, buf.getvalue())


@dataclass(frozen=True, eq=False)
class FinishedRun:
    """What :func:`finish_run` writes the outputs of.

    Attributes
    ----------
    out_dir : Path
    table : PoseTable
        The journal (``poses.csv``) as read back.
    settings : dict
        ``run.json`` ``settings`` (JSON-ready).
    calibration : Calibration
        The first person's (its body dimensions for ``poses.bvh``).
    camera : Camera
        The working camera.
    fps : float, frames per second
        The video's frame rate (``poses.bvh``).
    start : int
        The frame this session started from.
    wall_s : float, seconds
        This session's time.
    damaged : list of int
        Frames that did not decode cleanly.
    colour_frame : int or None
        The frame the colours were learnt on (None: given).
    segments : list of dict
        The people (:class:`mocap.run.journal.People`).
    ground_truth : PoseTable or None
    keypoints_ms : float or None, milliseconds
        The keypoint detector's median time per frame.
    live : dict or None
        A live run's ``run.json`` ``live`` (frames dropped, latency: :meth:`mocap.run.loop.RunLoop.live_record`).
    threads : int
        The tracker's threads this session (``run.json`` ``threads``; the poses do not depend on it).
    loop_fps : float or None, frames per second
        This session's rate by the wall clock (:func:`mocap.run.loop.session_fps`); None: none
        measured (``run.json`` ``fps`` is then 1000 over the rows' mean ``ms_total``).
    """

    out_dir: Path
    table: PoseTable
    settings: dict
    calibration: Calibration
    camera: Camera
    fps: float
    start: int
    wall_s: float
    damaged: list[int]
    colour_frame: int | None
    segments: list[dict]
    ground_truth: PoseTable | None = None
    keypoints_ms: float | None = None
    live: dict | None = None
    threads: int = 1
    loop_fps: float | None = None


def _metrics(run: FinishedRun, fps: float) -> dict | None:
    """Accuracy against the ground truth (:func:`mocap.metrics.summary`) and the rate."""
    if run.ground_truth is None:
        return None
    from mocap import metrics as mx

    table, truth = run.table, run.ground_truth
    index = {int(f): i for i, f in enumerate(truth.frames)}
    rows = [index[int(f)] for f in table.frames if int(f) in index]
    if len(rows) != len(table):
        raise ValueError("ground truth lacks some tracked frames")
    metrics = mx.summary(table.poses, truth.poses[rows], table.joints, truth.joints[rows], run.camera)
    metrics["fps"] = fps
    return metrics


def finish_run(run: FinishedRun) -> RunSummary:
    """Write ``poses.bvh``, ``residuals.png`` and ``run.json`` (once, atomically) of a run; its
    summary."""
    from mocap.io.bvh import write_bvh

    table, extra = run.table, run.table.extra
    # frames per second: this session's by the wall clock; else from the rows' timings, the first
    # frame of a session left out (it also loads the compiled kernels)
    ms_total = extra["ms_total"][1:] if len(table) > 1 else extra["ms_total"]
    fps = run.loop_fps if run.loop_fps is not None else float(1e3 / np.mean(ms_total))
    timings = {k[3:]: {"mean": float(np.mean(extra[k])), "std": float(np.std(extra[k])),
                       "median": float(np.median(extra[k]))} for k in extra if k.startswith("ms_")}
    metrics = _metrics(run, fps)
    failures = int(extra["failed"].sum())
    record = {"status": "finished", "settings": run.settings, "versions": versions(), "frames": len(table),
              "resumed_from_frame": run.start, "wall_seconds_this_session": run.wall_s,
              "fps": fps, "threads": run.threads, "timings_ms": timings,
              "failures": failures, "empty_frames": int(extra["empty"].sum()),
              "units": {"positions": "metres", "angles_in_csv": "degrees", "residual_edge": "pixels",
                        "time_s": "seconds from the first frame (the frame's own timestamp)"}}
    if metrics is not None:
        record["metrics"] = metrics
    record["colour_model_frame"] = run.colour_frame
    if run.damaged:
        record["damaged_frames"] = run.damaged
        record["damaged_frames_text"] = format_frames(run.damaged)
    record["segments"] = run.segments
    write_bvh(run.out_dir / files.POSES_BVH, table.poses, run.calibration.dims, run.fps)
    residual_plot(run.out_dir / files.RESIDUALS_PNG, table)
    if "dark" in extra:
        record["dark_frames"] = int(extra["dark"].sum())
    if run.keypoints_ms is not None:      # the detector's own time per frame, beside the tracker's ms_total
        record["keypoints_ms_per_frame"] = run.keypoints_ms
    if run.live is not None:
        record["live"] = run.live
    write_text_atomic(run.out_dir / files.RUN_JSON, json.dumps(record, indent=2))
    return RunSummary(out_dir=run.out_dir, frames=len(table), resumed_from=run.start, fps=record["fps"],
                      metrics=metrics, failures=failures, damaged_frames=tuple(run.damaged),
                      empty_frames=record["empty_frames"], dark_frames=record.get("dark_frames", 0), wall_s=run.wall_s,
                      setup=SetupAccount.from_settings(run.settings))
