"""Edges of the frame inside the (dilated) foreground, and the distance map to them.

Edges: scikit-image's Canny by default, or Deriche's recursive gradient filter (the paper's
choice) followed by the same non-maximum suppression and hysteresis. Distance map: the exact
Euclidean distance transform of scipy by default, or Borgefors' chamfer 3-4 distance; both
truncated at ``max_distance`` pixels. Both steps work on the bounding box of what matters and
fill the rest exactly (no edge outside the dilated foreground; every pixel farther than
``max_distance`` from all edges has the truncated value).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import ndimage as ndi
from skimage import color, feature

from mocap._numba import jit
from mocap.imaging._validate import check_mask, check_rgb, foreground_bbox
from mocap.imaging.config import DISTANCE_METHODS, EDGE_METHODS, ImagingConfig

__all__ = ["SOBEL_GAIN", "detect_edges", "distance_map", "deriche_gradient"]

_DEFAULTS = ImagingConfig()
#: Sobel's response to a unit slope ([-1, 0, 1] times the [1, 2, 1] smoothing): Deriche
#: gradients are multiplied by it so both edge methods share the thresholds' units.
SOBEL_GAIN = 8.0


# --------------------------------------------------------------------------- Deriche

def _deriche_coefficients(alpha: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Coefficients ``(a1, a2, a3, a4)`` of Deriche's smoothing and derivative filters and
    the shared feedback ``(b1, b2)``.

    The causal half is ``y1[n] = a1 x[n] + a2 x[n-1] + b1 y1[n-1] + b2 y1[n-2]``, the
    anti-causal half ``y2[n] = a3 x[n+1] + a4 x[n+2] + b1 y2[n+1] + b2 y2[n+2]``, the
    output ``y1 + y2``. Smoothing has unit gain on a constant; the derivative is scaled so a
    unit ramp ``x[n] = n`` gives exactly 1.
    """
    ea = math.exp(-alpha)
    e2a = math.exp(-2.0 * alpha)
    k = (1.0 - ea) ** 2 / (1.0 + 2.0 * alpha * ea - e2a)
    smooth = np.array([k, k * ea * (alpha - 1.0), k * ea * (alpha + 1.0), -k * e2a])
    b = np.array([2.0 * ea, -e2a])
    # Impulse response h[j] of the causal half of the derivative (a2 = 1; the anti-causal
    # half is its mirror with a3 = -1). The ramp response is sum_j j (h2[j] - h1[j])
    # = -2 sum_j j h[j], computed over enough terms for the e^(-alpha j) tail to vanish.
    length = int(60.0 / alpha) + 10
    h = np.zeros(length)
    h[1] = 1.0
    for j in range(2, length):
        h[j] = b[0] * h[j - 1] + b[1] * h[j - 2]
    ramp_gain = -2.0 * float(np.dot(np.arange(length), h))
    deriv = np.array([0.0, 1.0, -1.0, 0.0]) / ramp_gain
    return smooth, deriv, b


@jit
def _recursive_rows(src, a, b, out):  # pragma: no cover - compiled
    """Deriche causal + anti-causal recursion along each row, borders replicated."""
    height, width = src.shape
    a1, a2, a3, a4 = a[0], a[1], a[2], a[3]
    b1, b2 = b[0], b[1]
    gain = 1.0 - b1 - b2
    for r in range(height):
        x0 = src[r, 0]
        yp = (a1 + a2) * x0 / gain  # steady state of a constant signal x0
        ypp = yp
        xp = x0
        for c in range(width):
            xc = src[r, c]
            yc = a1 * xc + a2 * xp + b1 * yp + b2 * ypp
            out[r, c] = yc
            ypp = yp
            yp = yc
            xp = xc
        xn = src[r, width - 1]
        yn = (a3 + a4) * xn / gain
        ynn = yn
        xnn = xn
        for c in range(width - 1, -1, -1):
            yc = a3 * xn + a4 * xnn + b1 * yn + b2 * ynn
            out[r, c] += yc
            ynn = yn
            yn = yc
            xnn = xn
            xn = src[r, c]


@jit
def _recursive_cols(src, a, b, out):  # pragma: no cover - compiled
    """The same recursion down each column, rows outermost (cache-friendly)."""
    height, width = src.shape
    a1, a2, a3, a4 = a[0], a[1], a[2], a[3]
    b1, b2 = b[0], b[1]
    gain = 1.0 - b1 - b2
    xp = np.empty(width)
    xpp = np.empty(width)
    yp = np.empty(width)
    ypp = np.empty(width)
    for c in range(width):
        xp[c] = src[0, c]
        yp[c] = (a1 + a2) * src[0, c] / gain
        ypp[c] = yp[c]
    for r in range(height):
        for c in range(width):
            xc = src[r, c]
            yc = a1 * xc + a2 * xp[c] + b1 * yp[c] + b2 * ypp[c]
            out[r, c] = yc
            ypp[c] = yp[c]
            yp[c] = yc
            xp[c] = xc
    for c in range(width):
        xp[c] = src[height - 1, c]  # x[n+1]
        xpp[c] = xp[c]  # x[n+2]
        yp[c] = (a3 + a4) * xp[c] / gain
        ypp[c] = yp[c]
    for r in range(height - 1, -1, -1):
        for c in range(width):
            yc = a3 * xp[c] + a4 * xpp[c] + b1 * yp[c] + b2 * ypp[c]
            out[r, c] += yc
            ypp[c] = yp[c]
            yp[c] = yc
            xpp[c] = xp[c]
            xp[c] = src[r, c]


def deriche_gradient(image: np.ndarray, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """Deriche's recursive gradient of a grey image.

    Parameters
    ----------
    image : ndarray, shape (H, W)
        Grey image (float; any range).
    alpha : float
        Deriche's scale parameter in 1/pixels (larger = less smoothing; ``sqrt(pi) / sigma``
        matches a Gaussian of standard deviation ``sigma``).

    Returns
    -------
    gy, gx : ndarray of float64, shape (H, W)
        Derivatives along rows (axis 0) and columns (axis 1), in image units per pixel.
    """
    image = np.asarray(image, dtype=np.float64)
    if image.ndim != 2:
        raise ValueError(f"image must be 2-D, got shape {image.shape}")
    if not alpha > 0:
        raise ValueError(f"alpha must be > 0, got {alpha}")
    smooth, deriv, b = _deriche_coefficients(float(alpha))
    sx = np.empty_like(image)
    sy = np.empty_like(image)
    gx = np.empty_like(image)
    gy = np.empty_like(image)
    _recursive_rows(image, smooth, b, sx)
    _recursive_cols(image, smooth, b, sy)
    _recursive_rows(sy, deriv, b, gx)
    _recursive_cols(sx, deriv, b, gy)
    return gy, gx


@jit
def _nonmax_kernel(gy, gx, magnitude, low, out):  # pragma: no cover - compiled
    """Keep ridge pixels of ``magnitude`` across the gradient direction (bilinear)."""
    height, width = magnitude.shape
    for r in range(height):
        for c in range(width):
            out[r, c] = 0.0
    for r in range(1, height - 1):
        for c in range(1, width - 1):
            m = magnitude[r, c]
            if m < low:
                continue
            dy = gy[r, c]
            dx = gx[r, c]
            ady = abs(dy)
            adx = abs(dx)
            if adx >= ady:
                w = ady / adx
                sr = 1 if dy * dx >= 0.0 else -1
                m1 = (1.0 - w) * magnitude[r, c + 1] + w * magnitude[r + sr, c + 1]
                m2 = (1.0 - w) * magnitude[r, c - 1] + w * magnitude[r - sr, c - 1]
            else:
                w = adx / ady
                sc = 1 if dy * dx >= 0.0 else -1
                m1 = (1.0 - w) * magnitude[r + 1, c] + w * magnitude[r + 1, c + sc]
                m2 = (1.0 - w) * magnitude[r - 1, c] + w * magnitude[r - 1, c - sc]
            if m >= m1 and m > m2:
                out[r, c] = m


def _hysteresis(strength: np.ndarray, high: float) -> np.ndarray:
    """Connected (8-neighbour) ridge pixels that contain at least one strong pixel."""
    weak = strength > 0
    labels, count = ndi.label(weak, structure=np.ones((3, 3), bool))
    if count == 0:
        return weak
    good = np.zeros(count + 1, dtype=bool)
    good[labels[strength >= high]] = True
    good[0] = False
    return good[labels]


@jit
def _magnitude_kernel(gy, gx, gain, out):  # pragma: no cover - compiled
    height, width = out.shape
    for r in range(height):
        for c in range(width):
            out[r, c] = gain * math.sqrt(gy[r, c] * gy[r, c] + gx[r, c] * gx[r, c])


def _deriche_edges(grey, sigma, low, high):
    gy, gx = deriche_gradient(grey, math.sqrt(math.pi) / sigma)
    magnitude = np.empty_like(gy)
    _magnitude_kernel(gy, gx, SOBEL_GAIN, magnitude)
    strength = np.empty_like(magnitude)
    _nonmax_kernel(gy, gx, magnitude, low, strength)
    return _hysteresis(strength, high)


# --------------------------------------------------------------------------- edges

def detect_edges_unchecked(frame, scale, foreground, method, sigma, low, high, dilation, silhouette):
    h, w = frame.shape[:2]
    if foreground is None:
        region = None
        box = (slice(0, h), slice(0, w))
    else:
        margin = dilation + int(math.ceil(4.0 * sigma)) + 2
        box = foreground_bbox(foreground, margin)
        if box is None:
            return np.zeros((h, w), dtype=bool)
        region = foreground[box]
        if dilation > 0:
            region = ndi.maximum_filter(region, size=2 * dilation + 1, mode="constant",
                                        cval=False)
    crop = frame[box]
    grey = color.rgb2gray(crop) if scale == 1.0 else color.rgb2gray(crop.astype(np.float64))
    if method == "canny":
        found = feature.canny(grey, sigma=sigma, low_threshold=low, high_threshold=high,
                              mode="nearest")
    else:
        found = _deriche_edges(grey, sigma, low, high)
    if region is not None:
        found &= region
        if silhouette:
            inner = foreground[box]
            found |= inner & ~ndi.minimum_filter(inner, size=3, mode="nearest")
    out = np.zeros((h, w), dtype=bool)
    out[box] = found
    return out


def detect_edges(frame: np.ndarray, foreground: np.ndarray | None = None, *,
                 method: str = _DEFAULTS.edge_method, sigma: float = _DEFAULTS.edge_sigma,
                 low_threshold: float = _DEFAULTS.edge_low_threshold,
                 high_threshold: float = _DEFAULTS.edge_high_threshold,
                 dilation: int = _DEFAULTS.edge_dilation,
                 silhouette: bool = _DEFAULTS.silhouette_edges) -> np.ndarray:
    """Edges of ``frame`` near the foreground.

    The grey image (:func:`skimage.color.rgb2gray`) of the foreground's bounding box is
    processed (with a margin, so borders do not matter) and the edges are kept inside the
    foreground dilated by ``dilation`` pixels (a square).

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3)
        RGB, ``uint8`` or float in [0, 1].
    foreground : ndarray of bool, shape (H, W), optional
        Foreground mask; default: edges of the whole frame.
    method : {'canny', 'deriche'}
        :func:`skimage.feature.canny` (Gaussian ``sigma``), or Deriche's recursive gradient
        with ``alpha = sqrt(pi) / sigma`` followed by the same non-maximum suppression and
        hysteresis.
    sigma : float
        Smoothing scale in pixels.
    low_threshold, high_threshold : float
        Hysteresis thresholds on the gradient magnitude, in the units of
        :func:`skimage.feature.canny` on a grey image in [0, 1] (the Sobel response: 8 times
        the grey-level slope per pixel, so a sharp step of contrast ``d`` peaks near
        ``8 d / (sqrt(2 pi) sigma)``).
    dilation : int
        Edges farther than this (pixels, chessboard) from the foreground are dropped.
    silhouette : bool
        Add the outline of ``foreground`` (its pixels with a background 8-neighbour; the
        image border does not count) to the edges, so that a silhouette the grey image does
        not show (actor and background of equal luminance) still counts.

    Returns
    -------
    ndarray of bool, shape (H, W)
        True on edge pixels (one pixel wide).
    """
    frame, scale = check_rgb(frame, "frame")
    if foreground is not None:
        check_mask(foreground, frame.shape[:2], "foreground")
    if method not in EDGE_METHODS:
        raise ValueError(f"method must be one of {EDGE_METHODS}, got {method!r}")
    if not sigma > 0:
        raise ValueError(f"sigma must be > 0, got {sigma}")
    if not 0 <= low_threshold <= high_threshold:
        raise ValueError("thresholds must satisfy 0 <= low_threshold <= high_threshold")
    if isinstance(dilation, bool) or not isinstance(dilation, (int, np.integer)) or dilation < 0:
        raise ValueError(f"dilation must be a non-negative integer, got {dilation!r}")
    return detect_edges_unchecked(frame, scale, foreground, method, float(sigma), float(low_threshold),
                  float(high_threshold), int(dilation), bool(silhouette))


# --------------------------------------------------------------------------- distance

@jit
def _chamfer34_kernel(edges, cap, out):  # pragma: no cover - compiled
    """Two-pass chamfer 3-4 distance (in thirds of a pixel), values capped at ``cap``."""
    height, width = edges.shape
    for r in range(height):
        for c in range(width):
            out[r, c] = 0 if edges[r, c] else cap
    for r in range(height):
        for c in range(width):
            v = out[r, c]
            if v == 0:
                continue
            if c > 0:
                v = min(v, out[r, c - 1] + 3)
            if r > 0:
                v = min(v, out[r - 1, c] + 3)
                if c > 0:
                    v = min(v, out[r - 1, c - 1] + 4)
                if c < width - 1:
                    v = min(v, out[r - 1, c + 1] + 4)
            out[r, c] = v
    for r in range(height - 1, -1, -1):
        for c in range(width - 1, -1, -1):
            v = out[r, c]
            if v == 0:
                continue
            if c < width - 1:
                v = min(v, out[r, c + 1] + 3)
            if r < height - 1:
                v = min(v, out[r + 1, c] + 3)
                if c < width - 1:
                    v = min(v, out[r + 1, c + 1] + 4)
                if c > 0:
                    v = min(v, out[r + 1, c - 1] + 4)
            out[r, c] = v


def distance_map_unchecked(edges, method, max_distance):
    h, w = edges.shape
    out = np.full((h, w), max_distance, dtype=np.float32)
    box = foreground_bbox(edges, int(math.ceil(max_distance)))
    if box is None:
        return out
    crop = edges[box]
    if method == "edt":
        d = ndi.distance_transform_edt(~crop)
        np.minimum(d, max_distance, out=d)
        out[box] = d
    else:
        cap = int(math.ceil(3.0 * max_distance)) + 1
        thirds = np.empty(crop.shape, dtype=np.int32)
        _chamfer34_kernel(crop, cap, thirds)
        out[box] = np.minimum(thirds / np.float32(3.0), np.float32(max_distance))
    return out


def distance_map(edges: np.ndarray, *, max_distance: float = _DEFAULTS.max_distance,
                 method: str = _DEFAULTS.distance_method) -> np.ndarray:
    """Distance of every pixel to the nearest edge pixel, truncated.

    Parameters
    ----------
    edges : ndarray of bool, shape (H, W)
        Edge mask (e.g. :func:`detect_edges`).
    max_distance : float
        Truncation in pixels (> 0): farther pixels, and all pixels when there is no edge,
        get exactly ``max_distance``.
    method : {'edt', 'chamfer'}
        ``'edt'``: exact Euclidean distance (:func:`scipy.ndimage.distance_transform_edt`).
        ``'chamfer'``: Borgefors' chamfer 3-4 distance divided by 3 (steps of 1 and 4/3
        pixels; within -6 % / +4.3 % of the Euclidean distance), compiled two-pass.

    Returns
    -------
    ndarray of float32, shape (H, W)
        Distance in pixels, in ``[0, max_distance]``; 0 on edges.
    """
    if not isinstance(edges, np.ndarray) or edges.dtype != np.bool_ or edges.ndim != 2:
        raise ValueError("edges must be a 2-D boolean array")
    if method not in DISTANCE_METHODS:
        raise ValueError(f"method must be one of {DISTANCE_METHODS}, got {method!r}")
    if not (isinstance(max_distance, (int, float)) and math.isfinite(max_distance)
            and max_distance > 0):
        raise ValueError(f"max_distance must be a positive finite number, got {max_distance!r}")
    return distance_map_unchecked(edges, method, float(max_distance))
