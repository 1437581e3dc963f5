"""Synthetic scenes with a known foreground, for tests and benchmarks at any resolution.

A person-like group of blobs (skin face ellipse with darker eyes and mouth, neck, clothes
torso and upper arms, skin forearms and hands) stands on a textured background (wall, floor,
furniture). The frame carries a soft shadow of the person on the background and sensor noise;
the reference background is a separate noisy capture of the empty scene.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy import ndimage as ndi
from skimage import draw

from mocap.imaging._validate import Box
from mocap.labels import BACKGROUND, UNKNOWN

__all__ = ["SyntheticScene", "synthetic_scene", "synthetic_scene_with_labels"]

SKIN_RGB = (222.0, 168.0, 138.0)
CLOTHES_CHOICES = ((40.0, 70.0, 160.0), (30.0, 120.0, 60.0), (150.0, 35.0, 45.0),
                   (55.0, 60.0, 85.0))


@dataclasses.dataclass(frozen=True, eq=False)
class SyntheticScene:
    """A synthetic frame and what is true about it.

    Attributes
    ----------
    frame, background : ndarray of uint8, shape (H, W, 3)
        RGB frame (person, soft shadow, noise) and empty-scene capture (own noise).
    mask : ndarray of bool, shape (H, W)
        The person (shadow excluded).
    labels : ndarray of uint8, shape (H, W)
        True label image: 0 background, 1 skin, 2 clothes, 255 eyes and mouth.
    face_box, clothes_box : Box
        Boxes (row, col, height, width) of the face and of a chest sample.
    """

    frame: np.ndarray
    background: np.ndarray
    mask: np.ndarray
    labels: np.ndarray
    face_box: Box
    clothes_box: Box


def _segment(labels, r0, c0, r1, c1, half_width, value):
    """Paint a thick segment (a rectangle of the given half width) into ``labels``."""
    d = np.array([r1 - r0, c1 - c0], dtype=float)
    n = np.hypot(*d)
    if n == 0:
        return
    p = np.array([-d[1], d[0]]) / n * half_width
    rows = [r0 + p[0], r1 + p[0], r1 - p[0], r0 - p[0]]
    cols = [c0 + p[1], c1 + p[1], c1 - p[1], c0 - p[1]]
    rr, cc = draw.polygon(rows, cols, shape=labels.shape)
    labels[rr, cc] = value
    for r, c in ((r0, c0), (r1, c1)):
        rr, cc = draw.disk((r, c), half_width, shape=labels.shape)
        labels[rr, cc] = value


def synthetic_scene_with_labels(width: int, height: int, seed: int = 0, *,
                                noise: float = 3.0, shadow: bool = True) -> SyntheticScene:
    """A synthetic scene and its truth (see the module notes).

    Parameters
    ----------
    width, height : int
        Image size in pixels (at least 32 x 24).
    seed : int
        Seed of the scene's randomness (pose of the arms, colours, texture, noise).
    noise : float
        Standard deviation of the Gaussian sensor noise, 0-255 units, on frame and
        background independently.
    shadow : bool
        Cast a soft shadow (brightness times about 0.75) of the person on the background.

    Returns
    -------
    SyntheticScene
    """
    if width < 32 or height < 24:
        raise ValueError(f"synthetic scenes need at least 32x24 pixels, got {width}x{height}")
    if noise < 0:
        raise ValueError(f"noise must be >= 0, got {noise}")
    rng = np.random.default_rng(seed)
    h, w = height, width
    yy, xx = np.mgrid[0:h, 0:w]

    # -- background: wall and floor with low-frequency colour variation, texture, furniture
    wall = np.array([165.0, 172.0, 178.0]) + rng.uniform(-12, 12, 3)
    floor = np.array([120.0, 95.0, 70.0]) + rng.uniform(-10, 10, 3)
    horizon = int(h * rng.uniform(0.72, 0.8))
    bg = np.where((yy < horizon)[..., None], wall, floor)
    low = ndi.gaussian_filter(rng.normal(0, 1, (h, w, 3)), (h / 10, w / 10, 0))
    low *= 12.0 / max(low.std(), 1e-9)
    fine = ndi.gaussian_filter(rng.normal(0, 1, (h, w)), 0.8)
    fine *= 6.0 / max(fine.std(), 1e-9)
    bg = bg + low + fine[..., None]
    for _ in range(3):  # furniture / pictures in muted colours
        r0, c0 = int(rng.uniform(0.05, 0.6) * h), int(rng.uniform(0, 0.85) * w)
        rr, cc = draw.rectangle((r0, c0), extent=(int(rng.uniform(0.1, 0.3) * h),
                                                  int(rng.uniform(0.08, 0.2) * w)), shape=(h, w))
        bg[rr, cc] = rng.uniform(70, 200) + rng.uniform(-12, 12, 3)

    # -- person (labels: 1 skin, 2 clothes, 255 eyes/mouth)
    s = min(h, w * 0.75)
    cx = w / 2 + rng.uniform(-0.08, 0.08) * w
    head_r, head_c = 0.22 * h, cx
    ry, rx = 0.085 * s, 0.065 * s
    labels = np.zeros((h, w), dtype=np.uint8)
    torso_top = head_r + ry + 0.06 * s
    shoulder_half = 0.17 * s
    _segment(labels, head_r, cx, torso_top + 0.02 * s, cx, 0.03 * s, 1)  # neck
    rr, cc = draw.polygon([torso_top, torso_top, h + 1, h + 1],
                          [cx - shoulder_half, cx + shoulder_half, cx + shoulder_half * 0.9,
                           cx - shoulder_half * 0.9], shape=(h, w))
    labels[rr, cc] = 2
    for side in (-1.0, 1.0):
        sr, sc = torso_top + 0.04 * s, cx + side * shoulder_half * 0.92
        a1 = np.deg2rad(rng.uniform(10, 70))
        er, ec = sr + 0.22 * s * np.cos(a1), sc + side * 0.22 * s * np.sin(a1)
        a2 = np.deg2rad(rng.uniform(-60, 120))
        hr, hc = er + 0.2 * s * np.cos(a2), ec + side * 0.2 * s * np.sin(a2)
        _segment(labels, er, ec, hr, hc, 0.035 * s, 1)  # forearm
        rr, cc = draw.disk((hr, hc), 0.05 * s, shape=(h, w))
        labels[rr, cc] = 1  # hand
        _segment(labels, sr, sc, er, ec, 0.05 * s, 2)  # upper arm (sleeve)
    rr, cc = draw.ellipse(head_r, head_c, ry, rx, shape=(h, w))
    labels[rr, cc] = 1
    for side in (-1.0, 1.0):
        rr, cc = draw.ellipse(head_r - 0.2 * ry, head_c + side * 0.4 * rx, max(0.1 * ry, 0.6),
                              max(0.18 * rx, 0.6), shape=(h, w))
        labels[rr, cc] = UNKNOWN
    rr, cc = draw.ellipse(head_r + 0.5 * ry, head_c, max(0.07 * ry, 0.6), max(0.35 * rx, 0.6),
                          shape=(h, w))
    labels[rr, cc] = UNKNOWN
    mask = labels != BACKGROUND

    skin = np.array(SKIN_RGB) + rng.uniform(-12, 12, 3)
    clothes = np.array(CLOTHES_CHOICES[rng.integers(len(CLOTHES_CHOICES))]) + rng.uniform(-10, 10, 3)
    shade = 0.88 + 0.2 * np.clip(1 - np.abs(xx - cx) / (2 * shoulder_half), 0, 1)  # rounder look
    texture = ndi.gaussian_filter(rng.normal(0, 1, (h, w)), 1.0)
    texture *= 4.0 / max(texture.std(), 1e-9)
    person = np.zeros((h, w, 3))
    person[labels == 1] = skin
    person[labels == 2] = clothes
    person[labels == UNKNOWN] = (70.0, 45.0, 40.0)
    person = person * shade[..., None] + texture[..., None]

    frame = bg.copy()
    if shadow:
        offset = (int(0.02 * h), int(0.12 * w))
        cast = ndi.shift(mask.astype(float), offset, order=0)
        cast = ndi.gaussian_filter(cast, 0.015 * s + 0.5)
        frame *= (1.0 - 0.25 * cast)[..., None]
    frame[mask] = person[mask]

    frame = np.clip(np.round(frame + rng.normal(0, noise, frame.shape)), 0, 255).astype(np.uint8)
    background = np.clip(np.round(bg + rng.normal(0, noise, bg.shape)), 0, 255).astype(np.uint8)
    face = Box(int(head_r - ry), int(head_c - rx), int(2 * ry), int(2 * rx))
    chest = Box(int(torso_top + 0.12 * s), int(cx - 0.1 * s), max(int(0.15 * s), 2),
                max(int(0.2 * s), 2))
    return SyntheticScene(frame, background, mask, labels, face, chest)


def synthetic_scene(width: int, height: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray,
                                                                     np.ndarray]:
    """A synthetic frame, its empty background and the true foreground mask.

    Parameters
    ----------
    width, height : int
        Image size in pixels (at least 32 x 24).
    seed : int
        Seed of the scene's randomness.

    Returns
    -------
    frame : ndarray of uint8, shape (height, width, 3)
        RGB frame: a person-like figure (skin face and hands, clothes below) on a textured
        background, with a soft shadow and Gaussian noise (sigma 3).
    background : ndarray of uint8, shape (height, width, 3)
        RGB capture of the empty scene (independent noise).
    true_mask : ndarray of bool, shape (height, width)
        The person's pixels (the shadow is not foreground).
    """
    scene = synthetic_scene_with_labels(width, height, seed)
    return scene.frame, scene.background, scene.mask
