"""The body model: dimensions, kinematic constants, mesh and colour classes in one frozen object."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from mocap.body.dimensions import PART_NAMES, BodyDimensions
from mocap.body.kinematics import Skeleton, joint_positions, segment_transforms
from mocap.body.mesh import BodyMesh, build_mesh
from mocap.body.skeleton import DEFAULT_PART_CLASS
from mocap.labels import DEFAULT_CLASS_NAMES, MAX_CLASSES


@dataclass(frozen=True)
class BodyModel:
    """Everything about the actor that does not change from frame to frame.

    Attributes
    ----------
    dims : BodyDimensions
    skeleton : Skeleton
    mesh : BodyMesh
    class_names : tuple of str
        Colour classes; label of class ``c`` is ``c + 1``.
    part_label : ndarray, shape (9,), uint8
        Label (1..m) of each part in :data:`~mocap.body.dimensions.PART_NAMES` order.
    """

    dims: BodyDimensions
    skeleton: Skeleton
    mesh: BodyMesh
    class_names: tuple[str, ...]
    part_label: np.ndarray

    @classmethod
    def build(cls, dims: BodyDimensions | None = None, *, resolution: int = 12,
              part_class: Mapping[str, str] = DEFAULT_PART_CLASS,
              class_names: tuple[str, ...] = DEFAULT_CLASS_NAMES) -> "BodyModel":
        """Build the model.

        Parameters
        ----------
        dims : BodyDimensions, optional
            Default adult proportions when omitted.
        resolution : int
            Mesh level of detail (see :func:`~mocap.body.mesh.build_mesh`).
        part_class : mapping of part name to class name
            Colour class of every part (e.g. forearms as skin for bare arms).
        class_names : tuple of str
            The m colour classes, 1 <= m <= 254.
        """
        dims = BodyDimensions() if dims is None else dims
        class_names = tuple(class_names)
        if not 1 <= len(class_names) <= MAX_CLASSES or len(set(class_names)) != len(class_names):
            raise ValueError(f"need 1 to {MAX_CLASSES} distinct colour class names, got {class_names}")
        unknown = set(part_class) - set(PART_NAMES)
        if unknown:
            raise ValueError(f"unknown body part(s) in part_class: {', '.join(sorted(unknown))}")
        missing = [p for p in PART_NAMES if p not in part_class]
        if missing:
            raise ValueError(f"part_class lacks part(s): {', '.join(missing)}")
        labels = []
        for part in PART_NAMES:
            if part_class[part] not in class_names:
                raise ValueError(f"part {part!r} has class {part_class[part]!r}, not one of {class_names}")
            labels.append(class_names.index(part_class[part]) + 1)
        part_label = np.array(labels, dtype=np.uint8)
        part_label.setflags(write=False)
        return cls(dims, Skeleton.from_dimensions(dims), build_mesh(dims, resolution), class_names, part_label)

    @property
    def n_classes(self) -> int:
        return len(self.class_names)

    def with_resolution(self, resolution: int) -> "BodyModel":
        """The same model with another mesh level of detail."""
        return BodyModel(self.dims, self.skeleton, build_mesh(self.dims, resolution),
                         self.class_names, self.part_label)

    def with_dimensions(self, dims: BodyDimensions) -> "BodyModel":
        """The same model (resolution, classes) with other body dimensions."""
        return BodyModel(dims, Skeleton.from_dimensions(dims), build_mesh(dims, self.mesh.resolution),
                         self.class_names, self.part_label)

    def joint_positions(self, pose) -> np.ndarray:
        """Joint positions (10, 3), metres; see :func:`~mocap.body.kinematics.joint_positions`."""
        return joint_positions(pose, self.skeleton)

    def segment_transforms(self, pose) -> np.ndarray:
        """Segment transforms (8, 3, 4); see :func:`~mocap.body.kinematics.segment_transforms`."""
        return segment_transforms(pose, self.skeleton)

    def posed_vertices(self, pose) -> np.ndarray:
        """Mesh vertices in camera coordinates for ``pose``, shape (V, 3), float64, metres."""
        from mocap.body.kinematics import apply_transforms_into
        out = np.empty_like(self.mesh.vertices)
        apply_transforms_into(self.segment_transforms(pose), self.mesh.vertex_segment, self.mesh.vertices, out)
        return out
