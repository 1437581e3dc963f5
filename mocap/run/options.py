"""What a person may set for a run, as one JSON-backed record, and what it means, decided once.

:class:`OwnVideoOptions` is what ``python -m mocap track`` (and ``track-many``, ``calibrate``,
``demo``: one builder, ``mocap.commands._common.own_video_options``) turn their command lines
into, with the command line's defaults; :func:`mocap.run.track` takes it and resolves it once
into :class:`RunChoices` (which keypoints run and why, where the colours come from, the
background's mode), which the set-up, the loop, the outputs, the closing hint and ``run.json``
read.
"""
from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

from mocap.io.keypoints import KeypointSource

from mocap.config import JsonConfig
from mocap.render.camera import DEFAULT_HFOV_DEG
from mocap.track import TrackerConfig

__all__ = ["BACKGROUND_MODES", "COLOUR_SOURCES", "KEYPOINT_CHOICES", "OwnVideoOptions", "RunChoices",
           "available_cores", "background_mode", "default_threads", "keypoint_source", "resolve_keypoints"]

#: How the background is found: ``auto`` (estimate, use if the person moves enough), ``image``
#: (a file), ``frames`` (median of frames A:B), ``none`` (colour-only foreground).
BACKGROUND_MODES = ("auto", "image", "frames", "none")
#: ``--keypoints`` values other than a keypoint file (:func:`resolve_keypoints`).
KEYPOINT_CHOICES = ("auto", "mediapipe", "none")
#: Where the colour classes are learnt: inside the calibrated model's projected parts, or from
#: the detected face and a box under it (the paper's way).
COLOUR_SOURCES = ("calibration", "face")


def available_cores() -> int:
    """The cores this process may run on (its affinity where the system tells it, else all)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def default_threads(detector_process: bool, cores: int | None = None) -> int:
    """The tracker's threads when none are asked for: the cores (``cores``, default
    :func:`available_cores`) less the one a keypoint detector in its own process takes, but not
    fewer than two where there are two: MediaPipe works about half of a frame's time, and on two
    cores a second thread took 16.0 frames a second against 15.4 with one (docs/research-log.md,
    2026-11-29)."""
    cores = available_cores() if cores is None else cores
    return max(min(cores, 2), cores - (1 if detector_process else 0))


def background_mode(image: bool, frames: bool, none: bool) -> str:
    """The one choice of :data:`BACKGROUND_MODES` every command makes: an image (given, or a
    sequence folder's own) first, then empty frames ``A:B``, then none asked for, else ``auto``."""
    if image:
        return "image"
    if frames:
        return "frames"
    return "none" if none else "auto"


@dataclass(frozen=True)
class OwnVideoOptions(JsonConfig):
    """What ``python -m mocap track`` lets a person set, as one JSON-backed record
    (:func:`mocap.run.track`). Paths are strings (JSON); every field has the CLI's default.

    Attributes
    ----------
    background : str or None
        Image of the empty scene (input size).
    background_frames : (int, int) or None
        Frames ``A`` to ``B - 1`` of the video show the empty scene: their median.
    no_background : bool
        Colour-only foreground (no empty view).
    calibration : str or None
        ``calibration.json`` (:mod:`mocap.calibrate`), its camera at the input or the working size.
    hfov_deg : float, degrees
        Camera's horizontal field of view without a calibration.
    height_m : float or None, metres
        The person's stature (fixes the absolute scale).
    work_width : int or None, pixels
        Wanted working width (:func:`mocap.imaging.resample.working_factor`); None: chosen.
    colour : {"calibration", "face"}
        Where the colour classes are learnt (:data:`COLOUR_SOURCES`).
    ground_truth : str or None
        ``ground_truth.csv`` for accuracy metrics.
    start : int
        First frame to track.
    max_frames : int or None
        Track at most this many frames.
    allow_damaged : bool
        Track the frames of a damaged video that decode instead of stopping.
    overlay : bool
        Write ``overlay.mp4``.
    show : bool
        Show the overlay live in a window.
    overwrite : bool
        Start afresh instead of resuming a run in the output folder.
    keypoints : str or None
        2D keypoints: ``"auto"`` (the default, as on the command line: MediaPipe when the extra
        imports, none otherwise, :func:`resolve_keypoints`), ``"mediapipe"`` (MediaPipe Pose,
        the optional extra ``keypoints``), a keypoint file (:mod:`mocap.io.keypoints`) or
        ``"none"`` (or None); the tracker adds them as a cue (``tracker.keypoint_weight``).
    tracker : TrackerConfig
    threads : int or None
        Threads the tracker's registrations run on (:class:`mocap.track.Tracker`); the poses are
        the same for every count, and a run resumes with any. None: :func:`default_threads`.
    """

    background: str | None = None
    background_frames: tuple[int, int] | None = None
    no_background: bool = False
    calibration: str | None = None
    hfov_deg: float = DEFAULT_HFOV_DEG
    height_m: float | None = None
    work_width: int | None = None
    colour: str = "calibration"
    ground_truth: str | None = None
    start: int = 0
    max_frames: int | None = None
    allow_damaged: bool = False
    overlay: bool = True
    show: bool = False
    overwrite: bool = False
    keypoints: str | None = "auto"
    tracker: TrackerConfig = field(default_factory=TrackerConfig)
    threads: int | None = None

    def __post_init__(self) -> None:
        for key in ("background", "calibration", "ground_truth", "keypoints"):
            value = getattr(self, key)
            if isinstance(value, Path):
                object.__setattr__(self, key, str(value))
        if isinstance(self.tracker, dict):
            object.__setattr__(self, "tracker", TrackerConfig.from_dict(self.tracker))
        given = [name for name, on in (("background", self.background is not None),
                                       ("background_frames", self.background_frames is not None),
                                       ("no_background", self.no_background)) if on]
        if len(given) > 1:
            raise ValueError(f"give one of background, background_frames and no_background, not {' and '.join(given)}")
        if self.background_frames is not None:
            a, b = self.background_frames
            if a < 0 or b <= a:
                raise ValueError(f"background frames must be A:B with 0 <= A < B, got {a}:{b}")
        if self.colour not in COLOUR_SOURCES:
            raise ValueError(f"colour must be one of {COLOUR_SOURCES}, got {self.colour!r}")
        if isinstance(self.start, bool) or not isinstance(self.start, int) or self.start < 0:
            raise ValueError(f"the start frame must be a non-negative integer, got {self.start!r}")
        if self.max_frames is not None and self.max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {self.max_frames}")
        if self.keypoints is not None and self.keypoints not in KEYPOINT_CHOICES and not Path(self.keypoints).is_file():
            raise FileNotFoundError(f"keypoint file not found: {self.keypoints} (or give --keypoints "
                                    f"{'|'.join(KEYPOINT_CHOICES)})")
        if self.threads is not None and (isinstance(self.threads, bool) or not isinstance(self.threads, int)
                                         or self.threads < 1):
            raise ValueError(f"threads must be a positive integer, got {self.threads!r}")
        if self.work_width is not None and self.work_width < 16:
            raise ValueError(f"the working width must be at least 16 pixels, got {self.work_width}")

    def background_mode(self, sequence_background: bool = False) -> str:
        """One of :data:`BACKGROUND_MODES` (:func:`background_mode`; ``sequence_background``: a
        sequence folder's own ``background.png`` is used unless told otherwise)."""
        return background_mode(self.background is not None or sequence_background,
                               self.background_frames is not None, self.no_background)


@dataclass(frozen=True, eq=False, kw_only=True)
class RunChoices:
    """What a run's :class:`OwnVideoOptions` mean on this installation and input, decided once
    (:meth:`of`) by :func:`mocap.run.track`.

    Attributes
    ----------
    keypoints : str
        What runs: ``"mediapipe"``, a keypoint file's path or ``"none"``.
    keypoints_line : str
        Which, and why for ``auto`` (:func:`resolve_keypoints`): what the command prints and
        ``run.json`` ``settings.own_video.keypoints``.
    keypoint_source : KeypointSource or None
        The source itself (None for ``"none"``), made once; MediaPipe's is a process of its own
        (:func:`mocap.io.mediapipe_keypoints.mediapipe_process`), started by :meth:`of` and
        ended by :meth:`close`.
    colour : {"calibration", "face"}
        Where the colour classes are learnt (:data:`COLOUR_SOURCES`); ``face`` only where the
        run learns them itself (:meth:`check_colour`).
    background_mode : {"auto", "image", "frames", "none"}
        :data:`BACKGROUND_MODES`.
    threads : int
        The tracker's threads: the options' or :func:`default_threads` (less one core where
        MediaPipe runs in its own process).
    """

    keypoints: str
    keypoints_line: str
    keypoint_source: KeypointSource | None
    colour: str
    background_mode: str
    threads: int = 1

    @classmethod
    def of(cls, options: OwnVideoOptions, sequence_background: bool = False) -> "RunChoices":
        """The choices of ``options`` (``sequence_background``: a sequence folder's own
        ``background.png`` is used unless the options say otherwise). Raises as
        :func:`keypoint_source` does."""
        resolved, line = resolve_keypoints(options.keypoints)
        return cls(keypoints="none" if resolved is None else resolved, keypoints_line=line,
                   keypoint_source=_source(resolved, options.keypoints == "auto"), colour=options.colour,
                   background_mode=options.background_mode(sequence_background),
                   threads=options.threads or default_threads(detector_process=resolved == "mediapipe"))

    def close(self) -> None:
        """End the keypoint source's process, if it has one (safe to call twice)."""
        close = getattr(self.keypoint_source, "close", None)
        if close is not None:
            close()

    def __enter__(self) -> "RunChoices":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @property
    def keypoint_cue(self) -> str | None:
        """``keypoints``, None for ``"none"`` (:class:`mocap.run.advice.RunFacts`)."""
        return None if self.keypoints == "none" else self.keypoints

    def check_colour(self, learnt: bool, calibration: str, live: bool) -> None:
        """ValueError (one line) for ``colour="face"`` where the set-up has already learnt the
        colours (``learnt``): an automatic ``calibration`` learns them inside its own fit; a
        given one with a colour-only foreground or a ``live`` camera, inside the model."""
        if self.colour != "face" or not learnt:
            return
        if calibration == "automatic":
            why = "the automatic calibration learns the colours inside its own fit: give --calibration JSON"
        elif live:
            why = "a live camera's colours are learnt inside the calibrated model on its first frame"
        else:
            why = "a colour-only foreground learns the colours inside the calibrated model: give a background"
        raise ValueError(f"--colour face learns the colours from a detected face, which this run cannot: {why}, "
                         "or leave --colour at calibration")


def resolve_keypoints(name: str | None) -> tuple[str | None, str]:
    """What ``--keypoints NAME`` means on this installation.

    Parameters
    ----------
    name : str or None
        ``"auto"``, ``"mediapipe"``, ``"none"`` (or None) or a keypoint file's path.

    Returns
    -------
    (str or None, str)
        ``"mediapipe"``, the file's path or None (no keypoints), and one line saying which and,
        for ``"auto"``, why (what the command prints; ``run.json`` ``settings.own_video.keypoints``).
    """
    if name is None or name == "none":
        return None, "none"
    if name == "auto":
        from mocap.io import mediapipe_keypoints

        if mediapipe_keypoints.available():
            return "mediapipe", "mediapipe (auto: the optional extra 'keypoints' is installed)"
        how = ("pip install 'mocap[keypoints]' adds 2D keypoints as a cue" if sys.version_info < (3, 13) else
               "it needs Python 3.11 or 3.12: mediapipe 0.10.14, the last with its model inside, has no later wheel")
        return None, f"none (auto: MediaPipe Pose, the optional extra 'keypoints', is not installed; {how})"
    return name, name if name == "mediapipe" else f"file {name}"


def keypoint_source(name: str | None):
    """The :class:`~mocap.io.keypoints.KeypointSource` of ``OwnVideoOptions.keypoints``: None,
    MediaPipe Pose for ``"mediapipe"`` (ValueError in one line without the extra) and for
    ``"auto"`` where the extra imports (:func:`resolve_keypoints`), else a keypoint file
    (FileNotFoundError, ValueError naming the line of a malformed one)."""
    return _source(resolve_keypoints(name)[0], name == "auto")


def _source(resolved: str | None, auto: bool):
    """The keypoint source of a resolved name (:func:`resolve_keypoints`); ``auto``: chosen by
    ``--keypoints auto`` (said in its description)."""
    if resolved is None:
        return None
    if resolved == "mediapipe":       # started now, in a process of its own: its import overlaps the set-up
        from mocap.io.mediapipe_keypoints import mediapipe_process
        source = mediapipe_process()
        if auto:
            source.description += " (--keypoints auto)"
        return source
    from mocap.io.keypoints import KeypointFile
    return KeypointFile(resolved)
