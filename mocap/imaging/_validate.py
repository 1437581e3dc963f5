"""Input checks shared by the public functions of :mod:`mocap.imaging`.

Every public function validates its arguments here, then hands plain arrays to a private
kernel. Images stay in their own dtype (no copy): kernels receive a ``scale`` that maps a
sample to the 0-255 range (1 for ``uint8``, 255 for floats in [0, 1]).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Box(NamedTuple):
    """An axis-aligned pixel box: top row, left column, height, width (all in pixels).

    Same convention as :class:`skimage.feature.Cascade` detections (``r``, ``c``,
    ``height``, ``width``).
    """

    row: int
    col: int
    height: int
    width: int

    @property
    def slices(self) -> tuple[slice, slice]:
        """``(rows, cols)`` slices selecting the box in an image."""
        return slice(self.row, self.row + self.height), slice(self.col, self.col + self.width)


def image_scale(image: np.ndarray, name: str) -> float:
    """Factor that maps samples of ``image`` to the 0-255 range; raises on a bad dtype/range."""
    if image.dtype == np.uint8:
        return 1.0
    if image.dtype.kind == "f":
        if image.size == 0:
            return 255.0
        lo = float(image.min())
        hi = float(image.max())
        if not (np.isfinite(lo) and np.isfinite(hi)):
            raise ValueError(f"{name} contains NaN or infinite values")
        if lo < 0.0 or hi > 1.0:
            raise ValueError(
                f"{name} is a float image with values in [{lo:g}, {hi:g}]; float images must lie "
                "in [0, 1] (divide 0-255 data by 255, or pass it as uint8)")
        return 255.0
    raise ValueError(
        f"{name} has dtype {image.dtype}; expected uint8 (0-255) or float in [0, 1]")


def check_rgb(image: object, name: str = "frame") -> tuple[np.ndarray, float]:
    """Check an RGB image of shape ``(H, W, 3)``; return it as an array and its 0-255 scale."""
    if not isinstance(image, np.ndarray):
        raise ValueError(f"{name} must be a NumPy array, got {type(image).__name__}")
    if image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 1):
        raise ValueError(
            f"{name} is a grayscale image of shape {image.shape}; an RGB image (H, W, 3) is "
            "needed (colour classes need colour; replicate the channel if that is intended)")
    if image.ndim == 3 and image.shape[2] == 4:
        raise ValueError(
            f"{name} is an RGBA image of shape {image.shape}; pass RGB (H, W, 3), e.g. "
            "image[..., :3] after checking the alpha channel is opaque")
    if image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f"{name} must have shape (H, W, 3), got {image.shape}")
    if image.shape[0] < 1 or image.shape[1] < 1:
        raise ValueError(f"{name} is empty (shape {image.shape})")
    scale = image_scale(image, name)
    if image.dtype.kind == "f" and (image.dtype.itemsize < 4 or not image.dtype.isnative):
        image = image.astype(np.float32)  # half floats / foreign byte order: kernels need these
    return image, scale


def check_same_size(frame: np.ndarray, other: np.ndarray, other_name: str) -> None:
    """Raise if ``other`` does not cover the same ``(H, W)`` pixels as ``frame``."""
    if frame.shape[:2] != other.shape[:2]:
        raise ValueError(
            f"frame is {frame.shape[1]}x{frame.shape[0]} but {other_name} is "
            f"{other.shape[1]}x{other.shape[0]} (width x height); they must be the same size")


def check_mask(mask: object, shape: tuple[int, int], name: str) -> np.ndarray:
    """Check a boolean mask of the given ``(H, W)`` shape."""
    if not isinstance(mask, np.ndarray):
        raise ValueError(f"{name} must be a NumPy array, got {type(mask).__name__}")
    if mask.dtype != np.bool_:
        raise ValueError(f"{name} must be a boolean array, got dtype {mask.dtype}")
    if mask.shape != tuple(shape):
        raise ValueError(f"{name} has shape {mask.shape}, expected {tuple(shape)}")
    return mask


def check_box(box: object, shape: tuple[int, int], name: str) -> Box:
    """Check ``(row, col, height, width)`` and clip it to an image of ``shape`` ``(H, W)``.

    Raises if the box is malformed, empty or entirely outside the image.
    """
    try:
        values = [int(v) for v in box]  # type: ignore[union-attr]
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be four integers (row, col, height, width), got {box!r}") \
            from None
    if len(values) != 4:
        raise ValueError(f"{name} must be four integers (row, col, height, width), got {box!r}")
    row, col, height, width = values
    if height <= 0 or width <= 0:
        raise ValueError(f"{name} {tuple(values)} has a non-positive height or width")
    r0, c0 = max(row, 0), max(col, 0)
    r1, c1 = min(row + height, shape[0]), min(col + width, shape[1])
    if r1 <= r0 or c1 <= c0:
        raise ValueError(
            f"{name} {tuple(values)} (row, col, height, width) lies outside the "
            f"{shape[1]}x{shape[0]} image")
    return Box(r0, c0, r1 - r0, c1 - c0)


def foreground_bbox(mask: np.ndarray, margin: int) -> tuple[slice, slice] | None:
    """Bounding box of the ``True`` pixels grown by ``margin`` pixels (clipped), or None."""
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    h, w = mask.shape
    return (slice(max(int(rows[0]) - margin, 0), min(int(rows[-1]) + 1 + margin, h)),
            slice(max(int(cols[0]) - margin, 0), min(int(cols[-1]) + 1 + margin, w)))
