"""The run loop: frames and a :class:`~mocap.run.setup.RunSetup` in; ``poses.csv`` (a journal),
the checkpoint, ``overlay.mp4`` and, at the end, the outputs of :mod:`mocap.run.outputs` out
(docs/design.md sections 3-4).

Frames are decoded, reduced to the working resolution and prepared on a reader thread
(:class:`FrameReader`, :mod:`mocap.io.prefetch`) :data:`READ_AHEAD` frames ahead of the
tracker. Every finished frame is appended to ``poses.csv`` at once, and every
:data:`mocap.run.journal.CHECKPOINT_EVERY` frames (and after the last) the tracker's exact state
is saved with the journal length it belongs to (:mod:`mocap.run.journal`), so an interrupted
run — even killed at any instant — resumes with the same command from the last checkpoint and
gives bit for bit the poses of an uninterrupted run (the settings must be the same; they are
kept in ``run.json``). One run at a time may write to an output folder (:mod:`mocap.io.lock`).
A file's damage check decodes it alongside the run (:class:`DamageCheck`); people changing
start new segments (:class:`mocap.run.journal.People`). The progress bar is drawn from the
check's verdict on (:meth:`RunLoop.advance`): a refused video's run writes its one-line refusal
to stderr and nothing else, however fast the frames come.
"""
from __future__ import annotations

import collections
import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from itertools import chain, pairwise
from pathlib import Path

import numpy as np

import mocap.run.journal as journalling
from mocap._progress import ProgressBar
from mocap.body import BodyModel
from mocap.calibrate import Calibration
from mocap.io.files import write_text_atomic
from mocap.imaging import ColourModel, PreparedFrame, prepare_frame
from mocap.imaging.resample import downscale
from mocap.imaging.scene import SceneColours
from mocap.io.frames import VideoSource
from mocap.io.keypoint_pipeline import DETECT_AHEAD, KeypointPipeline
from mocap.io.keypoints import KeypointSource, Keypoints
from mocap.io.lock import one_writer
from mocap.io.pose_table import PoseTable
from mocap.io.prefetch import newest, prefetch
from mocap.run import files
from mocap.run.colours import learn_colours
from mocap.run.journal import Journal, People, Resumed, previous_run
from mocap.run.outputs import FinishedRun, RunSummary, finish_run, frame_row
from mocap.run.options import OwnVideoOptions, RunChoices
from mocap.run.overlay import OverlayGeometry, OverlayWriter, redraw_overlay
from mocap.run.setup import RunSetup
from mocap.track import FrameResult, Tracker

__all__ = ["DARK_MEAN", "READ_AHEAD", "RunParams", "track_frames"]

#: Mean brightness (0-255) below which a frame counts as very dark (column ``dark`` of ``poses.csv``).
DARK_MEAN = 20.0
#: Frames decoded, reduced and prepared ahead of the tracker on the reader thread.
READ_AHEAD = 4


@dataclass(frozen=True, eq=False, kw_only=True)
class RunParams:
    """How to run (:func:`track_frames`): the :class:`~mocap.run.options.OwnVideoOptions` and
    :class:`~mocap.run.options.RunChoices` the run was made from, as they are, and what the
    input or the caller adds.

    Attributes
    ----------
    options : OwnVideoOptions
        Read as they are: ``tracker``, ``start`` (the calibration's initial pose is the pose
        there), ``max_frames``, ``overwrite``, ``overlay``, ``show``, ``allow_damaged`` (a
        damaged video's frame numbers go to ``run.json``).
    choices : RunChoices or None
        What the options mean here (the keypoint source); None: :meth:`RunChoices.of`
        ``options``.
    ground_truth : str, Path or None
        ``ground_truth.csv``: adds the ``metrics`` object to ``run.json`` (the options' or a
        sequence folder's: :class:`mocap.run.tracking.RunInput`).
    fps : float, frames per second
        Frame rate of the output video and BVH.
    progress : bool
        Show a progress bar.
    newcomer : callable or None
        People change (:class:`mocap.run.person.NewcomerFinder`): once nobody has been in view
        for :data:`mocap.run.journal.PERSON_GONE_FRAMES` frames, it is called with ``(index,
        input-size frame)`` of every third frame that shows someone until it returns a set-up,
        which starts a new segment with a fresh tracker. The same frame must give the same answer.
    detect_ahead : int
        Frames the keypoint source may work ahead, in its own process or on a thread of its own
        (:class:`~mocap.io.keypoint_pipeline.KeypointPipeline`); 0 asks it on the reader thread,
        frame by frame. The outputs are the same either way (timings aside).
    """

    options: OwnVideoOptions = field(default_factory=OwnVideoOptions)
    choices: RunChoices | None = None
    ground_truth: str | Path | None = None
    fps: float = 25.0
    progress: bool = True
    newcomer: Callable[[int, np.ndarray], RunSetup | None] | None = None
    detect_ahead: int = DETECT_AHEAD

    def __post_init__(self) -> None:
        if self.choices is None:
            object.__setattr__(self, "choices", RunChoices.of(self.options))

    @property
    def keypoints(self) -> KeypointSource | None:
        """``choices.keypoint_source``: 2D keypoints of each frame (:mod:`mocap.io.keypoints`),
        asked on the input-size frame and given to the tracker in working pixels."""
        return self.choices.keypoint_source


@dataclass(frozen=True, eq=False)
class Person:
    """The tracked person: body model (with their colour classes), colours, scene, calibration."""

    model: BodyModel
    colour_model: ColourModel
    scene: SceneColours | None
    calibration: Calibration

    @classmethod
    def of_setup(cls, setup: RunSetup, resolution: int) -> "Person":
        """A new person's (their set-up must have its colour model)."""
        if setup.colour_model is None:
            raise ValueError("a new person's set-up needs its colour model")
        model = setup.calibration.body_model(resolution).with_class_names(setup.colour_model.names)
        return cls(model, setup.colour_model, setup.scene, setup.calibration)


@dataclass(frozen=True, eq=False)
class ReadFrame:
    """A frame as the reader thread hands it to the tracker.

    Attributes
    ----------
    index : int
    time_s : float, seconds
        A file's own timestamp; a live frame's arrival time.
    dark : bool
        Mean brightness under :data:`DARK_MEAN`.
    small : ndarray of uint8, shape (h, w, 3)
        Working size.
    segment : int
        The person whose colours ``prepared`` was made with.
    prepared : PreparedFrame
    full : ndarray of uint8, shape (H, W, 3), or None
        Input size, for a newcomer's calibration (None without one).
    picture : ndarray of uint8 or None
        At the overlay's size (None without an overlay).
    keypoints : Keypoints or None
        In working pixels.
    detected : Keypoints or None
        The same in input pixels, as the source gave them (for ``keypoints.csv``).
    """

    index: int
    time_s: float
    dark: bool
    small: np.ndarray
    segment: int
    prepared: PreparedFrame
    full: np.ndarray | None
    picture: np.ndarray | None
    keypoints: Keypoints | None
    detected: Keypoints | None


@dataclass(frozen=True, eq=False)
class Colours:
    """The colours the reader prepares frames with (replaced whole when a new person comes)."""

    segment: int
    model: ColourModel
    scene: SceneColours | None


@dataclass(frozen=True, eq=False)
class Span:
    """The frames of this session: ``start`` to ``stop - 1`` (``stop`` None: to the end) and the
    progress bar's ``expected`` end (None: unknown)."""

    first: int
    start: int
    stop: int | None
    expected: int | None


class FrameReader:
    """Decoded, reduced and prepared frames (:class:`ReadFrame`) on the reader thread."""

    def __init__(self, frames_in, setup: RunSetup, span: Span, colours: Colours, *, keypoints, full: bool,
                 overlay: OverlayGeometry | None, detect_ahead: int = DETECT_AHEAD) -> None:
        self.frames_in, self.setup, self.span, self.colours = frames_in, setup, span, colours
        self.keypoints, self.full, self.overlay, self.detect_ahead = keypoints, full, overlay, detect_ahead
        camera = setup.calibration.camera
        self.to_working = (camera.width / frames_in.width, camera.height / frames_in.height)
        self.clock = time.perf_counter()

    def prepare(self, small: np.ndarray) -> PreparedFrame:
        """A working-size frame prepared with the current person's colours."""
        return prepare_frame(small, self.setup.background, self.colours.model, self.setup.imaging,
                             scene=self.colours.scene)

    def __call__(self):
        """The frames, each with its keypoints when there is a source: the detector works beside
        this thread (:class:`~mocap.io.keypoint_pipeline.KeypointPipeline`: MediaPipe in a
        process of its own, another source on a thread), given each frame as it is decoded,
        while this thread prepares the frames; a frame is handed on once its keypoints are back
        (:data:`~mocap.io.keypoint_pipeline.DETECT_AHEAD` frames behind the newest decoded one at
        most)."""
        frames_in = self.frames_in
        # live, the detector works beside this thread on one frame: frames ahead would be frames late
        ahead = min(self.detect_ahead, 1) if frames_in.live else self.detect_ahead
        pipeline = None if self.keypoints is None or ahead == 0 else KeypointPipeline(self.keypoints, ahead)
        waiting: collections.deque[ReadFrame] = collections.deque()
        start, stop = self.span.start, self.span.stop
        camera = None
        if frames_in.live and frames_in.real_time:     # the newest frame each time (drops the ones it is too slow for)
            camera = newest(lambda: frames_in.frames(start, stop), name="mocap-camera")
            arrivals = ((start + a.position, a.time_s - self.clock, a.item) for a in camera)
        else:       # a file's frame time is its own timestamp; a replayed one's when it came
            arrivals = ((index, self.arrived(index), frame)
                        for index, frame in enumerate(frames_in.frames(start, stop), start=start))
        try:
            for index, when, frame in arrivals:
                if pipeline is not None:
                    if pipeline.pending == pipeline.depth:
                        yield self._with_keypoints(waiting.popleft(), pipeline)
                    pipeline.submit(index, frame)
                small = downscale(frame, self.setup.factor)
                colours = self.colours
                prepared = prepare_frame(small, self.setup.background, colours.model, self.setup.imaging,
                                         scene=colours.scene)
                read = ReadFrame(index, when, bool(small.mean() < DARK_MEAN), small, colours.segment, prepared,
                                 frame if self.full else None,
                                 None if self.overlay is None else self.overlay.frame(frame), None, None)
                if pipeline is None:
                    yield read if self.keypoints is None else self._detected(read, self.keypoints.keypoints(index, frame))
                else:
                    waiting.append(read)
            while waiting:
                yield self._with_keypoints(waiting.popleft(), pipeline)
        finally:
            arrivals.close()
            if camera is not None:
                camera.close()
            if pipeline is not None:
                pipeline.close()

    def arrived(self, index: int) -> float:
        """Frame ``index``'s time (seconds): a file's own timestamp, a live frame's arrival now."""
        return time.perf_counter() - self.clock if self.frames_in.live else self.frames_in.time_s(index)

    def _with_keypoints(self, read: ReadFrame, pipeline: KeypointPipeline) -> ReadFrame:
        """``read`` with its keypoints from the pipeline."""
        return self._detected(read, pipeline.take(read.index))

    def _detected(self, read: ReadFrame, detected: Keypoints) -> ReadFrame:
        """``read`` with the keypoints the source gave (input pixels) and the same in working pixels."""
        return replace(read, keypoints=detected.scaled(*self.to_working), detected=detected)


class DamageCheck:
    """The damage check's verdict, taken once: a damaged video stops the run unless allowed
    (what this run wrote is removed: a refused video leaves no results)."""

    def __init__(self, frames_in, allow_damaged: bool, made: list[Path]) -> None:
        self.frames_in, self.allow_damaged, self.made = frames_in, allow_damaged, made
        self.damaged: list[int] | None = [] if frames_in.live else None
        self.overlay: OverlayWriter | None = None
        if not frames_in.live and frames_in.checked:
            self.damaged = frames_in.damaged_frames(allow_damaged)

    def take(self, wait: bool) -> None:
        """Take the verdict if known (``wait``: wait for it)."""
        if self.damaged is not None or not (wait or self.frames_in.checked):
            return
        try:
            self.damaged = self.frames_in.damaged_frames(self.allow_damaged)
        except ValueError:
            if self.overlay is not None:
                self.overlay.close()
            for path in self.made:
                path.unlink(missing_ok=True)
            raise


def _span(frames_in, params: RunParams) -> tuple[int | None, int | None]:
    """The last frame (exclusive) to track and the progress bar's expected end, or None."""
    start_frame, max_frames = params.options.start, params.options.max_frames
    total = frames_in.count if frames_in.live or frames_in.checked else None
    if not frames_in.live and start_frame >= frames_in.count_hint and start_frame >= frames_in.count:
        raise ValueError(f"start frame {start_frame} is past the end of {frames_in.name} "
                         f"({frames_in.count} frames)")
    if max_frames is not None:
        if max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {max_frames}")
        total = start_frame + max_frames if total is None else min(total, start_frame + max_frames)
    expected = total if total is not None or frames_in.live else frames_in.count_hint
    if max_frames is not None and expected is not None:
        expected = min(expected, start_frame + max_frames)
    return total, expected


def _check_sizes(frames_in, setup: RunSetup) -> None:
    camera = setup.calibration.camera
    if camera.working(frames_in.width, frames_in.height, setup.factor) is not camera:
        raise ValueError(f"the calibration's camera is {camera.width}x{camera.height}, the input size: the run "
                         f"needs it at the working size (Camera.working)")
    if setup.background is not None and setup.background.shape != (*camera.shape, 3):
        raise ValueError(f"background is {setup.background.shape[1]}x{setup.background.shape[0]}, working frames "
                         f"are {camera.width}x{camera.height}")


def run_settings(frames_in, setup: RunSetup, params: RunParams, resolution: int) -> dict:
    """``run.json`` ``settings``: what a resumed run must share with the run it resumes."""
    source = frames_in.name
    source = str(Path(source).resolve()) if Path(source).exists() else source
    camera, background = setup.calibration.camera, setup.background_file
    settings = {"format": journalling.SETTINGS_FORMAT, "source": source, "background": str(background.resolve()) if background else None,
                "calibration": setup.calibration.to_dict(), "tracker": params.options.tracker.to_dict(),
                "imaging": setup.imaging.to_dict(), "colour_model_from": setup.colour_from,
                "mesh_resolution": resolution,
                "working_resolution": {"factor": setup.factor, "width": camera.width, "height": camera.height,
                                       "input_width": frames_in.width, "input_height": frames_in.height}}
    if setup.record is not None:
        settings["own_video"] = setup.record.to_dict()
    settings["start_frame"] = params.options.start
    settings["keypoints"] = "none" if params.keypoints is None else getattr(params.keypoints, "description",
                                                                            type(params.keypoints).__name__)
    return settings


class RunLoop:
    """One session of a run in an output folder: tracker, journal, people, overlay, progress.

    Build it with :meth:`open` (checks, settings, resume, colours); :meth:`run` tracks the
    frames; :meth:`finish` writes the outputs.
    """

    #: The damage check's verdict (:class:`DamageCheck`).
    damage: DamageCheck
    #: The frames of this session.
    span: Span
    #: ``run.json`` ``settings``.
    settings: dict
    #: Mesh level of detail of the body models.
    resolution: int
    #: The ground truth, for ``run.json`` ``metrics``.
    truth: PoseTable | None
    #: The person tracked now, and who was tracked when.
    person: Person
    people: People
    tracker: Tracker
    #: The overlay is drawn as frames come (else redrawn at the end), and where.
    overlay_now: bool
    geometry: OverlayGeometry
    #: When :meth:`run` started (``time.perf_counter``, seconds).
    started: float

    def __init__(self, frames_in, setup: RunSetup, out_dir: Path, params: RunParams) -> None:
        self.frames_in, self.setup, self.out_dir, self.params = frames_in, setup, out_dir, params
        self.config = params.options.tracker
        self.camera = setup.calibration.camera
        self.journal = Journal.in_folder(out_dir)
        self.run_json = out_dir / files.RUN_JSON
        self.times: dict[int, float] = {}          # a live source's frame times, until the frames are decided
        self.dark: dict[int, bool] = {}            # dark flags of the frames pushed but not decided yet
        self.pictures: dict[int, np.ndarray] = {}  # overlay-size frames not decided yet
        self.step_clock = StepClock()              # when this session's frames were done
        self.latency = LatencyRecord()             # live: each frame's arrival to its decision
        self.clock: float | None = None            # live: the reader's clock (frame times count from it)
        self.colour_frame: int | None = None
        self.overlay: OverlayWriter | None = None
        self.bar: ProgressBar | None = None
        self.tracked = 0                           # frames tracked in this session

    @classmethod
    def open(cls, frames_in, setup: RunSetup, out_dir: Path, params: RunParams) -> "RunLoop":
        """Checks, settings, the run to resume (if any) and the colours; raises ValueError on bad input."""
        from mocap.body.mesh import resolution_for_image

        loop = cls(frames_in, setup, out_dir, params)
        start_frame = params.options.start
        if isinstance(start_frame, bool) or not isinstance(start_frame, int) or start_frame < 0:
            raise ValueError(f"the start frame must be a non-negative integer, got {start_frame!r}")
        loop.damage = DamageCheck(frames_in, params.options.allow_damaged, [])
        stop, expected = _span(frames_in, params)
        _check_sizes(frames_in, setup)
        loop.truth = PoseTable.read(params.ground_truth) if params.ground_truth is not None else None
        camera = loop.camera
        loop.resolution = params.options.tracker.mesh_resolution or resolution_for_image(camera.width, camera.height)
        model = setup.calibration.body_model(loop.resolution)
        loop.settings = run_settings(frames_in, setup, params, loop.resolution)
        out_dir.mkdir(parents=True, exist_ok=True)
        checkpoint = previous_run(loop.journal, loop.run_json, loop.settings, params.options.overwrite)
        colour_model = setup.colour_model
        if colour_model is None:
            if frames_in.live:
                raise ValueError("a live source needs its colour model given")
            frames = ((i, downscale(f, setup.factor)) for i, f in enumerate(frames_in.frames(start_frame, stop),
                                                                            start=start_frame))
            learnt = learn_colours(frames, setup.colour_recipe(model), frames_in.name)
            colour_model, loop.colour_frame = learnt.model, learnt.frame
        colour_model.to_json(out_dir / files.COLOUR_MODEL_JSON)
        loop.person = Person(model.with_class_names(colour_model.names), colour_model, setup.scene,
                             setup.calibration)     # classes the first frame supports
        loop.people = People.first(start_frame, setup.calibration, colour_model)
        start = start_frame if checkpoint is None else checkpoint.next_index
        loop.span = Span(start_frame, start, stop, expected)
        loop.resume(checkpoint)
        return loop

    def new_tracker(self) -> Tracker:
        """A fresh tracker of the person, on the run's threads (:attr:`RunChoices.threads`)."""
        return Tracker(self.person.model, self.camera, self.config, self.person.calibration.initial_pose,
                       threads=self.params.choices.threads)

    def resume(self, checkpoint) -> None:
        """The tracker: fresh (``run.json`` says running) or restored from ``checkpoint``."""
        if checkpoint is None:
            self.damage.made.extend([self.journal.path, self.run_json, self.journal.state_path,
                                     self.journal.keypoints_path, self.out_dir / files.COLOUR_MODEL_JSON,
                                     self.out_dir / files.OVERLAY_MP4])
            self.tracker = self.new_tracker()
            write_text_atomic(self.run_json, json.dumps({"status": "running", "settings": self.settings}, indent=2))
            return
        if self.frames_in.live:
            raise ValueError(f"{self.out_dir} holds a run; a live source cannot resume it: use --overwrite or "
                             "another --out")
        resumed = Resumed.split(checkpoint)
        self.dark = resumed.dark
        if resumed.people is not None:
            self.people = resumed.people
        if len(self.people.segments) > 1:      # the person of the last segment, found again as before
            first = self.people.segments[-1]["first_frame"]
            newcomer = self.params.newcomer
            found = None if newcomer is None else newcomer(first, next(self.frames_in.frames(indices=[first])))
            if found is None:
                raise ValueError(f"{self.out_dir}: the person found on frame {first} is not found again; start "
                                 "afresh with --overwrite")
            self.person = Person.of_setup(found, self.resolution)
        self.tracker = self.new_tracker()
        self.tracker.restore(resumed.tracker_state)

    def _open_overlay(self) -> OverlayGeometry | None:
        """The overlay drawn as frames come (no second decoding pass) unless an earlier session's
        frames must be in it too (a resumed file run redraws it whole at the end)."""
        params, frames_in = self.params, self.frames_in
        self.overlay_now = frames_in.live or (params.options.overlay and self.span.start == self.span.first)
        self.geometry = OverlayGeometry.of(self.camera, self.setup.factor, frames_in.width, frames_in.height)
        if not (self.overlay_now or params.options.show):
            return None
        self.overlay = OverlayWriter(self.out_dir, params.fps, self.person.model, self.geometry.camera,
                                     show=params.options.show, write=self.overlay_now)
        self.damage.overlay = self.overlay
        return self.geometry

    def emit(self, results: list[FrameResult]) -> None:
        """Decided frames: rows to the journal, pictures to the overlay."""
        for result in results:
            when = self.times.pop(result.frame) if self.frames_in.live else self.frames_in.time_s(result.frame)
            self.journal.append(frame_row(result, self.camera, self.setup.factor, self.dark.pop(result.frame, None),
                                          when, self.people.segment))
            picture = self.pictures.pop(result.frame, None)
            if self.overlay is not None and picture is not None:
                self.overlay.update(picture, result.pose)
            shown = {"F": f"{result.region_residual:.2f}", "D": f"{result.edge_residual:.1f}"}
            recent_fps = self.step_clock.recent_fps()
            if recent_fps is not None:
                shown = {"fps": f"{recent_fps:.0f}", **shown}
            if self.frames_in.live and self.clock is not None:
                self.latency.add(1e3 * (time.perf_counter() - self.clock - when))
                shown["latency"] = f"{self.latency.last_ms:.0f}ms"
            if self.bar is not None:      # shown at the bar's next refresh (tqdm's mininterval), not now
                self.bar.set_postfix(refresh=False, **shown)

    def checkpoint(self, next_index: int) -> None:
        self.journal.checkpoint(self.tracker.state(), self.dark, self.people, next_index)

    def switch_person(self, index: int, found: RunSetup, reader: FrameReader) -> None:
        """Someone new from frame ``index``: the held-back frames decided, a segment of their own
        and a fresh tracker."""
        self.emit(self.tracker.finish())
        self.person = Person.of_setup(found, self.resolution)
        self.people.begin(index, self.person.calibration, self.person.colour_model,
                          None if found.record is None else found.record.calibration.to_dict(source=False))
        reader.colours = Colours(self.people.segment, self.person.colour_model, self.person.scene)
        self.tracker.close()
        self.tracker = self.new_tracker()
        if self.overlay is not None:
            self.overlay.model = self.person.model

    def step(self, frame: ReadFrame, reader: FrameReader, upcoming: ReadFrame | None = None) -> None:
        """One frame through the tracker, the people's bookkeeping and the checkpoint; the
        ``upcoming`` frame's leader is started (:meth:`Tracker.begin`) before this one's
        results are written."""
        index, prepared = frame.index, frame.prepared
        self.dark[index] = frame.dark
        if self.frames_in.live:
            self.times[index] = frame.time_s
        if frame.picture is not None:
            self.pictures[index] = frame.picture
        if frame.segment != self.people.segment:           # prepared with the last person's colours
            prepared = reader.prepare(frame.small)
        newcomer = self.params.newcomer
        if newcomer is not None and self.people.vacant and not prepared.is_empty and index % 3 == 0:
            found = newcomer(index, frame.full)
            if found is not None:                           # someone new: a segment of their own
                self.switch_person(index, found, reader)
                prepared = reader.prepare(frame.small)
        if frame.detected is not None:
            self.journal.append_keypoints(index, frame.detected)
        results = self.tracker.push(index, prepared, frame.keypoints)
        if upcoming is not None and upcoming.segment == self.people.segment:
            self.tracker.begin(upcoming.index, upcoming.prepared, upcoming.keypoints)
        self.emit(results)
        self.people.saw(index, prepared.is_empty)
        self.damage.take(wait=False)
        if (index + 1) % journalling.CHECKPOINT_EVERY == 0 or index + 1 == self.span.stop:
            self.checkpoint(index + 1)
        self.step_clock.tick(time.perf_counter())
        self.advance(1)

    def advance(self, frames: int) -> None:
        """``frames`` more tracked. The bar is drawn once the damage check's verdict is in (at
        once for an image folder or a camera): before it, the run may still be refused, and a
        refusal must be the only thing it writes to stderr."""
        self.tracked += frames
        if self.bar is not None:
            self.bar.update(frames)
        elif self.damage.damaged is not None:
            span = self.span
            self.bar = ProgressBar(total=None if span.expected is None else span.expected - span.first,
                                   initial=span.start - span.first + self.tracked, desc="tracking", unit="frame",
                                   disable=not self.params.progress)

    def run(self) -> None:
        """Track the session's frames (Ctrl-C ends a live run and keeps what was tracked)."""
        span, frames_in = self.span, self.frames_in
        # every kernel the frames need, loaded (compiled on a cold cache) before the first one
        self.tracker.warm_up(keypoints=self.params.keypoints is not None)
        geometry = self._open_overlay()
        reader = FrameReader(frames_in, self.setup, span,
                             Colours(self.people.segment, self.person.colour_model, self.person.scene),
                             keypoints=self.params.keypoints, full=self.params.newcomer is not None,
                             overlay=geometry if self.overlay is not None else None,
                             detect_ahead=self.params.detect_ahead)
        self.advance(0)
        self.started, self.clock = time.perf_counter(), reader.clock
        interrupted, last = False, None
        try:    # (live: one frame waits at most, a newer one is taken instead of a queue of old ones)
            frames = prefetch(reader, 1 if frames_in.live else READ_AHEAD, name="mocap-reader")
            # a file's next frame is read before this one is written (its leader starts meanwhile);
            # a camera's is not waited for
            pairs = ((f, None) for f in frames) if frames_in.live else pairwise(chain(frames, [None]))
            for frame, upcoming in pairs:
                self.step(frame, reader, upcoming)
                last = frame.index
            if span.stop is None:
                self.damage.take(wait=True)         # the end of the frames: damage or a cut file?
            every = journalling.CHECKPOINT_EVERY
            if span.stop is None and last is not None and (last + 1) % every != 0:    # the checkpoint after the last
                self.checkpoint(last + 1)
            # the held-back frames: not checkpointed, a resume continues from the last checkpoint instead
            self.emit(self.tracker.finish())
            # a run that stops early (--max-frames) writes its rows before the verdict, which
            # can take the check's decoding of the whole clip; a damaged video still removes them
            self.damage.take(wait=True)
            self.advance(0)
        except ValueError:
            self.damage.take(wait=True)   # a damaged video's reader may fail first: the damage is the reason
            raise
        except KeyboardInterrupt:
            if not frames_in.live:
                raise
            interrupted = True          # Ctrl-C ends a live run: what was tracked is kept
            self.emit(self.tracker.finish())
        finally:
            self.tracker.close()
            if self.bar is not None:
                self.bar.close()
            if self.overlay is not None:
                self.overlay.close()
        if interrupted:
            print("stopped by Ctrl-C: writing what was tracked")

    def finish(self) -> RunSummary:
        """The outputs (:func:`mocap.run.outputs.finish_run`), the overlay redrawn for a resumed run."""
        if not self.journal.path.exists():
            raise ValueError(f"no frame was tracked from {self.frames_in.name}")
        table = PoseTable.read(self.journal.path)     # (not rewritten: the checkpoint records its length)
        self.people.close()
        if self.params.options.overlay and not self.overlay_now:
            models = [Calibration.from_dict(seg["calibration"]).body_model(self.resolution)
                      .with_class_names(tuple(seg["colour_classes"])) for seg in self.people.segments]
            frames = enumerate(self.frames_in.frames(0, int(table.frames.max()) + 1))
            redraw_overlay(self.out_dir, frames, table, models, self.geometry, self.params.fps)
        detector_ms = getattr(self.params.keypoints, "milliseconds", None)
        return finish_run(FinishedRun(
            self.out_dir, table, self.settings, self.setup.calibration, self.camera, self.params.fps,
            self.span.start, time.perf_counter() - self.started, self.damage.damaged, self.colour_frame,
            self.people.segments, self.truth, float(np.median(detector_ms)) if detector_ms else None,
            self.live_record(table), threads=self.params.choices.threads,
            loop_fps=self.step_clock.session_fps(self.started)))

    def live_record(self, table: PoseTable) -> dict | None:
        """``run.json`` ``live`` of a live run: frames dropped (the gaps between the tracked ones:
        the run was slower than the camera) and the latency from a frame's arrival to its pose
        (median and 90th percentile, milliseconds, within :data:`LATENCY_BIN_RATIO`'s half-width:
        :class:`LatencyRecord`; the decoding's ``lag`` included); None for a file."""
        if not self.frames_in.live:
            return None
        frames = np.asarray(table.frames, dtype=np.int64)
        record = {"dropped_frames": int(frames[-1] - frames[0] + 1 - len(frames)) if len(frames) else 0}
        if self.latency.count:
            record["latency_ms"] = {"median": self.latency.quantile(0.5), "p90": self.latency.quantile(0.9)}
        return record


def session_fps(started: float, first_end: float | None, last_end: float | None, frames: int) -> float | None:
    """Frames a second of a session's loop by the wall clock (``time.perf_counter`` seconds):
    from the end of its first frame (which also waits for the reader's and the detector's start)
    to the end of its last (``frames`` frames in all), or from the loop's ``started`` with fewer
    than three frames; None without any. Everything the run does per frame counts: the image
    side, the tracker on its threads, the detector's wait, the writing."""
    if frames == 0 or first_end is None or last_end is None:
        return None
    first, count = (first_end, frames - 1) if frames > 2 else (started, frames)
    return count / (last_end - first) if last_end > first else None


#: Frames over which the progress bar's rate is taken.
SHOWN_RATE_FRAMES = 25


@dataclass
class StepClock:
    """When a session's frames were done (``time.perf_counter`` seconds), in the same memory
    however long the run: the first end, the count, and the last :data:`SHOWN_RATE_FRAMES` + 1."""

    first: float | None = None
    count: int = 0
    recent: collections.deque = field(default_factory=lambda: collections.deque(maxlen=SHOWN_RATE_FRAMES + 1))

    def tick(self, now: float) -> None:
        """A frame done at ``now``."""
        if self.first is None:
            self.first = now
        self.count += 1
        self.recent.append(now)

    def recent_fps(self) -> float | None:
        """Frames a second over the last :data:`SHOWN_RATE_FRAMES` (None before two frames)."""
        if len(self.recent) < 2 or self.recent[-1] <= self.recent[0]:
            return None
        return (len(self.recent) - 1) / (self.recent[-1] - self.recent[0])

    def session_fps(self, started: float) -> float | None:
        """The session's rate (:func:`session_fps`) for a loop started at ``started``."""
        return session_fps(started, self.first, self.recent[-1] if self.recent else None, self.count)


#: Each of :class:`LatencyRecord`'s bins is this many times wider than the one below it.
LATENCY_BIN_RATIO = 1.01
#: Latencies below this (milliseconds) are counted in the lowest bin.
MIN_LATENCY_MS = 0.01


@dataclass
class LatencyRecord:
    """A live session's latencies (milliseconds, a frame's arrival to its decided pose) in the same
    memory however long the run: counts in logarithmic bins, bin ``k`` holding
    (``r**(k-1)``, ``r**k``] for ``r`` = :data:`LATENCY_BIN_RATIO` (at most about 2,100 bins from
    :data:`MIN_LATENCY_MS` to three hours), and the last latency. A quantile is its bin's centre
    ``2 r**k / (r + 1)`` (DDSketch's estimate), within ``(r - 1) / (r + 1)`` (0.5 %) of the exact
    inverted-CDF quantile of the latencies added."""

    counts: collections.Counter = field(default_factory=collections.Counter)
    count: int = 0
    last_ms: float | None = None

    def add(self, latency_ms: float) -> None:
        """One frame's latency (milliseconds; below :data:`MIN_LATENCY_MS` counted as that)."""
        self.last_ms = float(latency_ms)
        self.count += 1
        self.counts[math.ceil(math.log(max(latency_ms, MIN_LATENCY_MS)) / math.log(LATENCY_BIN_RATIO))] += 1

    def quantile(self, q: float) -> float:
        """The ``q`` quantile (0 < q <= 1) of the latencies added (milliseconds): the smallest
        latency with at least ``q`` of them at or below it, as its bin's centre.

        Raises
        ------
        ValueError
            Before any latency, or ``q`` outside (0, 1].
        """
        if not self.count:
            raise ValueError("no latency recorded")
        if not 0.0 < q <= 1.0:
            raise ValueError(f"q must be in (0, 1], got {q!r}")
        bins = sorted(self.counts)
        reached = np.cumsum([self.counts[k] for k in bins])
        k = bins[int(np.searchsorted(reached, math.ceil(q * self.count)))]
        r = LATENCY_BIN_RATIO
        return float(2.0 * r ** k / (r + 1.0))


@one_writer("out_dir")
def track_frames(source, setup: RunSetup, out_dir: str | Path, params: RunParams) -> RunSummary:
    """Track every frame of a source with a set-up and write the run's files.

    Parameters
    ----------
    source : path or frame source
        Video file or folder of images, or a :mod:`mocap.io.frames` source (a camera).
    setup : RunSetup
        Calibration, background, working resolution, colours (:func:`mocap.run.setup.find_setup`).
    out_dir : path
        Output folder (created), locked for the run. If it holds an unfinished run with the
        same settings, the run resumes exactly where it stopped.
    params : RunParams

    Returns
    -------
    RunSummary

    Raises
    ------
    ValueError
        Frames and calibration of different sizes, an undecodable or (without
        ``allow_damaged``) damaged video, a background of another size, an out folder holding
        a run with other settings, bad settings.
    FileNotFoundError
        Missing video or ground truth.
    mocap.io.lock.FolderInUseError
        Another run writes to ``out_dir``.
    """
    frames_in = source if hasattr(source, "frames") else VideoSource(source, fps=params.fps)
    loop = RunLoop.open(frames_in, setup, Path(out_dir), params)
    loop.run()
    return loop.finish()
