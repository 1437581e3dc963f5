"""Posture prior: arms are seldom behind the body.

One view cannot tell an arm swung forward from the same arm swung back by the same angle:
both project to nearly the same silhouette and edges (the depth ambiguity of monocular
registration). People gesturing in front of a camera keep their elbows and wrists in front
of, or close to, the plane of their chest; so a penalty on an elbow or wrist that is
*behind* that plane by more than a margin breaks the tie towards the likely branch without
touching poses in front of the body.

The penalty of one pose is::

    sum over the elbows and wrists of (max(0, b - margin) / sigma) ** 2

where ``b`` (metres) is how far the joint lies behind its shoulder along the chest's backward
axis (the chest frame's +z: away from the camera for an actor facing it).
"""
from __future__ import annotations

import numpy as np

from mocap._numba import jit
from mocap.body.kinematics import Skeleton, segment_transforms_into
from mocap.body.pose import check_pose
from mocap.body.skeleton import SEGMENT_NAMES

_CHEST = SEGMENT_NAMES.index("chest")
#: (shoulder segment, elbow segment, wrist segment) per arm: each segment's origin is its joint.
ARM_SEGMENTS = np.array([[SEGMENT_NAMES.index(f"{side}_upper_arm"), SEGMENT_NAMES.index(f"{side}_forearm"),
                   SEGMENT_NAMES.index(f"{side}_hand")] for side in "rl"], dtype=np.int64)


@jit
def arm_behind_penalty_of_transforms(transforms, arms, margin_m, sigma_m):
    """Posture penalty of posed segment transforms (``transforms``: (segments, 3, 4), metres)."""
    total = 0.0
    for a in range(arms.shape[0]):
        s = arms[a, 0]
        for k in range(1, 3):
            j = arms[a, k]
            # backward component: chest z axis (third column of its rotation) . (joint - shoulder)
            b = 0.0
            for i in range(3):
                b += transforms[_CHEST, i, 2] * (transforms[j, i, 3] - transforms[s, i, 3])
            over = b - margin_m
            if over > 0.0:
                total += (over / sigma_m) ** 2
    return total


def arm_behind_penalty(pose, skeleton: Skeleton, *, margin_m: float = 0.05, sigma_m: float = 0.1) -> float:
    """Posture penalty of a pose: how far its elbows and wrists are behind the chest plane.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Metres and radians.
    skeleton : Skeleton
        The model's bone offsets (``BodyModel.skeleton``).
    margin_m : float
        Distance behind the shoulder (metres, >= 0) that costs nothing.
    sigma_m : float
        Distance beyond the margin (metres, > 0) that costs 1.

    Returns
    -------
    float
        ``sum((max(0, behind - margin) / sigma) ** 2)`` over both elbows and wrists; 0 for a
        pose with both arms in front of the body.

    Raises
    ------
    ValueError
        For a bad pose, a negative margin or a sigma that is not positive.
    """
    q = check_pose(pose)
    if not (np.isfinite(margin_m) and margin_m >= 0.0):
        raise ValueError(f"margin_m must be >= 0 metres, got {margin_m}")
    if not (np.isfinite(sigma_m) and sigma_m > 0.0):
        raise ValueError(f"sigma_m must be > 0 metres, got {sigma_m}")
    transforms = np.empty((len(SEGMENT_NAMES), 3, 4))
    segment_transforms_into(q, skeleton.offsets, transforms)
    return float(arm_behind_penalty_of_transforms(transforms, ARM_SEGMENTS, float(margin_m), float(sigma_m)))


__all__ = ["arm_behind_penalty"]
