"""Depth alternatives of a pose: each arm bone's depth flipped about its parent joint.

A bone seen in one image is known up to the sign of its depth: its child joint lies on the camera
ray through the child's pixel, at the bone's length from the parent joint, and that ray meets the
sphere of the bone's length about the parent twice (the near and the far intersection). A *depth
alternative* takes the other intersection for some of an arm's bones (the upper arm about the
shoulder, the forearm about the elbow), keeps the other bones' choice of intersection about their
now moved parent, and places the arm onto the body within the joint limits
(:func:`mocap.body.ik.place_arm`). It projects onto the same pixels as the pose it came from and
keeps every bone's length, so a keypoint distance cannot tell the two apart; the silhouette, the
edges, the prior and time may.

The exact geometry is :func:`mocap.body.jumps.flipped_arm_joints` (the kinematic jumps' too); this
module places the arm on it and prunes. Stateless: a pose, the model and the camera in, typed
records out. The tracker makes the depth alternatives of its converged leader candidates every
frame (:mod:`mocap.track.tracker`); ``experiments.branch_audit`` scores the truth against its own.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mocap.body.ik import ARM_JOINTS, place_arm
from mocap.body.jumps import flipped_arm_joints
from mocap.body.kinematics import joint_positions
from mocap.body.model import BodyModel
from mocap.body.pose import check_pose
from mocap.body.skeleton import JOINT_INDEX
from mocap.render.camera import Camera

#: The flips tried per arm by default: the upper arm, the forearm, both.
DEFAULT_FLIPS: tuple[tuple[str, ...], ...] = (("upper_arm",), ("forearm",), ("upper_arm", "forearm"))
#: Default largest move of any joint's projection (pixels) for an alternative to be kept.
MAX_SHIFT_PX = 0.5
#: Default largest miss (metres) of the placed arm's joints from the flipped joints: further, the
#: joint limits did not let the arm take the other branch.
MAX_MISS_M = 0.01
#: The placement's polish runs only where the closed form misses by at most this many times
#: ``max_miss_m``: farther, it brought 4 of 99 flips of random arm postures within 1 cm, each from
#: a miss of at most 1.1 cm.
POLISH_WITHIN = 2.0
#: Default smallest move (metres) of some arm joint for an alternative to count: a bone nearly
#: square to its camera ray has both intersections at almost the same point.
MIN_CHANGE_M = 0.03


@dataclass(frozen=True, kw_only=True)
class DepthAlternative:
    """One arm of a pose taken onto the other depth branch of some of its bones.

    Attributes
    ----------
    side : str
        ``"r"`` or ``"l"``: the actor's arm that changed.
    flipped : tuple of str
        The bones whose depth was flipped about their parent joint
        (:data:`~mocap.body.jumps.ARM_BONES` names).
    pose : ndarray, shape (23,), float64
        The alternative pose (metres, radians, inside the joint limits); only ``side``'s seven arm
        angles differ from the pose it came from.
    joints : ndarray, shape (10, 3), float64
        Its joints (camera coordinates, metres).
    shift_px : float
        Largest move of any joint's projection from the original pose's (pixels).
    miss_m : float
        Largest distance of the placed arm joints from the exactly flipped ones (metres).
    """

    side: str
    flipped: tuple[str, ...]
    pose: np.ndarray
    joints: np.ndarray
    shift_px: float
    miss_m: float


def depth_alternatives(pose, model: BodyModel, camera: Camera, *, sides=("r", "l"), flips=DEFAULT_FLIPS,
                       max_shift_px: float = MAX_SHIFT_PX, max_miss_m: float = MAX_MISS_M,
                       min_change_m: float = MIN_CHANGE_M) -> list[DepthAlternative]:
    """The depth alternatives of ``pose`` that the joint limits allow, per arm and flip.

    For each side and each set of flipped bones, :func:`~mocap.body.jumps.flipped_arm_joints` gives
    the exact joints and :func:`mocap.body.ik.place_arm` places the arm on them from ``pose``. An alternative
    is kept when some arm joint moved at least ``min_change_m``, the placed joints are within
    ``max_miss_m`` of the exact ones and every joint projects within ``max_shift_px`` of
    ``pose``'s.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Metres and radians.
    model : BodyModel
        The calibrated actor.
    camera : Camera
        The camera the projections are compared in (pixels).
    sides : iterable of {"r", "l"}
    flips : iterable of tuple of str
        Sets of bones (:data:`~mocap.body.jumps.ARM_BONES` names) to flip, each tried on every side.
    max_shift_px, max_miss_m, min_change_m : float
        The pruning thresholds (pixels, metres, metres); see the module's constants.

    Returns
    -------
    list of DepthAlternative
        In ``sides`` then ``flips`` order; an empty list when no flip is allowed.
    """
    q = check_pose(pose)
    for name, value in (("max_shift_px", max_shift_px), ("max_miss_m", max_miss_m), ("min_change_m", min_change_m)):
        if not np.isfinite(value) or value < 0:
            raise ValueError(f"{name} must be finite and non-negative, got {value!r}")
    joints = joint_positions(q, model.skeleton)
    pixels = camera.project(joints)
    out = []
    for side in sides:
        rows = [JOINT_INDEX[f"{side}_{j}"] for j in ARM_JOINTS]
        for flip in flips:
            target = flipped_arm_joints(joints, side, flip)
            if np.max(np.linalg.norm(target[rows] - joints[rows], axis=1)) < min_change_m:
                continue
            placed = place_arm(q, model.skeleton, side, target[rows], polish_within_m=POLISH_WITHIN * max_miss_m)
            if placed.miss_m > max_miss_m:
                continue
            moved = joint_positions(placed.pose, model.skeleton)
            if np.any(moved[:, 2] <= 0):
                continue
            shift = float(np.max(np.linalg.norm(camera.project(moved) - pixels, axis=1)))
            if shift > max_shift_px:
                continue
            out.append(DepthAlternative(side=side, flipped=tuple(flip), pose=placed.pose, joints=moved,
                                        shift_px=shift, miss_m=placed.miss_m))
    return out


__all__ = ["DEFAULT_FLIPS", "DepthAlternative", "depth_alternatives"]
