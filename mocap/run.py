"""Track a whole video: frames in; ``poses.csv``, ``poses.bvh``, ``overlay.mp4``,
``residuals.png`` and ``run.json`` out (DESIGN.md sections 3–4).

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

from mocap.calibrate import Calibration, colour_model_from_pose
from mocap.imaging import ColourModel, ImagingConfig, learn_colour_model, prepare_frame
from mocap.io.atomic import write_text_atomic
from mocap.io.checkpoint import Checkpoint, read_checkpoint, truncate_journal, write_checkpoint
from mocap.io.lock import one_writer
from mocap.io.pose_table import PoseTable
from mocap.io.video import count_frames, iter_frames, read_image
from mocap.io.video_check import check_video, format_frames
from mocap.track import FrameResult, Tracker, TrackerConfig

#: Per-frame columns of ``poses.csv`` after the pose and joint columns.
EXTRA_COLUMNS = ("region_residual", "edge_residual", "edge_residual_after_region", "failed", "empty", "hypothesis",
                 "score", "evaluations", "region_iterations",
                 "edge_iterations", "ms_prepare", "ms_region", "ms_edge", "ms_recovery", "ms_total")
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


def _frame_row(r: FrameResult) -> PoseTable:
    t = r.timings_ms
    extra = {"region_residual": [r.region_residual], "edge_residual": [r.edge_residual],
             "edge_residual_after_region": [r.edge_residual_after_region],
             "failed": np.array([int(r.failed)]), "empty": np.array([int(r.empty)]),
             "hypothesis": np.array([r.hypothesis]), "score": [r.score],
             "evaluations": np.array([r.evaluations]), "region_iterations": np.array([r.region_iterations]),
             "edge_iterations": np.array([r.edge_iterations]), "ms_prepare": [t.get("prepare", 0.0)],
             "ms_region": [t.get("region", 0.0)], "ms_edge": [t.get("edge", 0.0)],
             "ms_recovery": [t.get("recovery", 0.0)], "ms_total": [t.get("total", 0.0)]}
    return PoseTable([r.frame], r.pose[None], r.joints[None], {k: np.asarray(v) for k, v in extra.items()})


def _settings(source: Path, background: Path | None, calibration: Calibration, config: TrackerConfig,
              imaging: ImagingConfig, colour: str, resolution: int) -> dict:
    return {"source": str(source.resolve()), "background": str(background.resolve()) if background else None,
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
                write_overlay: bool = True, allow_damaged: bool = False, start_frame: int = 0) -> RunSummary:
    """Track every frame of a video or image folder and write the outputs.

    Parameters
    ----------
    source : path
        Video file or folder of images.
    background : path or None
        Image of the empty scene (same size as the frames).
    calibration : Calibration
        Actor dimensions, initial pose, camera (its size must match the frames).
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
    source, out_dir = Path(source), Path(out_dir)
    camera = calibration.camera
    total, damaged = _frames_to_track(source, allow_damaged)
    if isinstance(start_frame, bool) or not isinstance(start_frame, int) or start_frame < 0:
        raise ValueError(f"the start frame must be a non-negative integer, got {start_frame!r}")
    if total == 0:
        raise ValueError(f"{source} has no frames")
    if start_frame >= total:
        raise ValueError(f"start frame {start_frame} is past the end of {source} ({total} frames)")
    if max_frames is not None:
        if max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {max_frames}")
        total = min(total, start_frame + max_frames)
    first = next(iter_frames(source, start_frame, start_frame + 1))
    if first.shape[:2] != camera.shape:
        raise ValueError(f"frames are {first.shape[1]}x{first.shape[0]} but the calibration's camera is "
                         f"{camera.width}x{camera.height}: calibrate for this video (python -m mocap calibrate)")
    bg_image = None
    if background is not None:
        background = Path(background)
        bg_image = read_image(background)
        if bg_image.shape != first.shape:
            raise ValueError(f"background {background} is {bg_image.shape[1]}x{bg_image.shape[0]}, frames are "
                             f"{first.shape[1]}x{first.shape[0]}")
    gt = PoseTable.read(ground_truth) if ground_truth is not None else None

    resolution = config.mesh_resolution or resolution_for_image(camera.width, camera.height)
    model = calibration.body_model(resolution)
    settings = _settings(source, background, calibration, config, imaging, colour, resolution)
    settings["start_frame"] = start_frame
    out_dir.mkdir(parents=True, exist_ok=True)
    journal, run_json = out_dir / "poses.csv", out_dir / "run.json"
    checkpoint = _previous_run(journal, run_json, settings, overwrite)

    colour_model, colour_frame = _learn_colours(source, start_frame, total, bg_image, model, camera,
                                                calibration.initial_pose, imaging, colour)
    colour_model.to_json(out_dir / "colour_model.json")
    model = model.with_class_names(colour_model.names)        # classes the first frame supports

    tracker = Tracker(model, camera, config, calibration.initial_pose)
    state_path = out_dir / STATE_FILE
    start = start_frame
    if checkpoint is not None:
        start = checkpoint.next_index
        tracker.restore(checkpoint.state)
    else:
        write_text_atomic(run_json, json.dumps({"status": "running", "settings": settings}, indent=2))
    started = time.perf_counter()
    results_ms: collections.deque[float] = collections.deque(maxlen=25)   # for the frame rate shown
    bar = tqdm(total=total, initial=start, desc="tracking", unit="frame", disable=not progress)
    try:
        for index, frame in enumerate(iter_frames(source, start, total), start=start):
            prepared = prepare_frame(frame, bg_image, colour_model, imaging)
            for result in tracker.push(index, prepared):
                _frame_row(result).append_to(journal)
                results_ms.append(result.timings_ms["total"])
                bar.set_postfix(fps=f"{1e3 / np.mean(results_ms):.0f}", F=f"{result.region_residual:.2f}",
                                D=f"{result.edge_residual:.1f}")
            write_checkpoint(state_path, tracker.state(), index + 1, journal)
            bar.update(1)
        # the held-back frames: not checkpointed, a resume continues from the last push instead
        for result in tracker.finish():
            _frame_row(result).append_to(journal)
    finally:
        bar.close()
    table = PoseTable.read(journal)     # (not rewritten: the checkpoint records its length)
    return _finish(out_dir, table, settings, source, model, calibration, camera, gt, fps, start,
                   time.perf_counter() - started, write_overlay, bg_image, damaged=damaged,
                   colour_frame=colour_frame)


#: Fraction of the calibrated model's silhouette (pixels) the foreground must cover for a frame to
#: be taken as showing the person, to learn the colours on.
PLAUSIBLE_FOREGROUND = 0.5


def _learn_colours(source: Path, first: int, stop: int, bg_image, model, camera, pose, imaging,
                   colour: str) -> tuple[ColourModel, int]:
    """Colour model from the first frame in ``first``..``stop - 1`` that shows the person, and that
    frame's number; ValueError (with the last frame's reason) when none does."""
    from mocap.imaging import subtract_background
    from mocap.render import render

    silhouette = np.count_nonzero(render(pose, model, camera).labels)
    reason = "no frame"
    for index, frame in enumerate(iter_frames(source, first, stop), start=first):
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
    raise ValueError(f"no frame of {source} from frame {first} shows the person to learn the colours from "
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
            write_overlay, bg_image, *, damaged: list[int], colour_frame: int) -> RunSummary:
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
        _overlay_video(out_dir / "overlay.mp4", source, table, model, camera, fps)
    write_text_atomic(out_dir / "run.json", json.dumps(run, indent=2))
    return RunSummary(out_dir, tracked, start, run["fps"], metrics, failures, tuple(damaged))


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


def _overlay_video(path: Path, source: Path, table: PoseTable, model, camera, fps: float) -> None:
    from mocap.io.overlay import draw_model
    from mocap.io.video import VideoWriter
    from mocap.render import render

    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    poses = {int(f): p for f, p in zip(table.frames, table.poses)}
    with VideoWriter(tmp, fps) as video:
        for index, frame in enumerate(iter_frames(source, 0, int(table.frames.max()) + 1)):
            if index in poses:
                r = render(poses[index], model, camera)
                frame = draw_model(frame, r.labels, r.edges, model.n_classes, class_names=model.class_names)
            video.write(frame)
    os.replace(tmp, path)
