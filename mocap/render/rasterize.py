"""Public rendering API: labels, part ids, depth and occluding edges of a posed body or any mesh."""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from mocap._numba import jit
from mocap.body.kinematics import segment_transforms_into
from mocap.body.model import BodyModel
from mocap.body.pose import check_pose
from mocap.body.skeleton import SEGMENT_NAMES
from mocap.render import _raster
from mocap.render.camera import Camera

#: The rasterizer's compiled stages, for a profile that runs them one at a time inside a
#: compiled loop of its own (``experiments.evaluation_profile``; the renders above call them in
#: this order). ``project_vertices(transforms, vertices, vertex_segment, camera, vertex_x,
#: vertex_y, vertex_inverse_depth)`` poses and projects the vertices;
#: ``rasterize_triangles(vertex_x, vertex_y, vertex_inverse_depth, triangles, triangle_part,
#: width, height, cull, part_ids, inverse_depth, triangle_ids, coverage, box[, fill])`` draws
#: the triangles (``fill=False``: sets them up and grows ``box`` without drawing: the stage
#: switch, tested in tests/render/test_rasterize.py); ``clear_drawn(part_ids, inverse_depth,
#: width, box)`` clears the drawn box. The buffers are those of :class:`Buffers`.
project_vertices = _raster._project_vertices
rasterize_triangles = _raster._rasterize
clear_drawn = _raster._clear

#: Depth gap (metres) between a pixel and its 4-neighbour of another part above which the
#: boundary between them is an occluding contour (an arm in front of the chest) rather than a
#: crease where adjacent parts meet.
EDGE_DEPTH_GAP_M = 0.03


class Scene(NamedTuple):
    """What a compiled render of the body model reads (a named tuple Numba compiles).

    Attributes
    ----------
    offsets : ndarray, shape (segments, 3), float64, metres
        Skeleton offsets (:attr:`~mocap.body.kinematics.Skeleton.offsets`).
    vertices : ndarray, shape (V, 3), float64, metres
        Mesh vertices in their segment's frame.
    vertex_segment : ndarray, shape (V,), int64
        Segment of each vertex.
    triangles : ndarray, shape (T, 3), int64
        Vertex indices.
    triangle_part : ndarray, shape (T,), int64
        Index drawn for each triangle (the part buffer gets it + 1): the body part, or the colour
        class label - 1 for a label render.
    part_label : ndarray, shape (P,), uint8
        Colour class label of each part.
    camera : ndarray, shape (5,), float64
        :meth:`~mocap.render.camera.Camera.as_array` (fx, fy, cx, cy in pixels, near plane in metres).
    width, height : int64
        Image size in pixels.
    """

    offsets: np.ndarray
    vertices: np.ndarray
    vertex_segment: np.ndarray
    triangles: np.ndarray
    triangle_part: np.ndarray
    part_label: np.ndarray
    camera: np.ndarray
    width: np.int64
    height: np.int64

    @classmethod
    def of(cls, model: BodyModel, camera: Camera) -> "Scene":
        """The scene of ``model`` seen by ``camera`` (arrays shared with the model, not copied)."""
        m = model.mesh
        return cls(model.skeleton.offsets, m.vertices, m.vertex_segment, m.triangles, m.triangle_part,
                   model.part_label, camera.as_array(), np.int64(camera.width), np.int64(camera.height))


class Buffers(NamedTuple):
    """Scratch arrays one compiled render writes (a named tuple Numba compiles; one per thread).

    Attributes
    ----------
    part_ids : ndarray, shape (height * width,), uint8
        Flat part buffer: 0 background, else the triangle's part + 1. All 0 between renders.
    inverse_depth : ndarray, shape (height * width,), float32, 1/metres
        Flat inverse depth 1/z (0: nothing drawn). All 0 between renders.
    vertex_x, vertex_y : ndarray, shape (V,), int64
        Projected vertices in 1/:data:`~mocap.render._raster.SUBPIXEL` pixels.
    vertex_inverse_depth : ndarray, shape (V,), float64, 1/metres
        1/z of each vertex (-1 nearer than the near plane).
    transforms : ndarray, shape (segments, 3, 4), float64
        Segment-to-camera transforms of the last pose rendered.
    box : ndarray, shape (4,), int64
        Inclusive pixel box (x0, y0, x1, y1) of the last render (x0 > x1: nothing drawn).
    triangle_ids, coverage : ndarray, shape (0,), int32
        Empty: the costs ask for neither.
    """

    part_ids: np.ndarray
    inverse_depth: np.ndarray
    vertex_x: np.ndarray
    vertex_y: np.ndarray
    vertex_inverse_depth: np.ndarray
    transforms: np.ndarray
    box: np.ndarray
    triangle_ids: np.ndarray
    coverage: np.ndarray

    @classmethod
    def of(cls, model: BodyModel, camera: Camera) -> "Buffers":
        """Zeroed buffers for rendering ``model`` with ``camera``."""
        n_px = camera.width * camera.height
        n_v = model.mesh.vertices.shape[0]
        return cls(np.zeros(n_px, np.uint8), np.zeros(n_px, np.float32), np.empty(n_v, np.int64),
                   np.empty(n_v, np.int64), np.empty(n_v), np.empty((len(SEGMENT_NAMES), 3, 4)),
                   np.empty(4, np.int64), np.empty(0, np.int32), np.empty(0, np.int32))


@jit
def render_scene_into(pose, scene, buffers):
    """Compiled: pose the mesh and rasterize it (front faces) into ``buffers``, setting its box.

    ``pose`` is a float64 (23,) array (unchecked); ``scene`` a :class:`Scene`; ``buffers`` a
    :class:`Buffers` whose part and depth buffers are 0 (the caller clears the box after use).
    """
    segment_transforms_into(pose, scene.offsets, buffers.transforms)
    _raster._project_vertices(buffers.transforms, scene.vertices, scene.vertex_segment, scene.camera,
                              buffers.vertex_x, buffers.vertex_y, buffers.vertex_inverse_depth)
    _raster._rasterize(buffers.vertex_x, buffers.vertex_y, buffers.vertex_inverse_depth, scene.triangles,
                       scene.triangle_part, scene.width, scene.height, True, buffers.part_ids,
                       buffers.inverse_depth, buffers.triangle_ids, buffers.coverage, buffers.box)


@jit
def occluding_edge_sum_and_clear(scene, buffers, min_gap, distance, marks):
    """Compiled: (sum of ``distance`` over the occluding-edge pixels of the render in ``buffers``,
    their count), marking them in the flat bool ``marks``; clears the part, depth and mark
    buffers behind it. ``min_gap`` in metres (:data:`EDGE_DEPTH_GAP_M`)."""
    return _raster._edge_scan(buffers.part_ids, buffers.inverse_depth, scene.width, scene.height,
                              buffers.box, min_gap, distance, marks, True)


@jit
def occluding_edge_marks_into(scene, buffers, min_gap, distance, marks):
    """Compiled: as :func:`occluding_edge_sum_and_clear`, but the occluding-edge pixels stay
    marked in ``marks`` (the caller clears them: they lie in ``buffers.box``); the part and
    depth buffers are cleared."""
    out = _raster._edge_scan(buffers.part_ids, buffers.inverse_depth, scene.width, scene.height,
                             buffers.box, min_gap, distance, marks, False)
    _raster._clear(buffers.part_ids, buffers.inverse_depth, scene.width, buffers.box)
    return out


@jit
def occluding_edges_into(scene, buffers, min_gap, marks):
    """Compiled: mark the occluding-edge pixels of the render in ``buffers`` in the flat bool
    ``marks`` (they lie in ``buffers.box``), keeping the part and depth buffers (a drawer reads
    them: :func:`clear_render` clears them after)."""
    _raster._edge_scan(buffers.part_ids, buffers.inverse_depth, scene.width, scene.height, buffers.box, min_gap,
                       np.empty(0, np.float32), marks, False)


@jit
def clear_render(scene, buffers, marks):
    """Compiled: the part and depth buffers and the flat bool ``marks`` cleared in ``buffers.box``
    (zero and False again, ready for the next render)."""
    box = buffers.box
    if box[0] > box[2]:
        return
    _raster._clear(buffers.part_ids, buffers.inverse_depth, scene.width, box)
    for y in range(box[1], box[3] + 1):
        row = y * scene.width
        marks[row + box[0]: row + box[2] + 1] = False


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


def check_edge_gap(edge_gap: float) -> float:
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
        Metres and radians (docs/design.md section 2).
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
    edge_gap = check_edge_gap(edge_gap)
    transforms = np.empty((len(SEGMENT_NAMES), 3, 4))
    segment_transforms_into(q, model.skeleton.offsets, transforms)
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
    out = _draw(xs, ys, iz, t, tp, pl, camera, cull, check_edge_gap(edge_gap), triangle_ids, count)
    if return_coverage:
        return out, count.reshape(camera.height, camera.width)
    return out
