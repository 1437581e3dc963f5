"""Public rendering API: labels, part ids, depth and occluding edges of a posed body or any mesh."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mocap.body.model import BodyModel
from mocap.body.pose import check_pose
from mocap.body.skeleton import SEGMENT_NAMES
from mocap.render import _raster
from mocap.render.camera import Camera
from mocap.body.kinematics import _segment_transforms

#: Depth gap (metres) between a pixel and its 4-neighbour of another part above which the
#: boundary between them is an occluding contour (an arm in front of the chest) rather than a
#: crease where adjacent parts meet.
EDGE_DEPTH_GAP_M = 0.03


@dataclass(frozen=True)
class Rendering:
    """What one render produces (all arrays of shape (height, width)).

    Attributes
    ----------
    labels : ndarray, uint8
        0 background, 1..m colour class (see :mod:`mocap.labels`).
    parts : ndarray, uint8
        0 background, else part index + 1 (:data:`~mocap.body.dimensions.PART_NAMES`).
    depth : ndarray, float32, metres
        Depth z of the nearest surface; ``inf`` on background.
    edges : ndarray, bool
        Occluding edges: the silhouette outline and internal occluding contours.
    triangle_ids : ndarray, int32, or None
        Index of the visible triangle, -1 on background (only when asked for).
    """

    labels: np.ndarray
    parts: np.ndarray
    depth: np.ndarray
    edges: np.ndarray
    triangle_ids: np.ndarray | None = None


def _check_gap(edge_gap: float) -> float:
    if not np.isfinite(edge_gap) or edge_gap < 0:
        raise ValueError(f"edge depth gap must be a finite non-negative number of metres, got {edge_gap}")
    return float(edge_gap)


def _finish(camera: Camera, part_buf, depth_buf, tri_buf, bbox, part_label, edge_gap, want_tri) -> Rendering:
    w, h = camera.width, camera.height
    edge_buf = np.zeros(w * h, dtype=np.bool_)
    _raster._edge_scan(part_buf, depth_buf, w, h, bbox, edge_gap, np.empty(0, np.float32), edge_buf, False)
    lut = np.concatenate([np.zeros(1, np.uint8), np.asarray(part_label, dtype=np.uint8)])
    parts = part_buf.reshape(h, w)
    with np.errstate(divide="ignore"):
        depth = np.where(depth_buf > 0, 1.0 / depth_buf, np.inf).astype(np.float32).reshape(h, w)
    return Rendering(labels=lut[parts], parts=parts, depth=depth, edges=edge_buf.reshape(h, w),
                     triangle_ids=tri_buf.reshape(h, w) if want_tri else None)


def render(pose, model: BodyModel, camera: Camera, *, cull: bool = True,
           edge_gap: float = EDGE_DEPTH_GAP_M, triangle_ids: bool = False) -> Rendering:
    """Render the body model in a pose.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Metres and radians (DESIGN.md section 2).
    model : BodyModel
    camera : Camera
    cull : bool
        Draw only front-facing triangles (exact for the closed body mesh, and twice as fast).
    edge_gap : float, metres
        Depth gap that makes a part boundary an occluding contour (:data:`EDGE_DEPTH_GAP_M`).
    triangle_ids : bool
        Also return the visible triangle per pixel.

    Returns
    -------
    Rendering
    """
    q = check_pose(pose)
    edge_gap = _check_gap(edge_gap)
    transforms = np.empty((len(SEGMENT_NAMES), 3, 4))
    _segment_transforms(q, model.skeleton.offsets, transforms)
    mesh = model.mesh
    n = mesh.vertices.shape[0]
    xs, ys, iz = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
    _raster._project_vertices(transforms, mesh.vertices, mesh.vertex_segment, camera.as_array(), xs, ys, iz)
    return _draw(xs, ys, iz, mesh.triangles, mesh.triangle_part, model.part_label, camera, cull, edge_gap,
                 triangle_ids)


def _draw(xs, ys, iz, triangles, triangle_part, part_label, camera, cull, edge_gap, want_tri,
          count_buf=None) -> Rendering:
    w, h = camera.width, camera.height
    part_buf = np.zeros(w * h, np.uint8)
    depth_buf = np.zeros(w * h, np.float32)
    tri_buf = np.full(w * h, -1, np.int32) if want_tri else np.empty(0, np.int32)
    count = np.empty(0, np.int32) if count_buf is None else count_buf
    bbox = np.empty(4, np.int64)
    _raster._rasterize(xs, ys, iz, triangles, triangle_part, w, h, cull, part_buf, depth_buf, tri_buf, count, bbox)
    return _finish(camera, part_buf, depth_buf, tri_buf, bbox, part_label, edge_gap, want_tri)


def render_labels(pose, model: BodyModel, camera: Camera) -> np.ndarray:
    """Coloured silhouette: class-label image, uint8 (height, width); see :func:`render`."""
    return render(pose, model, camera).labels


def render_occluding_edges(pose, model: BodyModel, camera: Camera, *, edge_gap: float = EDGE_DEPTH_GAP_M) -> np.ndarray:
    """Occluding-edge mask, bool (height, width); see :func:`render`."""
    return render(pose, model, camera, edge_gap=edge_gap).edges


def rasterize_mesh(vertices, triangles, camera: Camera, *, triangle_part=None, part_label=None,
                   cull: bool = True, edge_gap: float = EDGE_DEPTH_GAP_M, triangle_ids: bool = False,
                   return_coverage: bool = False):
    """Rasterize an arbitrary triangle mesh given in camera coordinates.

    Parameters
    ----------
    vertices : array_like, shape (V, 3), metres
        Camera coordinates (x right, y down, z forward).
    triangles : array_like, shape (T, 3), int
        Vertex indices; counter-clockwise seen from outside for ``cull``.
    camera : Camera
    triangle_part : array_like, shape (T,), int, optional
        Part index (0..254) of each triangle; all 0 when omitted.
    part_label : array_like, shape (P,), uint8, optional
        Label of each part; 1 for all when omitted.
    cull : bool
        Skip back-facing triangles.
    return_coverage : bool
        Also return an int32 (height, width) count of the triangles covering each pixel
        centre (before the depth test): 1 everywhere inside a tiled surface when the fill
        rule is right.

    Returns
    -------
    Rendering, or (Rendering, ndarray) with ``return_coverage``
    """
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] != 3 or not np.isfinite(v).all():
        raise ValueError(f"vertices must be a finite (V, 3) array, got shape {v.shape}")
    t = np.ascontiguousarray(triangles)
    if t.ndim != 2 or t.shape[1] != 3 or not np.issubdtype(t.dtype, np.integer):
        raise ValueError(f"triangles must be an integer (T, 3) array, got {t.dtype} {t.shape}")
    t = t.astype(np.int64)
    if t.size and (t.min() < 0 or t.max() >= len(v)):
        raise ValueError("triangle vertex index out of range")
    tp = np.zeros(len(t), np.int64) if triangle_part is None else np.asarray(triangle_part, np.int64)
    if tp.shape != (len(t),) or (tp.size and (tp.min() < 0 or tp.max() > 253)):
        raise ValueError("triangle_part must have one index in [0, 253] per triangle")
    n_parts = int(tp.max()) + 1 if tp.size else 1
    pl = np.ones(n_parts, np.uint8) if part_label is None else np.asarray(part_label, np.uint8)
    if pl.shape[0] < n_parts:
        raise ValueError("part_label needs one label per part index")
    n = len(v)
    xs, ys, iz = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
    _raster._project_points(v, camera.as_array(), xs, ys, iz)
    count = np.zeros(camera.width * camera.height, np.int32) if return_coverage else None
    out = _draw(xs, ys, iz, t, tp, pl, camera, cull, _check_gap(edge_gap), triangle_ids, count)
    if return_coverage:
        return out, count.reshape(camera.height, camera.width)
    return out
