"""The synthetic actor: true body proportions, a finer mesh of its own, clothes and skin.

Nothing here is the tracker's model (no inverse crime):

* proportions are drawn per sequence around the adult defaults (overall size and every
  part's length, width and depth), so the tracker must be calibrated;
* the mesh has its own part shapes (:data:`ACTOR_SHAPES`, not the tracker's
  :data:`~mocap.body.mesh.PART_SHAPES`), a finer tessellation, cloth folds (a smooth radial
  displacement of the clothed parts) and a lower body (hips and thighs in trousers, below the
  chest base, which the tracker's model lacks);
* colours and textures vary per sequence: skin tone, clothes colour and pattern (plain,
  stripes, checks, with fabric noise), trousers, hair; a face (eyes, brows, mouth).

The actor's calibration (what a perfect calibration would find) is its
:class:`~mocap.body.dimensions.BodyDimensions` and part classes: the tracker's model built
from them overlaps the actor closely but not exactly.
"""
from __future__ import annotations

import colorsys
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from mocap.body.dimensions import PART_NAMES, BodyDimensions, PartSize
from mocap.body.kinematics import Skeleton, segment_transforms
from mocap.body.mesh import part_mesh
from mocap.body.skeleton import DEFAULT_PART_CLASS, PART_SEGMENT, SEGMENT_AXIS_SIGN, SEGMENT_NAMES, part_spans

__all__ = ["ACTOR_PART_NAMES", "ACTOR_SHAPES", "Actor", "ActorMesh", "Appearance", "build_actor_mesh",
           "random_appearance", "random_dimensions", "srgb_to_linear"]

#: The actor's parts: the model's nine, then the lower body (index 9).
ACTOR_PART_NAMES: tuple[str, ...] = PART_NAMES + ("lower_body",)
LOWER_BODY = len(PART_NAMES)
#: Actor part shapes (e_long, e_cross, taper), deliberately unlike the tracker's.
ACTOR_SHAPES = MappingProxyType({
    "torso": (0.5, 0.55, -0.2),
    "neck": (0.45, 1.0, 0.08),
    "head": (0.85, 0.9, 0.16),
    "r_upper_arm": (0.6, 0.85, 0.18),
    "r_forearm": (0.55, 0.9, 0.32),
    "r_hand": (0.75, 0.5, 0.15),
    "l_upper_arm": (0.6, 0.85, 0.18),
    "l_forearm": (0.55, 0.9, 0.32),
    "l_hand": (0.75, 0.5, 0.15),
    "lower_body": (0.4, 0.6, 0.1),
})
#: The actor's lower body (hips and thighs): length (metres), and width and depth as fractions of
#: the torso's; it starts LOWER_BODY_START_M above the chest base.
LOWER_BODY_SIZE = (0.8, 0.92, 1.05)
LOWER_BODY_START_M = 0.08
#: Length of the lower body a calibration describes (the model's lower-body part), metres: the
#: piece under the torso that the benchmark's framing shows.
LOWER_BODY_VISIBLE_M = 0.45
#: Forehead hairline of the actor's hair (see :mod:`mocap.synth.shading`), as
#: :attr:`~mocap.body.dimensions.BodyDimensions.hairline`.
ACTOR_HAIRLINE = 0.45
#: Cloth-fold amplitude (fraction of the part's half width) of clothed parts.
FOLD_AMPLITUDE = 0.035


def srgb_to_linear(c) -> np.ndarray:
    """sRGB values in [0, 1] to linear light (the sRGB transfer curve)."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


@dataclass(frozen=True)
class ActorMesh:
    """The actor's rigidly skinned mesh in segment-local coordinates.

    Attributes
    ----------
    vertices : ndarray, shape (V, 3), float64, metres
    normals : ndarray, shape (V, 3), float64
        Unit vertex normals (area-weighted face normals of the part).
    vertex_segment : ndarray, shape (V,), int64
        Segment of each vertex (:data:`~mocap.body.skeleton.SEGMENT_NAMES`).
    triangles : ndarray, shape (T, 3), int64
        Outward winding.
    triangle_part : ndarray, shape (T,), int64
        Part index (:data:`ACTOR_PART_NAMES`).
    """

    vertices: np.ndarray
    normals: np.ndarray
    vertex_segment: np.ndarray
    triangles: np.ndarray
    triangle_part: np.ndarray

    def posed(self, transforms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vertices and normals in camera coordinates for segment transforms (8, 3, 4)."""
        rot = transforms[self.vertex_segment, :, :3]
        v = np.einsum("vij,vj->vi", rot, self.vertices) + transforms[self.vertex_segment, :, 3]
        n = np.einsum("vij,vj->vi", rot, self.normals)
        return v, n


def _vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    face = np.cross(b - a, c - a)                       # area-weighted, outward
    out = np.zeros_like(vertices)
    for i in range(3):
        np.add.at(out, triangles[:, i], face)
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    return out / np.maximum(norm, 1e-12)


def build_actor_mesh(dims: BodyDimensions, *, resolution: int = 32, folds: np.ndarray | None = None,
                     clothed: tuple[str, ...] = ("torso", "r_upper_arm", "l_upper_arm", "r_forearm",
                                                 "l_forearm", "lower_body")) -> ActorMesh:
    """Tessellate the actor.

    Parameters
    ----------
    dims : BodyDimensions
        The actor's true proportions.
    resolution : int
        Longitudes per part (the tracker uses 8 to 24).
    folds : ndarray, shape (K, 4), optional
        Cloth folds: rows of (along-axis frequency, around-axis frequency, phase, phase);
        none when omitted.
    clothed : tuple of str
        Parts that get folds.

    Returns
    -------
    ActorMesh
    """
    spans = part_spans(dims)
    torso = dims["torso"]
    verts, norms, vseg, tris, tpart = [], [], [], [], []
    offset = 0
    for p, name in enumerate(ACTOR_PART_NAMES):
        e_long, e_cross, taper = ACTOR_SHAPES[name]
        if name == "lower_body":
            size = PartSize(LOWER_BODY_SIZE[0], LOWER_BODY_SIZE[1] * torso.width, LOWER_BODY_SIZE[2] * torso.depth)
            seg, start = SEGMENT_NAMES.index("chest"), -LOWER_BODY_START_M
            sign = 1                                        # downwards from the chest base
        else:
            size = dims[name]
            seg, start = SEGMENT_NAMES.index(PART_SEGMENT[name]), spans[p, 0]
            sign = SEGMENT_AXIS_SIGN[seg]
        v, t = part_mesh(size.length, size.width, size.depth, e_long=e_long, e_cross=e_cross, taper=taper,
                         resolution=resolution, start=start, axis_sign=sign)
        if folds is not None and name in clothed:
            u = (np.abs(v[:, 1]) - start) / size.length
            ang = np.arctan2(v[:, 2] / size.depth, v[:, 0] / size.width)
            bump = np.zeros(len(v))
            for fu, fa, ph1, ph2 in folds:
                bump += np.sin(2 * np.pi * fu * u + ph1) * np.sin(fa * ang + ph2)
            bump *= FOLD_AMPLITUDE / max(1.0, np.sqrt(len(folds)))
            radial = v[:, [0, 2]]
            v = v.copy()
            v[:, [0, 2]] = radial * (1.0 + bump[:, None])
        verts.append(v)
        norms.append(_vertex_normals(v, t))
        vseg.append(np.full(len(v), seg, dtype=np.int64))
        tris.append(t + offset)
        tpart.append(np.full(len(t), p, dtype=np.int64))
        offset += len(v)
    arrays = [np.concatenate(verts), np.concatenate(norms), np.concatenate(vseg), np.concatenate(tris),
              np.concatenate(tpart)]
    for a in arrays:
        a.setflags(write=False)
    return ActorMesh(*arrays)


def random_dimensions(rng: np.random.Generator, *, base: BodyDimensions | None = None) -> BodyDimensions:
    """Adult proportions drawn around ``base``: overall size +-8 %, each part +-7 % in length and
    +-12 % in width and depth, the two sides alike; the lower body as the actor's (its width and
    depth, :data:`LOWER_BODY_VISIBLE_M` of its length) and the actor's forehead hairline.

    Returns
    -------
    BodyDimensions
    """
    base = BodyDimensions() if base is None else base
    overall = rng.uniform(0.92, 1.08)
    factors: dict[str, tuple[float, float, float]] = {}
    for name in PART_NAMES:
        key = name[2:] if name[:2] in ("r_", "l_") else name
        if key not in factors:
            factors[key] = (rng.uniform(0.93, 1.07), rng.uniform(0.88, 1.12), rng.uniform(0.88, 1.12))
    parts = {}
    for name in PART_NAMES:
        key = name[2:] if name[:2] in ("r_", "l_") else name
        fl, fw, fd = factors[key]
        s = base[name]
        parts[name] = PartSize(round(s.length * overall * fl, 4), round(s.width * overall * fw, 4),
                               round(s.depth * overall * fd, 4))
    torso = parts["torso"]
    parts["lower_body"] = PartSize(round(LOWER_BODY_VISIBLE_M * overall, 4),
                                   round(LOWER_BODY_SIZE[1] * torso.width, 4), round(LOWER_BODY_SIZE[2] * torso.depth, 4))
    return BodyDimensions(parts, hairline=ACTOR_HAIRLINE)


#: Skin tones (sRGB 0-255), light to dark.
SKIN_TONES: tuple[tuple[int, int, int], ...] = (
    (243, 211, 188), (236, 192, 160), (224, 172, 138), (205, 150, 115), (190, 132, 95),
    (165, 110, 78), (141, 92, 62), (110, 72, 50))
#: Hair colours (sRGB 0-255).
HAIR_COLOURS: tuple[tuple[int, int, int], ...] = (
    (30, 24, 20), (58, 40, 28), (95, 66, 40), (150, 112, 70), (70, 62, 58), (20, 18, 18))
#: Clothes patterns.
PATTERNS: tuple[str, ...] = ("plain", "stripes", "checks")


@dataclass(frozen=True)
class Appearance:
    """Colours (sRGB in [0, 1]) and clothing of the actor.

    Attributes
    ----------
    skin, clothes, clothes_secondary, trousers, hair : tuple of 3 float
        sRGB colours.
    pattern : str
        One of :data:`PATTERNS`.
    pattern_period_m : float
        Stripe or check period on the body, metres.
    bare_forearms : bool
        Short sleeves: forearms are skin (and belong to the skin class).
    face : bool
        A face on the head (skin below a hairline, eyes, brows, a mouth); False draws hair all
        round the head (no face features and no face skin: a figure whose face is never seen,
        issue 49).
    """

    skin: tuple[float, float, float]
    clothes: tuple[float, float, float]
    clothes_secondary: tuple[float, float, float]
    trousers: tuple[float, float, float]
    hair: tuple[float, float, float]
    pattern: str = "plain"
    pattern_period_m: float = 0.06
    bare_forearms: bool = False
    face: bool = True

    def __post_init__(self) -> None:
        if self.pattern not in PATTERNS:
            raise ValueError(f"unknown clothes pattern {self.pattern!r}; known: {', '.join(PATTERNS)}")

    def part_class(self) -> dict[str, str]:
        """Colour class of every model part (forearms are skin with bare forearms)."""
        out = dict(DEFAULT_PART_CLASS)
        if self.bare_forearms:
            out["r_forearm"] = out["l_forearm"] = "skin"
        return out

    def to_dict(self) -> dict:
        """JSON-ready description, colours as sRGB 0-255 (for ``meta.json``)."""
        def rgb(c):
            return [int(round(255 * v)) for v in c]
        out = {"skin_srgb": rgb(self.skin), "clothes_srgb": rgb(self.clothes),
               "clothes_secondary_srgb": rgb(self.clothes_secondary), "trousers_srgb": rgb(self.trousers),
               "hair_srgb": rgb(self.hair), "pattern": self.pattern,
               "pattern_period_m": self.pattern_period_m, "bare_forearms": self.bare_forearms}
        if not self.face:                   # only then: the meta.json of a figure with a face is unchanged
            out["face"] = False
        return out


def _hsv(h: float, s: float, v: float) -> tuple[float, float, float]:
    return tuple(float(c) for c in colorsys.hsv_to_rgb(h % 1.0, s, v))


def random_appearance(rng: np.random.Generator, *, bare_forearms: bool = False,
                      pattern: str | None = None) -> Appearance:
    """Skin, clothes, trousers and hair drawn for one sequence (``pattern``: drawn when None).

    Clothes hues keep away from skin hues (orange, 0-50 degrees) so that skin and clothes are
    two colour classes, as in the paper's sequences; saturation and value vary widely.
    """
    skin = tuple(float(c) / 255.0 for c in SKIN_TONES[rng.integers(len(SKIN_TONES))])
    skin = tuple(float(np.clip(c * rng.uniform(0.96, 1.04), 0, 1)) for c in skin)
    hue = rng.uniform(70.0, 340.0) / 360.0                  # green, cyan, blue, violet, magenta
    sat, val = rng.uniform(0.45, 0.85), rng.uniform(0.35, 0.8)
    clothes = _hsv(hue, sat, val)
    drawn = PATTERNS[rng.integers(len(PATTERNS))]
    pattern = drawn if pattern is None else pattern
    secondary = _hsv(hue + rng.uniform(-0.06, 0.06), sat * rng.uniform(0.3, 0.7),
                     float(np.clip(val * rng.uniform(1.25, 1.6), 0, 0.95)))
    trousers = _hsv(rng.uniform(0.55, 0.65), rng.uniform(0.1, 0.5), rng.uniform(0.12, 0.35))
    hair = tuple(float(c) / 255.0 for c in HAIR_COLOURS[rng.integers(len(HAIR_COLOURS))])
    return Appearance(skin, clothes, secondary, trousers, hair, pattern,
                      float(rng.uniform(0.04, 0.09)), bare_forearms)


@dataclass(frozen=True)
class Actor:
    """One synthetic actor.

    Attributes
    ----------
    dims : BodyDimensions
        True proportions (what ``calibration.json`` holds).
    appearance : Appearance
    mesh : ActorMesh
    texture_waves : ndarray, shape (K, 4)
        Random plane waves (angular wave vector in radians per metre, phase) whose sum is the
        fabric and skin noise.
    vertex_noise : ndarray, shape (V,)
        That noise, in about [-1, 1], at every mesh vertex (interpolated over the triangles).
    """

    dims: BodyDimensions
    appearance: Appearance
    mesh: ActorMesh
    texture_waves: np.ndarray
    skeleton: Skeleton = field(init=False, repr=False)
    vertex_noise: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "skeleton", Skeleton.from_dimensions(self.dims))
        w = self.texture_waves
        noise = np.sin(self.mesh.vertices @ w[:, :3].T + w[:, 3]).sum(axis=1) / np.sqrt(0.5 * len(w)) / 2.0
        noise.setflags(write=False)
        object.__setattr__(self, "vertex_noise", noise)

    @classmethod
    def random(cls, rng: np.random.Generator, *, bare_forearms: bool = False, pattern: str | None = None,
               resolution: int = 32) -> "Actor":
        """Draw proportions, appearance, cloth folds and fabric noise from ``rng``."""
        dims = random_dimensions(rng)
        appearance = random_appearance(rng, bare_forearms=bare_forearms, pattern=pattern)
        n_folds = 5
        folds = np.stack([rng.uniform(1.0, 4.0, n_folds), rng.integers(2, 6, n_folds).astype(float),
                          rng.uniform(0, 2 * np.pi, n_folds), rng.uniform(0, 2 * np.pi, n_folds)], axis=1)
        clothed = ("torso", "r_upper_arm", "l_upper_arm", "lower_body") + (
            () if bare_forearms else ("r_forearm", "l_forearm"))
        mesh = build_actor_mesh(dims, resolution=resolution, folds=folds, clothed=clothed)
        k = 10
        direction = rng.normal(size=(k, 3))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        freq = rng.uniform(10.0, 40.0, size=(k, 1))           # cycles per metre: 2.5-10 cm features
        waves = np.concatenate([2 * np.pi * direction * freq, rng.uniform(0, 2 * np.pi, (k, 1))], axis=1)
        return cls(dims, appearance, mesh, waves)

    def posed(self, pose) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Segment transforms (8, 3, 4) and camera-coordinate vertices and normals (V, 3)."""
        transforms = segment_transforms(pose, self.skeleton)
        v, n = self.mesh.posed(transforms)
        return transforms, v, n
