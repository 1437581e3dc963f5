"""The colour classes of a run, learnt in one place (:func:`learn_colours`).

Every route that needs a colour model before tracking comes here: the run (the first frame
from the start that shows the person), the set-up with a given calibration (colour-only
foreground or a live camera: the first frame), and ``segment`` (a face or sample boxes the
user gives). How to learn is a :class:`ColourRecipe`; the learners themselves are the image
side's (:func:`mocap.imaging.learn_colour_model`: a face and boxes) and the calibration's
(:func:`mocap.calibrate.colour_model_from_pose`: inside a posed model). An automatic
calibration (:func:`mocap.calibrate.calibrate_person`) learns its colours inside its own fit,
with the same :func:`~mocap.calibrate.colour_model_from_pose`.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from mocap.body import BodyModel
from mocap.calibrate import SCENE_RATIO, Calibration, colour_model_from_pose
from mocap.imaging import Box, ColourModel, ImagingConfig, learn_colour_model, subtract_background
from mocap.imaging.scene import SceneColours

__all__ = ["PLAUSIBLE_FOREGROUND", "ColourRecipe", "LearntColours", "SampleBoxes", "learn_colours",
           "scene_around_model"]

#: Fraction of the calibrated model's silhouette (pixels) the foreground must cover for a frame to
#: be taken as showing the person, to learn the colours on.
PLAUSIBLE_FOREGROUND = 0.5


@dataclass(frozen=True)
class SampleBoxes:
    """Sample boxes in working pixels (:class:`mocap.imaging.Box` or ``(row, col, height,
    width)``), each None for the automatic one (the face's)."""

    skin: Box | tuple[int, int, int, int] | None = None
    clothes: Box | tuple[int, int, int, int] | None = None
    hair: Box | tuple[int, int, int, int] | None = None
    lower_body: Box | tuple[int, int, int, int] | None = None


@dataclass(frozen=True, eq=False)
class ColourRecipe:
    """How to learn a run's colour classes.

    Attributes
    ----------
    source : {"calibration", "face"}
        Inside the calibrated model's projected parts (``calibration``), or from the detected
        face and the boxes under and above it (``face``, the paper's way; ``boxes`` replace them).
    background : ndarray of uint8, shape (h, w, 3), or None
        The empty scene at the working resolution; None: colour-only foreground.
    imaging : ImagingConfig
    calibration : Calibration or None
        The person's calibration (camera at the working size), for ``calibration``.
    model : BodyModel or None
        Its body model, for ``calibration``.
    boxes : SampleBoxes or None
        For ``face``: boxes given instead of the face's.
    person_check : bool
        With a background, ``calibration`` skips frames whose foreground covers less than
        :data:`PLAUSIBLE_FOREGROUND` of the model's silhouette (nobody there yet).
    scene_around : bool
        Colour-only ``calibration``: learn the scene's colours around the model first and the
        classes on the foreground they leave inside it (:func:`scene_around_model`).
    """

    source: str
    background: np.ndarray | None
    imaging: ImagingConfig
    calibration: Calibration | None = None
    model: BodyModel | None = None
    boxes: SampleBoxes | None = None
    person_check: bool = True
    scene_around: bool = False


@dataclass(frozen=True, eq=False)
class LearntColours:
    """What :func:`learn_colours` found.

    Attributes
    ----------
    model : ColourModel
    frame : int
        The frame it was learnt on.
    scene : SceneColours or None
        The scene's colours (``scene_around``), else None.
    """

    model: ColourModel
    frame: int
    scene: SceneColours | None = None


def scene_around_model(frame: np.ndarray, model: BodyModel, calibration: Calibration):
    """Scene colours learnt outside the calibrated model's silhouette grown by a fifth of its
    size each way, and the foreground (bool, shape (h, w)) they leave inside the silhouette."""
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


def learn_colours(frames: Iterable[tuple[int, np.ndarray]], recipe: ColourRecipe, name: str) -> LearntColours:
    """The colour model learnt on the first of ``frames`` that shows the person.

    Parameters
    ----------
    frames : iterable of (int, ndarray of uint8, shape (h, w, 3))
        Frame numbers and working-size frames, in order.
    recipe : ColourRecipe
    name : str
        The video's name, for the error.

    Raises
    ------
    ValueError
        No frame shows the person (with the last frame's reason).
    """
    silhouette = None
    reason = "no frame"
    for index, frame in frames:
        try:
            if recipe.source == "face":
                boxes = recipe.boxes or SampleBoxes()
                return LearntColours(learn_colour_model(frame, recipe.background, boxes.skin, boxes.clothes,
                                                        hair_box=boxes.hair, lower_body_box=boxes.lower_body,
                                                        config=recipe.imaging), index)
            calibration = recipe.calibration
            if recipe.scene_around:
                scene, foreground = scene_around_model(frame, recipe.model, calibration)
                return LearntColours(colour_model_from_pose(frame, None, recipe.model, calibration.camera,
                                                            calibration.initial_pose, recipe.imaging,
                                                            foreground=foreground), index, scene)
            if recipe.background is not None and recipe.person_check:
                if silhouette is None:
                    silhouette = _silhouette_pixels(recipe.model, calibration)
                covered = np.count_nonzero(subtract_background(frame, recipe.background, recipe.imaging))
                if covered < PLAUSIBLE_FOREGROUND * silhouette:
                    reason = (f"frame {index} has {covered} foreground pixels, fewer than {PLAUSIBLE_FOREGROUND:g} "
                              f"of the calibrated model's {silhouette}")
                    continue
            return LearntColours(colour_model_from_pose(frame, recipe.background, recipe.model, calibration.camera,
                                                        calibration.initial_pose, recipe.imaging), index)
        except ValueError as exc:
            reason = f"frame {index}: {exc}"
    how = {"face": "a detected face" if recipe.boxes is None else "the sample boxes",
           "calibration": "a foreground the size of the model"}[recipe.source]
    raise ValueError(f"no frame of {name} shows the person to learn the colours from ({how}); last: {reason}")


def _silhouette_pixels(model: BodyModel, calibration: Calibration) -> int:
    """Pixels of the calibrated model's silhouette in its initial pose."""
    from mocap.render import render

    return int(np.count_nonzero(render(calibration.initial_pose, model, calibration.camera).labels))
