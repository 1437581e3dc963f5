"""Foreground without an image of the empty scene: the scene's own colours.

When nobody ever leaves the view there is no background image to subtract, and the colour
classes alone (skin, clothes) also explain a grey wall behind grey clothes. The scene around
the person still shows which colours belong to it: an RGB histogram of the pixels outside a
generous box around the person (the *scene*) against one of the pixels inside it (person
and some scene). A colour is the scene's when it is more than ``ratio`` times as frequent
outside the box as inside; the foreground is the pixels of other colours that a colour class
explains (a lookup table over
RGB quantised to 16 levels a channel, so one frame costs one table look-up per pixel).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage as ndi

from mocap._numba import jit
from mocap.imaging._validate import Box, check_box, check_rgb

__all__ = ["SceneColours", "person_box_of_face"]

#: Quantisation levels per channel of the colour histograms.
LEVELS = 16


def person_box_of_face(face: Box, shape: tuple[int, int]) -> Box:
    """A generous box around a person below a face: from a fifth of a face height above the
    face to the bottom of the image, 2.2 face widths either side of the face's centre (the
    shoulders and hanging arms), clipped to ``shape`` ``(H, W)``."""
    centre = face.col + 0.5 * face.width
    top = face.row - round(0.2 * face.height)
    left = round(centre - 2.2 * face.width)
    return check_box((top, left, shape[0] - top, round(4.4 * face.width)), shape, "person box")


def _histogram(frame: np.ndarray, mask: np.ndarray) -> np.ndarray:
    q = frame[mask].astype(np.int64) * LEVELS // 256
    hist = np.bincount((q[:, 0] * LEVELS + q[:, 1]) * LEVELS + q[:, 2], minlength=LEVELS ** 3).astype(np.float64)
    hist = ndi.gaussian_filter(hist.reshape(LEVELS, LEVELS, LEVELS), 0.7, mode="constant").ravel()
    return hist / max(hist.sum(), 1.0)


@jit
def _lookup_kernel(frame, table, out):  # pragma: no cover - compiled
    height, width = out.shape
    shift = 4  # 256 // LEVELS == 16
    for y in range(height):
        for x in range(width):
            r = frame[y, x, 0] >> shift
            g = frame[y, x, 1] >> shift
            b = frame[y, x, 2] >> shift
            out[y, x] = table[(r * 16 + g) * 16 + b]


@dataclass(frozen=True, eq=False)
class SceneColours:
    """Which RGB colours belong to the person rather than to the scene.

    Attributes
    ----------
    person : ndarray of bool, shape (4096,)
        Per quantised colour ``(r // 16 * 16 + g // 16) * 16 + b // 16``: True for the
        person's colours.
    """

    person: np.ndarray

    def __post_init__(self) -> None:
        table = np.asarray(self.person, dtype=np.bool_)
        if table.shape != (LEVELS ** 3,):
            raise ValueError(f"person table must have shape ({LEVELS ** 3},), got {table.shape}")
        object.__setattr__(self, "person", table)

    @classmethod
    def learn(cls, frame: np.ndarray, person_box, *, ratio: float = 2.0) -> "SceneColours":
        """Learn the table from a frame and a box holding the person (and some scene).

        Parameters
        ----------
        frame : ndarray of uint8, shape (H, W, 3)
        person_box : (row, col, height, width), pixels
            Must leave some of the image outside it.
        ratio : float
            How much more frequent outside the box than inside a scene colour is (> 1).
        """
        frame, scale = check_rgb(frame, "frame")
        if scale != 1.0:
            raise ValueError("frame must be uint8")
        if not ratio > 1.0:
            raise ValueError(f"ratio must be > 1, got {ratio}")
        box = check_box(person_box, frame.shape[:2], "person box")
        inside = np.zeros(frame.shape[:2], np.bool_)
        inside[box.slices] = True
        if inside.all():
            raise ValueError("the person box covers the whole image: no scene to learn from")
        h_in, h_out = _histogram(frame, inside), _histogram(frame, ~inside)
        return cls(~(h_out > ratio * h_in))

    def foreground(self, frame: np.ndarray) -> np.ndarray:
        """Raw mask of the pixels of person colours.

        Parameters
        ----------
        frame : ndarray of uint8, shape (H, W, 3)

        Returns
        -------
        ndarray of bool, shape (H, W)
        """
        frame, scale = check_rgb(frame, "frame")
        if scale != 1.0:
            raise ValueError("frame must be uint8")
        out = np.empty(frame.shape[:2], np.bool_)
        _lookup_kernel(frame, self.person, out)
        return out

    def to_dict(self) -> dict:
        """JSON-ready: the person colours' indices."""
        return {"levels": LEVELS, "person_colours": np.flatnonzero(self.person).tolist()}
