"""The kinematic tree: segments (rigid frames), named joints and where the parts sit.

One table each, as smplx does: segments with their parents, parts with their segment and
colour class, joints with the segment and local point that define them.

Coordinates: camera frame, metres, x right, y down, z forward. With every angle zero the
actor faces the camera (towards -z), so the actor's right is -x and up is -y. Every segment's
long axis is its local y axis: the chest and head point up (-y), the arm segments down (+y).
"""
from __future__ import annotations

from types import MappingProxyType

import numpy as np

from mocap.body.dimensions import PART_NAMES, SIZED_PART_NAMES, BodyDimensions

#: Rigid segments (one transform each), in an order where parents come first.
SEGMENT_NAMES: tuple[str, ...] = (
    "chest", "head",
    "r_upper_arm", "r_forearm", "r_hand",
    "l_upper_arm", "l_forearm", "l_hand",
)
#: Parent of each segment (-1 for the root).
SEGMENT_PARENTS: tuple[int, ...] = (-1, 0, 0, 2, 3, 0, 5, 6)
#: Direction of each segment's long axis in its local frame: -1 up (-y), +1 down (+y).
SEGMENT_AXIS_SIGN: tuple[int, ...] = (-1, -1, 1, 1, 1, 1, 1, 1)

#: Parts of the mesh (the index of :attr:`~mocap.body.mesh.BodyMesh.triangle_part` and, plus
#: one, of a rendering's part image): the sized parts, then ``hair``, the region of the head
#: above and behind the hairline (no size of its own). A model whose dimensions lack the
#: optional lower body or the hairline has no triangles of that part.
MESH_PART_NAMES: tuple[str, ...] = SIZED_PART_NAMES + ("hair",)
#: Segment that carries each part.
PART_SEGMENT = MappingProxyType({
    "torso": "chest", "neck": "head", "head": "head",
    "r_upper_arm": "r_upper_arm", "r_forearm": "r_forearm", "r_hand": "r_hand",
    "l_upper_arm": "l_upper_arm", "l_forearm": "l_forearm", "l_hand": "l_hand",
    "lower_body": "chest", "hair": "head",
})
#: Default colour class of each part (paper: skin for head and hands, clothes for the rest;
#: here also hair for the hair region and lower_body for the part under the torso).
DEFAULT_PART_CLASS = MappingProxyType({
    "torso": "clothes", "neck": "skin", "head": "skin",
    "r_upper_arm": "clothes", "r_forearm": "clothes", "r_hand": "skin",
    "l_upper_arm": "clothes", "l_forearm": "clothes", "l_hand": "skin",
    "lower_body": "lower_body", "hair": "hair",
})

#: Named joints (docs/design.md section 4 column order).
JOINT_NAMES: tuple[str, ...] = (
    "head", "neck",
    "r_shoulder", "r_elbow", "r_wrist", "r_hand",
    "l_shoulder", "l_elbow", "l_wrist", "l_hand",
)
#: Row of each named joint in the joint arrays (shape (10, 3), :data:`JOINT_NAMES` order).
JOINT_INDEX = MappingProxyType({name: i for i, name in enumerate(JOINT_NAMES)})

#: Shoulder joint placement relative to the torso: lateral offset = SHOULDER_OUT_TORSO * torso
#: width + SHOULDER_OUT_ARM * upper-arm width; height below the neck = SHOULDER_DROP_ARM *
#: upper-arm width.
SHOULDER_OUT_TORSO = 0.5
SHOULDER_OUT_ARM = 0.1
SHOULDER_DROP_ARM = 0.55
#: Fraction of the neck length by which the head overlaps the neck.
HEAD_NECK_OVERLAP = 0.3
#: Fraction of the lower body's length by which it reaches up into the torso from the chest
#: base (the chest segment's origin), so that no gap opens between them.
LOWER_BODY_OVERLAP = 0.25


def segment_offsets(dims: BodyDimensions) -> np.ndarray:
    """Origin of each segment in its parent's frame (the root's is zero), metres.

    Returns
    -------
    ndarray, shape (8, 3), float64
    """
    torso, ua_r, ua_l = dims["torso"], dims["r_upper_arm"], dims["l_upper_arm"]
    off = np.zeros((len(SEGMENT_NAMES), 3))
    off[1] = (0.0, -torso.length, 0.0)
    for side, ua, sign in (("r", ua_r, -1.0), ("l", ua_l, 1.0)):
        i = SEGMENT_NAMES.index(f"{side}_upper_arm")
        off[i] = (sign * (SHOULDER_OUT_TORSO * torso.width + SHOULDER_OUT_ARM * ua.width),
                  -(torso.length - SHOULDER_DROP_ARM * ua.width), 0.0)
        off[i + 1] = (0.0, ua.length, 0.0)
        off[i + 2] = (0.0, dims[f"{side}_forearm"].length, 0.0)
    return off


def part_spans(dims: BodyDimensions) -> np.ndarray:
    """Where each part of :data:`~mocap.body.dimensions.PART_NAMES` lies along its segment's
    long axis: (start, end) distances, metres (the optional lower body: :func:`lower_body_span`).

    Returns
    -------
    ndarray, shape (9, 2), float64
    """
    parts = dims.parts
    head_start = (1.0 - HEAD_NECK_OVERLAP) * parts["neck"].length
    rows = []
    for name in PART_NAMES:
        start = head_start if name == "head" else 0.0
        rows.append((start, start + parts[name].length))
    return np.array(rows)


def lower_body_span(dims: BodyDimensions) -> tuple[float, float]:
    """(start, end) of the lower body along the chest axis, metres, measured downwards from the
    chest base (start < 0: it begins inside the torso, :data:`LOWER_BODY_OVERLAP`).

    Raises
    ------
    ValueError
        If ``dims`` has no lower body.
    """
    length = dims["lower_body"].length
    start = -LOWER_BODY_OVERLAP * length
    return start, start + length


def joint_points(dims: BodyDimensions) -> tuple[np.ndarray, np.ndarray]:
    """Segment and local position (metres) defining each named joint.

    ``head`` is the centre of the head, ``neck`` the neck joint, the hand joints the centre of
    the hand; the others are the joint centres (segment origins).

    Returns
    -------
    segment : ndarray, shape (10,), int64
    local : ndarray, shape (10, 3), float64
    """
    spans = part_spans(dims)
    local = np.zeros((len(JOINT_NAMES), 3))
    s = PART_NAMES.index("head")
    local[JOINT_NAMES.index("head"), 1] = -0.5 * (spans[s, 0] + spans[s, 1])
    for hand in ("r_hand", "l_hand"):
        local[JOINT_NAMES.index(hand), 1] = 0.5 * dims[hand].length
    return _JOINT_SEGMENT.copy(), local


def _joint_segments() -> np.ndarray:
    """The segment of each joint of :data:`JOINT_NAMES` (what :func:`joint_points` gives), int64 (10,)."""
    seg = np.zeros(len(JOINT_NAMES), dtype=np.int64)
    for j, name in enumerate(JOINT_NAMES):
        if name in ("head", "neck"):
            seg[j] = SEGMENT_NAMES.index("head")
        elif name.endswith("_hand"):
            seg[j] = SEGMENT_NAMES.index(name)
        else:
            side, joint = name.split("_")
            seg[j] = SEGMENT_NAMES.index({"shoulder": f"{side}_upper_arm", "elbow": f"{side}_forearm",
                                          "wrist": f"{side}_hand"}[joint])
    return seg


#: :func:`_joint_segments`, read-only.
_JOINT_SEGMENT = _joint_segments()
_JOINT_SEGMENT.setflags(write=False)
