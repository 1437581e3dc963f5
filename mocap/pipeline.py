"""Track a whole video: frames in; ``poses.csv``, ``poses.bvh``, ``overlay.mp4``,
``residuals.png`` and ``run.json`` out (docs/design.md sections 3–4): the run loop; the
outputs are :mod:`mocap.io.run_outputs`'s.

Frames are decoded, reduced to the working resolution and prepared on a reader thread
(:mod:`mocap.io.prefetch`) :data:`READ_AHEAD` frames ahead of the tracker. ``poses.csv`` is a
journal: every finished frame is appended at once, and every :data:`CHECKPOINT_EVERY` frames
(and after the last) the tracker's exact state is saved with the journal length it belongs to,
the journal synced to disk first (:mod:`mocap.io.checkpoint`), so an interrupted run — even
killed at any instant — resumes with the same command from the last checkpoint (the rows after
it are cut off and done again) and gives bit for bit the poses of an uninterrupted run (the
settings must be the same; they are kept in ``run.json``). One run at a time may write to an output folder
(:mod:`mocap.io.lock`). The other outputs are written atomically at the end.
"""
from __future__ import annotations

import collections
import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mocap.calibrate import Calibration, colour_model_from_pose
from mocap.imaging import ColourModel, ImagingConfig, learn_colour_model, prepare_frame
from mocap.io.atomic import write_text_atomic
from mocap.io.checkpoint import Checkpoint, read_checkpoint, truncate_journal, write_checkpoint
from mocap.io.frames import VideoSource
from mocap.io.lock import one_writer
from mocap.io.pose_table import PoseTable
from mocap.io.prefetch import prefetch
from mocap.io.run_outputs import OverlayWriter, RunSummary, finish_run, frame_row
from mocap.io.video import read_image
from mocap.track import FrameResult, Tracker, TrackerConfig

__all__ = ["RunSetup", "RunSummary", "track_video", "STATE_FILE"]


COLOUR_SOURCES = ("calibration", "face")
#: Mean brightness (0-255) below which a frame counts as very dark (column ``dark`` of ``poses.csv``).
DARK_MEAN = 20.0


@dataclass(frozen=True, eq=False)
class RunSetup:
    """What a run needs besides its frames: everything at the working resolution.

    Attributes
    ----------
    calibration : Calibration
        Actor dimensions, initial pose and the camera at the working resolution (the input
        frames reduced by ``factor``: :meth:`mocap.render.Camera.working`).
    background : ndarray of uint8, shape (h, w, 3), or None
        The empty scene at the working resolution; None: colour-only foreground.
    factor : int
        Input pixels per working pixel (:func:`mocap.imaging.resample.downscale`).
    imaging : ImagingConfig
    colour_model : ColourModel or None
        Colour classes to use as they are; None: learnt on the first frame that shows the
        person, the way ``colour_from`` says.
    colour_from : {"calibration", "face"}
        Learn the colour classes inside the calibrated model's projected parts, or from the
        detected face and a box under it (the paper's way).
    scene : mocap.imaging.scene.SceneColours or None
        The scene's colours, for a foreground without background (:func:`mocap.imaging.prepare_frame`).
    record : dict or None
        How background and calibration were found (:mod:`mocap.own_video`), kept in
        ``run.json`` (``settings.own_video``).
    background_file : Path or None
        The file the background came from, for ``run.json``.
    """

    calibration: Calibration
    background: np.ndarray | None = None
    factor: int = 1
    imaging: ImagingConfig = field(default_factory=ImagingConfig)
    colour_model: ColourModel | None = None
    colour_from: str = "calibration"
    scene: object = None
    record: dict | None = None
    background_file: Path | None = None

    @classmethod
    def from_files(cls, calibration: Calibration | str | Path, background: str | Path | None = None,
                   colour_from: str = "calibration") -> "RunSetup":
        """The paper's set-up at the input resolution: a calibration (or its JSON file) and an
        image of the empty scene (or none)."""
        if not isinstance(calibration, Calibration):
            calibration = Calibration.from_json(calibration)
        image = None if background is None else read_image(background)
        return cls(calibration, image, colour_from=colour_from,
                   background_file=None if background is None else Path(background))


def _settings(source: str, background: Path | None, calibration: Calibration, config: TrackerConfig,
              imaging: ImagingConfig, colour: str, resolution: int) -> dict:
    source = str(Path(source).resolve()) if Path(source).exists() else source
    return {"source": source, "background": str(background.resolve()) if background else None,
            "calibration": calibration.to_dict(), "tracker": config.to_dict(), "imaging": imaging.to_dict(),
            "colour_model_from": colour, "mesh_resolution": resolution}


@one_writer("out_dir")
def track_video(source, setup: RunSetup, out_dir: str | Path, config: TrackerConfig | None = None, *,
                ground_truth: str | Path | None = None, fps: float = 25.0, max_frames: int | None = None,
                overwrite: bool = False, progress: bool = True, write_overlay: bool = True,
                allow_damaged: bool = False, start_frame: int = 0, show: bool = False,
                newcomer: Callable[[int, np.ndarray], RunSetup | None] | None = None,
                keypoints=None) -> RunSummary:
    """Track every frame of a video or image folder and write the outputs.

    Parameters
    ----------
    source : path or frame source
        Video file or folder of images, or a :mod:`mocap.io.frames` source (a camera).
    setup : RunSetup
        Calibration, background, working resolution, colours (:mod:`mocap.own_video` finds
        them for a person's own video; :meth:`RunSetup.from_files` for the paper's set-up).
    out_dir : path
        Output folder (created), locked for the run. If it holds an unfinished run with the
        same settings, the run resumes exactly where it stopped.
    config : TrackerConfig, optional
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
        The colours, unless given, are learnt on the first frame from there that shows the
        person: whose foreground covers at least :data:`PLAUSIBLE_FOREGROUND` of the model's
        silhouette, or where a face is detected (``run.json``: ``colour_model_frame``).
    show : bool
        Show the overlay live in a window (needs a display).
    newcomer : callable, optional
        People change: once nobody has been in view for :data:`PERSON_GONE_FRAMES` frames, it is
        called with ``(index, input-size frame)`` of every third frame that shows someone until
        it returns a set-up: that set-up (a new person's calibration, colours and scene:
        :func:`mocap.own_video.newcomer_finder`) ends the segment and starts a new one with a
        fresh tracker. Segments go to ``run.json`` (``segments``) and the ``segment`` column
        of ``poses.csv``. It must give the same answer for the same frame (a resumed run asks
        again).
    keypoints : KeypointSource, optional
        2D keypoints of each frame (:mod:`mocap.io.keypoints`: a file, MediaPipe), asked on the
        input-resolution frame and given to the tracker in working pixels (``config``'s
        ``keypoint_weight``); ``run.json`` records the source and its time per frame.

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
        Missing video or ground truth.
    mocap.io.lock.FolderInUseError
        Another run writes to ``out_dir``.
    """
    from tqdm import tqdm

    from mocap.body.mesh import resolution_for_image
    from mocap.imaging.resample import downscale

    config = TrackerConfig() if config is None else config
    imaging, work_factor = setup.imaging, setup.factor
    if setup.colour_from not in COLOUR_SOURCES:
        raise ValueError(f"colour must be one of {COLOUR_SOURCES}, got {setup.colour_from!r}")
    frames_in = source if hasattr(source, "frames") else VideoSource(source, fps=fps)
    out_dir = Path(out_dir)
    if isinstance(start_frame, bool) or not isinstance(start_frame, int) or start_frame < 0:
        raise ValueError(f"the start frame must be a non-negative integer, got {start_frame!r}")
    # a file's damage check decodes it alongside the run (VideoSource): its verdict is taken as
    # soon as it is known and at the latest before the outputs are finished (verdict())
    damaged: list[int] | None = [] if frames_in.live else None
    total = frames_in.count if frames_in.live or frames_in.checked else None
    if not frames_in.live:
        if frames_in.checked:
            damaged = frames_in.damaged_frames(allow_damaged)
        if start_frame >= frames_in.count_hint and start_frame >= frames_in.count:
            raise ValueError(f"start frame {start_frame} is past the end of {frames_in.name} "
                             f"({frames_in.count} frames)")
    if max_frames is not None:
        if max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {max_frames}")
        total = start_frame + max_frames if total is None else min(total, start_frame + max_frames)
    camera = setup.calibration.camera
    if camera.working(frames_in.width, frames_in.height, work_factor) is not camera:
        raise ValueError(f"the calibration's camera is {camera.width}x{camera.height}, the input size: the run "
                         f"needs it at the working size (Camera.working)")
    bg_image = setup.background
    if bg_image is not None and bg_image.shape != (*camera.shape, 3):
        raise ValueError(f"background is {bg_image.shape[1]}x{bg_image.shape[0]}, working frames are "
                         f"{camera.width}x{camera.height}")
    gt = PoseTable.read(ground_truth) if ground_truth is not None else None

    calibration = setup.calibration
    resolution = config.mesh_resolution or resolution_for_image(camera.width, camera.height)
    model = calibration.body_model(resolution)
    settings = _settings(frames_in.name, setup.background_file, calibration, config, imaging, setup.colour_from,
                         resolution)
    settings["working_resolution"] = {"factor": work_factor, "width": camera.width, "height": camera.height,
                                      "input_width": frames_in.width, "input_height": frames_in.height}
    if setup.record is not None:
        settings["own_video"] = setup.record
    settings["start_frame"] = start_frame
    settings["keypoints"] = "none" if keypoints is None else getattr(keypoints, "description",
                                                                     type(keypoints).__name__)
    to_working = (camera.width / frames_in.width, camera.height / frames_in.height)
    out_dir.mkdir(parents=True, exist_ok=True)
    journal, run_json = out_dir / "poses.csv", out_dir / "run.json"
    checkpoint = _previous_run(journal, run_json, settings, overwrite)

    colour_frame = None
    colour_model = setup.colour_model
    if colour_model is None:
        if frames_in.live:
            raise ValueError("a live source needs its colour model given")
        colour_model, colour_frame = _learn_colours(
            ((i, downscale(f, work_factor)) for i, f in enumerate(frames_in.frames(start_frame, total),
                                                                 start=start_frame)),
            frames_in.name, bg_image, model, camera, calibration.initial_pose, imaging, setup.colour_from)
    colour_model.to_json(out_dir / "colour_model.json")
    model = model.with_class_names(colour_model.names)        # classes the first frame supports

    # people: the segments (one per person), frames in a row with nobody in view, the last with someone
    people = {"segments": [_segment_record(start_frame, calibration, colour_model, None)], "absent": 0,
              "last_seen": start_frame - 1, "vacant": False}
    person = (model, colour_model, setup.scene, calibration)
    state_path = out_dir / STATE_FILE
    start = start_frame
    if checkpoint is not None:
        if frames_in.live:
            raise ValueError(f"{out_dir} holds a run; a live source cannot resume it: use --overwrite or another --out")
        start = checkpoint.next_index
        state = dict(checkpoint.state)
        pending_dark = state.pop(PENDING_DARK, np.zeros((0, 2), np.int64))
        people = json.loads(str(state.pop(PEOPLE, np.array(json.dumps(people)))))
        if len(people["segments"]) > 1:      # the person of the last segment, found again as before
            first = people["segments"][-1]["first_frame"]
            found = None if newcomer is None else newcomer(first, next(frames_in.frames(indices=[first])))
            if found is None:
                raise ValueError(f"{out_dir}: the person found on frame {first} is not found again; start afresh "
                                 "with --overwrite")
            person = _person(found, config, resolution)
    tracker = Tracker(person[0], camera, config, person[3].initial_pose)
    if checkpoint is not None:
        tracker.restore(state)
    else:
        write_text_atomic(run_json, json.dumps({"status": "running", "settings": settings}, indent=2))
    started = time.perf_counter()
    results_ms: collections.deque[float] = collections.deque(maxlen=25)   # for the frame rate shown
    # the overlay is drawn as frames come (no second decoding pass) unless an earlier session's
    # frames must be in it too (a resumed file run redraws it whole at the end)
    overlay_now = frames_in.live or (write_overlay and start == start_frame)
    live = OverlayWriter(out_dir, fps, person[0], camera, show=show, write=overlay_now) \
        if (overlay_now or show) else None
    pending: dict[int, np.ndarray] = {}
    # dark flags of the frames pushed but not decided yet (kept in the checkpoint with the tracker)
    dark: dict[int, bool] = {} if checkpoint is None else {int(f): bool(v) for f, v in pending_dark}
    expected = total if total is not None or frames_in.live else frames_in.count_hint
    if max_frames is not None and expected is not None:
        expected = min(expected, start_frame + max_frames)
    bar = tqdm(total=None if expected is None else expected - start_frame, initial=start - start_frame,
               desc="tracking", unit="frame", disable=not progress)
    made = [] if checkpoint is not None else [journal, run_json, state_path, out_dir / "colour_model.json",
                                              out_dir / "overlay.mp4"]

    def verdict(wait: bool) -> None:
        """The damage check's verdict, once: a damaged video stops the run unless allowed (what
        this run wrote is removed: a refused video leaves no results)."""
        nonlocal damaged
        if damaged is not None or not (wait or frames_in.checked):
            return
        try:
            damaged = frames_in.damaged_frames(allow_damaged)
        except ValueError:
            if live is not None:
                live.close()
            for path in made:
                path.unlink(missing_ok=True)
            raise
    interrupted = False

    clock = time.perf_counter()
    every = CHECKPOINT_EVERY

    # the colours the frames are prepared with: (segment, colour model, scene), replaced whole
    # when a new person comes (frames the reader prepared before are prepared again)
    colours = [(len(people["segments"]) - 1, person[1], person[2])]

    def read():
        """Decoded, reduced and prepared frames (on the reader thread, ahead of the tracker)."""
        for index, frame in enumerate(frames_in.frames(start, total), start=start):
            # a live source's frame time is when it came; a file's its own timestamp
            when = time.perf_counter() - clock if frames_in.live else frames_in.time_s(index)
            small = downscale(frame, work_factor)
            segment, colour, scene = colours[0]
            seen = None if keypoints is None else keypoints.keypoints(index, frame).scaled(*to_working)
            yield index, when, bool(small.mean() < DARK_MEAN), small, segment, \
                prepare_frame(small, bg_image, colour, imaging, scene=scene), frame if newcomer else None, seen

    times: dict[int, float] = {}         # a live source's frame times, until the frames are decided

    def emit(results: list[FrameResult]) -> None:
        for result in results:
            when = times.pop(result.frame) if frames_in.live else frames_in.time_s(result.frame)
            frame_row(result, camera, work_factor, dark.pop(result.frame, None), when,
                      len(people["segments"]) - 1).append_to(journal, sync=False)
            results_ms.append(result.timings_ms["total"])
            frame = pending.pop(result.frame, None)
            if live is not None and frame is not None:
                live.update(frame, result.pose)
            bar.set_postfix(fps=f"{1e3 / np.mean(results_ms):.0f}", F=f"{result.region_residual:.2f}",
                            D=f"{result.edge_residual:.1f}")

    def checkpoint_before(next_index: int) -> None:
        write_checkpoint(state_path, {**tracker.state(), PENDING_DARK: np.array(sorted(dark.items()),
                                                                                 np.int64).reshape(-1, 2),
                                      PEOPLE: np.array(json.dumps(people))}, next_index, journal)

    last = None
    try:
        for index, when, is_dark, small, segment, prepared, frame, seen in prefetch(read, READ_AHEAD,
                                                                                     name="mocap-reader"):
            dark[index] = is_dark
            if frames_in.live:
                times[index] = when
            if live is not None:
                pending[index] = small
            if segment != len(people["segments"]) - 1:           # prepared with the last person's colours
                prepared = prepare_frame(small, bg_image, colours[0][1], imaging, scene=colours[0][2])
            if newcomer is not None and people["vacant"] and not prepared.is_empty and index % 3 == 0:
                found = newcomer(index, frame)
                if found is not None:                           # someone new: a segment of their own
                    emit(tracker.finish())
                    people["vacant"] = False
                    person = _person(found, config, resolution)
                    people["segments"].append(_segment_record(index, person[3], person[1], found.record))
                    colours[0] = (len(people["segments"]) - 1, person[1], person[2])
                    tracker = Tracker(person[0], camera, config, person[3].initial_pose)
                    if live is not None:
                        live.model = person[0]
                    prepared = prepare_frame(small, bg_image, person[1], imaging, scene=person[2])
            del frame
            emit(tracker.push(index, prepared, seen))        # seen: the frame's keypoints, if any
            if prepared.is_empty:
                people["absent"] += 1
                seen = people["last_seen"] >= people["segments"][-1]["first_frame"]
                if people["absent"] == PERSON_GONE_FRAMES and seen and not people["vacant"]:   # the person left
                    people["vacant"] = True
                    people["segments"][-1]["last_frame"] = people["last_seen"]
            else:
                people["absent"], people["last_seen"] = 0, index
            verdict(wait=False)
            if (index + 1) % every == 0 or index + 1 == total:
                checkpoint_before(index + 1)
            bar.update(1)
            last = index
        verdict(wait=True)
        if total is None and last is not None and (last + 1) % every != 0:     # the checkpoint after the last
            checkpoint_before(last + 1)
        # the held-back frames: not checkpointed, a resume continues from the last checkpoint instead
        emit(tracker.finish())
    except ValueError:
        verdict(wait=True)              # a damaged video's reader may fail first: the damage is the reason
        raise
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
    redraw = write_overlay and not overlay_now
    overlay_frames = ((i, downscale(f, work_factor)) for i, f in
                      enumerate(frames_in.frames(0, int(table.frames.max()) + 1))) if redraw else None
    if not people["vacant"]:
        people["segments"][-1]["last_frame"] = people["last_seen"]
    models = [Calibration.from_dict(seg["calibration"]).body_model(resolution)
              .with_class_names(tuple(seg["colour_classes"])) for seg in people["segments"]]
    summary = finish_run(out_dir, table, settings, calibration=calibration, camera=camera, ground_truth=gt, fps=fps,
                         start=start, wall_s=time.perf_counter() - started, damaged=damaged, colour_frame=colour_frame,
                         overlay_frames=overlay_frames, models=models, extra_run={"segments": people["segments"]})
    detector_ms = getattr(keypoints, "milliseconds", None)
    if detector_ms:         # the detector's own time per frame, beside the tracker's ms_total
        from mocap.io.jsonfile import read_json, write_json
        write_json(run_json, {**read_json(run_json), "keypoints_ms_per_frame": float(np.median(detector_ms))})
    return summary


def _segment_record(first_frame: int, calibration: Calibration, colour_model: ColourModel,
                    found: dict | None) -> dict:
    """A segment of ``run.json``: its frames, the person's calibration, colours and how found."""
    return {"first_frame": int(first_frame), "last_frame": None, "calibration": calibration.to_dict(),
            "colour_classes": list(colour_model.names), "found": found}


def _person(setup: RunSetup, config: TrackerConfig, resolution: int):
    """(body model, colour model, scene, calibration) of a new person's set-up."""
    if setup.colour_model is None:
        raise ValueError("a new person's set-up needs its colour model")
    model = setup.calibration.body_model(resolution).with_class_names(setup.colour_model.names)
    return model, setup.colour_model, setup.scene, setup.calibration


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


#: Frames between two checkpoints (and after the last frame of a file): a resumed run redoes at
#: most this many frames (the journal is cut back to the checkpoint), bit for bit the same.
CHECKPOINT_EVERY = 25
#: Frames decoded, reduced and prepared ahead of the tracker on the reader thread.
READ_AHEAD = 4
#: Frames in a row with nobody in view after which the tracked person has left: the next person
#: seen is calibrated afresh (``newcomer`` of :func:`track_video`).
PERSON_GONE_FRAMES = 10
#: Checkpoint entry holding the people's bookkeeping (segments, JSON text).
PEOPLE = "run_people"
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
