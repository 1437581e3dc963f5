"""Track a whole video: frames in; ``poses.csv``, ``poses.bvh``, ``overlay.mp4``,
``residuals.png`` and ``run.json`` out (docs/design.md sections 3–4).

``poses.csv`` is a journal: every finished frame is appended and flushed at once, and after
every frame the tracker's exact state is saved with the journal length it belongs to
(:mod:`mocap.io.checkpoint`), so an interrupted run — even killed at any instant — loses
nothing and the same command resumes bit for bit where it stopped (the settings must be the
same; they are kept in ``run.json``). One run at a time may write to an output folder
(:mod:`mocap.io.lock`). The other outputs are written atomically at the end.
"""
from __future__ import annotations

import collections
import json
import os
import platform
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.body.skeleton import JOINT_NAMES
from mocap.calibrate import Calibration, colour_model_from_pose
from mocap.imaging import ColourModel, ImagingConfig, learn_colour_model, prepare_frame
from mocap.io.atomic import write_text_atomic
from mocap.io.checkpoint import Checkpoint, read_checkpoint, truncate_journal, write_checkpoint
from mocap.io.lock import one_writer
from mocap.io.pose_table import PoseTable
from mocap.io.frames import VideoSource
from mocap.io.video import count_frames, read_image
from mocap.io.video_check import check_video, format_frames
from mocap.track import FrameResult, Tracker, TrackerConfig

#: Per-frame columns of ``poses.csv`` after the pose and joint columns.
EXTRA_COLUMNS = ("region_residual", "edge_residual", "edge_residual_after_region", "failed", "empty", "hypothesis",
                 "score", "origin", "evaluations", "region_iterations",
                 "edge_iterations", "ms_prepare", "ms_region", "ms_edge", "ms_beam", "ms_proposals", "ms_total")
COLOUR_SOURCES = ("calibration", "face")


@dataclass
class RunSummary:
    """What :func:`track_video` did."""

    out_dir: Path
    frames: int
    resumed_from: int
    fps: float
    metrics: dict | None
    failures: int
    damaged_frames: tuple[int, ...] = ()
    empty_frames: int = 0
    dark_frames: int = 0


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


#: Names of the 2D keypoint columns of ``poses.csv`` (input-video pixels).
PIXEL_COLUMNS = tuple(f"{j}_{a}" for j in JOINT_NAMES for a in "uv")


#: Mean brightness (0-255) below which a frame counts as very dark (column ``dark`` of ``poses.csv``).
DARK_MEAN = 20.0


def _frame_row(r: FrameResult, camera=None, work_factor: int = 1, dark: bool | None = None) -> PoseTable:
    t = r.timings_ms
    extra = {}
    if camera is not None:
        uv = joint_pixels(r.joints, camera, work_factor).reshape(-1)
        extra.update({name: [value] for name, value in zip(PIXEL_COLUMNS, uv)})
    extra |= {"region_residual": [r.region_residual], "edge_residual": [r.edge_residual],
             "edge_residual_after_region": [r.edge_residual_after_region],
             "failed": np.array([int(r.failed)]), "empty": np.array([int(r.empty)]),
             "hypothesis": np.array([r.hypothesis]), "score": [r.score], "origin": np.array([r.origin]),
             "evaluations": np.array([r.evaluations]), "region_iterations": np.array([r.region_iterations]),
             "edge_iterations": np.array([r.edge_iterations]), "ms_prepare": [t.get("prepare", 0.0)],
             "ms_region": [t.get("region", 0.0)], "ms_edge": [t.get("edge", 0.0)],
             "ms_beam": [t.get("beam", 0.0)], "ms_proposals": [t.get("proposals", 0.0)], "ms_total": [t.get("total", 0.0)]}
    if dark is not None:
        extra["dark"] = np.array([int(dark)])
    return PoseTable([r.frame], r.pose[None], r.joints[None], {k: np.asarray(v) for k, v in extra.items()})


def _settings(source: str, background: Path | None, calibration: Calibration, config: TrackerConfig,
              imaging: ImagingConfig, colour: str, resolution: int) -> dict:
    source = str(Path(source).resolve()) if Path(source).exists() else source
    return {"source": source, "background": str(background.resolve()) if background else None,
            "calibration": calibration.to_dict(), "tracker": config.to_dict(), "imaging": imaging.to_dict(),
            "colour_model_from": colour, "mesh_resolution": resolution}


def _versions() -> dict:
    import numba
    import scipy
    import skimage

    import mocap
    return {"python": platform.python_version(), "mocap": mocap.__version__, "numpy": np.__version__,
            "numba": numba.__version__, "scipy": scipy.__version__, "scikit-image": skimage.__version__}


@one_writer("out_dir")
def track_video(source: str | Path, background: str | Path | None, calibration: Calibration, out_dir: str | Path,
                config: TrackerConfig | None = None, *, imaging: ImagingConfig | None = None,
                colour: str = "calibration", ground_truth: str | Path | None = None, fps: float = 25.0,
                max_frames: int | None = None, overwrite: bool = False, progress: bool = True,
                write_overlay: bool = True, allow_damaged: bool = False, start_frame: int = 0,
                work_factor: int = 1, colour_model: ColourModel | None = None, scene=None,
                setup_record: dict | None = None, show: bool = False) -> RunSummary:
    """Track every frame of a video or image folder and write the outputs.

    Parameters
    ----------
    source : path or frame source
        Video file or folder of images, or a :mod:`mocap.io.frames` source (a camera).
    background : path, ndarray of uint8 (H, W, 3), or None
        Image of the empty scene: a file the size of the input frames, or an array the size
        of the working frames.
    calibration : Calibration
        Actor dimensions, initial pose, camera (its size must match the working frames:
        the input frames reduced by ``work_factor``).
    out_dir : path
        Output folder (created), locked for the run. If it holds an unfinished run with the
        same settings, the run resumes exactly where it stopped.
    config : TrackerConfig, optional
    imaging : ImagingConfig, optional
    colour : {"calibration", "face"}
        Learn the colour classes inside the calibrated model's projected parts, or from the
        detected face and a box under it (the paper's way), on the first frame (from
        ``start_frame``) that shows the person: whose foreground covers at least
        :data:`PLAUSIBLE_FOREGROUND` of the model's silhouette, or where a face is detected.
        The frame used goes to ``run.json`` (``colour_model_frame``).
    ground_truth : path, optional
        ``ground_truth.csv``: adds the ``metrics`` object to ``run.json``.
    fps : float
        Frame rate of the output video and BVH.
    max_frames : int, optional
        Track only the first ``max_frames`` frames (from ``start_frame``).
    overwrite : bool
        Start afresh even if ``out_dir`` holds a run.
    progress : bool
        Show a progress bar.
    write_overlay : bool
        Also write ``overlay.mp4``.
    allow_damaged : bool
        Track a video whose frames do not all decode (:func:`mocap.io.video_check.check_video`)
        instead of refusing it; the damaged frame numbers go to ``run.json``
        (``damaged_frames``) and the summary.
    start_frame : int
        First frame to track (0-based); the calibration's initial pose is the pose there.
    work_factor : int
        The input frames are reduced by this factor (:func:`mocap.imaging.resample.downscale`)
        before anything else; ``poses.csv``'s ``<joint>_u``, ``<joint>_v`` columns are in
        input pixels all the same.
    colour_model : ColourModel, optional
        Colour classes to use as they are (``colour`` is then ignored).
    scene : mocap.imaging.scene.SceneColours, optional
        The scene's colours, for a foreground without background (:func:`mocap.imaging.prepare_frame`).
    setup_record : dict, optional
        How background and calibration were found (own-video path), kept in ``run.json``.
    show : bool
        Show the overlay live in a window (needs a display).

    Returns
    -------
    RunSummary

    Raises
    ------
    ValueError
        Frames and calibration of different sizes, an undecodable or (without
        ``allow_damaged``) damaged video, a background of
        another size, an out folder holding a run with other settings, bad settings.
    FileNotFoundError
        Missing video, background or ground truth.
    mocap.io.lock.FolderInUseError
        Another run writes to ``out_dir``.
    """
    from tqdm import tqdm

    from mocap.body.mesh import resolution_for_image

    config = TrackerConfig() if config is None else config
    imaging = ImagingConfig() if imaging is None else imaging
    if colour not in COLOUR_SOURCES:
        raise ValueError(f"colour must be one of {COLOUR_SOURCES}, got {colour!r}")
    from mocap.imaging.resample import downscale

    frames_in = source if hasattr(source, "frames") else VideoSource(source)
    out_dir = Path(out_dir)
    camera = calibration.camera
    if isinstance(start_frame, bool) or not isinstance(start_frame, int) or start_frame < 0:
        raise ValueError(f"the start frame must be a non-negative integer, got {start_frame!r}")
    if frames_in.live:
        total, damaged = frames_in.count, []
    else:
        total, damaged = _frames_to_track(frames_in.path, allow_damaged)
        if total == 0:
            raise ValueError(f"{frames_in.name} has no frames")
        if start_frame >= total:
            raise ValueError(f"start frame {start_frame} is past the end of {frames_in.name} ({total} frames)")
    if max_frames is not None:
        if max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {max_frames}")
        total = start_frame + max_frames if total is None else min(total, start_frame + max_frames)
    work_shape = (frames_in.height // work_factor, frames_in.width // work_factor)
    if work_shape != camera.shape:
        raise ValueError(f"frames are {frames_in.width}x{frames_in.height} (working size {work_shape[1]}x"
                         f"{work_shape[0]}) but the calibration's camera is {camera.width}x{camera.height}: "
                         "calibrate for this video (python -m mocap calibrate)")
    bg_image = None
    if isinstance(background, np.ndarray):
        bg_image = background
        if bg_image.shape != (*work_shape, 3):
            raise ValueError(f"background is {bg_image.shape[1]}x{bg_image.shape[0]}, working frames are "
                             f"{work_shape[1]}x{work_shape[0]}")
        background = None
    elif background is not None:
        background = Path(background)
        bg_image = read_image(background)
        if bg_image.shape[:2] != (frames_in.height, frames_in.width):
            raise ValueError(f"background {background} is {bg_image.shape[1]}x{bg_image.shape[0]}, frames are "
                             f"{frames_in.width}x{frames_in.height}")
        bg_image = downscale(bg_image, work_factor)
    gt = PoseTable.read(ground_truth) if ground_truth is not None else None

    resolution = config.mesh_resolution or resolution_for_image(camera.width, camera.height)
    model = calibration.body_model(resolution)
    settings = _settings(frames_in.name, background, calibration, config, imaging, colour, resolution)
    settings["working_resolution"] = {"factor": work_factor, "width": camera.width, "height": camera.height,
                                      "input_width": frames_in.width, "input_height": frames_in.height}
    if setup_record is not None:
        settings["own_video"] = setup_record
    settings["start_frame"] = start_frame
    out_dir.mkdir(parents=True, exist_ok=True)
    journal, run_json = out_dir / "poses.csv", out_dir / "run.json"
    checkpoint = _previous_run(journal, run_json, settings, overwrite)

    colour_frame = None
    if colour_model is None:
        if frames_in.live:
            raise ValueError("a live source needs its colour model given")
        colour_model, colour_frame = _learn_colours(
            ((i, downscale(f, work_factor)) for i, f in enumerate(frames_in.frames(start_frame, total), start=start_frame)),
            frames_in.name, bg_image, model, camera, calibration.initial_pose, imaging, colour)
    colour_model.to_json(out_dir / "colour_model.json")
    model = model.with_class_names(colour_model.names)        # classes the first frame supports

    tracker = Tracker(model, camera, config, calibration.initial_pose)
    state_path = out_dir / STATE_FILE
    start = start_frame
    if checkpoint is not None:
        if frames_in.live:
            raise ValueError(f"{out_dir} holds a run; a live source cannot resume it: use --overwrite or another --out")
        start = checkpoint.next_index
        state = dict(checkpoint.state)
        pending_dark = state.pop(PENDING_DARK, np.zeros((0, 2), np.int64))
        tracker.restore(state)
    else:
        write_text_atomic(run_json, json.dumps({"status": "running", "settings": settings}, indent=2))
    started = time.perf_counter()
    results_ms: collections.deque[float] = collections.deque(maxlen=25)   # for the frame rate shown
    # the overlay is drawn as frames come (no second decoding pass) unless an earlier session's
    # frames must be in it too (a resumed file run redraws it whole at the end)
    overlay_now = frames_in.live or (write_overlay and start == start_frame)
    live = _LiveView(out_dir, fps, model, camera, show, overlay_now) if (overlay_now or show) else None
    pending: dict[int, np.ndarray] = {}
    # dark flags of the frames pushed but not decided yet (kept in the checkpoint with the tracker)
    dark: dict[int, bool] = {} if checkpoint is None else {int(f): bool(v) for f, v in pending_dark}
    bar = tqdm(total=None if total is None else total - start_frame, initial=start - start_frame, desc="tracking",
               unit="frame", disable=not progress)
    interrupted = False

    def emit(results: list[FrameResult]) -> None:
        for result in results:
            _frame_row(result, camera, work_factor, dark.pop(result.frame, None)).append_to(journal)
            results_ms.append(result.timings_ms["total"])
            frame = pending.pop(result.frame, None)
            if live is not None and frame is not None:
                live.update(frame, result)
            bar.set_postfix(fps=f"{1e3 / np.mean(results_ms):.0f}", F=f"{result.region_residual:.2f}",
                            D=f"{result.edge_residual:.1f}")

    try:
        for index, frame in enumerate(frames_in.frames(start, total), start=start):
            small = downscale(frame, work_factor)
            dark[index] = bool(small.mean() < DARK_MEAN)
            if live is not None:
                pending[index] = small
            prepared = prepare_frame(small, bg_image, colour_model, imaging, scene=scene)
            emit(tracker.push(index, prepared))
            write_checkpoint(state_path, {**tracker.state(), PENDING_DARK: np.array(sorted(dark.items()), np.int64)
                                          .reshape(-1, 2)}, index + 1, journal)
            bar.update(1)
        # the held-back frames: not checkpointed, a resume continues from the last push instead
        emit(tracker.finish())
    except KeyboardInterrupt:
        if not frames_in.live:
            raise
        interrupted = True          # Ctrl-C ends a live run: what was tracked is kept
        emit(tracker.finish())
    finally:
        bar.close()
        if live is not None:
            live.close()
    if interrupted:
        print("stopped by Ctrl-C: writing what was tracked")
    if not journal.exists():
        raise ValueError(f"no frame was tracked from {frames_in.name}")
    table = PoseTable.read(journal)     # (not rewritten: the checkpoint records its length)
    return _finish(out_dir, table, settings, frames_in, model, calibration, camera, gt, fps, start,
                   time.perf_counter() - started, write_overlay and not overlay_now, work_factor,
                   damaged=damaged, colour_frame=colour_frame)


#: Fraction of the calibrated model's silhouette (pixels) the foreground must cover for a frame to
#: be taken as showing the person, to learn the colours on.
PLAUSIBLE_FOREGROUND = 0.5


def _learn_colours(frames, name: str, bg_image, model, camera, pose, imaging,
                   colour: str) -> tuple[ColourModel, int]:
    """Colour model from the first of ``frames`` (``(index, working-size frame)`` pairs) that shows
    the person, and that frame's number; ValueError (with the last frame's reason) when none does."""
    from mocap.imaging import subtract_background
    from mocap.render import render

    silhouette = np.count_nonzero(render(pose, model, camera).labels)
    reason = "no frame"
    for index, frame in frames:
        try:
            if colour == "face":
                return learn_colour_model(frame, bg_image, config=imaging), index
            if bg_image is not None:
                covered = np.count_nonzero(subtract_background(frame, bg_image, imaging))
                if covered < PLAUSIBLE_FOREGROUND * silhouette:
                    reason = (f"frame {index} has {covered} foreground pixels, fewer than {PLAUSIBLE_FOREGROUND:g} "
                              f"of the calibrated model's {silhouette}")
                    continue
            return colour_model_from_pose(frame, bg_image, model, camera, pose, imaging), index
        except ValueError as exc:
            reason = f"frame {index}: {exc}"
    raise ValueError(f"no frame of {name} shows the person to learn the colours from "
                     f"({'a detected face' if colour == 'face' else 'a foreground the size of the model'}); "
                     f"last: {reason}")


def _frames_to_track(source: Path, allow_damaged: bool) -> tuple[int, list[int]]:
    """Frames a video or folder delivers, and the damaged frame numbers of a video (what
    decodes checked against what its container announces); ValueError on damage unless allowed."""
    if source.is_dir():
        return count_frames(source), []
    check = check_video(source)
    if check.damaged and not allow_damaged:
        raise ValueError(f"{check.describe(source)}; to track the frames that decode anyway, add --allow-damaged")
    return check.readable, check.damaged_frames


#: Checkpoint entry holding ``(frame, dark)`` of the frames the tracker still holds back.
PENDING_DARK = "run_pending_dark"
#: Checkpoint (:mod:`mocap.io.checkpoint`): the tracker's exact state after the last pushed
#: frame and the length of ``poses.csv`` that goes with it, for bit-identical resumes.
STATE_FILE = ".tracker_state.npz"


def _previous_run(journal: Path, run_json: Path, settings: dict, overwrite: bool) -> Checkpoint | None:
    """The checkpoint to resume from (the journal cut back to it), or None to start afresh."""
    state_path = journal.parent / STATE_FILE
    if overwrite or not (journal.exists() or state_path.exists()):
        journal.unlink(missing_ok=True)
        state_path.unlink(missing_ok=True)
        return None
    try:
        previous = json.loads(run_json.read_text()) if run_json.exists() else {}
    except json.JSONDecodeError:
        previous = {}
    if previous.get("settings") != json.loads(json.dumps(settings)):
        raise ValueError(f"{journal.parent} holds a run with other settings (or no run.json); "
                         "use --overwrite or another --out")
    checkpoint = read_checkpoint(state_path)
    truncate_journal(journal, checkpoint)   # rows after the checkpoint (and a partial line) are redone
    return checkpoint


def _finish(out_dir, table, settings, source, model, calibration, camera, gt, fps, start, wall_s,
            write_overlay, work_factor, *, damaged: list[int], colour_frame: int | None) -> RunSummary:
    from mocap.io.bvh import write_bvh

    extra = table.extra
    # frames per second: the first frame of a session also loads the compiled kernels, leave it out
    ms_total = extra["ms_total"][1:] if len(table) > 1 else extra["ms_total"]
    timings = {k[3:]: {"mean": float(np.mean(extra[k])), "std": float(np.std(extra[k])),
                       "median": float(np.median(extra[k]))} for k in extra if k.startswith("ms_")}
    tracked = len(table)
    metrics = None
    if gt is not None:
        from mocap import metrics as mx
        index = {int(f): i for i, f in enumerate(gt.frames)}
        rows = [index[int(f)] for f in table.frames if int(f) in index]
        if len(rows) != tracked:
            raise ValueError("ground truth lacks some tracked frames")
        metrics = mx.summary(table.poses, gt.poses[rows], table.joints, gt.joints[rows], camera)
        metrics["fps"] = float(1e3 / np.mean(ms_total))
    failures = int(extra["failed"].sum())
    run = {"status": "finished", "settings": settings, "versions": _versions(), "frames": tracked,
           "resumed_from_frame": start, "wall_seconds_this_session": wall_s,
           "fps": float(1e3 / np.mean(ms_total)), "timings_ms": timings,
           "failures": failures, "empty_frames": int(extra["empty"].sum()),
           "units": {"positions": "metres", "angles_in_csv": "degrees", "residual_edge": "pixels"}}
    if metrics is not None:
        run["metrics"] = metrics
    run["colour_model_frame"] = colour_frame
    if damaged:
        run["damaged_frames"] = damaged
        run["damaged_frames_text"] = format_frames(damaged)
    write_bvh(out_dir / "poses.bvh", table.poses, calibration.dims, fps)
    _residual_plot(out_dir / "residuals.png", table, settings["tracker"])
    if write_overlay:
        _overlay_video(out_dir / "overlay.mp4", source, table, model, camera, fps, work_factor)
    if "dark" in extra:
        run["dark_frames"] = int(extra["dark"].sum())
    write_text_atomic(out_dir / "run.json", json.dumps(run, indent=2))
    return RunSummary(out_dir, tracked, start, run["fps"], metrics, failures, tuple(damaged), run["empty_frames"],
                      run.get("dark_frames", 0))


def _residual_plot(path: Path, table: PoseTable, tracker: dict) -> None:
    """Both residuals per frame with their failure thresholds and the failed frames."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mocap.io.atomic import write_bytes_atomic
    import io

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


def _overlay_video(path: Path, source, table: PoseTable, model, camera, fps: float, work_factor: int = 1) -> None:
    from mocap.imaging.resample import downscale
    from mocap.io.overlay import draw_model
    from mocap.io.video import VideoWriter
    from mocap.render import render

    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    poses = {int(f): p for f, p in zip(table.frames, table.poses)}
    with VideoWriter(tmp, fps) as video:
        for index, frame in enumerate(source.frames(0, int(table.frames.max()) + 1)):
            frame = downscale(frame, work_factor)
            if index in poses:
                r = render(poses[index], model, camera)
                frame = draw_model(frame, r.labels, r.edges, model.n_classes, class_names=model.class_names)
            video.write(frame)
    os.replace(tmp, path)


class _LiveView:
    """The overlay as frames come: written to ``overlay.mp4`` (``write``), and shown in a
    window when asked and a display exists."""

    def __init__(self, out_dir: Path, fps: float, model, camera, show: bool, write: bool) -> None:
        from mocap.io.video import VideoWriter

        self.model, self.camera = model, camera
        self.path, self.tmp = out_dir / "overlay.mp4", out_dir / ".overlay.tmp.mp4"
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

    def update(self, frame: np.ndarray, result: FrameResult) -> None:
        from mocap.io.overlay import draw_model
        from mocap.render import render

        r = render(result.pose, self.model, self.camera)
        picture = draw_model(frame, r.labels, r.edges, self.model.n_classes)
        if self.video is not None:
            self.video.write(picture)
        if self.figure is not None:
            if self.image is None:
                self.image = self.figure.axes[0].imshow(picture)
            else:
                self.image.set_data(picture)
            self.plt.pause(0.001)

    def close(self) -> None:
        if self.video is not None:
            self.video.close()
            if self.video.frames:
                os.replace(self.tmp, self.path)
            self.video = None
        if self.figure is not None:
            self.plt.close(self.figure)
