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
   with a face (:func:`mocap.imaging.detect_face`, at input resolution), or without a face
   but with a background, the first with a person-sized foreground
   (:func:`mocap.calibrate.calibrate_person`). The camera is a pinhole of horizontal field of
   view ``hfov_deg`` (default a typical webcam's); ``height_m`` fixes the absolute scale.

What was chosen and why goes into ``run.json`` (``settings.own_video``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mocap.calibrate import AutoCalibrationConfig, Calibration, calibrate_person
from mocap.imaging import Box, ColourModel, ImagingConfig, detect_face, median_background
from mocap.imaging.background import PERSON_MIN_SHARE, estimate_background, person_against_background, \
    subtract_background
from mocap.imaging.resample import downscale
from mocap.render.camera import DEFAULT_HFOV_DEG, Camera

__all__ = ["BACKGROUND_MODES", "OwnVideoSetup", "choose_background", "setup_own_video", "working_camera"]

#: How the background is found: ``auto`` (estimate, use if the person moves enough), ``image``
#: (a file), ``frames`` (median of frames A:B), ``none`` (colour-only foreground).
BACKGROUND_MODES = ("auto", "image", "frames", "none")
#: Share of the sample frames with someone in view (against the estimate) needed to use it.
MIN_FRAMES_WITH_PERSON = 0.3
#: Smallest face looked for, in working pixels (its skin sample must hold enough pixels).
MIN_FACE_WORKING_PX = 9
#: Share of the face box that must be foreground against the estimate to use it.
MIN_FACE_FOREGROUND = 0.5


def working_camera(width: int, height: int, factor: int, hfov_deg: float = DEFAULT_HFOV_DEG) -> Camera:
    """Pinhole camera of an input ``width`` x ``height`` with field of view ``hfov_deg``, at
    the working resolution ``(width // factor, height // factor)`` (intrinsics divided by
    ``factor``, so that working pixel coordinates times ``factor`` are input pixels)."""
    full = Camera.default(width, height, hfov_deg)
    return Camera(width // factor, height // factor, full.fx / factor, full.fy / factor, full.cx / factor,
                  full.cy / factor)


@dataclass(frozen=True, eq=False)
class OwnVideoSetup:
    """What :func:`setup_own_video` found (everything at the working resolution).

    Attributes
    ----------
    factor : int
        Input pixels per working pixel.
    background : ndarray of uint8, shape (h, w, 3), or None
    calibration : Calibration
    colour_model : ColourModel
    scene : SceneColours or None
    record : dict
        JSON-ready account of the choices (background mode and evidence, calibration frame,
        face, field of view, height).
    """

    factor: int
    background: np.ndarray | None
    calibration: Calibration
    colour_model: ColourModel
    scene: object
    record: dict


def _sample(frames, count: int, limit: int) -> list[tuple[int, np.ndarray]]:
    """Up to ``count`` frames spread evenly over the first ``limit`` (index, frame) pairs."""
    frames = list(frames)[:limit]
    if len(frames) <= count:
        return frames
    picks = np.unique(np.linspace(0, len(frames) - 1, count).round().astype(int))
    return [frames[i] for i in picks]


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


def setup_own_video(source, factor: int, *, background_mode: str = "auto", background_image=None,
                    background_frames: tuple[int, int] | None = None, calibration: Calibration | None = None,
                    hfov_deg: float = DEFAULT_HFOV_DEG, height_m: float | None = None,
                    imaging: ImagingConfig | None = None, auto: AutoCalibrationConfig | None = None,
                    sample_frames: int = 60, sample_limit: int = 600, search_frames: int = 90,
                    progress: bool = True) -> tuple[OwnVideoSetup, list[np.ndarray]]:
    """Background and calibration of a video of a person, found from the video itself.

    Parameters
    ----------
    source : VideoSource or CameraSource
        :mod:`mocap.io.frames`.
    factor : int
        Working-resolution factor (:func:`mocap.imaging.resample.working_factor`).
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
        ``sample_limit``.
    search_frames : int
        Calibration looks at most this many frames into the video for a usable frame.

    Returns
    -------
    setup : OwnVideoSetup
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
    imaging = ImagingConfig() if imaging is None else imaging
    camera = working_camera(source.width, source.height, factor, hfov_deg)
    record: dict = {"hfov_deg": hfov_deg, "height_m": height_m}
    consumed: list[np.ndarray] = []
    # frames the setup may look at: a file is read again later, a camera is not
    if source.live:
        def early(limit):
            while len(consumed) < limit:
                frame = next(stream, None)
                if frame is None:
                    break
                consumed.append(frame)
            return list(enumerate(consumed[:limit]))
        stream = iter(source.frames())
    else:
        def early(limit):
            return list(enumerate(source.frames(0, limit)))

    # 1. background
    background = None
    if background_mode == "image":
        if background_image.shape[:2] != (source.height, source.width):
            raise ValueError(f"background is {background_image.shape[1]}x{background_image.shape[0]}, frames are "
                             f"{source.width}x{source.height}")
        background = downscale(background_image, factor)
        record["background"] = {"mode": "image", "reason": "given"}
    elif background_mode == "frames":
        a, b = background_frames
        empty = [f for i, f in early(b) if i >= a]
        if not empty:
            raise ValueError(f"background frames {a}:{b}: the video has no such frames")
        background = downscale(median_background(empty), factor)
        record["background"] = {"mode": "frames", "frames": [a, b], "reason": "median of the given empty frames"}
    elif background_mode == "none":
        record["background"] = {"mode": "none", "reason": "asked for: colour-only foreground"}
    elif source.live:
        record["background"] = {"mode": "none", "reason": "live camera without --background: colour-only foreground"}

    # 2. the first usable frame: a face (or, with a background, a person-sized foreground)
    face = None
    calib_index = None
    candidates = early(search_frames)
    if not candidates:
        raise ValueError(f"{source.name} has no frames")
    if calibration is None:
        for index, frame in tqdm(candidates[::3], desc="looking for a face", unit="frame", disable=not progress):
            found = detect_face(frame, min_size=max(24, MIN_FACE_WORKING_PX * factor))
            if found is not None:
                face_full, calib_index = found, index
                face = Box(*(int(round(v / factor)) for v in found))
                break

    if background_mode == "auto" and not source.live:
        sample = _sample(enumerate(source.frames(0, sample_limit)), sample_frames, sample_limit)
        face_frame = downscale(candidates[calib_index][1], factor) if face is not None else None
        background, record["background"] = choose_background([downscale(f, factor) for _, f in sample], imaging,
                                                             face=face, face_frame=face_frame)

    if calibration is not None:
        first = downscale(candidates[0][1], factor)
        if calibration.camera.shape != first.shape[:2]:
            raise ValueError(f"the calibration's camera is {calibration.camera.width}x{calibration.camera.height}, "
                             f"the working frames {first.shape[1]}x{first.shape[0]}")
        model = calibration.body_model()
        colour = colour_model_from_pose(first, background, model, calibration.camera, calibration.initial_pose,
                                        imaging)
        record["calibration"] = {"from": "given"}
        return OwnVideoSetup(factor, background, calibration, colour, None, record), consumed

    if face is None:
        if background is None:
            raise ValueError(f"no face found in the first {len(candidates)} frames and no background to find the "
                             "person by: pass --background IMG or --background-frames A:B, or --calibration JSON")
        for index, frame in candidates:
            if subtract_background(downscale(frame, factor), background, imaging).mean() >= PERSON_MIN_SHARE:
                calib_index = index
                break
        if calib_index is None:
            raise ValueError(f"nobody in view in the first {len(candidates)} frames: cannot calibrate")
    frame = downscale(candidates[calib_index][1], factor)
    person = calibrate_person(frame, camera, background=background, face=face, height_m=height_m,
                              imaging=imaging, config=auto)
    record["calibration"] = {"from": "automatic", "frame": int(calib_index),
                             "face_input_px": [int(v) for v in face_full] if face is not None else None,
                             "depth_m": round(float(person.calibration.initial_pose[2]), 3)}
    return OwnVideoSetup(factor, background, person.calibration, person.colour_model, person.scene, record), consumed
