"""One call per frame: foreground, label image, edges and distance map."""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from mocap.imaging._validate import check_rgb, check_same_size
from mocap.imaging.background import change_mask_unchecked, clean_mask_unchecked
from mocap.imaging.colour import ColourModel
from mocap.imaging.config import ImagingConfig
from mocap.imaging.edges import distance_map_unchecked, detect_edges_unchecked
from mocap.labels import BACKGROUND, UNKNOWN

__all__ = ["PreparedFrame", "prepare_frame"]

_DEFAULT_CONFIG = ImagingConfig()  # frozen: sharing it is safe


@dataclasses.dataclass(frozen=True, eq=False)
class PreparedFrame:
    """What the costs compare the model against, for one frame.

    Attributes
    ----------
    labels : ndarray of uint8, shape (H, W)
        Segmented image (:mod:`mocap.labels`): 0 background, 1..m colour classes, 255
        foreground of no class.
    foreground : ndarray of bool, shape (H, W)
        The cleaned foreground mask (``labels != 0``).
    edges : ndarray of bool, shape (H, W)
        Edge pixels near the foreground.
    distance : ndarray of float32, shape (H, W)
        Distance to the nearest edge in pixels, truncated at ``config.max_distance``.
    is_empty : bool
        True when there is no foreground (nobody in the scene): labels are all 0, there are
        no edges and the distance is ``max_distance`` everywhere. The caller decides what
        to do (the tracker skips or flags the frame).
    timings : dict of str to float
        Seconds spent in ``background``, ``colour``, ``edges`` and ``distance``.
    """

    labels: np.ndarray
    foreground: np.ndarray
    edges: np.ndarray
    distance: np.ndarray
    is_empty: bool
    timings: dict[str, float]


def prepare_frame(frame: np.ndarray, background: np.ndarray | None, colour_model: ColourModel,
                  config: ImagingConfig | None = None, *, scene=None) -> PreparedFrame:
    """Segment a frame into colour classes and compute its edges and edge distance map.

    Stages (each timed): background subtraction with morphological clean-up
    (:func:`subtract_background`), colour classification of the foreground
    (:meth:`ColourModel.classify`), edges inside the dilated foreground
    (:func:`detect_edges`), truncated distance map (:func:`distance_map`).

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3)
        RGB frame, ``uint8`` (0-255) or float in [0, 1].
    background : ndarray, shape (H, W, 3), or None
        RGB image of the empty scene, same size, ``uint8`` or float in [0, 1]. ``None``
        when no empty view exists: the foreground is then the set of pixels that a colour
        class explains, cleaned the same way (less reliable; the background must not share
        the actor's colours).
    colour_model : ColourModel
        The m colour classes.
    config : ImagingConfig, optional
        All parameters; defaults to ``ImagingConfig()``.
    scene : mocap.imaging.scene.SceneColours, optional
        Without a background: the scene's colours, left out of the foreground (uint8 frames).

    Returns
    -------
    PreparedFrame

    Raises
    ------
    ValueError
        If ``frame`` or ``background`` is not ``(H, W, 3)`` RGB (grayscale, RGBA), has a
        dtype other than uint8/float, a float range outside [0, 1] or NaN, or if their
        sizes differ.
    """
    frame, scale = check_rgb(frame, "frame")
    if not isinstance(colour_model, ColourModel):
        raise ValueError(f"colour_model must be a ColourModel, got {type(colour_model).__name__}")
    if config is None:
        config = _DEFAULT_CONFIG
    elif not isinstance(config, ImagingConfig):
        raise ValueError(f"config must be an ImagingConfig, got {type(config).__name__}")
    if background is not None:
        background, background_scale = check_rgb(background, "background")
        check_same_size(frame, background, "background")

    clock = time.perf_counter
    t0 = clock()
    if background is not None:
        foreground = clean_mask_unchecked(change_mask_unchecked(frame, scale, background, background_scale, config),
                            config)
        t1 = clock()
        labels = colour_model._classify(frame, scale, foreground, config.colour_threshold)
        t2 = clock()
        background_time, colour_time = t1 - t0, t2 - t1
    else:
        everything = np.ones(frame.shape[:2], dtype=np.bool_)
        labels = colour_model._classify(frame, scale, everything, config.colour_threshold)
        t1 = clock()
        explained = (labels != UNKNOWN) & (labels != BACKGROUND)
        if scene is not None:
            explained &= scene.foreground(frame)
        foreground = clean_mask_unchecked(explained, config)
        labels[~foreground] = BACKGROUND
        t2 = clock()
        colour_time, background_time = t1 - t0, t2 - t1
    is_empty = not foreground.any()
    edges = detect_edges_unchecked(frame, scale, foreground, config.edge_method, config.edge_sigma,
                   config.edge_low_threshold, config.edge_high_threshold, config.edge_dilation,
                   config.silhouette_edges)
    t3 = clock()
    distance = distance_map_unchecked(edges, config.distance_method, config.max_distance)
    t4 = clock()
    timings = {"background": background_time, "colour": colour_time, "edges": t3 - t2,
               "distance": t4 - t3}
    return PreparedFrame(labels, foreground, edges, distance, is_empty, timings)
