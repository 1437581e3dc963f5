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
    return np.array(((1.0, 0.0, 0.0), (0.0, c, -s), (0.0, s, c)))


@jit
def _rot_y(a):
    c, s = np.cos(a), np.sin(a)
    return np.array(((c, 0.0, s), (0.0, 1.0, 0.0), (-s, 0.0, c)))


@jit
def _rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0)))


@jit
def _segment_transforms(pose, offsets, out):
    """Fill ``out`` (8, 3, 4) with [R | t] of every segment in camera coordinates.

    The angle layout is DESIGN.md section 2; see :mod:`mocap.body.pose` for the signs.
    """
    r_chest = _rot_y(pose[3]) @ _rot_x(pose[4]) @ _rot_z(pose[5])
    t_chest = pose[0:3].copy()
    out[0, :, :3] = r_chest
    out[0, :, 3] = t_chest
    r_head = r_chest @ _rot_x(pose[6]) @ _rot_z(pose[7]) @ _rot_y(pose[8])
    out[1, :, :3] = r_head
    out[1, :, 3] = r_chest @ offsets[1] + t_chest
    for side in range(2):
        base = 9 + 7 * side          # first arm parameter of this side
        seg = 2 + 3 * side           # upper-arm segment index
        mirror = 1.0 if side == 0 else -1.0
        r_ua = r_chest @ _rot_x(-pose[base]) @ _rot_z(mirror * pose[base + 1]) @ _rot_y(mirror * pose[base + 2])
        t_ua = r_chest @ offsets[seg] + t_chest
        r_fa = r_ua @ _rot_x(-pose[base + 3]) @ _rot_y(mirror * pose[base + 4])
        t_fa = r_ua @ offsets[seg + 1] + t_ua
        r_h = r_fa @ _rot_x(-pose[base + 5]) @ _rot_z(mirror * pose[base + 6])
        t_h = r_fa @ offsets[seg + 2] + t_fa
        out[seg, :, :3] = r_ua
        out[seg, :, 3] = t_ua
        out[seg + 1, :, :3] = r_fa
        out[seg + 1, :, 3] = t_fa
        out[seg + 2, :, :3] = r_h
        out[seg + 2, :, 3] = t_h


@jit
def _apply_transforms(transforms, segment, local, out):
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
        Metres and radians (DESIGN.md section 2).
    skeleton : Skeleton

    Returns
    -------
    ndarray, shape (8, 3, 4), float64
        ``[R | t]`` mapping segment-local points (metres) to camera coordinates (metres), in
        :data:`~mocap.body.skeleton.SEGMENT_NAMES` order.
    """
    q = check_pose(pose)
    out = np.empty((len(SEGMENT_NAMES), 3, 4))
    _segment_transforms(q, skeleton.offsets, out)
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
    _apply_transforms(transforms, skeleton.joint_segment, skeleton.joint_local, out)
    return out
