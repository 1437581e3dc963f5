"""Slow, obviously-correct pure-NumPy reference rasterizer (for tests and for reading).

It follows the same specification as the compiled rasterizer — vertices snapped to 1/16 pixel,
pixel centres at (j + 0.5, i + 0.5), the top-left fill rule, inverse depth interpolated
linearly in screen space, nearest surface wins — but triangle by triangle with whole-array
NumPy operations and no incremental tricks.
"""
from __future__ import annotations

import numpy as np

from mocap.render._raster import SUBPIXEL
from mocap.render.camera import Camera, NEAR_PLANE_M


def reference_rasterize(vertices: np.ndarray, triangles: np.ndarray, triangle_part: np.ndarray,
                        camera: Camera, *, cull: bool = True):
    """Rasterize a mesh given in camera coordinates.

    Parameters
    ----------
    vertices : ndarray, shape (V, 3), float, metres
    triangles : ndarray, shape (T, 3), int
    triangle_part : ndarray, shape (T,), int
    camera : Camera
    cull : bool
        Skip back-facing triangles (positive signed area in y-down pixel coordinates).

    Returns
    -------
    parts : ndarray, shape (H, W), uint8
        0 background, else part + 1.
    inv_depth : ndarray, shape (H, W), float64
        1/z of the nearest surface, 1/metres (0 on background).
    """
    h, w = camera.height, camera.width
    parts = np.zeros((h, w), np.uint8)
    inv_depth = np.zeros((h, w))
    z = vertices[:, 2]
    ok = z >= NEAR_PLANE_M
    zs = np.where(ok, z, 1.0)
    u = camera.fx * vertices[:, 0] / zs + camera.cx
    v = camera.fy * vertices[:, 1] / zs + camera.cy
    X = np.floor(u * SUBPIXEL + 0.5).astype(np.int64)
    Y = np.floor(v * SUBPIXEL + 0.5).astype(np.int64)
    cols, rows = np.meshgrid(np.arange(w), np.arange(h))
    PX = cols * SUBPIXEL + SUBPIXEL // 2
    PY = rows * SUBPIXEL + SUBPIXEL // 2
    for t, (a, b, c) in enumerate(triangles):
        if not (ok[a] and ok[b] and ok[c]):
            continue
        area = (X[b] - X[a]) * (Y[c] - Y[a]) - (X[c] - X[a]) * (Y[b] - Y[a])
        if area == 0 or (cull and area > 0):
            continue
        if area < 0:
            b, c = c, b
            area = -area
        inside = np.ones((h, w), bool)
        weights = []
        for (p, q, opposite) in ((b, c, a), (c, a, b), (a, b, c)):
            dx, dy = X[q] - X[p], Y[q] - Y[p]
            e = dx * (PY - Y[p]) - dy * (PX - X[p])
            top_left = dy < 0 or (dy == 0 and dx > 0)
            inside &= (e >= 0) if top_left else (e > 0)
            weights.append((e, opposite))
        if not inside.any():
            continue
        iz = sum(e * (1.0 / zs[o]) for e, o in weights) / area
        nearer = inside & (iz > inv_depth)
        inv_depth[nearer] = iz[nearer]
        parts[nearer] = triangle_part[t] + 1
    return parts, inv_depth


def reference_occluding_edges(parts: np.ndarray, inv_depth: np.ndarray, min_gap: float) -> np.ndarray:
    """Occluding-edge mask by its definition: a model pixel with a 4-neighbour inside the image
    that is background, or of another part and farther by more than ``min_gap`` metres.

    Returns
    -------
    ndarray, shape (H, W), bool
    """
    h, w = parts.shape
    with np.errstate(divide="ignore"):
        depth = np.where(inv_depth > 0, 1.0 / inv_depth, np.inf)
    edges = np.zeros((h, w), bool)
    for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        for i in range(h):
            for j in range(w):
                ni, nj = i + dy, j + dx
                if parts[i, j] == 0 or not (0 <= ni < h and 0 <= nj < w):
                    continue
                q = parts[ni, nj]
                if q == 0 or (q != parts[i, j] and depth[ni, nj] - depth[i, j] > min_gap):
                    edges[i, j] = True
    return edges
