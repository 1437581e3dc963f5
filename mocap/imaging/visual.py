"""Pictures of what the image side sees, for people (the ``segment`` command)."""
from __future__ import annotations

import numpy as np

from mocap.labels import UNKNOWN

__all__ = ["label_palette", "colour_labels", "colour_distance", "overlay_edges", "tile"]

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
