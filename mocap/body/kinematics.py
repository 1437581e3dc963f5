"""Forward kinematics: pose vector → segment transforms → joint positions.

Stateless: every function takes the pose and the model data and returns new arrays.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mocap._numba import jit
from mocap.body.dimensions import BodyDimensions
from mocap.body.pose import N_PARAMETERS, PARAMETER_NAMES, POSITION_NAMES, check_pose
from mocap.body.skeleton import JOINT_NAMES, SEGMENT_NAMES, SEGMENT_PARENTS, joint_points, segment_offsets


@jit
def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return (1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)


@jit
def _rot_y(a):
    c, s = np.cos(a), np.sin(a)
    return (c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)


@jit
def _rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return (c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)


@jit
def _mul(a, b):
    """Product of two row-major 3x3 matrices held as 9-tuples (kept in registers)."""
    return (a[0] * b[0] + a[1] * b[3] + a[2] * b[6], a[0] * b[1] + a[1] * b[4] + a[2] * b[7],
            a[0] * b[2] + a[1] * b[5] + a[2] * b[8],
            a[3] * b[0] + a[4] * b[3] + a[5] * b[6], a[3] * b[1] + a[4] * b[4] + a[5] * b[7],
            a[3] * b[2] + a[4] * b[5] + a[5] * b[8],
            a[6] * b[0] + a[7] * b[3] + a[8] * b[6], a[6] * b[1] + a[7] * b[4] + a[8] * b[7],
            a[6] * b[2] + a[7] * b[5] + a[8] * b[8])


@jit
def _store(out, k, r, parent, offset):
    """out[k] = [r | parent_R @ offset + parent_t] where parent is segment index or -1."""
    for i in range(3):
        for j in range(3):
            out[k, i, j] = r[3 * i + j]
    for i in range(3):
        if parent < 0:
            out[k, i, 3] = offset[i]
        else:
            out[k, i, 3] = (out[parent, i, 0] * offset[0] + out[parent, i, 1] * offset[1]
                            + out[parent, i, 2] * offset[2] + out[parent, i, 3])


#: The arms' sides in the order of :func:`arm_transforms_into`'s ``side`` index (and of the
#: segment table: right first).
ARM_SIDES: tuple[str, ...] = ("r", "l")


@jit
def _arm_into(pose, offsets, r_chest, side, out):
    """Fill ``out``'s three segments of arm ``side`` (0: right, 1: left) below the chest's
    rotation ``r_chest`` (a 9-tuple; ``out[0]`` holds the chest's transform)."""
    base = 9 + 7 * side          # first arm parameter of this side
    seg = 2 + 3 * side           # upper-arm segment index
    mirror = 1.0 if side == 0 else -1.0
    r_ua = _mul(_mul(_mul(r_chest, _rot_x(-pose[base])), _rot_z(mirror * pose[base + 1])),
                _rot_y(mirror * pose[base + 2]))
    _store(out, seg, r_ua, 0, offsets[seg])
    r_fa = _mul(_mul(r_ua, _rot_x(-pose[base + 3])), _rot_y(mirror * pose[base + 4]))
    _store(out, seg + 1, r_fa, seg, offsets[seg + 1])
    r_h = _mul(_mul(r_fa, _rot_x(-pose[base + 5])), _rot_z(mirror * pose[base + 6]))
    _store(out, seg + 2, r_h, seg + 1, offsets[seg + 2])


@jit
def _chest_into(pose, out):
    """Fill ``out[0]`` with the chest's [R | t]; return its rotation as a 9-tuple."""
    r_chest = _mul(_mul(_rot_y(pose[3]), _rot_x(pose[4])), _rot_z(pose[5]))
    _store(out, 0, r_chest, -1, pose[0:3])
    return r_chest


@jit
def segment_transforms_into(pose, offsets, out):
    """Fill ``out`` (8, 3, 4) with [R | t] of every segment in camera coordinates.

    The angle layout is docs/design.md section 2; see :mod:`mocap.body.pose` for the signs.
    """
    r_chest = _chest_into(pose, out)
    r_head = _mul(_mul(_mul(r_chest, _rot_x(pose[6])), _rot_z(pose[7])), _rot_y(pose[8]))
    _store(out, 1, r_head, 0, offsets[1])
    for side in range(2):
        _arm_into(pose, offsets, r_chest, side, out)


@jit
def arm_transforms_into(pose, offsets, side, out):
    """Fill the chest's and arm ``side``'s (0: right, 1: left) [R | t] in ``out`` (8, 3, 4),
    exactly as :func:`segment_transforms_into` does; the other segments are left as they were."""
    _arm_into(pose, offsets, _chest_into(pose, out), side, out)


@jit
def apply_transforms_into(transforms, segment, local, out):
    """out[i] = R[segment[i]] @ local[i] + t[segment[i]] for every point."""
    for i in range(local.shape[0]):
        s = segment[i]
        for r in range(3):
            out[i, r] = (transforms[s, r, 0] * local[i, 0] + transforms[s, r, 1] * local[i, 1]
                         + transforms[s, r, 2] * local[i, 2] + transforms[s, r, 3])


def _parameter_segment(name: str) -> int:
    """Segment whose joint a parameter turns (-1 for the root position)."""
    if name in POSITION_NAMES:
        return -1
    if name.startswith("chest_"):
        return SEGMENT_NAMES.index("chest")
    if name.startswith("head_"):
        return SEGMENT_NAMES.index("head")
    side, joint = name.split("_", 1)
    segment = {"shoulder": "upper_arm", "elbow": "forearm", "forearm": "forearm", "wrist": "hand"}[joint.split("_")[0]]
    return SEGMENT_NAMES.index(f"{side}_{segment}")


#: Segment whose joint each pose parameter turns (-1 for the three root positions), in
#: :data:`~mocap.body.pose.PARAMETER_NAMES` order.
PARAMETER_SEGMENT: tuple[int, ...] = tuple(_parameter_segment(n) for n in PARAMETER_NAMES)


def _moves_table() -> np.ndarray:
    out = np.zeros((N_PARAMETERS, len(SEGMENT_NAMES)), np.bool_)
    for k, joint_segment in enumerate(PARAMETER_SEGMENT):
        for s in range(len(SEGMENT_NAMES)):
            a = s
            while a >= 0 and a != joint_segment:
                a = SEGMENT_PARENTS[a]
            out[k, s] = joint_segment < 0 or a == joint_segment
    out.setflags(write=False)
    return out


#: ``PARAMETER_MOVES[k, s]``: whether parameter k moves segment s (its joint's segment or a
#: descendant; the root positions move every segment). bool, shape (23, 8). Read-only.
PARAMETER_MOVES: np.ndarray = _moves_table()


@jit
def _column(t, s, j):
    return t[s, 0, j], t[s, 1, j], t[s, 2, j]


@jit
def _rotate(t, s, x, y, z):
    """R[s] @ (x, y, z)."""
    return (t[s, 0, 0] * x + t[s, 0, 1] * y + t[s, 0, 2] * z, t[s, 1, 0] * x + t[s, 1, 1] * y + t[s, 1, 2] * z,
            t[s, 2, 0] * x + t[s, 2, 1] * y + t[s, 2, 2] * z)


@jit
def _set_axis(axes, pivots, k, axis, t, s, sign):
    axes[k, 0], axes[k, 1], axes[k, 2] = sign * axis[0], sign * axis[1], sign * axis[2]
    pivots[k, 0], pivots[k, 1], pivots[k, 2] = t[s, 0, 3], t[s, 1, 3], t[s, 2, 3]


@jit
def parameter_axes_into(pose, transforms, axes, pivots):
    """Instantaneous motion of every pose parameter, in camera coordinates.

    ``transforms`` (8, 3, 4) must be :func:`segment_transforms_into` of ``pose``. For the root
    positions (k < 3) ``axes[k]`` is the unit vector of that coordinate (a translation); for an
    angle, ``axes[k]`` is its rotation axis (unit, camera coordinates) and ``pivots[k]`` the
    joint it turns about, metres, so that a point X of a segment the angle moves
    (:data:`PARAMETER_MOVES`) has ``dX/dq_k = axes[k] x (X - pivots[k])`` (per radian).

    Each rotation of the chain ``R = A Rot_e(s q) B`` turns about ``s A e``: the axis of the
    rotation, carried by every rotation applied before it.
    """
    for k in range(3):
        for i in range(3):
            axes[k, i] = 1.0 if i == k else 0.0
            pivots[k, i] = 0.0
    t = transforms
    # chest: Ry(yaw) Rx(pitch) Rz(roll) about the root
    _set_axis(axes, pivots, 3, (0.0, 1.0, 0.0), t, 0, 1.0)
    _set_axis(axes, pivots, 4, (np.cos(pose[3]), 0.0, -np.sin(pose[3])), t, 0, 1.0)
    _set_axis(axes, pivots, 5, _column(t, 0, 2), t, 0, 1.0)
    # head: R_chest Rx(flex) Rz(tilt) Ry(turn)
    _set_axis(axes, pivots, 6, _column(t, 0, 0), t, 1, 1.0)
    _set_axis(axes, pivots, 7, _rotate(t, 0, 0.0, -np.sin(pose[6]), np.cos(pose[6])), t, 1, 1.0)
    _set_axis(axes, pivots, 8, _column(t, 1, 1), t, 1, 1.0)
    for side in range(2):
        base = 9 + 7 * side
        seg = 2 + 3 * side
        mirror = 1.0 if side == 0 else -1.0
        # upper arm: R_chest Rx(-flex) Rz(m abd) Ry(m rot)
        _set_axis(axes, pivots, base, _column(t, 0, 0), t, seg, -1.0)
        _set_axis(axes, pivots, base + 1, _rotate(t, 0, 0.0, np.sin(pose[base]), np.cos(pose[base])), t, seg,
                  mirror)
        _set_axis(axes, pivots, base + 2, _column(t, seg, 1), t, seg, mirror)
        # forearm: R_ua Rx(-flex) Ry(m twist)
        _set_axis(axes, pivots, base + 3, _column(t, seg, 0), t, seg + 1, -1.0)
        _set_axis(axes, pivots, base + 4, _column(t, seg + 1, 1), t, seg + 1, mirror)
        # hand: R_fa Rx(-flex) Rz(m dev)
        _set_axis(axes, pivots, base + 5, _column(t, seg + 1, 0), t, seg + 2, -1.0)
        _set_axis(axes, pivots, base + 6, _column(t, seg + 2, 2), t, seg + 2, mirror)


@jit
def point_jacobian_into(x, y, z, segment, axes, pivots, moves, out):
    """``out`` (3, 23) = dX/dq of the camera point X = (x, y, z), metres, carried by ``segment``
    (metres per metre for the root, metres per radian for the angles), from
    :func:`parameter_axes_into`'s ``axes`` and ``pivots`` and :data:`PARAMETER_MOVES`."""
    for k in range(axes.shape[0]):
        if k < 3:
            for i in range(3):
                out[i, k] = axes[k, i]
        elif moves[k, segment]:
            dx, dy, dz = x - pivots[k, 0], y - pivots[k, 1], z - pivots[k, 2]
            out[0, k] = axes[k, 1] * dz - axes[k, 2] * dy
            out[1, k] = axes[k, 2] * dx - axes[k, 0] * dz
            out[2, k] = axes[k, 0] * dy - axes[k, 1] * dx
        else:
            out[0, k] = 0.0
            out[1, k] = 0.0
            out[2, k] = 0.0


@dataclass(frozen=True)
class Skeleton:
    """Kinematic constants derived from body dimensions (frozen, computed once).

    Attributes
    ----------
    offsets : ndarray, shape (8, 3), float64, metres
        Segment origins in their parent's frame.
    joint_segment : ndarray, shape (10,), int64
    joint_local : ndarray, shape (10, 3), float64, metres
    """

    offsets: np.ndarray
    joint_segment: np.ndarray
    joint_local: np.ndarray

    @classmethod
    def from_dimensions(cls, dims: BodyDimensions) -> "Skeleton":
        seg, local = joint_points(dims)
        arrays = [segment_offsets(dims), seg, local]
        for a in arrays:
            a.setflags(write=False)
        return cls(*arrays)


def segment_transforms(pose, skeleton: Skeleton) -> np.ndarray:
    """Rigid transform of every segment for a pose.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Metres and radians (docs/design.md section 2).
    skeleton : Skeleton

    Returns
    -------
    ndarray, shape (8, 3, 4), float64
        ``[R | t]`` mapping segment-local points (metres) to camera coordinates (metres), in
        :data:`~mocap.body.skeleton.SEGMENT_NAMES` order.
    """
    q = check_pose(pose)
    out = np.empty((len(SEGMENT_NAMES), 3, 4))
    segment_transforms_into(q, skeleton.offsets, out)
    return out


def point_jacobians(pose, skeleton: Skeleton, segment, local) -> np.ndarray:
    """Analytic derivative of body points with respect to the pose.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Metres and radians.
    skeleton : Skeleton
    segment : array_like, shape (n,), int
        Segment (:data:`~mocap.body.skeleton.SEGMENT_NAMES` index) carrying each point.
    local : array_like, shape (n, 3), metres
        The points in their segment's frame.

    Returns
    -------
    ndarray, shape (n, 3, 23), float64
        ``d X_i / d q_k`` of each point's camera coordinates: metres per metre for the root
        positions, metres per radian for the angles.
    """
    q = check_pose(pose)
    seg = np.asarray(segment, dtype=np.int64)
    pts = np.asarray(local, dtype=np.float64)
    if seg.ndim != 1 or pts.shape != (len(seg), 3):
        raise ValueError(f"need (n,) segments and (n, 3) points, got {seg.shape} and {pts.shape}")
    if seg.size and (seg.min() < 0 or seg.max() >= len(SEGMENT_NAMES)):
        raise ValueError(f"segment indices must be in [0, {len(SEGMENT_NAMES)})")
    transforms = segment_transforms(q, skeleton)
    world = np.empty((len(seg), 3))
    apply_transforms_into(transforms, seg, pts, world)
    axes, pivots = np.empty((N_PARAMETERS, 3)), np.empty((N_PARAMETERS, 3))
    parameter_axes_into(q, transforms, axes, pivots)
    out = np.empty((len(seg), 3, N_PARAMETERS))
    for i in range(len(seg)):
        point_jacobian_into(world[i, 0], world[i, 1], world[i, 2], seg[i], axes, pivots, PARAMETER_MOVES, out[i])
    return out


def joint_positions(pose, skeleton: Skeleton) -> np.ndarray:
    """3D position of every named joint.

    Returns
    -------
    ndarray, shape (10, 3), float64
        Camera coordinates in metres, rows in :data:`~mocap.body.skeleton.JOINT_NAMES` order.
    """
    transforms = segment_transforms(pose, skeleton)
    out = np.empty((len(JOINT_NAMES), 3))
    apply_transforms_into(transforms, skeleton.joint_segment, skeleton.joint_local, out)
    return out
