"""Pictures of what the image side sees, for people (the ``segment`` command and the overlay).

:func:`draw_model_box` is the overlay's compiled drawer: a body model rendered straight into
reused buffers and blended into a frame in its box, with no full-size label image
(:func:`blend_table` makes its blend equal to NumPy's float32 one, bit for bit).
"""
from __future__ import annotations

import functools

import numpy as np

from mocap._numba import jit
from mocap.labels import UNKNOWN
from mocap.render.rasterize import clear_render, occluding_edges_into, render_scene_into

__all__ = ["blend_table", "blend_into_box", "colour_labels", "colour_distance", "draw_model_box", "label_palette",
           "overlay_edges", "tile"]

#: Colours of the named classes (others: tab10).
CLASS_COLOURS = {"skin": (255, 196, 150), "clothes": (40, 110, 255), "hair": (120, 60, 20),
                 "lower_body": (40, 170, 110)}
_FIRST_COLOURS = np.array([(255, 196, 150), (40, 110, 255)], dtype=np.uint8)  # skin, clothes


def _tab10() -> np.ndarray:
    """matplotlib's tab10 colours, uint8 RGB, shape (10, 3) (matplotlib imported when needed)."""
    from matplotlib import colormaps

    return (np.array(colormaps["tab10"].colors) * 255).round().astype(np.uint8)


def label_palette(n_classes: int, class_names: tuple[str, ...] | None = None) -> np.ndarray:
    """RGB colour of every label value: 0 black, 255 grey; classes by name
    (:data:`CLASS_COLOURS`: skin tone, blue clothes, brown hair, green lower body) when
    ``class_names`` are given, else 1 skin tone, 2 blue, then tab10.

    Returns
    -------
    ndarray of uint8, shape (256, 3)
    """
    palette = np.zeros((256, 3), dtype=np.uint8)
    if class_names is not None and len(class_names) != n_classes:
        raise ValueError(f"need {n_classes} class names, got {class_names}")
    for c in range(1, n_classes + 1):
        if class_names is not None and class_names[c - 1] in CLASS_COLOURS:
            palette[c] = CLASS_COLOURS[class_names[c - 1]]
        else:
            palette[c] = _FIRST_COLOURS[c - 1] if c <= 2 else _tab10()[(c - 3) % 10]
    palette[UNKNOWN] = (150, 150, 150)
    return palette


def colour_labels(labels: np.ndarray, n_classes: int, class_names: tuple[str, ...] | None = None) -> np.ndarray:
    """Label image (uint8, shape (H, W)) as RGB (uint8, shape (H, W, 3)) with
    :func:`label_palette`."""
    return label_palette(n_classes, class_names)[labels]


def colour_distance(distance: np.ndarray, max_distance: float) -> np.ndarray:
    """Distance map (pixels, shape (H, W)) as RGB (uint8, (H, W, 3)) with viridis:
    dark on edges, yellow at ``max_distance``."""
    from matplotlib import colormaps     # imported when drawn: matplotlib takes ~0.1 s to import

    lut = (colormaps["viridis"](np.linspace(0, 1, 256))[:, :3] * 255).round().astype(np.uint8)
    index = np.clip(distance / max_distance * 255.0, 0, 255).astype(np.uint8)
    return lut[index]


def overlay_edges(frame: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The frame (uint8 RGB) darkened and greyed, with the edge pixels in white."""
    grey = (frame.astype(np.float32).mean(axis=2) * 0.4).astype(np.uint8)
    out = np.repeat(grey[..., np.newaxis], 3, axis=2)
    out[edges] = 255
    return out


def tile(images: list[np.ndarray], columns: int = 2) -> np.ndarray:
    """Same-size uint8 RGB images in a grid, row by row (missing cells black)."""
    h, w = images[0].shape[:2]
    rows = -(-len(images) // columns)
    out = np.zeros((rows * h, columns * w, 3), dtype=np.uint8)
    for i, image in enumerate(images):
        r, c = divmod(i, columns)
        out[r * h:(r + 1) * h, c * w:(c + 1) * w] = image
    return out


@functools.lru_cache(maxsize=8)
def blend_table(alpha: float) -> np.ndarray:
    """``table[f, c]``: a frame value ``f`` with a colour value ``c`` blended at opacity ``alpha``,
    as NumPy computes it in float32 (``(1 - alpha) * f + alpha * c``, clipped to 0-255 and cut
    to uint8): the compiled drawers look it up, so their pictures equal NumPy's bit for bit.

    Returns
    -------
    ndarray of uint8, shape (256, 256), read-only
    """
    if not 0.0 <= alpha <= 1.0:
        raise ValueError(f"alpha must be in [0, 1], got {alpha}")
    values = np.arange(256, dtype=np.float32)
    table = np.clip((1 - alpha) * values[:, None] + alpha * values[None, :], 0, 255).astype(np.uint8)
    table.setflags(write=False)
    return table


@jit
def blend_into_box(out, frame, ids, lut, marks, width, box, palette, table, edge_colour):
    """Compiled: in the inclusive pixel ``box`` (int64 (4,): x0, y0, x1, y1), the pixels of the
    flat ``ids`` (uint8, (H * W,)) whose label ``lut[id]`` is not 0 get ``frame`` blended with
    ``palette[label]`` by ``table`` (:func:`blend_table`), and those marked in the flat bool
    ``marks`` get ``edge_colour``; ``out`` and ``frame`` are uint8 (H, W, 3) (the same array
    may be both). Other pixels are not touched."""
    for y in range(box[1], box[3] + 1):
        row = y * width
        for x in range(box[0], box[2] + 1):
            i = row + x
            if marks[i]:
                out[y, x, 0] = edge_colour[0]
                out[y, x, 1] = edge_colour[1]
                out[y, x, 2] = edge_colour[2]
                continue
            label = lut[ids[i]]
            if label != 0:
                for c in range(3):
                    out[y, x, c] = table[frame[y, x, c], palette[label, c]]


@jit
def draw_model_box(out, pose, scene, buffers, marks, lut, min_gap, palette, table, edge_colour):
    """Compiled: the body model of ``scene`` (:class:`mocap.render.rasterize.Scene`) in ``pose``
    (float64 (23,), checked) rendered into ``buffers`` (:class:`mocap.render.rasterize.Buffers`,
    zero) with its occluding edges (depth gap ``min_gap``, metres) marked in the flat bool
    ``marks`` (all False), and drawn into the uint8 (H, W, 3) picture ``out`` in place by
    :func:`blend_into_box` (``lut``: uint8 (256,), the label of each part id, 0 for 0); the
    buffers and marks are cleared behind it."""
    render_scene_into(pose, scene, buffers)
    if buffers.box[0] > buffers.box[2]:
        return
    occluding_edges_into(scene, buffers, min_gap, marks)
    blend_into_box(out, out, buffers.part_ids, lut, marks, scene.width, buffers.box, palette, table, edge_colour)
    clear_render(scene, buffers, marks)
