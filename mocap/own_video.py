"""Your own video: no background plate, no calibration file, no known camera.

:func:`setup_own_video` finds what ``python -m mocap track VIDEO`` needs before frame 0 from
the video itself, at the tracker's working resolution (:mod:`mocap.imaging.resample`):

1. **Background** — given (an image, or the median of empty frames ``A:B``), none
   (colour-only foreground) or, by default, chosen: a background estimated from up to
   ``sample_frames`` frames of the clip (:func:`mocap.imaging.background.estimate_background`,
   temporal median with a motion mask) is used when the person moves enough to be seen
   against it (:func:`mocap.imaging.background.person_against_background`: the detected face
   at least half foreground, and someone in view in at least :data:`MIN_FRAMES_WITH_PERSON` of
   the frames); otherwise the foreground is colour-only (the colour classes, less the scene's
   colours: :mod:`mocap.imaging.scene`). A live camera has no clip to look at: colour-only
   unless a background is given.
2. **Calibration** — on the first usable frame among the first ``search_frames``: the first
   with a face (:func:`find_face`, on the frame reduced to about 640 pixels), or without a face
   but with a background, the first with a person-sized foreground
   (:func:`mocap.calibrate.calibrate_person`). The camera is a pinhole of horizontal field of
   view ``hfov_deg`` (default a typical webcam's); ``height_m`` fixes the absolute scale.

What was chosen and why goes into ``run.json`` (``settings.own_video``).

:func:`track_own_video` is the one entry point of "track my own video" (``python -m mocap
track``, ``bench``, experiments): it composes the set-up above (or a given background and
calibration, rescaled to the working resolution) with the run (:func:`mocap.pipeline.track_video`)
from an :class:`OwnVideoOptions`.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mocap.calibrate import AutoCalibrationConfig, Calibration, calibrate_person
from mocap.config import JsonConfig
from mocap.imaging import Box, ImagingConfig, detect_face, median_background, rgb_to_hsv
from mocap.imaging.background import PERSON_MIN_SHARE, estimate_background, person_against_background, \
    subtract_background
from mocap.imaging.resample import downscale, working_factor
from mocap.pipeline import COLOUR_SOURCES, RunSetup, RunSummary, track_video
from mocap.render.camera import DEFAULT_HFOV_DEG, Camera
from mocap.track import TrackerConfig

__all__ = ["BACKGROUND_MODES", "OwnVideoOptions", "choose_background", "setup_own_video", "track_own_video",
           "working_camera"]

#: How the background is found: ``auto`` (estimate, use if the person moves enough), ``image``
#: (a file), ``frames`` (median of frames A:B), ``none`` (colour-only foreground).
BACKGROUND_MODES = ("auto", "image", "frames", "none")
#: ``--keypoints`` values other than a keypoint file (:func:`resolve_keypoints`).
KEYPOINT_CHOICES = ("auto", "mediapipe", "none")
#: Share of the sample frames with someone in view (against the estimate) needed to use it.
MIN_FRAMES_WITH_PERSON = 0.3
#: Smallest part of the foreground (share of the image) kept when the background is estimated
#: or absent: smaller specks (a misjudged background pixel, a colour patch) are not a person,
#: and a frame with nothing larger has nobody in view.
MIN_PERSON_FRACTION = 0.01
#: Face width in working pixels the automatic working resolution aims at (at most): the
#: synthetic benchmark's actors at 160x120 have faces of 12-15 pixels.
FACE_WORKING_PX = 14
#: Smallest face looked for, in working pixels (its skin sample must hold enough pixels).
MIN_FACE_WORKING_PX = 9
#: Longer side (pixels) of the image the face search looks at: a larger frame is first reduced
#: by an integer factor (block means, :func:`mocap.imaging.resample.downscale`) to about this.
FACE_SEARCH_SIDE = 640
#: Share of skin-toned pixels a face's centre must hold to be calibrated on.
MIN_FACE_SKIN = 0.3
#: Share of the face box that must be foreground against the estimate to use it.
MIN_FACE_FOREGROUND = 0.5


def working_camera(width: int, height: int, factor: int, hfov_deg: float = DEFAULT_HFOV_DEG) -> Camera:
    """Pinhole camera of an input ``width`` x ``height`` with field of view ``hfov_deg``, at
    the working resolution (:meth:`mocap.render.Camera.working`)."""
    return Camera.default(width, height, hfov_deg).working(width, height, factor)


def spread(start: int, stop: int, count: int) -> list[int]:
    """Up to ``count`` frame numbers spread evenly over ``start`` to ``stop - 1`` (sorted, unique)."""
    if stop <= start:
        return []
    return sorted({int(i) for i in np.linspace(start, stop - 1, min(count, stop - start)).round()})


def _scene_around_model(frame: np.ndarray, model, calibration: Calibration):
    """Scene colours learnt outside the calibrated model's silhouette grown by a fifth of its
    size each way, and the foreground they leave inside the silhouette."""
    from mocap.calibrate import SCENE_RATIO
    from mocap.imaging.scene import SceneColours
    from mocap.render import render

    silhouette = render(calibration.initial_pose, model, calibration.camera).labels > 0
    rows, cols = np.nonzero(silhouette)
    if rows.size == 0:
        raise ValueError("the calibration's initial pose is outside the image")
    h, w = silhouette.shape
    dr, dc = (rows.max() - rows.min()) // 5 + 1, (cols.max() - cols.min()) // 5 + 1
    top, left = max(rows.min() - dr, 0), max(cols.min() - dc, 0)
    box = (top, left, min(rows.max() + dr, h - 1) - top + 1, min(cols.max() + dc, w - 1) - left + 1)
    scene = SceneColours.learn(frame, box, ratio=SCENE_RATIO)
    return scene, scene.foreground(frame) & silhouette


def _whole_person(foreground: np.ndarray) -> bool:
    """Someone to calibrate on without a face: a foreground covering :data:`PERSON_MIN_SHARE` of
    the image whose largest part stays a pixel clear of the image's borders."""
    from scipy import ndimage

    if foreground.mean() < PERSON_MIN_SHARE:
        return False
    parts, n = ndimage.label(foreground)
    largest = 1 + int(np.argmax(ndimage.sum(foreground, parts, range(1, n + 1))))
    rows, cols = np.nonzero(parts == largest)
    h, w = foreground.shape
    return bool(rows.min() > 0 and cols.min() > 0 and rows.max() < h - 1 and cols.max() < w - 1)


def find_face(frame: np.ndarray, factor: int) -> Box | None:
    """The face in an input-size frame (:func:`mocap.imaging.detect_face`, smallest side
    ``max(24, MIN_FACE_WORKING_PX * factor)`` pixels of the searched image), searched on the
    frame reduced by an integer factor to about :data:`FACE_SEARCH_SIDE` pixels (a block mean:
    cheaper than the detector's own smoothing of the whole input frame), or None.

    Parameters
    ----------
    frame : ndarray of uint8, shape (H, W, 3)
        Input-size frame.
    factor : int
        Working-resolution factor.

    Returns
    -------
    Box or None
        In input pixels.
    """
    search = max(1, int(np.ceil(max(frame.shape[:2]) / FACE_SEARCH_SIDE - 1e-9)))
    found = detect_face(downscale(frame, search), min_size=max(24, MIN_FACE_WORKING_PX * factor),
                        max_side=FACE_SEARCH_SIDE)
    return None if found is None else Box(*(int(v) * search for v in found))


def _plausible_face(frame: np.ndarray, face: Box) -> bool:
    """A detection to calibrate on: skin-toned (at least :data:`MIN_FACE_SKIN` of its centre
    under the broad skin prior) and with room for the clothes box under it."""
    from mocap.imaging.colour import clothes_box_of_face, skin_box_of_face, skin_prior

    h, w = frame.shape[:2]
    clothes = clothes_box_of_face(face)
    if clothes.row + clothes.height > h or clothes.col < 0 or clothes.col + clothes.width > w:
        return False
    centre = frame[skin_box_of_face(face).slices]
    return float(skin_prior(rgb_to_hsv(centre)).mean()) >= MIN_FACE_SKIN


def choose_background(frames: list[np.ndarray], imaging: ImagingConfig | None = None, *, face: Box | None = None,
                      face_frame: np.ndarray | None = None) -> tuple[np.ndarray | None, dict]:
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
    record : dict
        ``mode`` ("estimated" or "none"), ``reason``, ``evidence``, ``sample_frames``.
    """
    estimate, _ = estimate_background(frames, imaging)
    evidence = person_against_background(frames, estimate, imaging, face=face, face_frame=face_frame)
    moves = evidence["frames_with_person"] >= MIN_FRAMES_WITH_PERSON and \
        evidence.get("face_foreground", 1.0) >= MIN_FACE_FOREGROUND
    record = {"mode": "estimated" if moves else "none", "sample_frames": len(frames),
              "evidence": {k: round(v, 4) for k, v in evidence.items()},
              "reason": ("the person moves enough: background estimated from the video (temporal median with a "
                         "motion mask)") if moves else
                        ("the person hardly moves: an estimated background would hold them; colour-only foreground")}
    return (estimate if moves else None), record


def find_person(frame: np.ndarray, factor: int, camera: Camera, background: np.ndarray | None,
                imaging: ImagingConfig, *, height_m: float | None = None, auto: AutoCalibrationConfig | None = None,
                whole_person: bool = True):
    """Calibrate the person in one input-size frame, or None when there is nobody to calibrate.

    The face first (:func:`find_face`, :func:`_plausible_face`);
    without one and with a background, a person-sized foreground clear of the borders.

    Parameters
    ----------
    frame : ndarray of uint8, shape (H, W, 3)
        Input-size frame.
    factor : int
        Working-resolution factor; ``camera`` is the working camera.
    background : ndarray of uint8, shape (H // factor, W // factor, 3), or None
    whole_person : bool
        Also try without a face (with a background).

    Returns
    -------
    (PersonCalibration, face box in input pixels or None) or None
    """
    small = downscale(frame, factor)
    found = find_face(frame, factor)
    if found is not None and _plausible_face(frame, found):
        face = Box(*(int(round(v / factor)) for v in found))
        try:
            return calibrate_person(small, camera, background=background, face=face, height_m=height_m,
                                    imaging=imaging, config=auto), found
        except ValueError:
            pass
    if not whole_person or background is None or not _whole_person(subtract_background(small, background, imaging)):
        return None
    try:
        return calibrate_person(small, camera, background=background, height_m=height_m, imaging=imaging,
                                config=auto), None
    except ValueError:
        return None             # a person too small or cut off for every colour class


def newcomer_finder(setup: RunSetup, width: int, height: int, *, hfov_deg: float = DEFAULT_HFOV_DEG,
                    height_m: float | None = None, auto: AutoCalibrationConfig | None = None):
    """The run's way to calibrate a new person (:func:`mocap.pipeline.track_video` ``newcomer``):
    a function of ``(frame index, input-size frame)`` giving the new person's
    :class:`mocap.pipeline.RunSetup` (same working resolution and background, a fresh
    calibration, colours and scene) or None (:func:`find_person`)."""
    camera = Camera.default(width, height, hfov_deg).working(width, height, setup.factor)

    def newcomer(index: int, frame: np.ndarray):
        found = find_person(frame, setup.factor, camera, setup.background, setup.imaging, height_m=height_m,
                            auto=auto)
        if found is None:
            return None
        person, face = found
        record = {"frame": int(index), "face_input_px": None if face is None else [int(v) for v in face],
                  "depth_m": round(float(person.calibration.initial_pose[2]), 3)}
        return dataclasses.replace(setup, calibration=person.calibration, colour_model=person.colour_model,
                                   scene=person.scene, record=record)
    return newcomer


def setup_own_video(source, factor: int | None = None, *, background_mode: str = "auto", background_image=None,
                    background_frames: tuple[int, int] | None = None, calibration: Calibration | None = None,
                    hfov_deg: float = DEFAULT_HFOV_DEG, height_m: float | None = None,
                    imaging: ImagingConfig | None = None, auto: AutoCalibrationConfig | None = None,
                    sample_frames: int = 60, sample_limit: int = 1500, search_frames: int = 90,
                    progress: bool = True, keypoints=None) -> tuple[RunSetup, list[np.ndarray]]:
    """Background and calibration of a video of a person, found from the video itself.

    Parameters
    ----------
    source : VideoSource or CameraSource
        :mod:`mocap.io.frames`.
    factor : int, optional
        Working-resolution factor. By default the tracker chooses: the factor that brings the
        width nearest to 160 pixels (:func:`mocap.imaging.resample.working_factor`), or a
        larger one when the face found is bigger than :data:`FACE_WORKING_PX` working pixels
        (a person close to the camera fills the frame: fewer pixels describe them as well,
        and every cost evaluation is cheaper).
    background_mode : {"auto", "image", "frames", "none"}
    background_image : ndarray of uint8, shape (H, W, 3), optional
        Input-size image of the empty scene (mode ``image``).
    background_frames : (int, int), optional
        Frames ``A:B`` of empty scene (mode ``frames``).
    calibration : Calibration, optional
        A calibration to use (its camera at the working resolution); its colours are learnt
        inside its initial pose on the first frame.
    hfov_deg : float, degrees
        Horizontal field of view of the camera.
    height_m : float, optional
        The person's stature, metres.
    imaging : ImagingConfig, optional
    auto : AutoCalibrationConfig, optional
    sample_frames, sample_limit : int
        Background estimation uses ``sample_frames`` frames spread over the first
        ``sample_limit`` (chosen by number first, each reduced to the working resolution as it
        is read: the set-up holds at most ``sample_frames`` working-size frames and one
        input-size frame of a file); ``--background-frames A:B`` likewise.
    search_frames : int
        Calibration looks at most this many frames into the video for a usable frame.
    progress : bool
        Progress bars.
    keypoints : KeypointSource, optional
        2D keypoints (:mod:`mocap.io.keypoints`): the calibration frame's pull the fitted model's
        joints onto them (:func:`mocap.calibrate.calibrate_person`).

    Returns
    -------
    setup : mocap.pipeline.RunSetup
        Everything at the working resolution; with a found (not given) background, parts of
        the foreground smaller than :data:`MIN_PERSON_FRACTION` of the image are not a person
        (``setup.imaging``); ``setup.record`` is the JSON-ready account of the choices
        (background mode and evidence, calibration frame, face, field of view, height).
    consumed : list of ndarray
        For a live source, the input frames read so far (the run tracks them first); empty
        for a file.

    Raises
    ------
    ValueError
        An unknown mode, a background of another size, no usable frame.
    """
    from tqdm import tqdm

    from mocap.calibrate import colour_model_from_pose

    if background_mode not in BACKGROUND_MODES:
        raise ValueError(f"background mode must be one of {BACKGROUND_MODES}, got {background_mode!r}")
    auto_factor = factor is None
    if auto_factor:
        factor = working_factor(source.width, source.height)
    imaging = ImagingConfig() if imaging is None else imaging
    if background_mode in ("auto", "none"):
        imaging = dataclasses.replace(imaging, min_object_fraction=max(imaging.min_object_fraction,
                                                                       MIN_PERSON_FRACTION))
    record: dict = {"hfov_deg": hfov_deg, "height_m": height_m}
    consumed: list[np.ndarray] = []
    # frames the setup looks at, by index: a file is read again later (only the chosen frames
    # are converted, and only one input-size frame is held at a time); a camera is not, so
    # what it delivered is kept to be tracked (at most ``search_frames`` frames)
    if source.live:
        stream = iter(source.frames())

        def frames_at(indices):
            for index in indices:
                while len(consumed) <= index:
                    frame = next(stream, None)
                    if frame is None:
                        return
                    consumed.append(frame)
                yield index, consumed[index]
        count = search_frames
    else:
        def frames_at(indices):
            indices = list(indices)
            return zip(indices, source.frames(indices=indices))
        count = source.count_hint          # not waiting for the damage check

    # 1. the first usable frame: a face (or, with a background, a person-sized foreground)
    face = face_frame_full = None
    calib_index = None
    searched = range(0, min(search_frames, count), 3)
    first = next(iter(frames_at([0])), (0, None))[1]
    if first is None:
        raise ValueError(f"{source.name} has no frames")
    if calibration is None:
        for index, frame in tqdm(frames_at(searched), total=len(searched), desc="looking for a face", unit="frame",
                                 disable=not progress):
            found = find_face(frame, factor)
            if found is not None and _plausible_face(frame, found):
                face_full, calib_index, face_frame_full = found, index, frame
                if auto_factor:
                    factor = max(factor, int(found.width // FACE_WORKING_PX))
                face = Box(*(int(round(v / factor)) for v in found))
                break

    # 2. background (at the working resolution now settled), from frames reduced as they are read
    camera = working_camera(source.width, source.height, factor, hfov_deg)
    face_frame = downscale(face_frame_full, factor) if face is not None else None

    def keypoints_of(index: int, full: np.ndarray):
        """The calibration frame's keypoints in working pixels (None without a source)."""
        if keypoints is None:
            return None
        return keypoints.keypoints(index, full).scaled(camera.width / source.width, camera.height / source.height)

    face_keypoints = keypoints_of(calib_index, face_frame_full) if face is not None else None
    del face_frame_full
    background = None
    if background_mode == "image":
        if background_image.shape[:2] != (source.height, source.width):
            raise ValueError(f"background is {background_image.shape[1]}x{background_image.shape[0]}, frames are "
                             f"{source.width}x{source.height}")
        background = downscale(background_image, factor)
        record["background"] = {"mode": "image", "reason": "given"}
    elif background_mode == "frames":
        a, b = background_frames
        empty = [downscale(f, factor) for _, f in frames_at(spread(a, min(b, count), sample_frames))]
        if not empty:
            raise ValueError(f"background frames {a}:{b}: the video has no such frames")
        background = median_background(empty)
        record["background"] = {"mode": "frames", "frames": [a, b], "reason": "median of the given empty frames"}
    elif background_mode == "none":
        record["background"] = {"mode": "none", "reason": "asked for: colour-only foreground"}
    elif source.live:
        record["background"] = {"mode": "none", "reason": "live camera without --background: colour-only foreground"}

    if background_mode == "auto" and not source.live:
        sample = [downscale(f, factor) for _, f in frames_at(spread(0, min(sample_limit, count), sample_frames))]
        background, record["background"] = choose_background(sample, imaging, face=face, face_frame=face_frame)
        del sample

    if calibration is not None:
        first = downscale(first, factor)
        if calibration.camera.shape != first.shape[:2]:
            raise ValueError(f"the calibration's camera is {calibration.camera.width}x{calibration.camera.height}, "
                             f"the working frames {first.shape[1]}x{first.shape[0]}")
        from mocap.body.mesh import resolution_for_image
        model = calibration.body_model(resolution_for_image(calibration.camera.width, calibration.camera.height))
        scene = colour = foreground = None   # a file with a background: the run learns the colours on the
        if background is None:               # first frame that shows the person; colour-only: the scene's
            scene, foreground = _scene_around_model(first, model, calibration)   # colours around the model
        if background is None or source.live:
            colour = colour_model_from_pose(first, background, model, calibration.camera, calibration.initial_pose,
                                            imaging, foreground=foreground)
        record["working_factor"] = factor
        record["calibration"] = {"from": "given"}
        return RunSetup(calibration, background, factor, imaging, colour, scene=scene, record=record), consumed

    if face is not None:
        person = calibrate_person(face_frame, camera, background=background, face=face, height_m=height_m,
                                  imaging=imaging, config=auto, keypoints=face_keypoints)
    else:
        if background is None:
            raise ValueError(f"no face found in the first {searched.stop} frames and no background to find the "
                             "person by: pass --background IMG or --background-frames A:B, or --calibration JSON")
        person = None
        for index, full in frames_at(range(0, min(sample_limit, count), 3)):
            frame = downscale(full, factor)
            if not _whole_person(subtract_background(frame, background, imaging)):
                continue
            try:
                person = calibrate_person(frame, camera, background=background, height_m=height_m,
                                          imaging=imaging, config=auto, keypoints=keypoints_of(index, full))
            except ValueError:
                continue            # a person too small or cut off for every colour class: the next frame
            calib_index = index
            break
        if person is None:
            raise ValueError("nobody wholly in view (a person covering 2 % of the image, clear of its borders) "
                             f"in the first {sample_limit} frames: cannot calibrate")
    record["working_factor"] = factor
    record["calibration"] = {"from": "automatic", "frame": int(calib_index),
                             "face_input_px": [int(v) for v in face_full] if face is not None else None,
                             "depth_m": round(float(person.calibration.initial_pose[2]), 3)}
    return RunSetup(person.calibration, background, factor, imaging, person.colour_model, scene=person.scene,
                    record=record), consumed


@dataclass(frozen=True)
class OwnVideoOptions(JsonConfig):
    """What ``python -m mocap track`` lets a person set, as one JSON-backed record
    (:func:`track_own_video`). Paths are strings (JSON); every field has the CLI's default.

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
        Where the colour classes are learnt (:class:`mocap.pipeline.RunSetup` ``colour_from``).
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
        2D keypoints: ``"mediapipe"`` (MediaPipe Pose, the optional extra ``keypoints``), a
        keypoint file (:mod:`mocap.io.keypoints`), ``"auto"`` (MediaPipe when the extra imports,
        none otherwise: the command line's default, :func:`resolve_keypoints`) or None /
        ``"none"``; the tracker adds them as a cue (``tracker.keypoint_weight``).
    tracker : TrackerConfig
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
    keypoints: str | None = None
    tracker: TrackerConfig = field(default_factory=TrackerConfig)

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
        if self.work_width is not None and self.work_width < 16:
            raise ValueError(f"the working width must be at least 16 pixels, got {self.work_width}")

    def background_mode(self, sequence_background: bool = False) -> str:
        """One of :data:`BACKGROUND_MODES` (``sequence_background``: a sequence folder's own
        ``background.png`` is used unless told otherwise)."""
        if self.background is not None or sequence_background:
            return "image"
        if self.background_frames is not None:
            return "frames"
        return "none" if self.no_background else "auto"


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
        return None, ("none (auto: MediaPipe Pose, the optional extra 'keypoints', is not installed; "
                      "pip install 'mocap[keypoints]' adds 2D keypoints as a cue)")
    return name, name if name == "mediapipe" else f"file {name}"


def keypoint_source(name: str | None):
    """The :class:`~mocap.io.keypoints.KeypointSource` of ``OwnVideoOptions.keypoints``: None,
    MediaPipe Pose for ``"mediapipe"`` (ValueError in one line without the extra) and for
    ``"auto"`` where the extra imports (:func:`resolve_keypoints`), else a keypoint file
    (FileNotFoundError, ValueError naming the line of a malformed one)."""
    resolved, _ = resolve_keypoints(name)
    if resolved is None:
        return None
    if resolved == "mediapipe":
        from mocap.io.mediapipe_keypoints import MediaPipeKeypoints
        source = MediaPipeKeypoints()
        if name == "auto":
            source.description += " (--keypoints auto)"
        return source
    from mocap.io.keypoints import KeypointFile
    return KeypointFile(resolved)


def track_own_video(source, out_dir: str | Path, options: OwnVideoOptions | None = None, *, progress: bool = True,
                    on_setup: Callable[[dict], None] | None = None) -> RunSummary:
    """Track a person's own video: set-up from the video (or as given), then the run.

    Parameters
    ----------
    source : str, Path or CameraSource
        A video file, a folder of images, a sequence folder (its ``background.png``,
        ``calibration.json``, ``ground_truth.csv`` and ``meta.json`` frame rate are used when
        ``options`` give none), or a live :class:`mocap.io.frames.CameraSource`.
    out_dir : str or Path
        Output folder (:func:`mocap.pipeline.track_video`).
    options : OwnVideoOptions, optional
    progress : bool
        Progress bars.
    on_setup : callable, optional
        Called with the set-up's account (``run.json`` ``settings.own_video``, plus
        ``input_width``, ``input_height``, ``working_width``, ``working_height``) before the
        first frame is tracked (the CLI prints it).

    Returns
    -------
    RunSummary
        ``setup`` is the account given to ``on_setup``.

    Raises
    ------
    ValueError, FileNotFoundError
        Bad options, missing files, a damaged video, no usable frame (one sentence each).
    """
    from mocap.imaging.resample import working_factor
    from mocap.io.frames import VideoSource
    from mocap.io.sequence import find_sequence
    from mocap.io.video import read_image

    options = OwnVideoOptions() if options is None else options
    keypoints = keypoint_source(options.keypoints)          # a bad keypoint file stops the run first
    keypoints_used = resolve_keypoints(options.keypoints)[1]
    live = bool(getattr(source, "live", False))
    if live:
        if options.background_frames is not None:
            raise ValueError("background frames need a video file, not a live camera")
        seq, frames_in = None, source
    else:
        seq = find_sequence(source)
        frames_in = VideoSource(seq.frames, fps=seq.fps() if seq.meta is not None else None)
    try:
        seq_background = seq.background if seq is not None and not options.no_background and \
            options.background_frames is None else None
        background = options.background or seq_background
        calibration = options.calibration or (seq.calibration if seq is not None else None)
        for what, path in (("background", background), ("calibration", calibration)):
            if path is not None and not Path(path).is_file():
                raise FileNotFoundError(f"{what} file not found: {path}")
        width, height = frames_in.width, frames_in.height
        factor = None if options.work_width is None else working_factor(width, height, options.work_width)
        given = None
        if calibration is not None:
            given = Calibration.from_json(calibration)
            factor = factor or working_factor(width, height)
            given = dataclasses.replace(given, camera=given.camera.working(width, height, factor))
        setup, consumed = setup_own_video(
            frames_in, factor, background_mode=options.background_mode(seq_background is not None),
            background_image=read_image(background) if background else None,
            background_frames=options.background_frames, calibration=given, hfov_deg=options.hfov_deg,
            height_m=options.height_m, progress=progress, keypoints=keypoints)
        if live:
            frames_in.hold(consumed)
        setup = dataclasses.replace(setup, colour_from=options.colour,
                                    background_file=Path(background) if background else None,
                                    record={**setup.record, "keypoints": keypoints_used})
        account = {**setup.record, "input_width": width, "input_height": height,
                   "working_width": setup.calibration.camera.width, "working_height": setup.calibration.camera.height}
        if on_setup is not None:
            on_setup(account)
        fps = (seq.fps(frames_in.fps or 25.0) if seq is not None and seq.meta is not None else frames_in.fps) or 25.0
        ground_truth = options.ground_truth or (seq.ground_truth if seq is not None else None)
        newcomer = newcomer_finder(setup, width, height, hfov_deg=options.hfov_deg, height_m=options.height_m)
        summary = track_video(frames_in, setup, out_dir, options.tracker, ground_truth=ground_truth, fps=fps,
                              max_frames=options.max_frames, overwrite=options.overwrite, progress=progress,
                              write_overlay=options.overlay, allow_damaged=options.allow_damaged,
                              start_frame=options.start, show=options.show, newcomer=newcomer,
                              keypoints=keypoints)
        summary.setup = account
        return summary
    finally:
        if not live:
            frames_in.close()       # the damage check's ffmpeg, when the run ended before it did
