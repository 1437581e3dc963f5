"""Connected regions of one colour class: where the hands (skin blobs) are in a label image."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

__all__ = ["Blobs", "label_blobs"]


@dataclass(frozen=True)
class Blobs:
    """Connected regions of one label, largest first.

    Attributes
    ----------
    centroids : ndarray of float64, shape (n, 2), pixels
        Centre of mass ``(u, v)`` (column, row) of each region.
    sizes : ndarray of int64, shape (n,), pixels
    """

    centroids: np.ndarray
    sizes: np.ndarray

    def __len__(self) -> int:
        return len(self.sizes)


def label_blobs(labels: np.ndarray, label: int, *, min_pixels: int = 1) -> Blobs:
    """Connected regions (8-connected) of the pixels equal to ``label``.

    Parameters
    ----------
    labels : ndarray of uint8, shape (H, W)
        Label image (:mod:`mocap.labels`).
    label : int
        The label value whose regions are wanted (e.g. the skin class).
    min_pixels : int
        Regions smaller than this are left out.

    Returns
    -------
    Blobs
        Sorted by decreasing size (ties by position, so the order is deterministic).
    """
    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise ValueError(f"labels must be a 2D label image, got shape {labels.shape}")
    if not 0 <= int(label) <= 255:
        raise ValueError(f"label must be a label value in [0, 255], got {label!r}")
    if isinstance(min_pixels, bool) or not isinstance(min_pixels, (int, np.integer)) or min_pixels < 1:
        raise ValueError(f"min_pixels must be a positive integer, got {min_pixels!r}")
    regions, n = ndimage.label(labels == label, structure=np.ones((3, 3), dtype=bool))
    if n == 0:
        return Blobs(np.zeros((0, 2)), np.zeros(0, dtype=np.int64))
    index = np.arange(1, n + 1)
    sizes = np.bincount(regions.ravel(), minlength=n + 1)[1:].astype(np.int64)
    rows_cols = np.array(ndimage.center_of_mass(np.ones(regions.shape), regions, index), dtype=np.float64)
    centroids = rows_cols[:, ::-1].copy()
    keep = np.flatnonzero(sizes >= min_pixels)
    order = keep[np.lexsort((centroids[keep, 0], centroids[keep, 1], -sizes[keep]))]
    return Blobs(centroids[order], sizes[order])
