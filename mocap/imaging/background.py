"""Background subtraction: a foreground mask robust to sensor noise and soft shadows.

The colour test follows Horprasert, Harwood and Davis (1999): the frame colour ``I`` of a
pixel is compared with the background colour ``E`` through its brightness ratio
``alpha = <I, E> / <E, E>`` and its chromaticity distortion ``|I - alpha E|``. A shadow
darkens a pixel without changing its chromaticity, so a changed pixel is foreground only
when its brightness ratio leaves the shadow/highlight range or its chromaticity changed.
The raw mask is then cleaned with scipy/scikit-image morphology.
"""
from __future__ import annotations

import inspect
import math
from collections.abc import Iterable

import numpy as np
from scipy import ndimage as ndi
from skimage import morphology

from mocap._numba import jit
from mocap.imaging._validate import check_rgb, check_same_size, foreground_bbox
from mocap.imaging.config import ImagingConfig

__all__ = ["subtract_background", "median_background", "clean_mask", "estimate_background",
           "person_against_background", "PERSON_MIN_SHARE"]

_DEFAULT_CONFIG = ImagingConfig()  # frozen: sharing it is safe


@jit
def _change_mask_kernel(frame, frame_scale, background, background_scale, change2,
                        alpha_lo, alpha_hi, chroma_rel, chroma_abs, out):  # pragma: no cover
    height, width = out.shape
    for y in range(height):
        for x in range(width):
            r = frame[y, x, 0] * frame_scale
            g = frame[y, x, 1] * frame_scale
            b = frame[y, x, 2] * frame_scale
            er = background[y, x, 0] * background_scale
            eg = background[y, x, 1] * background_scale
            eb = background[y, x, 2] * background_scale
            dr = r - er
            dg = g - eg
            db = b - eb
            if dr * dr + dg * dg + db * db <= change2:
                out[y, x] = False
                continue
            ee = er * er + eg * eg + eb * eb
            if ee <= 0.0:
                out[y, x] = True
                continue
            alpha = (r * er + g * eg + b * eb) / ee
            if alpha < alpha_lo or alpha > alpha_hi:
                out[y, x] = True
                continue
            cr = r - alpha * er
            cg = g - alpha * eg
            cb = b - alpha * eb
            allowed = chroma_abs + chroma_rel * alpha * math.sqrt(ee)
            out[y, x] = cr * cr + cg * cg + cb * cb > allowed * allowed


def change_mask_unchecked(frame, frame_scale, background, background_scale, config):
    out = np.empty(frame.shape[:2], dtype=np.bool_)
    _change_mask_kernel(frame, frame_scale, background, background_scale,
                        config.change_threshold ** 2, config.shadow_min_brightness,
                        config.shadow_max_brightness, config.shadow_max_chroma,
                        config.chroma_noise, out)
    return out


# scikit-image 0.26 replaced min_size (remove objects < n) and area_threshold (fill holes
# < n) by max_size (remove/fill <= n) and deprecated the old names; support both.
_SKIMAGE_MAX_SIZE = "max_size" in inspect.signature(morphology.remove_small_objects).parameters


def _remove_small_objects(mask: np.ndarray, min_area: int) -> np.ndarray:
    """Drop connected parts (4-connected) with fewer than ``min_area`` pixels."""
    if _SKIMAGE_MAX_SIZE:
        return morphology.remove_small_objects(mask, max_size=min_area - 1)
    return morphology.remove_small_objects(mask, min_size=min_area)


def _remove_small_holes(mask: np.ndarray, max_area: int) -> np.ndarray:
    """Fill holes (4-connected) of at most ``max_area`` pixels."""
    if _SKIMAGE_MAX_SIZE:
        return morphology.remove_small_holes(mask, max_size=max_area)
    return morphology.remove_small_holes(mask, area_threshold=max_area + 1)


def clean_mask_unchecked(raw: np.ndarray, config: ImagingConfig) -> np.ndarray:
    """Morphological clean-up (square structuring elements, scipy rank filters).

    Only the erosion of the opening sees the whole frame; the rest works on the bounding box
    of what survived it, with margins that make the result identical to a full-frame run.
    """
    size = raw.shape[0] * raw.shape[1]
    k_open, k_close = config.opening_size, config.closing_size
    mask = ndi.minimum_filter(raw, size=k_open, mode="nearest") if k_open > 1 else raw
    box = foreground_bbox(mask, k_open // 2 + k_close)
    out = np.zeros_like(raw)
    if box is None:
        return out
    crop = mask[box]
    if k_open > 1:
        crop = ndi.maximum_filter(crop, size=k_open, mode="constant", cval=False)
    min_area = int(math.ceil(config.min_object_fraction * size))
    if min_area > 1:
        crop = _remove_small_objects(crop, min_area)
    if k_close > 1:
        closed = ndi.maximum_filter(crop, size=k_close, mode="constant", cval=False)
        closed = ndi.minimum_filter(closed, size=k_close, mode="nearest")
        crop = closed | crop
    max_hole = int(math.floor(config.max_hole_fraction * size))
    if max_hole > 0:
        crop = _remove_small_holes(crop, max_hole)
    out[box] = crop
    return out


def clean_mask(raw: np.ndarray, config: ImagingConfig | None = None) -> np.ndarray:
    """Morphological clean-up of a raw foreground mask.

    Opening (removes speckle), removal of small connected parts, closing (bridges small
    gaps), filling of small holes, with the sizes of ``config``.

    Parameters
    ----------
    raw : ndarray of bool, shape (H, W)
        Raw foreground mask.
    config : ImagingConfig, optional
        ``opening_size``, ``closing_size`` (pixels), ``min_object_fraction``,
        ``max_hole_fraction`` (fractions of ``H * W``).

    Returns
    -------
    ndarray of bool, shape (H, W)
    """
    if not isinstance(raw, np.ndarray) or raw.dtype != np.bool_ or raw.ndim != 2:
        raise ValueError("raw must be a 2-D boolean array")
    return clean_mask_unchecked(raw, config or _DEFAULT_CONFIG)


def subtract_background(frame: np.ndarray, background: np.ndarray,
                        config: ImagingConfig | None = None, *, clean: bool = True) -> np.ndarray:
    """Foreground mask of ``frame`` against a reference image of the empty scene.

    A pixel is foreground when its colour moved more than ``config.change_threshold`` from
    the background *and* the change is not a shadow or highlight: its brightness ratio
    ``alpha = <I, E> / <E, E>`` is outside ``[shadow_min_brightness,
    shadow_max_brightness]`` or its chromaticity distortion ``|I - alpha E|`` exceeds
    ``chroma_noise + shadow_max_chroma * |alpha E|`` (0-255 units).

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3)
        RGB frame, ``uint8`` (0-255) or float in [0, 1].
    background : ndarray, shape (H, W, 3)
        RGB image of the empty scene (e.g. :func:`median_background` of empty frames), same
        size as ``frame``, ``uint8`` or float in [0, 1] (the two dtypes may differ).
    config : ImagingConfig, optional
        Thresholds and clean-up sizes; defaults to ``ImagingConfig()``.
    clean : bool
        Apply :func:`clean_mask` (default). ``False`` returns the raw per-pixel test.

    Returns
    -------
    ndarray of bool, shape (H, W)
        True on the foreground (the actor).

    Raises
    ------
    ValueError
        If an image is not ``(H, W, 3)`` (grayscale, RGBA), has an unsupported dtype or a
        float range outside [0, 1], or if the two sizes differ.
    """
    frame, frame_scale = check_rgb(frame, "frame")
    background, background_scale = check_rgb(background, "background")
    check_same_size(frame, background, "background")
    config = config or _DEFAULT_CONFIG
    raw = change_mask_unchecked(frame, frame_scale, background, background_scale, config)
    return clean_mask_unchecked(raw, config) if clean else raw


def median_background(frames: Iterable[np.ndarray]) -> np.ndarray:
    """Per-pixel median of several frames of the empty scene.

    Parameters
    ----------
    frames : iterable of ndarray, each shape (H, W, 3)
        RGB frames of the same size, ``uint8`` or float in [0, 1].

    Returns
    -------
    ndarray of uint8, shape (H, W, 3)
        The background estimate (0-255).
    """
    stack = []
    for i, frame in enumerate(frames):
        frame, scale = check_rgb(frame, f"frame {i}")
        if stack:
            check_same_size(stack[0], frame, f"frame {i}")
        if scale != 1.0:
            frame = np.round(frame * 255.0).astype(np.uint8)
        stack.append(frame)
    if not stack:
        raise ValueError("median_background needs at least one frame")
    return np.median(np.stack(stack), axis=0).round().astype(np.uint8)


def estimate_background(frames: Iterable[np.ndarray], config: ImagingConfig | None = None, *,
                        motion_dilation: int = 3, min_free_share: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    """Background of a clip with nobody standing still: temporal median with a motion mask.

    A first rough background takes at every pixel the colour seen most often: the sample with
    the most other samples within ``config.change_threshold`` of it (a mode; people who come and
    go differ from one another, the empty scene does not, so it wins even when someone covers
    the pixel in more than half of the frames). In every frame the
    pixels that differ from it (:func:`subtract_background`, dilated by ``motion_dilation``
    pixels) are taken for the moving actor and left out, and the median of what is left is
    the estimate. A pixel the actor covers in fewer than half of the frames is recovered
    exactly; one covered by the same still actor in most frames keeps the actor (see
    :func:`person_against_background` to tell).

    Parameters
    ----------
    frames : iterable of ndarray, each shape (H, W, 3)
        RGB frames of the same size, ``uint8`` or float in [0, 1] (a sample of the clip).
    config : ImagingConfig, optional
        Thresholds of the change test.
    motion_dilation : int, pixels
        Margin added around the changed pixels (mixed colours at the actor's border).
    min_free_share : float in (0, 1]
        Fewest share of frames a pixel must be free of motion in to take the masked median.

    Returns
    -------
    background : ndarray of uint8, shape (H, W, 3)
        The estimate (0-255).
    free_share : ndarray of float64, shape (H, W)
        Share of the frames in which each pixel was free of motion.
    """
    if not 0.0 < min_free_share <= 1.0:
        raise ValueError(f"min_free_share must be in (0, 1], got {min_free_share}")
    if isinstance(motion_dilation, bool) or not isinstance(motion_dilation, int) or motion_dilation < 0:
        raise ValueError(f"motion_dilation must be a non-negative integer, got {motion_dilation!r}")
    config = config or _DEFAULT_CONFIG
    stack = []
    for i, frame in enumerate(frames):
        frame, scale = check_rgb(frame, f"frame {i}")
        if stack:
            check_same_size(stack[0], frame, f"frame {i}")
        stack.append(np.round(frame * 255.0).astype(np.uint8) if scale != 1.0 else frame)
    if len(stack) < 3:
        raise ValueError(f"estimating a background needs at least 3 frames, got {len(stack)}")
    video = np.stack(stack)
    rough = _densest_sample(video, config.change_threshold)
    moving = np.empty(video.shape[:3], dtype=np.bool_)
    for t, frame in enumerate(video):
        raw = change_mask_unchecked(frame, 1.0, rough, 1.0, config)
        moving[t] = ndi.binary_dilation(raw, iterations=motion_dilation) if motion_dilation else raw
    free_share = 1.0 - moving.mean(axis=0)
    masked = np.ma.masked_array(video, mask=np.repeat(moving[..., None], 3, axis=3))
    estimate = np.ma.median(masked, axis=0).filled(0).round().astype(np.uint8)
    reliable = free_share >= min_free_share
    background = np.where(reliable[..., None], estimate, rough)
    return background, free_share


def _densest_sample(video: np.ndarray, radius: float) -> np.ndarray:
    """Per pixel, the sample (of ``video`` (N, H, W, 3) uint8) with the most samples within
    ``radius`` (0-255 units) of it; ties go to the earlier sample. Returns (H, W, 3) uint8."""
    video = np.ascontiguousarray(video)
    out = np.empty(video.shape[1:], np.uint8)
    # the squared distances are integers (exact in float32); the radius is compared in float32
    _densest_sample_kernel(video, np.float32(radius * radius), out)
    return out


@jit
def _densest_sample_kernel(video, radius2, out):  # pragma: no cover - compiled
    """Kernel of :func:`_densest_sample`: each pair of samples of a pixel compared once."""
    n, height, width = video.shape[0], video.shape[1], video.shape[2]
    counts = np.empty(n, np.int32)
    for y in range(height):
        for x in range(width):
            counts[:] = 0
            for i in range(n):
                for j in range(i, n):
                    d = np.float32(0.0)
                    for c in range(3):
                        e = np.float32(video[i, y, x, c]) - np.float32(video[j, y, x, c])
                        d += e * e
                    if d <= radius2:
                        counts[i] += 1
                        if j != i:
                            counts[j] += 1
            best = 0
            for i in range(1, n):
                if counts[i] > counts[best]:
                    best = i
            for c in range(3):
                out[y, x, c] = video[best, y, x, c]


def person_against_background(frames: Iterable[np.ndarray], background: np.ndarray,
                              config: ImagingConfig | None = None, *, face=None,
                              face_frame: np.ndarray | None = None) -> dict[str, float]:
    """How well an estimated background separates the actor: the evidence for using it.

    Parameters
    ----------
    frames : iterable of ndarray, each shape (H, W, 3)
        Sample frames (RGB, ``uint8`` or float in [0, 1]).
    background : ndarray, shape (H, W, 3)
        The background to judge (:func:`estimate_background`).
    config : ImagingConfig, optional
    face : Box, optional
        A face found in ``face_frame`` (pixels of the same size).
    face_frame : ndarray, shape (H, W, 3), optional

    Returns
    -------
    dict
        ``foreground_share`` (median over the frames of the cleaned foreground's share of the
        image), ``frames_with_person`` (share of frames whose foreground covers at least 2 %
        of the image) and, with a face, ``face_foreground`` (share of the face box that is
        foreground in ``face_frame``: near 1 when the background is free of the actor, near
        0 when the actor sat still and was taken into it).
    """
    shares = [float(subtract_background(f, background, config).mean()) for f in frames]
    if not shares:
        raise ValueError("person_against_background needs at least one frame")
    out = {"foreground_share": float(np.median(shares)),
           "frames_with_person": float(np.mean(np.asarray(shares) >= PERSON_MIN_SHARE))}
    if face is not None:
        if face_frame is None:
            raise ValueError("face needs face_frame")
        mask = subtract_background(face_frame, background, config)
        out["face_foreground"] = float(mask[face.row:face.row + face.height, face.col:face.col + face.width].mean())
    return out


#: Share of the image a person covers at the least (foreground share that counts as someone in view).
PERSON_MIN_SHARE = 0.02
