"""Body dimensions: length, width and depth of every body part, in metres, and the hairline.

These are the calibration of the paper's section 3.1 and are saved as JSON. Two entries go
beyond the paper's model and are optional, so that a calibration without them is the paper's
model (and older calibration files load unchanged):

* ``lower_body`` (a part of :data:`OPTIONAL_PART_NAMES`): a short piece under the torso (hips,
  trousers or skirt) that explains what the camera sees below the chest base;
* ``hairline``: where the hair region of the head begins (see :class:`BodyDimensions`); the
  head above it (crown) and behind it (back of the head) is its own mesh part ``hair``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

#: Body parts (mesh pieces) in their fixed order.
PART_NAMES: tuple[str, ...] = (
    "torso", "neck", "head",
    "r_upper_arm", "r_forearm", "r_hand",
    "l_upper_arm", "l_forearm", "l_hand",
)

#: Parts a calibration may leave out (the model then has no such part).
OPTIONAL_PART_NAMES: tuple[str, ...] = ("lower_body",)
#: Sized parts that may appear in :class:`BodyDimensions`, in mesh order.
SIZED_PART_NAMES: tuple[str, ...] = PART_NAMES + OPTIONAL_PART_NAMES

#: Default adult proportions, metres: (length, width, depth) per part. Length runs along the
#: part's long axis (torso: chest base to neck; arms: joint to joint).
DEFAULT_PART_SIZES: Mapping[str, tuple[float, float, float]] = MappingProxyType({
    "torso": (0.50, 0.34, 0.22),
    "neck": (0.10, 0.11, 0.11),
    "head": (0.23, 0.16, 0.20),
    "r_upper_arm": (0.29, 0.10, 0.10),
    "r_forearm": (0.26, 0.08, 0.075),
    "r_hand": (0.18, 0.085, 0.035),
    "l_upper_arm": (0.29, 0.10, 0.10),
    "l_forearm": (0.26, 0.08, 0.075),
    "l_hand": (0.18, 0.085, 0.035),
    "lower_body": (0.30, 0.32, 0.23),
})
#: Default forehead hairline: height above the head's centre as a fraction of half the head
#: length (-1 chin, +1 crown); see :class:`BodyDimensions`.
DEFAULT_HAIRLINE: float = 0.45


@dataclass(frozen=True)
class PartSize:
    """Size of one body part, metres. All three must be finite and positive."""

    length: float
    width: float
    depth: float

    def __post_init__(self) -> None:
        length, width, depth = self.length, self.width, self.depth
        if (type(length) is float and type(width) is float and type(depth) is float   # the common case
                and 0.0 < length < math.inf and 0.0 < width < math.inf and 0.0 < depth < math.inf):
            return
        for key in ("length", "width", "depth"):
            value = getattr(self, key)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ValueError(f"part {key} must be a finite positive number of metres, got {value!r}")
            object.__setattr__(self, key, float(value))


@dataclass(frozen=True)
class BodyDimensions:
    """Sizes of all body parts (metres) and the hairline, the output of body calibration.

    Parameters
    ----------
    parts : mapping of str to PartSize
        One entry for every name in :data:`PART_NAMES`, optionally ``lower_body``
        (:data:`OPTIONAL_PART_NAMES`), no others. Default: adult proportions with a lower body.
    hairline : float or None
        Height of the forehead hairline above the head's centre, as a fraction of half the
        head's length (-1 chin ... +1 crown; default :data:`DEFAULT_HAIRLINE`). The hair region
        is the head above it, and its back half (away from the face) down to
        :data:`~mocap.body.mesh.HAIR_NAPE_DROP` half-lengths lower. None: no hair region (the
        whole head is the ``head`` part, as in the paper).
    """

    parts: Mapping[str, PartSize] = field(default_factory=lambda: {
        k: PartSize(*v) for k, v in DEFAULT_PART_SIZES.items()})
    hairline: float | None = DEFAULT_HAIRLINE

    def __post_init__(self) -> None:
        unknown = set(self.parts) - set(SIZED_PART_NAMES)
        if unknown:
            raise ValueError(f"unknown body part(s): {', '.join(sorted(unknown))}; known: {', '.join(SIZED_PART_NAMES)}")
        missing = [p for p in PART_NAMES if p not in self.parts]
        if missing:
            raise ValueError(f"missing body part(s): {', '.join(missing)}")
        parts = {}
        for name in SIZED_PART_NAMES:
            if name not in self.parts:
                continue
            size = self.parts[name]
            if not isinstance(size, PartSize):
                size = PartSize(*size)
            parts[name] = size
        object.__setattr__(self, "parts", MappingProxyType(parts))
        if self.hairline is not None:
            h = self.hairline
            if isinstance(h, bool) or not isinstance(h, (int, float)) or not -1.0 < h < 1.0:
                raise ValueError(f"hairline must be a number in (-1, 1) (fraction of half the head length "
                                 f"above its centre) or None, got {h!r}")
            object.__setattr__(self, "hairline", float(h))

    def has(self, part: str) -> bool:
        """Whether the optional ``part`` (or a required one) is in these dimensions."""
        return part in self.parts

    def without_extensions(self) -> "BodyDimensions":
        """The paper's model: these sizes without the optional parts and without a hair region."""
        return BodyDimensions({n: s for n, s in self.parts.items() if n in PART_NAMES}, hairline=None)

    def with_hairline(self, hairline: float | None) -> "BodyDimensions":
        """A copy with another hairline (None: no hair region)."""
        return BodyDimensions(self.parts, hairline)

    def __getitem__(self, part: str) -> PartSize:
        if part not in self.parts:
            raise ValueError(f"unknown body part {part!r}; known: {', '.join(self.parts)}")
        return self.parts[part]

    def replace(self, part: str, *, length: float | None = None, width: float | None = None,
                depth: float | None = None) -> "BodyDimensions":
        """A copy with some sizes of one part changed (metres)."""
        old = self[part]
        new = PartSize(old.length if length is None else length,
                       old.width if width is None else width,
                       old.depth if depth is None else depth)
        return BodyDimensions({**self.parts, part: new}, self.hairline)

    def scaled(self, factor: float, *, parts: tuple[str, ...] = SIZED_PART_NAMES) -> "BodyDimensions":
        """A copy with every size of ``parts`` multiplied by ``factor``."""
        if not math.isfinite(factor) or factor <= 0:
            raise ValueError(f"scale factor must be finite and positive, got {factor}")
        return BodyDimensions({name: (PartSize(s.length * factor, s.width * factor, s.depth * factor)
                                      if name in parts else s) for name, s in self.parts.items()},
                              self.hairline)

    def to_dict(self) -> dict:
        """JSON-ready dict: ``{"units": "metres", "parts": {name: {length, width, depth}}}``,
        plus ``"hairline"`` (fraction of half the head length) when there is a hair region."""
        out = {"units": "metres",
               "parts": {n: {"length": s.length, "width": s.width, "depth": s.depth}
                         for n, s in self.parts.items()}}
        if self.hairline is not None:
            out["hairline"] = self.hairline
        return out

    @classmethod
    def from_dict(cls, data: Mapping) -> "BodyDimensions":
        """Inverse of :meth:`to_dict`; unknown keys are an error. Without ``"hairline"`` (and
        ``lower_body``) it is the paper's model: no hair region (no lower body)."""
        if not isinstance(data, Mapping) or "parts" not in data:
            raise ValueError("body dimensions must be an object with a 'parts' entry")
        extra = set(data) - {"units", "parts", "hairline"}
        if extra:
            raise ValueError(f"unknown keys in body dimensions: {', '.join(sorted(extra))}")
        if data.get("units", "metres") != "metres":
            raise ValueError(f"body dimensions must be in metres, got {data['units']!r}")
        parts = {}
        for name, size in data["parts"].items():
            if not isinstance(size, Mapping) or set(size) != {"length", "width", "depth"}:
                raise ValueError(f"part {name!r} needs exactly length, width and depth")
            for key, value in size.items():
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    raise ValueError(f"part {name!r} {key} must be a number of metres, got {value!r}")
            parts[name] = PartSize(size["length"], size["width"], size["depth"])
        return cls(parts, data.get("hairline"))

    def to_json(self, path: str | Path) -> None:
        """Save as JSON (written atomically)."""
        from mocap.io.files import write_json
        write_json(path, self.to_dict())

    @classmethod
    def from_json(cls, path: str | Path) -> "BodyDimensions":
        """Load from JSON written by :meth:`to_json`."""
        from mocap.io.files import read_json
        return cls.from_dict(read_json(path))
