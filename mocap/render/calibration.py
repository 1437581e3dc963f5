"""The calibration record of one actor in one camera (paper section 3.1).

:class:`Calibration` holds body dimensions, initial pose, camera and colour classes, saved as
``calibration.json`` (docs/design.md section 4) with angles in degrees for people to read. It
is data only, low in the layers so that every module can read it; fitting one to a frame is
:func:`mocap.calibrate.auto_calibrate`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

import numpy as np

from mocap.body.dimensions import BodyDimensions
from mocap.body.model import BodyModel
from mocap.body.pose import JOINT_LIMITS, PARAMETER_NAMES, check_pose, neutral_pose, pose_from_dict, pose_to_dict
from mocap.body.skeleton import DEFAULT_PART_CLASS, MESH_PART_NAMES
from mocap.io.files import read_json, write_json
from mocap.labels import DEFAULT_CLASS_NAMES
from mocap.render.camera import Camera

__all__ = ["FORMAT", "Calibration"]

_KEYS = frozenset({"format", "dimensions", "initial_pose_deg", "camera", "class_names", "part_class"})
#: Format tag of ``calibration.json``.
FORMAT = "mocap-calibration-1"


@dataclass(frozen=True)
class Calibration:
    """Everything the tracker needs to know about the actor and the camera before frame 0.

    Attributes
    ----------
    dims : BodyDimensions
    initial_pose : ndarray, shape (23,), float64
        Pose in the first frame (metres, radians).
    camera : Camera
    class_names : tuple of str
        Colour classes (default: skin, clothes, hair, lower body; a file from before the
        hair and lower-body classes has skin and clothes).
    part_class : mapping of part name to class name
        Parts left out keep their default class; a part whose class is not in
        ``class_names`` takes the class it merges into (:data:`mocap.labels.CLASS_MERGES_INTO`).
    """

    dims: BodyDimensions = field(default_factory=BodyDimensions)
    initial_pose: np.ndarray = field(default_factory=neutral_pose)
    camera: Camera = field(default_factory=Camera.default)
    class_names: tuple[str, ...] = DEFAULT_CLASS_NAMES
    part_class: Mapping[str, str] = field(default_factory=lambda: dict(DEFAULT_PART_CLASS))

    def __post_init__(self) -> None:
        q = check_pose(self.initial_pose, name="initial pose")
        q.setflags(write=False)
        object.__setattr__(self, "initial_pose", q)
        object.__setattr__(self, "class_names", tuple(self.class_names))
        object.__setattr__(self, "part_class", MappingProxyType(dict(self.part_class)))
        self.body_model()  # validates classes and parts

    def body_model(self, resolution: int | None = None) -> BodyModel:
        """The body model of this actor (mesh level of detail ``resolution``, default 12)."""
        return BodyModel.build(self.dims, resolution=12 if resolution is None else resolution,
                               part_class=self.part_class, class_names=self.class_names)

    def to_dict(self) -> dict:
        return {"format": FORMAT, "dimensions": self.dims.to_dict(),
                "initial_pose_deg": pose_to_dict(self.initial_pose, degrees=True),
                "camera": self.camera.to_dict(), "class_names": list(self.class_names),
                "part_class": {p: c for p, c in zip(MESH_PART_NAMES, self.body_model(4).part_class)}}

    @classmethod
    def from_dict(cls, data: Mapping) -> "Calibration":
        if not isinstance(data, Mapping):
            raise ValueError("calibration must be a JSON object")
        extra = set(data) - _KEYS
        if extra:
            raise ValueError(f"unknown keys in calibration: {', '.join(sorted(extra))}")
        missing = _KEYS - set(data)
        if missing:
            raise ValueError(f"calibration lacks: {', '.join(sorted(missing))}")
        if data["format"] != FORMAT:
            raise ValueError(f"calibration format {data['format']!r} is not {FORMAT!r}")
        return cls(BodyDimensions.from_dict(data["dimensions"]),
                   _pose_within_limits(data["initial_pose_deg"]),
                   Camera.from_dict(data["camera"]), tuple(data["class_names"]), dict(data["part_class"]))

    def to_json(self, path: str | Path) -> None:
        """Save (atomically) as JSON."""
        write_json(path, self.to_dict())

    @classmethod
    def from_json(cls, path: str | Path) -> "Calibration":
        """Load a file written by :meth:`to_json`; raises ValueError with the file name on bad content."""
        data = read_json(path)
        try:
            return cls.from_dict(data)
        except (ValueError, TypeError, KeyError) as exc:
            raise ValueError(f"{path}: {exc}") from None


def _pose_within_limits(values_deg) -> np.ndarray:
    """The calibration file's ``initial_pose_deg`` as a pose (metres, radians); ValueError naming
    the first parameter that is not a number or lies outside :data:`JOINT_LIMITS`."""
    if not isinstance(values_deg, Mapping):
        raise ValueError("initial_pose_deg must be an object of parameter: value")
    for name, value in values_deg.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"initial_pose_deg {name} must be a number, got {value!r}")
    pose = pose_from_dict(dict(values_deg), degrees=True)
    for i, name in enumerate(PARAMETER_NAMES):
        lo, hi = JOINT_LIMITS[i]
        if not lo - 1e-9 <= pose[i] <= hi + 1e-9:           # (slack for the degree round trip)
            unit = " m" if i < 3 else " deg"
            lo, hi = (lo, hi) if i < 3 else (math.degrees(lo), math.degrees(hi))
            raise ValueError(f"initial_pose_deg {name} = {values_deg[name]:g}{unit} is outside its joint limits "
                             f"[{lo:g}, {hi:g}]{unit}")
    return pose
