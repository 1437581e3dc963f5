"""Pictures of the registration: the projected model drawn over the frame (paper Fig. 1)."""
from __future__ import annotations

import numpy as np

from mocap.imaging.visual import label_palette

#: RGB colour of the model's occluding edges.
EDGE_COLOUR = np.array([255, 255, 0], np.uint8)


def draw_model(frame: np.ndarray, labels: np.ndarray, edges: np.ndarray, n_classes: int = 2, *,
               alpha: float = 0.35, class_names: tuple[str, ...] | None = None) -> np.ndarray:
    """The frame with the model's coloured silhouette blended in and its occluding edges drawn.

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3), uint8
    labels : ndarray, shape (H, W), uint8
        Rendered class labels (colours of :func:`mocap.imaging.visual.label_palette`).
    edges : ndarray, shape (H, W), bool
        Rendered occluding edges (yellow).
    n_classes : int
    alpha : float
        Opacity of the silhouette colours.
    class_names : tuple of str, optional
        The ``n_classes`` class names, for the colours of named classes (hair, lower body).

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
    """
    if frame.ndim != 3 or frame.shape[:2] != labels.shape or labels.shape != edges.shape:
        raise ValueError(f"frame {frame.shape}, labels {labels.shape} and edges {edges.shape} must match")
    out = frame.astype(np.float32)
    colours = label_palette(n_classes, class_names)[labels].astype(np.float32)
    model = labels > 0
    out[model] = (1 - alpha) * out[model] + alpha * colours[model]
    out[edges] = EDGE_COLOUR
    return np.clip(out, 0, 255).astype(np.uint8)
