"""Finding a person on one frame: the face (:func:`find_face`), a person to calibrate on
(:func:`find_person`), and the run's way to calibrate a newcomer (:class:`NewcomerFinder`).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from mocap.calibrate import AutoCalibrationConfig, PersonCalibration, calibrate_person
from mocap.imaging import Box, ImagingConfig, detect_face, rgb_to_hsv
from mocap.imaging.background import PERSON_MIN_SHARE, subtract_background
from mocap.imaging.resample import downscale
from mocap.render.camera import DEFAULT_HFOV_DEG, Camera
from mocap.run.accounts import CalibrationAccount

__all__ = ["FACE_SEARCH_SIDE", "FoundPerson", "NewcomerFinder", "find_face", "find_person", "plausible_face",
           "whole_person"]

#: Smallest face looked for, in working pixels (its skin sample must hold enough pixels).
MIN_FACE_WORKING_PX = 9
#: Longer side (pixels) of the image the face search looks at: a larger frame is first reduced
#: by an integer factor (block means, :func:`mocap.imaging.resample.downscale`) to about this.
FACE_SEARCH_SIDE = 640
#: Share of skin-toned pixels a face's centre must hold to be calibrated on.
MIN_FACE_SKIN = 0.3


@dataclass(frozen=True, eq=False)
class FoundPerson:
    """A person calibrated on one frame (:func:`find_person`).

    Attributes
    ----------
    person : PersonCalibration
        Calibration (working camera), colour classes and scene colours.
    face : Box or None
        The face in input pixels, None when found without one.
    """

    person: PersonCalibration
    face: Box | None


def whole_person(foreground: np.ndarray) -> bool:
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


def plausible_face(frame: np.ndarray, face: Box) -> bool:
    """A detection to calibrate on: skin-toned (at least :data:`MIN_FACE_SKIN` of its centre
    under the broad skin prior) and with room for the clothes box under it."""
    from mocap.imaging.colour import clothes_box_of_face, skin_box_of_face, skin_prior

    h, w = frame.shape[:2]
    clothes = clothes_box_of_face(face)
    if clothes.row + clothes.height > h or clothes.col < 0 or clothes.col + clothes.width > w:
        return False
    centre = frame[skin_box_of_face(face).slices]
    return float(skin_prior(rgb_to_hsv(centre)).mean()) >= MIN_FACE_SKIN


def find_person(frame: np.ndarray, factor: int, camera: Camera, background: np.ndarray | None,
                imaging: ImagingConfig, *, height_m: float | None = None, auto: AutoCalibrationConfig | None = None,
                whole_person: bool = True):
    """Calibrate the person in one input-size frame, or None when there is nobody to calibrate.

    The face first (:func:`find_face`, :func:`plausible_face`);
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
    FoundPerson or None
    """
    small = downscale(frame, factor)
    found = find_face(frame, factor)
    if found is not None and plausible_face(frame, found):
        face = Box(*(int(round(v / factor)) for v in found))
        try:
            return FoundPerson(calibrate_person(small, camera, background=background, face=face, height_m=height_m,
                                    imaging=imaging, config=auto), found)
        except ValueError:
            pass
    if not whole_person or background is None or not whole_person(subtract_background(small, background, imaging)):
        return None
    try:
        return FoundPerson(calibrate_person(small, camera, background=background, height_m=height_m,
                                            imaging=imaging, config=auto), None)
    except ValueError:
        return None             # a person too small or cut off for every colour class


@dataclass(frozen=True, eq=False)
class NewcomerFinder:
    """The run's way to calibrate a new person (:class:`mocap.run.loop.RunLoop`'s ``newcomer``):
    called with ``(frame index, input-size frame)``, it gives the new person's
    :class:`mocap.run.setup.RunSetup` (the same working resolution and background, a fresh
    calibration, colours and scene; its record the run's, the calibration's account the
    newcomer's) or None (:func:`find_person`). The same frame gives the same answer (a resumed
    run asks again).

    Attributes
    ----------
    setup : mocap.run.setup.RunSetup
        The run's set-up (its ``record`` a :class:`~mocap.run.accounts.SetupAccount`, or None).
    camera : Camera
        The default camera of the input at the working resolution.
    height_m : float or None, metres
    auto : AutoCalibrationConfig or None
    """

    setup: object  # mocap.run.setup.RunSetup (that module imports this one)
    camera: Camera
    height_m: float | None = None
    auto: AutoCalibrationConfig | None = None

    @classmethod
    def of(cls, setup, width: int, height: int, *, hfov_deg: float = DEFAULT_HFOV_DEG,
           height_m: float | None = None, auto: AutoCalibrationConfig | None = None) -> "NewcomerFinder":
        """The finder of a run on ``width`` x ``height`` input frames."""
        camera = Camera.default(width, height, hfov_deg).working(width, height, setup.factor)
        return cls(setup, camera, height_m, auto)

    def __call__(self, index: int, frame: np.ndarray):
        setup = self.setup
        found = find_person(frame, setup.factor, self.camera, setup.background, setup.imaging,
                            height_m=self.height_m, auto=self.auto)
        if found is None:
            return None
        person, face = found.person, found.face
        account = CalibrationAccount(source="automatic", frame=int(index),
                                     face_input_px=None if face is None else [int(v) for v in face],
                                     depth_m=round(float(person.calibration.initial_pose[2]), 3))
        record = None if setup.record is None else dataclasses.replace(setup.record, calibration=account)
        return dataclasses.replace(setup, calibration=person.calibration, colour_model=person.colour_model,
                                   scene=person.scene, record=record)
