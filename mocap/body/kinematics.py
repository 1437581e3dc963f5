"""Forward kinematics: pose vector → segment transforms → joint positions.

Stateless: every function takes the pose and the model data and returns new arrays.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mocap._numba import jit
from mocap.body.dimensions import BodyDimensions
from mocap.body.pose import check_pose
from mocap.body.skeleton import JOINT_NAMES, SEGMENT_NAMES, joint_points, segment_offsets


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


@jit
def segment_transforms_into(pose, offsets, out):
    """Fill ``out`` (8, 3, 4) with [R | t] of every segment in camera coordinates.

    The angle layout is docs/design.md section 2; see :mod:`mocap.body.pose` for the signs.
    """
    r_chest = _mul(_mul(_rot_y(pose[3]), _rot_x(pose[4])), _rot_z(pose[5]))
    _store(out, 0, r_chest, -1, pose[0:3])
    r_head = _mul(_mul(_mul(r_chest, _rot_x(pose[6])), _rot_z(pose[7])), _rot_y(pose[8]))
    _store(out, 1, r_head, 0, offsets[1])
    for side in range(2):
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
def apply_transforms_into(transforms, segment, local, out):
    """out[i] = R[segment[i]] @ local[i] + t[segment[i]] for every point."""
    for i in range(local.shape[0]):
        s = segment[i]
        for r in range(3):
            out[i, r] = (transforms[s, r, 0] * local[i, 0] + transforms[s, r, 1] * local[i, 1]
                         + transforms[s, r, 2] * local[i, 2] + transforms[s, r, 3])


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
