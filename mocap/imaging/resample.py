"""Working resolution: real clips are reduced by an integer factor before the image side.

The tracker's costs are cheap at the paper's 160x120 and grow with the pixel count; a
640x480 clip is therefore tracked at a *working resolution*, the input reduced by an integer
factor ``k`` (block mean over ``k x k`` pixels). Working pixel ``(i, j)`` covers input pixels
``[k i, k i + k) x [k j, k j + k)``, so a point at working coordinates ``(u, v)`` sits at
``(k u, k v)`` in the input (:meth:`mocap.render.Camera.scaled` is *not* used: the input may be
cropped by up to ``k - 1`` pixels on the right and bottom to a multiple of ``k``).
"""
from __future__ import annotations

import numpy as np

from mocap._numba import jit
from mocap.imaging._validate import check_rgb

__all__ = ["DEFAULT_WORK_WIDTH", "working_factor", "downscale"]

#: Default working width in pixels (the paper's webcam resolution, 160x120).
DEFAULT_WORK_WIDTH = 160


def working_factor(width: int, height: int, work_width: int = DEFAULT_WORK_WIDTH) -> int:
    """Integer reduction factor that brings an input ``width`` nearest to ``work_width``.

    Parameters
    ----------
    width, height : int, pixels
        Input frame size.
    work_width : int, pixels
        Wanted working width (>= 16); the input is never enlarged.

    Returns
    -------
    int
        ``k >= 1`` with ``width // k`` nearest to ``work_width`` (the smaller ``k`` on ties);
        the working size is ``(width // k, height // k)``.
    """
    for name, v in (("width", width), ("height", height)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be a positive integer, got {v!r}")
    if isinstance(work_width, bool) or not isinstance(work_width, (int, np.integer)) or work_width < 16:
        raise ValueError(f"working width must be an integer >= 16 pixels, got {work_width!r}")
    if width <= work_width:
        return 1
    candidates = range(1, width // 16 + 1)
    return min(candidates, key=lambda k: (abs(width // k - work_width), k))


@jit
def _block_mean_kernel(frame, k, out):  # pragma: no cover - compiled
    height, width = out.shape[:2]
    inv = 1.0 / (k * k)
    for i in range(height):
        for j in range(width):
            r = 0
            g = 0
            b = 0
            for y in range(i * k, i * k + k):
                for x in range(j * k, j * k + k):
                    r += frame[y, x, 0]
                    g += frame[y, x, 1]
                    b += frame[y, x, 2]
            out[i, j, 0] = np.uint8(int(r * inv + 0.5))
            out[i, j, 1] = np.uint8(int(g * inv + 0.5))
            out[i, j, 2] = np.uint8(int(b * inv + 0.5))


def downscale(frame: np.ndarray, factor: int) -> np.ndarray:
    """Reduce an RGB frame by an integer factor (mean of each ``factor x factor`` block).

    Parameters
    ----------
    frame : ndarray of uint8, shape (H, W, 3)
    factor : int
        ``>= 1``; rows and columns beyond the last whole block are dropped.

    Returns
    -------
    ndarray of uint8, shape (H // factor, W // factor, 3)
        Block means rounded half up (``factor == 1`` returns ``frame`` itself).
    """
    frame, scale = check_rgb(frame, "frame")
    if scale != 1.0:
        raise ValueError(f"frame must be uint8 to downscale, got {frame.dtype}")
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ValueError(f"factor must be a positive integer, got {factor!r}")
    if factor == 1:
        return frame
    h, w = frame.shape[0] // factor, frame.shape[1] // factor
    if h < 1 or w < 1:
        raise ValueError(f"a {frame.shape[1]}x{frame.shape[0]} frame is smaller than one {factor}x{factor} block")
    out = np.empty((h, w, 3), np.uint8)
    _block_mean_kernel(frame, int(factor), out)
    return out
