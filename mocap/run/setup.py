"""The set-up of a run, decided once before frame 0: working resolution, background,
calibration and colours, each a small step with a typed result (:func:`find_setup`).

For a person's own video (no background plate, no calibration file, no known camera) the steps
find what is not given, from the video itself, at the tracker's working resolution
(:mod:`mocap.imaging.resample`):

1. **Face and working resolution** (:func:`look_for_face`) — without a calibration, the first
   frame among the first :data:`SEARCH_FRAMES` with a plausible face (:func:`mocap.run.person.find_face`);
   a face larger than :data:`FACE_WORKING_PX` working pixels makes the working resolution
   coarser (a person close to the camera fills the frame).
2. **Background** (:func:`find_background`) — given (an image, or the median of empty frames
   ``A:B``), none (colour-only foreground) or, by default, chosen (:func:`choose_background`):
   estimated from up to :data:`SAMPLE_FRAMES` frames of the clip and used when the person moves
   enough to be seen against it; otherwise the foreground is colour-only (the colour classes,
   less the scene's colours: :mod:`mocap.imaging.scene`). A live camera has no clip to look
   at: colour-only unless a background is given.
3. **Calibration and colours** — a given calibration (:func:`setup_with_calibration`; its
   colours from :func:`mocap.run.colours.learn_colours`), or automatic
   (:func:`calibrate_automatically`): on the face's frame, or without a face but with a
   background, the first frame with a person-sized foreground clear of the borders. The
   camera is a pinhole of horizontal field of view ``hfov_deg``; ``height_m`` fixes the scale.

What was chosen and why is the set-up's ``record``, a :class:`mocap.run.accounts.SetupAccount`
(``run.json`` ``settings.own_video`` is its :meth:`~mocap.run.accounts.SetupAccount.to_dict`).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mocap.calibrate import Calibration, PersonCalibration, calibrate_person
from mocap.imaging import Box, ColourModel, ImagingConfig, median_background
from mocap.imaging.background import estimate_background, person_against_background, subtract_background
from mocap.imaging.resample import downscale, working_factor
from mocap.imaging.scene import SceneColours
from mocap.io.keypoints import KeypointSource
from mocap.render.camera import DEFAULT_HFOV_DEG, Camera
from mocap.run.accounts import BackgroundAccount, CalibrationAccount, SetupAccount
from mocap.run.colours import ColourRecipe, learn_colours
from mocap.run.options import BACKGROUND_MODES, COLOUR_SOURCES
from mocap.run.person import find_face, plausible_face, whole_person

__all__ = ["FoundSetup", "RunSetup", "SAMPLE_FRAMES", "SAMPLE_LIMIT", "SEARCH_FRAMES", "SetupRequest",
           "choose_background", "find_setup", "spread", "working_camera"]

#: Share of the sample frames with someone in view (against the estimate) needed to use it.
MIN_FRAMES_WITH_PERSON = 0.3
#: Smallest part of the foreground (share of the image) kept when the background is estimated
#: or absent: smaller specks (a misjudged background pixel, a colour patch) are not a person,
#: and a frame with nothing larger has nobody in view.
MIN_PERSON_FRACTION = 0.01
#: Face width in working pixels the automatic working resolution aims at (at most): the
#: synthetic benchmark's actors at 160x120 have faces of 12-15 pixels.
FACE_WORKING_PX = 14
#: Share of the face box that must be foreground against the estimate to use it.
MIN_FACE_FOREGROUND = 0.5
#: Background estimation (and a background's empty frames ``A:B``) uses this many frames spread
#: over the first :data:`SAMPLE_LIMIT`, each reduced to the working resolution as it is read (the
#: set-up holds working-size frames and one input-size frame of a file): a long video's key
#: frames, decoded without the frames between them (:meth:`mocap.io.frames.VideoSource.sample`).
SAMPLE_FRAMES = 60
SAMPLE_LIMIT = 1500
#: Calibration looks at most this many frames into the video for a face (a camera's frames read
#: so far are kept to be tracked).
SEARCH_FRAMES = 90


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
        person, the way ``colour_from`` says (:func:`mocap.run.colours.learn_colours`).
    colour_from : {"calibration", "face"}
        Learn the colour classes inside the calibrated model's projected parts, or from the
        detected face and a box under it (the paper's way).
    scene : SceneColours or None
        The scene's colours, for a foreground without background (:func:`mocap.imaging.prepare_frame`).
    record : SetupAccount or None
        How background and calibration were found (``run.json`` ``settings.own_video``); a
        newcomer's set-up (:class:`mocap.run.person.NewcomerFinder`): the run's, with how they
        were calibrated (``run.json`` ``segments[].found``).
    background_file : Path or None
        The file the background came from, for ``run.json``.
    """

    calibration: Calibration
    background: np.ndarray | None = None
    factor: int = 1
    imaging: ImagingConfig = field(default_factory=ImagingConfig)
    colour_model: ColourModel | None = None
    colour_from: str = "calibration"
    scene: SceneColours | None = None
    record: SetupAccount | None = None
    background_file: Path | None = None

    def __post_init__(self) -> None:
        if self.colour_from not in COLOUR_SOURCES:
            raise ValueError(f"colour must be one of {COLOUR_SOURCES}, got {self.colour_from!r}")

    def colour_recipe(self, model) -> ColourRecipe:
        """How the run learns its colours when the set-up has none (``model``: the body model)."""
        return ColourRecipe(self.colour_from, self.background, self.imaging, self.calibration, model)


@dataclass(frozen=True, eq=False, kw_only=True)
class SetupRequest:
    """What the set-up is told (:func:`find_setup`); everything else it finds.

    Attributes
    ----------
    factor : int or None
        Working-resolution factor. None: the tracker chooses, the factor that brings the width
        nearest to 160 pixels (:func:`mocap.imaging.resample.working_factor`), or a larger one
        when the face found is bigger than :data:`FACE_WORKING_PX` working pixels.
    background_mode : {"auto", "image", "frames", "none"}
        :data:`mocap.run.options.BACKGROUND_MODES`.
    background_image : ndarray of uint8, shape (H, W, 3), or None
        Input-size image of the empty scene (mode ``image``).
    background_frames : (int, int) or None
        Frames ``A:B`` of empty scene (mode ``frames``).
    calibration : Calibration or None
        A calibration to use (its camera at the working resolution).
    hfov_deg : float, degrees
        Horizontal field of view of the camera.
    height_m : float or None, metres
        The person's stature.
    progress : bool
        Progress bars.
    keypoints : KeypointSource or None
        2D keypoints (:mod:`mocap.io.keypoints`): the calibration frame's pull the fitted
        model's joints onto them (:func:`mocap.calibrate.calibrate_person`).
    """

    factor: int | None = None
    background_mode: str = "auto"
    background_image: np.ndarray | None = None
    background_frames: tuple[int, int] | None = None
    calibration: Calibration | None = None
    hfov_deg: float = DEFAULT_HFOV_DEG
    height_m: float | None = None
    progress: bool = True
    keypoints: KeypointSource | None = None

    def __post_init__(self) -> None:
        if self.background_mode not in BACKGROUND_MODES:
            raise ValueError(f"background mode must be one of {BACKGROUND_MODES}, got {self.background_mode!r}")


@dataclass(frozen=True, eq=False)
class FoundSetup:
    """What :func:`find_setup` found.

    Attributes
    ----------
    setup : RunSetup
        Everything at the working resolution; with a found (not given) background, parts of
        the foreground smaller than :data:`MIN_PERSON_FRACTION` of the image are not a person
        (``setup.imaging``).
    consumed : list of ndarray of uint8, shape (H, W, 3)
        For a live source, the input frames read so far (the run tracks them first); empty
        for a file.
    """

    setup: RunSetup
    consumed: list[np.ndarray]


def working_camera(width: int, height: int, factor: int, hfov_deg: float = DEFAULT_HFOV_DEG) -> Camera:
    """Pinhole camera of an input ``width`` x ``height`` with field of view ``hfov_deg``, at
    the working resolution (:meth:`mocap.render.Camera.working`)."""
    return Camera.default(width, height, hfov_deg).working(width, height, factor)


def spread(start: int, stop: int, count: int) -> list[int]:
    """Up to ``count`` frame numbers spread evenly over ``start`` to ``stop - 1`` (sorted, unique)."""
    if stop <= start:
        return []
    return sorted({int(i) for i in np.linspace(start, stop - 1, min(count, stop - start)).round()})


def choose_background(frames: list[np.ndarray], imaging: ImagingConfig | None = None, *, face: Box | None = None,
                      face_frame: np.ndarray | None = None) -> tuple[np.ndarray | None, BackgroundAccount]:
    """Estimate a background from sample frames and decide whether to use it.

    Parameters
    ----------
    frames : list of ndarray of uint8, shape (H, W, 3)
        Frames spread over the clip (working resolution), at least 3.
    imaging : ImagingConfig, optional
    face : Box, optional
        The person's face in ``face_frame``.
    face_frame : ndarray of uint8, shape (H, W, 3), optional

    Returns
    -------
    background : ndarray of uint8, shape (H, W, 3), or None
        The estimate when the person moves enough (someone in view against it in at least
        :data:`MIN_FRAMES_WITH_PERSON` of the frames and, with a face, the face box at least
        :data:`MIN_FACE_FOREGROUND` foreground), else None (colour-only foreground).
    account : BackgroundAccount
        Mode ``auto``: ``used`` (the estimate), ``sample_frames``, ``evidence`` and ``reason``.
    """
    estimate, _ = estimate_background(frames, imaging)
    evidence = person_against_background(frames, estimate, imaging, face=face, face_frame=face_frame)
    moves = evidence["frames_with_person"] >= MIN_FRAMES_WITH_PERSON and \
        evidence.get("face_foreground", 1.0) >= MIN_FACE_FOREGROUND
    account = BackgroundAccount(
        mode="auto", used=bool(moves),
        details={"sample_frames": len(frames), "evidence": {k: round(v, 4) for k, v in evidence.items()}},
        reason=("the person moves enough: background estimated from the video (temporal median with a "
                "motion mask)") if moves else
               ("the person hardly moves: an estimated background would hold them; colour-only foreground"))
    return (estimate if moves else None), account


class FrameAccess:
    """Frames of the source by number, for the set-up: a file is read again later (only the
    chosen frames are decoded, one input-size frame held at a time); a camera is not, so what
    it delivered is kept (:attr:`consumed`, at most :data:`SEARCH_FRAMES` frames) to be tracked.

    Attributes
    ----------
    source : VideoSource or CameraSource
    consumed : list of ndarray
        A live source's frames read so far.
    count : int
        Frames to look at: a file's announced count (not waiting for the damage check), a
        camera's :data:`SEARCH_FRAMES`.
    """

    def __init__(self, source, search_frames: int = SEARCH_FRAMES) -> None:
        self.source, self.consumed = source, []
        self.count = search_frames if source.live else source.count_hint
        self._stream = iter(source.frames()) if source.live else None

    def at(self, indices):
        """``(index, input-size frame)`` of the frames ``indices`` that exist, in order."""
        if self._stream is None:
            indices = list(indices)
            return zip(indices, self.source.frames(indices=indices))
        return self._live_at(indices)

    def _live_at(self, indices):
        for index in indices:
            while len(self.consumed) <= index:
                frame = next(self._stream, None)
                if frame is None:
                    return
                self.consumed.append(frame)
            yield index, self.consumed[index]


@dataclass(frozen=True, eq=False)
class FaceSearch:
    """What :func:`look_for_face` found.

    Attributes
    ----------
    factor : int
        The working-resolution factor, settled.
    face_input : Box or None
        The face in input pixels.
    index : int or None
        Its frame.
    frame : ndarray of uint8, shape (H, W, 3), or None
        That input-size frame.
    """

    factor: int
    face_input: Box | None = None
    index: int | None = None
    frame: np.ndarray | None = None

    @property
    def face(self) -> Box | None:
        """The face in working pixels."""
        if self.face_input is None:
            return None
        return Box(*(int(round(v / self.factor)) for v in self.face_input))


def look_for_face(access: FrameAccess, request: SetupRequest, factor: int, choose_factor: bool) -> FaceSearch:
    """The first plausible face among every third of the first :data:`SEARCH_FRAMES` frames (none
    looked for with a given calibration), and the working factor (``choose_factor``: grown so
    that the face is at most :data:`FACE_WORKING_PX` working pixels wide)."""
    from tqdm import tqdm

    if request.calibration is not None:
        return FaceSearch(factor)
    searched = range(0, min(SEARCH_FRAMES, access.count), 3)
    for index, frame in tqdm(access.at(searched), total=len(searched), desc="looking for a face", unit="frame",
                             disable=not request.progress):
        found = find_face(frame, factor)
        if found is not None and plausible_face(frame, found):
            if choose_factor:
                factor = max(factor, int(found.width // FACE_WORKING_PX))
            return FaceSearch(factor, found, index, frame)
    return FaceSearch(factor)


@dataclass(frozen=True, eq=False)
class BackgroundFound:
    """What :func:`find_background` found.

    Attributes
    ----------
    image : ndarray of uint8, shape (h, w, 3), or None
        The empty scene at the working resolution; None: colour-only foreground.
    record : BackgroundAccount
    """

    image: np.ndarray | None
    record: BackgroundAccount


def find_background(access: FrameAccess, request: SetupRequest, factor: int, face: FaceSearch,
                    imaging: ImagingConfig) -> BackgroundFound:
    """The background of ``request.background_mode`` at the working resolution ``factor``."""
    source, mode = access.source, request.background_mode
    if mode == "image":
        image = request.background_image
        if image.shape[:2] != (source.height, source.width):
            raise ValueError(f"background is {image.shape[1]}x{image.shape[0]} but the video is "
                             f"{source.width}x{source.height}")
        return BackgroundFound(downscale(image, factor), BackgroundAccount(mode="image", used=True, reason="given"))
    if mode == "frames":
        a, b = request.background_frames
        empty = [downscale(f, factor) for _, f in access.at(spread(a, min(b, access.count), SAMPLE_FRAMES))]
        if not empty:
            raise ValueError(f"background frames {a}:{b}: the video has no such frames")
        return BackgroundFound(median_background(empty), BackgroundAccount(
            mode="frames", used=True, reason="median of the given empty frames", details={"frames": [a, b]}))
    if mode == "none":
        return BackgroundFound(None, BackgroundAccount(mode="none", used=False,
                                                       reason="asked for: colour-only foreground"))
    if source.live:
        return BackgroundFound(None, BackgroundAccount(
            mode="auto", used=False, reason="live camera without --background: colour-only foreground"))
    sample = source.sample(SAMPLE_FRAMES, min(SAMPLE_LIMIT, access.count), lambda frame: downscale(frame, factor))
    face_frame = downscale(face.frame, factor) if face.face_input is not None else None
    return BackgroundFound(*choose_background(sample, imaging, face=face.face, face_frame=face_frame))


def setup_with_calibration(first: np.ndarray, request: SetupRequest, background: np.ndarray | None, factor: int,
                           imaging: ImagingConfig, source) -> RunSetup:
    """The set-up of a given calibration on the input's first frame ``first``: with a
    background, a file's colours are learnt by the run (on the first frame that shows the
    person); colour-only, the scene's colours around the model and the classes inside it on
    the first frame; a live camera's on its first frame."""
    from mocap.body.mesh import resolution_for_image

    calibration, name, live = request.calibration, source.name, source.live
    first = downscale(first, factor)
    if calibration.camera.shape != first.shape[:2]:
        raise ValueError(f"the calibration's camera is {calibration.camera.width}x{calibration.camera.height}, "
                         f"the working frames {first.shape[1]}x{first.shape[0]}")
    model = calibration.body_model(resolution_for_image(calibration.camera.width, calibration.camera.height))
    colours = None
    if background is None or live:
        recipe = ColourRecipe("calibration", background, imaging, calibration, model, person_check=False,
                              scene_around=background is None)
        colours = learn_colours([(0, first)], recipe, name)
    return RunSetup(calibration, background, factor, imaging, None if colours is None else colours.model,
                    scene=None if colours is None else colours.scene)


def calibrate_automatically(access: FrameAccess, request: SetupRequest, camera: Camera, background: np.ndarray | None,
                            face: FaceSearch, imaging: ImagingConfig) -> tuple[PersonCalibration, int]:
    """The person calibrated on the face's frame, or without a face (with a background) on the
    first of every third frame with a person-sized foreground clear of the borders; and that
    frame's number."""
    source = access.source
    scale = (camera.width / source.width, camera.height / source.height)
    keypoints = request.keypoints

    def keypoints_of(index: int, full: np.ndarray):
        return None if keypoints is None else keypoints.keypoints(index, full).scaled(*scale)

    if face.face_input is not None:
        face_keypoints = keypoints_of(face.index, face.frame)
        return calibrate_person(downscale(face.frame, face.factor), camera, background=background, face=face.face,
                                height_m=request.height_m, imaging=imaging, keypoints=face_keypoints), face.index
    if background is None:
        searched = min(SEARCH_FRAMES, access.count)
        raise ValueError(f"no face found in the first {searched} frames and no background to find the "
                         "person by: pass --background IMG or --background-frames A:B, or --calibration JSON")
    for index, full in access.at(range(0, min(SAMPLE_LIMIT, access.count), 3)):
        frame = downscale(full, face.factor)
        if not whole_person(subtract_background(frame, background, imaging)):
            continue
        try:
            return calibrate_person(frame, camera, background=background, height_m=request.height_m,
                                    imaging=imaging, keypoints=keypoints_of(index, full)), index
        except ValueError:
            continue            # a person too small or cut off for every colour class: the next frame
    raise ValueError("nobody wholly in view (a person covering 2 % of the image, clear of its borders) "
                     f"in the first {SAMPLE_LIMIT} frames: cannot calibrate")


def find_setup(source, request: SetupRequest | None = None) -> FoundSetup:
    """Working resolution, background, calibration and colours of a video of a person, found
    from the video itself where ``request`` does not give them (the module's steps 1-3).

    Parameters
    ----------
    source : VideoSource or CameraSource
        :mod:`mocap.io.frames`.
    request : SetupRequest, optional

    Raises
    ------
    ValueError
        A background of another size, no usable frame, nobody to calibrate (one sentence each).
    """
    request = SetupRequest() if request is None else request
    factor = working_factor(source.width, source.height) if request.factor is None else request.factor
    imaging = ImagingConfig()
    if request.background_mode in ("auto", "none"):
        imaging = dataclasses.replace(imaging, min_object_fraction=max(imaging.min_object_fraction,
                                                                       MIN_PERSON_FRACTION))
    access = FrameAccess(source)
    first = next(iter(access.at([0])), (0, None))[1]
    if first is None:
        raise ValueError(f"{source.name} has no frames")
    face = look_for_face(access, request, factor, request.factor is None)
    factor = face.factor
    background = find_background(access, request, factor, face, imaging)

    def account(calibration: CalibrationAccount) -> SetupAccount:
        return SetupAccount(hfov_deg=request.hfov_deg, height_m=request.height_m, background=background.record,
                            working_factor=factor, calibration=calibration)

    if request.calibration is not None:
        setup = setup_with_calibration(first, request, background.image, factor, imaging, source)
        return FoundSetup(dataclasses.replace(setup, record=account(CalibrationAccount(source="given"))),
                          access.consumed)
    camera = working_camera(source.width, source.height, factor, request.hfov_deg)
    person, index = calibrate_automatically(access, request, camera, background.image, face, imaging)
    record = account(CalibrationAccount(
        source="automatic", frame=int(index),
        face_input_px=None if face.face_input is None else [int(v) for v in face.face_input],
        depth_m=round(float(person.calibration.initial_pose[2]), 3)))
    return FoundSetup(RunSetup(person.calibration, background.image, factor, imaging, person.colour_model,
                               scene=person.scene, record=record), access.consumed)
