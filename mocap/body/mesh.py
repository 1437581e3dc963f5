"""Triangle mesh of the body: one closed, tapered superellipsoid per part.

Each part is tessellated on a latitude/longitude grid with a single vertex at each pole, so
every part is a closed, consistently outward-wound mesh (needed for back-face culling and for
occluding contours). ``resolution`` (longitudes per part) is the level of detail: the torso gets
``resolution`` longitudes and ``resolution // 2 + 1`` latitude rings, smaller parts a fraction
(:data:`PART_DETAIL`, at least 4 longitudes); a part with n longitudes and r rings has
``2 n r`` triangles.

The head is cut into a face and a hair region: with a hairline in the body dimensions its
tessellation moves two latitude rings to the forehead hairline and :data:`HAIR_NAPE_DROP`
lower, and the triangles above the first ring, or behind the head's centre plane (away from
the face) and above the second, belong to the part ``hair``
(:data:`~mocap.body.skeleton.MESH_PART_NAMES`); the rest stay ``head`` (the face). The cut
follows rings, so the split is exact and costs no triangle.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import lru_cache
from types import MappingProxyType

import numpy as np

from mocap.body.dimensions import DEFAULT_HAIRLINE, BodyDimensions
from mocap.body.skeleton import (MESH_PART_NAMES, PART_SEGMENT, SEGMENT_AXIS_SIGN, SEGMENT_NAMES, lower_body_span,
                                 part_spans)

#: Shape of each part: (e_long, e_cross, taper). ``e_long`` < 1 flattens the ends (1 is an
#: ellipsoid), ``e_cross`` < 1 squares the cross-section, ``taper`` is the fraction by which the
#: width shrinks from the start to the end of the part (negative widens).
PART_SHAPES = MappingProxyType({
    "torso": (0.35, 0.7, -0.12),
    "neck": (0.3, 1.0, 0.0),
    "head": (1.0, 1.0, 0.1),
    "r_upper_arm": (0.45, 1.0, 0.2),
    "r_forearm": (0.45, 1.0, 0.25),
    "r_hand": (0.6, 0.6, 0.0),
    "l_upper_arm": (0.45, 1.0, 0.2),
    "l_forearm": (0.45, 1.0, 0.25),
    "l_hand": (0.6, 0.6, 0.0),
    "lower_body": (0.4, 0.6, 0.0),
})
#: Level of detail of each part relative to the torso: small parts need fewer triangles to
#: look the same in the image, and per-triangle work dominates the rasterizer's time.
PART_DETAIL = MappingProxyType({
    "torso": 1.0, "neck": 0.5, "head": 0.75,
    "r_upper_arm": 0.75, "r_forearm": 0.75, "r_hand": 0.5,
    "l_upper_arm": 0.75, "l_forearm": 0.75, "l_hand": 0.5,
    "lower_body": 0.5,
})
#: How far below the forehead hairline the hair reaches at the back of the head, in half head
#: lengths (the synthetic actor's hair: 0.45 at the forehead, -0.35 at the back).
HAIR_NAPE_DROP = 0.8
#: Smallest and largest accepted resolution (longitudes per part).
MIN_RESOLUTION = 4
MAX_RESOLUTION = 128


def _signed_power(x: np.ndarray, e: float) -> np.ndarray:
    return np.sign(x) * np.abs(x) ** e


def _unit_part(n_lon: int, e_long: float, e_cross: float, taper: float, cuts: tuple[float, ...]):
    """The shape of a part of unit size: what :func:`part_mesh` scales by its length, width and
    depth. Returns ``u`` (rings,), 0..1 along the axis; ``scale`` (rings,), the cross-section's
    half-size in half widths; ``cx``, ``cz`` (n_lon,), the cross-section's unit outline."""
    eta = np.linspace(-np.pi / 2, np.pi / 2, n_lon // 2 + 3)[1:-1]   # latitudes, poles excluded
    if cuts:
        cut = np.asarray(cuts, dtype=np.float64)
        if not ((cut > 0) & (cut < 1)).all():
            raise ValueError(f"cuts must lie strictly between 0 and 1, got {cuts}")
        # invert u = (1 + sin(eta)^e_long) / 2 (signed power); each cut moves the nearest ring
        # not moved yet (same triangle count), or adds one when none is left
        eta = eta.copy()
        moved = np.zeros(len(eta), bool)
        extra = []
        for e in np.arcsin(_signed_power(2.0 * cut - 1.0, 1.0 / e_long)):
            free = np.flatnonzero(~moved)
            if free.size == 0:
                extra.append(e)
                continue
            k = free[np.argmin(np.abs(eta[free] - e))]
            eta[k], moved[k] = e, True
        eta = np.unique(np.r_[eta, extra])
    omega = np.linspace(-np.pi, np.pi, n_lon, endpoint=False)
    u = 0.5 * (1.0 + _signed_power(np.sin(eta), e_long))             # 0..1 along the axis
    radial = np.abs(np.cos(eta)) ** e_long
    scale = radial * (1.0 - taper * u)
    return u, scale, _signed_power(np.cos(omega), e_cross), _signed_power(np.sin(omega), e_cross)


@lru_cache(maxsize=64)
def _grid_triangles(n_lon: int, rings: int) -> np.ndarray:
    """Triangles of a part with ``n_lon`` longitudes and ``rings`` latitude rings (vertices ring
    by ring, then the south and the north pole), longitude by longitude: the south pole's
    triangle, two per ring gap, the north pole's; shape (2 n_lon rings, 3), int64, read-only.
    Wound one way; :func:`part_mesh` reverses them when that is inwards."""
    south, north = rings * n_lon, rings * n_lon + 1
    k = np.arange(n_lon, dtype=np.int64)[:, None]
    k1 = (k + 1) % n_lon
    r = np.arange(rings - 1, dtype=np.int64)[None, :]
    a, b = r * n_lon + k, r * n_lon + k1
    c, d = a + n_lon, b + n_lon
    quads = np.stack([np.stack([a, b, d], axis=-1), np.stack([a, d, c], axis=-1)], axis=2).reshape(n_lon, -1, 3)
    top = (rings - 1) * n_lon
    first = np.concatenate([np.full_like(k, south), k1, k], axis=1)[:, None, :]
    last = np.concatenate([np.full_like(k, north), top + k, top + k1], axis=1)[:, None, :]
    triangles = np.concatenate([first, quads, last], axis=1).reshape(-1, 3)
    triangles.setflags(write=False)
    return triangles


def part_mesh(length: float, width: float, depth: float, *, e_long: float, e_cross: float,
              taper: float, resolution: int, start: float = 0.0, axis_sign: int = 1,
              cuts: tuple[float, ...] = ()):
    """Closed tapered superellipsoid along the local y axis.

    Parameters
    ----------
    length, width, depth : float, metres
        Extent along y (long axis), x and z.
    start : float, metres
        Distance along the axis where the part begins.
    axis_sign : {1, -1}
        The part extends towards +y (1) or -y (-1).
    cuts : tuple of float
        Latitude rings at these fractions of the length (0 start ... 1 end, exclusive), so
        that a region bounded there is a union of whole triangles: each moves the nearest
        ring of the regular grid (the triangle count stays ``2 n r``).

    Returns
    -------
    vertices : ndarray, shape (V, 3), float64, metres
        Ring by ring (``n`` longitudes each), then the two poles (start, end).
    triangles : ndarray, shape (T, 3), int64
        Wound counter-clockwise seen from outside (outward normals by the right-hand rule).
    """
    n_lon = int(resolution)
    u, scale, cx, cz = _unit_part(n_lon, e_long, e_cross, taper, tuple(cuts))
    rings = len(u)
    along = start + length * u
    ring = np.stack([
        0.5 * width * scale[:, None] * cx[None, :],
        np.broadcast_to(along[:, None], (rings, n_lon)),
        0.5 * depth * scale[:, None] * cz[None, :],
    ], axis=-1).reshape(-1, 3)
    poles = np.array([[0.0, start, 0.0], [0.0, start + length, 0.0]])
    vertices = np.concatenate([ring, poles])
    vertices[:, 1] *= axis_sign
    triangles = _grid_triangles(n_lon, rings)
    if signed_volume(vertices, triangles) < 0:
        return vertices, triangles[:, ::-1].copy()
    return vertices, triangles.copy()


def signed_volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """Signed volume enclosed by a closed triangle mesh (positive when wound outwards), m³."""
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


@dataclass(frozen=True)
class BodyMesh:
    """The body's triangle mesh in segment-local coordinates.

    Attributes
    ----------
    vertices : ndarray, shape (V, 3), float64, metres
        Vertex positions in the frame of their segment.
    vertex_segment : ndarray, shape (V,), int64
        Segment index (:data:`~mocap.body.skeleton.SEGMENT_NAMES`) of each vertex.
    triangles : ndarray, shape (T, 3), int64
        Vertex indices, outward (counter-clockwise from outside) winding.
    triangle_part : ndarray, shape (T,), int64
        Part index (:data:`~mocap.body.skeleton.MESH_PART_NAMES`) of each triangle.
    resolution : int
        Longitudes per part (level of detail).
    """

    vertices: np.ndarray
    vertex_segment: np.ndarray
    triangles: np.ndarray
    triangle_part: np.ndarray
    resolution: int

    @property
    def n_triangles(self) -> int:
        return int(self.triangles.shape[0])


def part_resolution(part: str, resolution: int) -> int:
    """Longitudes of ``part`` at mesh ``resolution`` (see :data:`PART_DETAIL`)."""
    return max(MIN_RESOLUTION, int(round(resolution * PART_DETAIL[part])))


def hair_cuts(hairline: float) -> tuple[float, ...]:
    """Fractions of the head's length (0 chin ... 1 crown) of the rings that bound the hair
    region: the forehead hairline and :data:`HAIR_NAPE_DROP` lower (when above the chin)."""
    front = 0.5 * (1.0 + hairline)
    back = 0.5 * (1.0 + hairline - HAIR_NAPE_DROP)
    return (front, back) if back > 0.0 else (front,)


def hair_triangles(vertices: np.ndarray, triangles: np.ndarray, start: float, length: float, depth: float,
                   hairline: float, axis_sign: int = -1) -> np.ndarray:
    """Which head triangles are hair: centroid above the hairline, or behind the head's centre
    plane (z > 0, away from the face) and above the hairline less :data:`HAIR_NAPE_DROP`.

    Parameters
    ----------
    vertices : ndarray, shape (V, 3), metres
        Head vertices in the head segment's frame (the face looks towards -z).
    triangles : ndarray, shape (T, 3), int
    start, length, depth : float, metres
        Where the head starts along its axis, its length and depth.
    hairline : float
        Forehead hairline, fraction of half the head length above its centre.

    Returns
    -------
    ndarray, shape (T,), bool
    """
    # the centroids' y and z (the same sums, in the same order, as vertices[triangles].mean(axis=1))
    y, z = vertices[:, 1][triangles], vertices[:, 2][triangles]
    centroid_y, centroid_z = (y[:, 0] + y[:, 1] + y[:, 2]) / 3.0, (z[:, 0] + z[:, 1] + z[:, 2]) / 3.0
    v = (axis_sign * centroid_y - (start + 0.5 * length)) / (0.5 * length)    # -1 chin ... +1 crown
    behind = centroid_z > 1e-9 * depth
    return (v >= hairline) | (behind & (v >= hairline - HAIR_NAPE_DROP))


@dataclass(frozen=True)
class _PartTemplate:
    """A part of unit size, as :func:`_part_template` makes it; per vertex (ring by ring, then
    the two poles): ``along`` 0..1 along the axis, ``ring_scale`` the cross-section's half-size
    in half widths (0 at the poles), ``cross_x``/``cross_z`` the unit outline (0 at the poles);
    ``triangles`` wound outwards for the part's axis sign (read-only)."""

    along: np.ndarray
    ring_scale: np.ndarray
    cross_x: np.ndarray
    cross_z: np.ndarray
    triangles: np.ndarray


@lru_cache(maxsize=256)
def _part_template(n_lon: int, e_long: float, e_cross: float, taper: float, cuts: tuple[float, ...],
                   axis_sign: int) -> _PartTemplate:
    u, scale, cx, cz = _unit_part(n_lon, e_long, e_cross, taper, cuts)
    rings = len(u)
    poles = np.zeros(2)
    along = np.concatenate([np.repeat(u, n_lon), [0.0, 1.0]])
    ring_scale = np.concatenate([np.repeat(scale, n_lon), poles])
    cross_x = np.concatenate([np.tile(cx, rings), poles])
    cross_z = np.concatenate([np.tile(cz, rings), poles])
    triangles = _grid_triangles(n_lon, rings)
    # the winding's sense does not change when the axes are scaled by positive sizes or the
    # part is moved along its axis: the unit part's decides it
    unit = np.stack([0.5 * ring_scale * cross_x, along * axis_sign, 0.5 * ring_scale * cross_z], axis=1)
    if signed_volume(unit, triangles) < 0:
        triangles = triangles[:, ::-1].copy()
        triangles.setflags(write=False)
    return _PartTemplate(along, ring_scale, cross_x, cross_z, triangles)


@dataclass(frozen=True)
class _Topology:
    """Everything of the body mesh that its sizes do not change, for one resolution, hairline
    and set of parts (see :func:`_topology`). Per present part (``part_names`` order): its mesh
    part index, axis sign; per vertex: ``vertex_slot`` (which present part) and the unit part's
    ``along``, ``ring_scale``, ``cross_x``, ``cross_z`` (:class:`_PartTemplate`); the
    triangles with the part of each (the head's hair not yet marked); ``head``: the head's
    vertex and triangle ranges and its triangles in its own vertex numbering, when it has a
    hair region."""

    part_names: tuple[str, ...]
    part_index: tuple[int, ...]
    axis_sign: np.ndarray
    vertex_slot: np.ndarray
    along: np.ndarray
    ring_scale: np.ndarray
    cross_x: np.ndarray
    cross_z: np.ndarray
    vertex_segment: np.ndarray
    triangles: np.ndarray
    triangle_part: np.ndarray
    head: tuple[int, int, int, int, np.ndarray] | None


@lru_cache(maxsize=32)
def _topology(resolution: int, hairline: float | None, present: tuple[str, ...]) -> _Topology:
    names, indices, segments, signs, templates = [], [], [], [], []
    head = None
    for p, name in enumerate(MESH_PART_NAMES):
        if name not in present:
            continue                                    # hair: part of the head; lower body: optional
        seg = SEGMENT_NAMES.index(PART_SEGMENT[name])
        sign = 1 if name == "lower_body" else int(SEGMENT_AXIS_SIGN[seg])    # lower body: downwards
        cuts = hair_cuts(hairline) if name == "head" and hairline is not None else ()
        if cuts:
            head = len(names)
        names.append(name)
        indices.append(p)
        segments.append(seg)
        signs.append(sign)
        templates.append(_part_template(part_resolution(name, resolution), *PART_SHAPES[name], cuts, sign))
    n_vertices = np.array([len(t.along) for t in templates])
    n_triangles = np.array([len(t.triangles) for t in templates])
    first_vertex = np.r_[0, np.cumsum(n_vertices)]
    first_triangle = np.r_[0, np.cumsum(n_triangles)]
    arrays = [np.repeat(np.arange(len(names)), n_vertices),
              *(np.concatenate([getattr(t, k) for t in templates]) for k in ("along", "ring_scale", "cross_x", "cross_z")),
              np.repeat(np.array(signs, dtype=np.float64), n_vertices),
              np.repeat(np.array(segments, dtype=np.int64), n_vertices),
              np.concatenate([t.triangles + first for t, first in zip(templates, first_vertex)]),
              np.repeat(np.array(indices, dtype=np.int64), n_triangles)]
    for a in arrays:
        a.setflags(write=False)
    slot, along, ring_scale, cross_x, cross_z, axis_sign, vseg, tris, tpart = arrays
    if head is not None:
        head = (int(first_vertex[head]), int(first_vertex[head + 1]), int(first_triangle[head]),
                int(first_triangle[head + 1]), templates[head].triangles)
    return _Topology(tuple(names), tuple(indices), axis_sign, slot, along, ring_scale, cross_x, cross_z, vseg,
                     tris, tpart, head)


#: Hairlines whose topologies stand for every other with as many hair cuts (:func:`hair_cuts`):
#: two cuts above -0.2, one below.
_REFERENCE_HAIRLINES = {2: DEFAULT_HAIRLINE, 1: -0.5}


def _topology_for(resolution: int, hairline: float | None, present: tuple[str, ...]) -> _Topology:
    """:func:`_topology`, without building one per hairline: a calibration's colour fit tries a
    new hairline at every evaluation. Another hairline moves only the head's rings along its axis
    (the same count, so the same triangles), so the kept topology of a reference hairline with
    as many cuts (:data:`_REFERENCE_HAIRLINES`) is reused with the head's ``along`` and
    ``ring_scale`` of this hairline: the same numbers :func:`_topology` would give. Where the
    count differs (a cut on a ring), :func:`_topology` itself."""
    if hairline is None or "head" not in present:
        return _topology(resolution, hairline, present)
    cuts = hair_cuts(hairline)
    reference = _topology(resolution, _REFERENCE_HAIRLINES[len(cuts)], present)
    if reference.head is None or hairline == _REFERENCE_HAIRLINES[len(cuts)]:
        return _topology(resolution, hairline, present)
    v0, v1 = reference.head[0], reference.head[1]
    n_lon = part_resolution("head", resolution)
    e_long, e_cross, taper = PART_SHAPES["head"]
    u, scale, _, _ = _unit_part(n_lon, e_long, e_cross, taper, cuts)
    if len(u) * n_lon + 2 != v1 - v0:
        return _topology(resolution, hairline, present)
    along, ring_scale = reference.along.copy(), reference.ring_scale.copy()
    along[v0:v1 - 2], ring_scale[v0:v1 - 2] = np.repeat(u, n_lon), np.repeat(scale, n_lon)
    along.setflags(write=False)
    ring_scale.setflags(write=False)
    return dataclasses.replace(reference, along=along, ring_scale=ring_scale)


def build_mesh(dims: BodyDimensions, resolution: int = 12) -> BodyMesh:
    """Tessellate every body part: the sized parts the dimensions have, the head split into
    face (``head``) and ``hair`` when they have a hairline.

    What does not depend on the sizes (the triangles, each part's unit shape) is made once per
    resolution, hairline and set of parts and kept (a few dozen such topologies); a build then
    scales the unit parts, a few array operations (tens of microseconds). The vertices are the
    same numbers, operation for operation, as tessellating each part with :func:`part_mesh`.

    Parameters
    ----------
    dims : BodyDimensions
    resolution : int
        Torso longitudes, in [MIN_RESOLUTION, MAX_RESOLUTION]; 12 gives 832 triangles for the
        paper's model (no lower body, no hairline).

    Returns
    -------
    BodyMesh
        Its index arrays (``vertex_segment``, ``triangles`` and, without a hair region,
        ``triangle_part``) are shared, read-only, by the meshes of one topology.
    """
    if isinstance(resolution, bool) or not isinstance(resolution, (int, np.integer)):
        raise ValueError(f"mesh resolution must be an integer, got {resolution!r}")
    if not MIN_RESOLUTION <= resolution <= MAX_RESOLUTION:
        raise ValueError(f"mesh resolution must be in [{MIN_RESOLUTION}, {MAX_RESOLUTION}], got {resolution}")
    parts = dims.parts
    topology = _topology_for(int(resolution), dims.hairline, tuple([n for n in MESH_PART_NAMES if n in parts]))
    spans = part_spans(dims)
    sizes = [parts[name] for name in topology.part_names]
    half_width = np.array([0.5 * size.width for size in sizes])
    length = np.array([size.length for size in sizes])
    half_depth = np.array([0.5 * size.depth for size in sizes])
    start = np.array([lower_body_span(dims)[0] if name == "lower_body" else spans[p, 0]
                      for name, p in zip(topology.part_names, topology.part_index)])
    slot = topology.vertex_slot
    vertices = np.empty((len(slot), 3))
    vertices[:, 0] = half_width[slot] * topology.ring_scale * topology.cross_x
    vertices[:, 1] = (start[slot] + length[slot] * topology.along) * topology.axis_sign
    vertices[:, 2] = half_depth[slot] * topology.ring_scale * topology.cross_z
    vertices.setflags(write=False)
    triangle_part = topology.triangle_part
    if topology.head is not None:
        v0, v1, t0, t1, head_triangles = topology.head
        h = topology.part_names.index("head")
        size = dims["head"]
        hair = hair_triangles(vertices[v0:v1], head_triangles, start[h], size.length, size.depth, dims.hairline,
                              int(topology.axis_sign[v0]))
        triangle_part = triangle_part.copy()
        triangle_part[t0:t1][hair] = MESH_PART_NAMES.index("hair")
        triangle_part.setflags(write=False)
    return BodyMesh(vertices, topology.vertex_segment, topology.triangles, triangle_part, resolution=int(resolution))


def resolution_for_image(width: int, height: int) -> int:
    """Mesh level of detail matched to the image size.

    Per-triangle work dominates small images, so the triangle count grows with the image:
    ``resolution = 8 * sqrt(max(width, height) / 160)`` clamped to [8, 24], i.e. 8 (392
    triangles) at 160x120, 11 (696) at 320x240 and 16 (1,472) at 640x480.
    """
    if width < 1 or height < 1:
        raise ValueError(f"image size must be positive, got {width}x{height}")
    return int(np.clip(round(8.0 * np.sqrt(max(width, height) / 160.0)), 8, 24))


def edge_faces(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The edges of a closed triangle mesh and the two triangles that share each.

    Parameters
    ----------
    triangles : ndarray, shape (T, 3), int
        Vertex indices of a closed, consistently wound mesh (every edge in exactly two triangles).

    Returns
    -------
    edges : ndarray, shape (E, 2), int64
        Vertex indices of each edge, lower first.
    faces : ndarray, shape (E, 2), int64
        The two triangles sharing it.

    Raises
    ------
    ValueError
        If an edge is not shared by exactly two triangles (the mesh is not closed).
    """
    t = np.asarray(triangles, dtype=np.int64)
    if t.ndim != 2 or t.shape[1] != 3:
        raise ValueError(f"triangles must have shape (T, 3), got {t.shape}")
    pairs = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    pairs.sort(axis=1)
    owner = np.tile(np.arange(len(t), dtype=np.int64), 3)
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    pairs, owner = pairs[order], owner[order]
    if len(pairs) % 2 or not (np.array_equal(pairs[0::2], pairs[1::2])
                              and (len(pairs) < 4 or (np.diff(pairs[0::2], axis=0) != 0).any(axis=1).all())):
        raise ValueError("the mesh is not closed: every edge must be shared by exactly two triangles")
    return pairs[0::2].copy(), np.stack([owner[0::2], owner[1::2]], axis=1)
