"""The body model: dimensions, kinematic constants, mesh and colour classes in one frozen object."""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Mapping

import numpy as np

from mocap.body.dimensions import BodyDimensions
from mocap.body.kinematics import Skeleton, joint_positions, segment_transforms
from mocap.body.mesh import BodyMesh, build_mesh
from mocap.body.skeleton import DEFAULT_PART_CLASS, MESH_PART_NAMES
from mocap.labels import DEFAULT_CLASS_NAMES, MAX_CLASSES, merged_class


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
    part_label : ndarray, shape (11,), uint8
        Label (1..m) of each part in :data:`~mocap.body.skeleton.MESH_PART_NAMES` order (also
        of parts the mesh lacks: the label of the class they would merge into).
    part_class : tuple of str
        Colour class of each part, same order (as given, before merging).
    """

    dims: BodyDimensions
    skeleton: Skeleton
    mesh: BodyMesh
    class_names: tuple[str, ...]
    part_label: np.ndarray
    part_class: tuple[str, ...] = tuple(DEFAULT_PART_CLASS[p] for p in MESH_PART_NAMES)

    @classmethod
    def build(cls, dims: BodyDimensions | None = None, *, resolution: int = 12,
              part_class: Mapping[str, str] = DEFAULT_PART_CLASS,
              class_names: tuple[str, ...] | None = None) -> "BodyModel":
        """Build the model.

        Parameters
        ----------
        dims : BodyDimensions, optional
            Default adult proportions (with the lower body and the hair region) when omitted.
        resolution : int
            Mesh level of detail (see :func:`~mocap.body.mesh.build_mesh`).
        part_class : mapping of part name to class name
            Colour class of the parts (:data:`~mocap.body.skeleton.MESH_PART_NAMES`, e.g.
            forearms as skin for bare arms); a part left out keeps its default class
            (:data:`~mocap.body.skeleton.DEFAULT_PART_CLASS`).
        class_names : tuple of str, optional
            The m colour classes, 1 <= m <= 254. A part whose class is not among them takes
            the class it merges into (:data:`mocap.labels.CLASS_MERGES_INTO`: no hair class,
            the hair region is skin; no lower-body class, the lower body is clothes). Default:
            the classes of :data:`~mocap.labels.DEFAULT_CLASS_NAMES` that the mesh's parts use
            (other classes must be listed).
        """
        dims = BodyDimensions() if dims is None else dims
        unknown = set(part_class) - set(MESH_PART_NAMES)
        if unknown:
            raise ValueError(f"unknown body part(s) in part_class: {', '.join(sorted(unknown))}")
        classes = tuple({**DEFAULT_PART_CLASS, **part_class}[p] for p in MESH_PART_NAMES)
        mesh = build_mesh(dims, resolution)
        if class_names is None:
            used = {classes[p] for p in np.unique(mesh.triangle_part)}
            class_names = tuple(c for c in DEFAULT_CLASS_NAMES if c in used) or DEFAULT_CLASS_NAMES[:1]
        return cls._with_classes(dims, Skeleton.from_dimensions(dims), mesh, tuple(class_names), classes)

    @classmethod
    def _with_classes(cls, dims, skeleton, mesh, class_names: tuple[str, ...],
                      part_class: tuple[str, ...]) -> "BodyModel":
        labels, unresolved = _part_labels(class_names, part_class)
        if unresolved:
            present = set(np.unique(mesh.triangle_part).tolist())
            for p in unresolved:
                if p in present:
                    raise ValueError(f"part {MESH_PART_NAMES[p]!r} has class {part_class[p]!r}, not one of "
                                     f"{class_names}")
        return cls(dims, skeleton, mesh, class_names, labels, part_class)

    def with_class_names(self, class_names: tuple[str, ...]) -> "BodyModel":
        """The same model with other colour classes (e.g. those a colour model kept): parts of a
        class that is gone take the class it merges into (:data:`mocap.labels.CLASS_MERGES_INTO`).

        Raises
        ------
        ValueError
            If a part's class is gone and merges into none of ``class_names``.
        """
        return self._with_classes(self.dims, self.skeleton, self.mesh, tuple(class_names), self.part_class)

    @property
    def n_classes(self) -> int:
        return len(self.class_names)

    def with_resolution(self, resolution: int) -> "BodyModel":
        """The same model with another mesh level of detail."""
        return BodyModel(self.dims, self.skeleton, build_mesh(self.dims, resolution),
                         self.class_names, self.part_label, self.part_class)

    def with_dimensions(self, dims: BodyDimensions) -> "BodyModel":
        """The same model (resolution, classes) with other body dimensions."""
        return self._with_classes(dims, Skeleton.from_dimensions(dims), build_mesh(dims, self.mesh.resolution),
                                  self.class_names, self.part_class)

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


@lru_cache(maxsize=64)
def _part_labels(class_names: tuple[str, ...], part_class: tuple[str, ...]) -> tuple[np.ndarray, tuple[int, ...]]:
    """Each part's label (class index + 1 in ``class_names``, after merging; read-only uint8
    (11,), :data:`~mocap.body.skeleton.MESH_PART_NAMES` order) and the parts whose class
    merges into none of ``class_names`` (label 1: an error if the mesh has such a part).
    Depends on the classes alone, so a model rebuilt with other proportions reuses it.

    Raises
    ------
    ValueError
        Not 1 to :data:`~mocap.labels.MAX_CLASSES` distinct class names.
    """
    if not 1 <= len(class_names) <= MAX_CLASSES or len(set(class_names)) != len(class_names):
        raise ValueError(f"need 1 to {MAX_CLASSES} distinct colour class names, got {class_names}")
    labels, unresolved = [], []
    for p, name in enumerate(part_class):
        try:
            labels.append(class_names.index(merged_class(name, class_names)) + 1)
        except ValueError:
            unresolved.append(p)
            labels.append(1)                        # no triangles: never drawn
    part_label = np.array(labels, dtype=np.uint8)
    part_label.setflags(write=False)
    return part_label, tuple(unresolved)
