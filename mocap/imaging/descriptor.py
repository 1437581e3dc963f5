"""A shape descriptor of the person in a label image, normalised for position and scale.

The foreground's bounding box, widened to the grid's aspect ratio about its centre, is cut out
of the label image and resampled (:func:`skimage.transform.resize`, anti-aliased) to a small
grid of cells per channel: the whole foreground, the skin (with the hair: a person without a
hair class has it labelled skin) and the hair. Each cell holds the square root of the share of
its area the channel covers, so that thin parts (forearms, hands) weigh more than their area.
The exemplar pose proposer (:mod:`mocap.track.exemplars`) compares such descriptors.
"""
from __future__ import annotations

import numpy as np
from skimage.transform import resize

from mocap.labels import BACKGROUND

__all__ = ["DESCRIPTOR_CHANNELS", "DESCRIPTOR_GRID", "descriptor_size", "silhouette_descriptor"]

#: Cells of the descriptor grid, (rows, columns): 3:4 (width:height), the upper body's framing.
DESCRIPTOR_GRID: tuple[int, int] = (32, 24)
#: Channels of the descriptor and the colour classes each one gathers (the foreground channel
#: takes every label but the background, "unknown" included).
DESCRIPTOR_CHANNELS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("foreground", ()), ("skin", ("skin", "hair")), ("hair", ("hair",)))


def descriptor_size(grid: tuple[int, int] = DESCRIPTOR_GRID) -> int:
    """Length of a descriptor on ``grid`` (rows, columns)."""
    return len(DESCRIPTOR_CHANNELS) * int(grid[0]) * int(grid[1])


def silhouette_descriptor(labels: np.ndarray, class_names: tuple[str, ...],
                          grid: tuple[int, int] = DESCRIPTOR_GRID) -> np.ndarray:
    """Descriptor of the person in a label image.

    Parameters
    ----------
    labels : ndarray of uint8, shape (H, W)
        Label image (:mod:`mocap.labels`): 0 background, ``c`` the class ``class_names[c - 1]``,
        255 foreground of no class.
    class_names : tuple of str
        The image's colour classes; those named in :data:`DESCRIPTOR_CHANNELS` are used.
    grid : (int, int)
        Cells (rows, columns).

    Returns
    -------
    ndarray of float32, shape (descriptor_size(grid),)
        Channel by channel, row by row: the square root of each cell's covered share, in [0, 1].
        All zeros when the image has no foreground.

    Raises
    ------
    ValueError
        If ``labels`` is not a 2-D uint8 array or ``grid`` has a side under 2.
    """
    if not isinstance(labels, np.ndarray) or labels.ndim != 2 or labels.dtype != np.uint8:
        raise ValueError(f"labels must be a 2-D uint8 label image, got {getattr(labels, 'dtype', type(labels))} "
                         f"of shape {np.shape(labels)}")
    rows, cols = int(grid[0]), int(grid[1])
    if rows < 2 or cols < 2:
        raise ValueError(f"the descriptor grid needs at least 2x2 cells, got {grid}")
    foreground = labels != BACKGROUND
    any_row, any_col = foreground.any(axis=1), foreground.any(axis=0)
    if not any_row.any():
        return np.zeros(descriptor_size((rows, cols)), dtype=np.float32)
    r0, r1 = np.flatnonzero(any_row)[[0, -1]] + (0, 1)
    c0, c1 = np.flatnonzero(any_col)[[0, -1]] + (0, 1)
    height, width = float(r1 - r0), float(c1 - c0)
    if width * rows < height * cols:          # widen to the grid's aspect ratio about the box's centre
        width = height * cols / rows
    else:
        height = width * rows / cols
    top = int(round(0.5 * (r0 + r1 - height)))
    left = int(round(0.5 * (c0 + c1 - width)))
    box_h, box_w = max(int(round(height)), 1), max(int(round(width)), 1)
    channels = np.zeros((box_h, box_w, len(DESCRIPTOR_CHANNELS)), dtype=np.float32)
    src = (slice(max(top, 0), min(top + box_h, labels.shape[0])), slice(max(left, 0), min(left + box_w, labels.shape[1])))
    dst = (slice(src[0].start - top, src[0].stop - top), slice(src[1].start - left, src[1].stop - left))
    window = labels[src]
    for k, (_, names) in enumerate(DESCRIPTOR_CHANNELS):
        if names:
            values = [i + 1 for i, name in enumerate(class_names) if name in names]
            mask = np.isin(window, values)
        else:
            mask = window != BACKGROUND
        channels[dst + (k,)] = mask
    cells = resize(channels, (rows, cols), order=1, mode="constant", anti_aliasing=True, preserve_range=True)
    return np.sqrt(np.clip(cells, 0.0, 1.0)).transpose(2, 0, 1).ravel().astype(np.float32)
