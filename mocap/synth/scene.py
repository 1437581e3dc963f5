"""The empty scene behind the actor: a textured room wall, in linear light.

A painted wall (a desaturated colour, uneven lighting, paint texture) with a few objects drawn
at random: a door, framed pictures, a bookshelf, a window, a poster. The layout is in relative
coordinates, so a seed gives the same room at every image size.
"""
from __future__ import annotations

import colorsys

import numpy as np
from scipy.ndimage import gaussian_filter
from skimage.draw import disk, rectangle
from skimage.transform import resize

from mocap.synth.actor import srgb_to_linear

__all__ = ["make_background"]


def _hsv(h: float, s: float, v: float) -> np.ndarray:
    return srgb_to_linear(colorsys.hsv_to_rgb(h % 1.0, float(np.clip(s, 0, 1)), float(np.clip(v, 0, 1))))


def _smooth_field(rng: np.random.Generator, shape: tuple[int, int], coarse: tuple[int, int]) -> np.ndarray:
    """Smooth random field in about [-1, 1], the same pattern at every resolution."""
    field = rng.normal(size=coarse)
    field = resize(field, shape, order=3, mode="reflect", anti_aliasing=False)
    return field / max(3.0 * field.std(), 1e-9)


def _rect(img: np.ndarray, top: float, left: float, bottom: float, right: float, colour) -> None:
    h, w = img.shape[:2]
    r0, c0 = int(np.clip(round(top * h), 0, h - 1)), int(np.clip(round(left * w), 0, w - 1))
    r1, c1 = int(np.clip(round(bottom * h), 0, h - 1)), int(np.clip(round(right * w), 0, w - 1))
    if r1 <= r0 or c1 <= c0:
        return
    rr, cc = rectangle((r0, c0), end=(r1, c1), shape=img.shape[:2])
    img[rr, cc] = colour


def _door(img, rng, x):
    width = rng.uniform(0.17, 0.26)
    wood = _hsv(rng.uniform(0.05, 0.11), rng.uniform(0.3, 0.6), rng.uniform(0.3, 0.75))
    frame = wood * 0.6
    top = rng.uniform(0.0, 0.12)
    _rect(img, top - 0.02, x - 0.015, 1.0, x + width + 0.015, frame)
    _rect(img, top, x, 1.0, x + width, wood)
    for k in range(2):                                   # panels
        y0 = top + 0.08 + k * 0.45
        _rect(img, y0, x + 0.03, y0 + 0.33, x + width - 0.03, wood * 0.85)
    h, w = img.shape[:2]
    rr, cc = disk((0.62 * h, (x + width - 0.025) * w), max(1.0, 0.012 * w), shape=img.shape[:2])
    img[rr, cc] = _hsv(0.12, 0.3, 0.8)


def _picture(img, rng, x):
    width, height = rng.uniform(0.12, 0.22), rng.uniform(0.12, 0.25)
    top = rng.uniform(0.05, 0.35)
    border = _hsv(rng.uniform(0, 1), rng.uniform(0, 0.3), rng.choice([0.1, 0.85]))
    _rect(img, top, x, top + height, x + width, border)
    inner = (top + 0.02, x + 0.015, top + height - 0.02, x + width - 0.015)
    base = _hsv(rng.uniform(0, 1), rng.uniform(0.2, 0.7), rng.uniform(0.3, 0.9))
    _rect(img, *inner, base)
    h, w = img.shape[:2]
    for _ in range(rng.integers(2, 5)):                  # blobs of colour: a painting
        cy = rng.uniform(inner[0], inner[2]) * h
        cx = rng.uniform(inner[1], inner[3]) * w
        rr, cc = disk((cy, cx), max(1.0, rng.uniform(0.015, 0.05) * w), shape=img.shape[:2])
        keep = (rr >= inner[0] * h) & (rr < inner[2] * h) & (cc >= inner[1] * w) & (cc < inner[3] * w)
        img[rr[keep], cc[keep]] = _hsv(rng.uniform(0, 1), rng.uniform(0.3, 0.9), rng.uniform(0.2, 0.9))


def _shelf(img, rng, x):
    width = rng.uniform(0.18, 0.3)
    top = rng.uniform(0.15, 0.45)
    plank = _hsv(rng.uniform(0.06, 0.1), rng.uniform(0.2, 0.5), rng.uniform(0.3, 0.7))
    _rect(img, top, x, top + 0.025, x + width, plank)
    pos = x + 0.01
    while pos < x + width - 0.02:                        # books standing on the plank
        bw = rng.uniform(0.01, 0.025)
        bh = rng.uniform(0.07, 0.13)
        _rect(img, top - bh, pos, top - 0.002, min(pos + bw, x + width - 0.01),
              _hsv(rng.uniform(0, 1), rng.uniform(0.3, 0.8), rng.uniform(0.2, 0.8)))
        pos += bw + rng.uniform(0.0, 0.006)


def _window(img, rng, x):
    width, height = rng.uniform(0.16, 0.26), rng.uniform(0.25, 0.4)
    top = rng.uniform(0.02, 0.2)
    frame = _hsv(0.0, 0.0, rng.uniform(0.75, 0.95))
    _rect(img, top, x, top + height, x + width, frame)
    sky = _hsv(rng.uniform(0.55, 0.62), rng.uniform(0.15, 0.4), rng.uniform(0.8, 0.95)) * rng.uniform(1.1, 1.4)
    _rect(img, top + 0.015, x + 0.012, top + height - 0.015, x + width - 0.012, sky)
    _rect(img, top + 0.5 * height - 0.006, x, top + 0.5 * height + 0.006, x + width, frame)
    _rect(img, top, x + 0.5 * width - 0.005, top + height, x + 0.5 * width + 0.005, frame)


def _poster(img, rng, x):
    width, height = rng.uniform(0.1, 0.16), rng.uniform(0.15, 0.25)
    top = rng.uniform(0.05, 0.3)
    paper = _hsv(rng.uniform(0, 1), rng.uniform(0.0, 0.2), rng.uniform(0.75, 0.95))
    _rect(img, top, x, top + height, x + width, paper)
    ink = _hsv(rng.uniform(0, 1), rng.uniform(0.3, 0.9), rng.uniform(0.1, 0.5))
    y = top + 0.03
    while y < top + height - 0.03:                       # lines of "text"
        _rect(img, y, x + 0.015, y + 0.008, x + width * rng.uniform(0.5, 0.9), ink)
        y += 0.022


_OBJECTS = (_door, _picture, _shelf, _window, _poster)


def make_background(rng: np.random.Generator, width: int, height: int) -> np.ndarray:
    """A room wall with objects, as linear radiance.

    Parameters
    ----------
    rng : numpy.random.Generator
    width, height : int
        Pixels.

    Returns
    -------
    ndarray, shape (height, width, 3), float64
        Linear radiance, roughly in [0, 1].
    """
    shape = (height, width)
    wall = _hsv(rng.uniform(0.0, 1.0), rng.uniform(0.03, 0.2), rng.uniform(0.5, 0.8))
    img = np.broadcast_to(wall, (height, width, 3)).copy()
    n = int(rng.integers(3, 6))
    slots = np.sort(rng.uniform(-0.05, 0.85, n))
    for x in slots:
        _OBJECTS[rng.integers(len(_OBJECTS))](img, rng, float(x))
    # soften the drawn edges a little (objects are not pixel-sharp)
    sigma = 0.004 * width
    img = gaussian_filter(img, sigma=(sigma, sigma, 0))
    # uneven illumination: a broad gradient from the light side plus slow variation
    yy, xx = np.mgrid[0:height, 0:width]
    gx = rng.uniform(-0.25, 0.25)
    light = 1.0 + gx * (xx / width - 0.5) - 0.12 * (yy / height - 0.3) ** 2
    light = light + 0.06 * _smooth_field(rng, shape, (6, 8))
    # paint and plaster texture
    texture = 1.0 + 0.04 * _smooth_field(rng, shape, (24, 32)) + 0.025 * _smooth_field(rng, shape, (90, 120))
    return img * (light * texture)[:, :, None]
