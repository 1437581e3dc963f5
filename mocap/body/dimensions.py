"""Body dimensions: length, width and depth of every body part, in metres.

These are the calibration of the paper's section 3.1 and are saved as JSON.
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
})


@dataclass(frozen=True)
class PartSize:
    """Size of one body part, metres. All three must be finite and positive."""

    length: float
    width: float
    depth: float

    def __post_init__(self) -> None:
        for key in ("length", "width", "depth"):
            value = getattr(self, key)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ValueError(f"part {key} must be a finite positive number of metres, got {value!r}")
            object.__setattr__(self, key, float(value))


@dataclass(frozen=True)
class BodyDimensions:
    """Sizes of all body parts (metres), the output of body calibration.

    Parameters
    ----------
    parts : mapping of str to PartSize
        One entry for every name in :data:`PART_NAMES`, no others.
    """

    parts: Mapping[str, PartSize] = field(default_factory=lambda: {
        k: PartSize(*v) for k, v in DEFAULT_PART_SIZES.items()})

    def __post_init__(self) -> None:
        unknown = set(self.parts) - set(PART_NAMES)
        if unknown:
            raise ValueError(f"unknown body part(s): {', '.join(sorted(unknown))}; known: {', '.join(PART_NAMES)}")
        missing = [p for p in PART_NAMES if p not in self.parts]
        if missing:
            raise ValueError(f"missing body part(s): {', '.join(missing)}")
        parts = {}
        for name in PART_NAMES:
            size = self.parts[name]
            if not isinstance(size, PartSize):
                size = PartSize(*size)
            parts[name] = size
        object.__setattr__(self, "parts", MappingProxyType(parts))

    def __getitem__(self, part: str) -> PartSize:
        if part not in self.parts:
            raise ValueError(f"unknown body part {part!r}; known: {', '.join(PART_NAMES)}")
        return self.parts[part]

    def replace(self, part: str, *, length: float | None = None, width: float | None = None,
                depth: float | None = None) -> "BodyDimensions":
        """A copy with some sizes of one part changed (metres)."""
        old = self[part]
        new = PartSize(old.length if length is None else length,
                       old.width if width is None else width,
                       old.depth if depth is None else depth)
        return BodyDimensions({**self.parts, part: new})

    def scaled(self, factor: float, *, parts: tuple[str, ...] = PART_NAMES) -> "BodyDimensions":
        """A copy with every size of ``parts`` multiplied by ``factor``."""
        if not math.isfinite(factor) or factor <= 0:
            raise ValueError(f"scale factor must be finite and positive, got {factor}")
        return BodyDimensions({name: (PartSize(s.length * factor, s.width * factor, s.depth * factor)
                                      if name in parts else s) for name, s in self.parts.items()})

    def to_dict(self) -> dict:
        """JSON-ready dict: ``{"units": "metres", "parts": {name: {length, width, depth}}}``."""
        return {"units": "metres",
                "parts": {n: {"length": s.length, "width": s.width, "depth": s.depth}
                          for n, s in self.parts.items()}}

    @classmethod
    def from_dict(cls, data: Mapping) -> "BodyDimensions":
        """Inverse of :meth:`to_dict`; unknown keys are an error."""
        if not isinstance(data, Mapping) or "parts" not in data:
            raise ValueError("body dimensions must be an object with a 'parts' entry")
        extra = set(data) - {"units", "parts"}
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
        return cls(parts)

    def to_json(self, path: str | Path) -> None:
        """Save as JSON (written atomically)."""
        from mocap.io.jsonfile import write_json
        write_json(path, self.to_dict())

    @classmethod
    def from_json(cls, path: str | Path) -> "BodyDimensions":
        """Load from JSON written by :meth:`to_json`."""
        from mocap.io.jsonfile import read_json
        return cls.from_dict(read_json(path))
