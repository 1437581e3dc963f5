"""Shaded, textured rendering of the synthetic actor in linear light.

Visibility comes from the project's rasterizer (:func:`mocap.render.rasterize_mesh`, which
returns the visible triangle of every pixel); everything else is computed here per pixel:
the pixel ray is intersected with its triangle (perspective-correct barycentric
coordinates), vertex normals are interpolated (smooth shading), the texture is evaluated on
the segment-local surface point (solid texturing: seamless and attached to the body), and a
key light, a fill light, sky-like ambient light and a faint specular highlight on skin light
it. Render at a multiple of the output size and average blocks of pixels
(:func:`downsample`) for anti-aliased edges, as a camera integrates light over a pixel.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skimage.transform import downscale_local_mean

from mocap._numba import jit
from mocap.body.dimensions import PART_NAMES
from mocap.body.skeleton import HEAD_NECK_OVERLAP
from mocap.render.camera import Camera
from mocap.render.rasterize import rasterize_mesh
from mocap.synth.actor import ACTOR_HAIRLINE, LOWER_BODY, Actor, srgb_to_linear

__all__ = ["Light", "downsample", "render_actor"]

_HEAD = PART_NAMES.index("head")
_SKIN_PARTS = frozenset(PART_NAMES.index(p) for p in ("neck", "head", "r_hand", "l_hand"))
_FOREARMS = frozenset(PART_NAMES.index(p) for p in ("r_forearm", "l_forearm"))


@dataclass(frozen=True)
class Light:
    """Lighting of a scene (camera coordinates; directions point from the surface to the light).

    Attributes
    ----------
    key_direction : tuple of 3 float
        Main light direction (normalised on use).
    key : float
        Main light intensity.
    fill : float
        Fill light intensity, from the mirror side of the key.
    ambient : float
        Ambient light, brighter from above.
    """

    key_direction: tuple[float, float, float] = (-0.5, -0.8, -0.7)
    key: float = 0.8
    fill: float = 0.25
    ambient: float = 0.22

    @classmethod
    def random(cls, rng: np.random.Generator) -> "Light":
        """A key light from above and in front, left or right at random, with fill and ambient."""
        side = 1.0 if rng.uniform() < 0.5 else -1.0
        return cls((side * rng.uniform(0.2, 0.8), -rng.uniform(0.5, 1.0), -rng.uniform(0.5, 1.0)),
                   float(rng.uniform(0.65, 0.9)), float(rng.uniform(0.15, 0.35)), float(rng.uniform(0.15, 0.28)))

    def to_dict(self) -> dict:
        """JSON-ready settings (for ``meta.json``)."""
        return {"key_direction": [round(float(v), 6) for v in self.key_direction], "key": self.key,
                "fill": self.fill, "ambient": self.ambient}


@jit
def _surface_samples(rows, cols, tri, triangles, verts, normals, local, vnoise, cam,
                     out_normal, out_local, out_point, out_noise):
    """Surface attributes at the centre of every listed pixel.

    For pixel ``k`` (``rows[k]``, ``cols[k]``) showing triangle ``tri[k]``: intersect the
    pixel's ray (from the camera centre through the pixel centre, ``cam`` = fx, fy, cx, cy) with
    the triangle's plane (Moller-Trumbore), clamp the barycentric coordinates into the
    triangle, and interpolate the vertex normals (renormalised), the segment-local positions,
    the camera-coordinate positions and the vertex noise.
    """
    fx, fy, cx, cy = cam[0], cam[1], cam[2], cam[3]
    for k in range(rows.shape[0]):
        i0, i1, i2 = triangles[tri[k], 0], triangles[tri[k], 1], triangles[tri[k], 2]
        dx = (cols[k] + 0.5 - cx) / fx
        dy = (rows[k] + 0.5 - cy) / fy
        dz = 1.0
        e1x, e1y, e1z = verts[i1, 0] - verts[i0, 0], verts[i1, 1] - verts[i0, 1], verts[i1, 2] - verts[i0, 2]
        e2x, e2y, e2z = verts[i2, 0] - verts[i0, 0], verts[i2, 1] - verts[i0, 1], verts[i2, 2] - verts[i0, 2]
        hx, hy, hz = dy * e2z - dz * e2y, dz * e2x - dx * e2z, dx * e2y - dy * e2x
        det = e1x * hx + e1y * hy + e1z * hz
        if abs(det) < 1e-15:
            det = 1e-15
        sx, sy, sz = -verts[i0, 0], -verts[i0, 1], -verts[i0, 2]
        b1 = (sx * hx + sy * hy + sz * hz) / det
        qx, qy, qz = sy * e1z - sz * e1y, sz * e1x - sx * e1z, sx * e1y - sy * e1x
        b2 = (dx * qx + dy * qy + dz * qz) / det
        b1 = min(max(b1, 0.0), 1.0)
        b2 = min(max(b2, 0.0), 1.0)
        if b1 + b2 > 1.0:
            total = b1 + b2
            b1 /= total
            b2 /= total
        b0 = 1.0 - b1 - b2
        norm = 0.0
        for a in range(3):
            n = b0 * normals[i0, a] + b1 * normals[i1, a] + b2 * normals[i2, a]
            out_normal[k, a] = n
            norm += n * n
            out_local[k, a] = b0 * local[i0, a] + b1 * local[i1, a] + b2 * local[i2, a]
            out_point[k, a] = b0 * verts[i0, a] + b1 * verts[i1, a] + b2 * verts[i2, a]
        norm = max(np.sqrt(norm), 1e-12)
        for a in range(3):
            out_normal[k, a] /= norm
        out_noise[k] = b0 * vnoise[i0] + b1 * vnoise[i1] + b2 * vnoise[i2]


def _smoothstep(e0: float, e1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _albedo(actor: Actor, part: np.ndarray, local: np.ndarray, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear albedo (K, 3) and specular weight (K,) of surface points of the given parts
    (segment-local positions ``local``, texture noise ``noise`` in about [-1, 1])."""
    app = actor.appearance
    skin = srgb_to_linear(app.skin)
    k = part.shape[0]
    albedo = np.empty((k, 3))
    spec = np.zeros(k)
    is_skin = np.isin(part, sorted(_SKIN_PARTS | (_FOREARMS if app.bare_forearms else frozenset())))
    is_lower = part == LOWER_BODY
    is_cloth = ~is_skin & ~is_lower
    # skin: slight mottling, faint highlight
    albedo[is_skin] = skin * (1.0 + 0.05 * noise[is_skin])[:, None]
    spec[is_skin] = 0.06
    # clothes: pattern of two colours plus fabric noise
    if is_cloth.any():
        p = local[is_cloth]
        period = app.pattern_period_m
        if app.pattern == "stripes":
            mix = 0.5 + 0.5 * np.tanh(4.0 * np.sin(2 * np.pi * p[:, 1] / period))
        elif app.pattern == "checks":
            sx = np.tanh(4.0 * np.sin(2 * np.pi * (p[:, 0] + 0.7 * p[:, 2]) / period))
            sy = np.tanh(4.0 * np.sin(2 * np.pi * p[:, 1] / period))
            mix = 0.25 * (2.0 + sx + sy)
        else:
            mix = 0.15 + 0.1 * noise[is_cloth]
        c1, c2 = srgb_to_linear(app.clothes), srgb_to_linear(app.clothes_secondary)
        col = c1 + (c2 - c1) * mix[:, None]
        albedo[is_cloth] = col * (1.0 + 0.1 * noise[is_cloth])[:, None]
    if is_lower.any():
        albedo[is_lower] = srgb_to_linear(app.trousers) * (1.0 + 0.1 * noise[is_lower])[:, None]
    # face and hair on the head (head frame: origin at the neck joint, up is -y, face towards -z)
    head = part == _HEAD
    if head.any():
        albedo[head] = _head_albedo(actor, local[head], albedo[head], noise[head])
    return albedo, spec


def _head_albedo(actor: Actor, p: np.ndarray, base: np.ndarray, noise: np.ndarray) -> np.ndarray:
    dims = actor.dims
    start = (1.0 - HEAD_NECK_OVERLAP) * dims["neck"].length
    length, half_w, half_d = dims["head"].length, 0.5 * dims["head"].width, 0.5 * dims["head"].depth
    v = (-p[:, 1] - (start + 0.5 * length)) / (0.5 * length)    # -1 chin ... +1 crown
    x = p[:, 0] / half_w
    z = p[:, 2] / half_d                                        # -1 face ... +1 back of the head
    hair = srgb_to_linear(actor.appearance.hair) * (1.0 + 0.12 * noise)[:, None]
    if not actor.appearance.face:                               # hair all round: no face skin, no features
        return hair
    out = base.copy()
    # hairline: high on the forehead, low at the back, with a ragged edge
    line = ACTOR_HAIRLINE - 0.8 * _smoothstep(-0.3, 0.6, z) + 0.05 * noise
    w_hair = _smoothstep(line - 0.04, line + 0.04, v)
    out = out * (1.0 - w_hair[:, None]) + hair * w_hair[:, None]
    front = _smoothstep(-0.35, -0.6, z)
    # eyes and brows
    for cx in (-0.38, 0.38):
        eye = np.exp(-(((x - cx) / 0.16) ** 2 + ((v - 0.08) / 0.07) ** 2)) * front
        out = out * (1.0 - 0.85 * eye[:, None]) + 0.02 * eye[:, None]
        brow = np.exp(-(((x - cx) / 0.22) ** 2 + ((v - 0.27) / 0.045) ** 2)) * front
        out = out * (1.0 - 0.6 * brow[:, None]) + hair * 0.6 * brow[:, None]
    mouth = np.exp(-((x / 0.28) ** 2 + ((v + 0.5) / 0.06) ** 2)) * front
    out = out * (1.0 - 0.5 * mouth[:, None]) + out * np.array([0.6, 0.25, 0.25]) * 0.5 * mouth[:, None]
    return out


def render_actor(actor: Actor, pose, camera: Camera, light: Light,
                 background: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Render the actor over a background, in linear light.

    Parameters
    ----------
    actor : Actor
    pose : array_like, shape (23,)
        Metres and radians.
    camera : Camera
        Render camera (usually a supersampled one; see :func:`downsample`).
    light : Light
    background : ndarray, shape (H, W, 3), float
        Linear radiance of the empty scene at the camera's size.

    Returns
    -------
    image : ndarray, shape (H, W, 3), float64
        Linear radiance.
    parts : ndarray, shape (H, W), int16
        Actor part index per pixel (:data:`~mocap.synth.actor.ACTOR_PART_NAMES`), -1 on
        the background.
    """
    if background.shape != (camera.height, camera.width, 3):
        raise ValueError(f"background must have shape {(camera.height, camera.width, 3)}, got {background.shape}")
    _, verts, normals = actor.posed(pose)
    mesh = actor.mesh
    ren = rasterize_mesh(verts, mesh.triangles, camera, triangle_part=mesh.triangle_part, triangle_ids=True)
    tri_ids = ren.triangle_ids
    image = np.array(background, dtype=np.float64, copy=True)
    parts = np.full(tri_ids.shape, -1, dtype=np.int16)
    rows, cols = np.nonzero(tri_ids >= 0)
    if rows.size == 0:
        return image, parts
    tri = tri_ids[rows, cols]
    k = rows.size
    normal, local, point, noise = np.empty((k, 3)), np.empty((k, 3)), np.empty((k, 3)), np.empty(k)
    _surface_samples(rows.astype(np.int64), cols.astype(np.int64), tri, mesh.triangles, verts, normals,
                     mesh.vertices, actor.vertex_noise, camera.as_array(), normal, local, point, noise)
    part = mesh.triangle_part[tri]
    albedo, spec = _albedo(actor, part, local, noise)
    key = np.asarray(light.key_direction, dtype=np.float64)
    key /= np.linalg.norm(key)
    fill = key * np.array([-1.0, 0.3, 1.0])
    fill /= np.linalg.norm(fill)
    n_key = np.clip(normal @ key, 0.0, None)
    n_fill = np.clip(normal @ fill, 0.0, None)
    sky = 0.75 + 0.25 * np.clip(-normal[:, 1], -1.0, 1.0)       # up is -y
    irradiance = light.key * n_key + light.fill * n_fill + light.ambient * sky
    view = -point / np.linalg.norm(point, axis=1, keepdims=True)
    half = key + view
    half /= np.linalg.norm(half, axis=1, keepdims=True)
    specular = spec * light.key * np.clip(np.einsum("ij,ij->i", normal, half), 0.0, None) ** 24
    image[rows, cols] = albedo * irradiance[:, None] + specular[:, None]
    parts[rows, cols] = part
    return image, parts


def downsample(image: np.ndarray, factor: int) -> np.ndarray:
    """Average ``factor`` x ``factor`` pixel blocks (a box filter), (H*f, W*f, C) -> (H, W, C)."""
    if factor == 1:
        return image
    return downscale_local_mean(image, (factor, factor, 1))
