"""A detector's own 3D as evidence of the score (issue 34): MediaPipe Pose's world landmarks.

When the keypoints come from MediaPipe they carry its 3D world joints
(:attr:`mocap.io.keypoints.Keypoints.world`: metres about its hips, on the camera's axes). The
tracker places them onto the calibrated body within the joint limits
(:func:`mocap.body.ik.fit_pose_to_joints`, started from the leading hypothesis's pose: one fit
a frame, the torso's other headings tried only when that fit misses by more than
:data:`REFIT_RMS_M`), and every candidate of the frame pays ``world_weight`` times
``0.5 * sum_j min(d_j^2 / WORLD_SIGMA_M^2, WORLD_CAP)`` over the six arm joints (shoulders,
elbows, wrists), ``d_j`` the distance of the candidate's joint from the placed pose's, both about
their shoulders' midpoint (no rotation: MediaPipe's world axes are the camera's; issue 34's check
on renders of CMU motion: 59-120 mm mean joint error about the centroids as given, 220-374 mm with
y flipped, 99-224 mm with z flipped). Per joint and capped: a joint MediaPipe has wrong costs a
fixed price, the others still count.

Placed poses as proposals of their own were measured and did not pay (docs/research-log.md).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mocap.body.ik import FIT_MIN_JOINTS, fit_pose_to_joints
from mocap.body.model import BodyModel
from mocap.body.skeleton import JOINT_INDEX

#: Scale of an arm joint's distance from MediaPipe's placed pose in the score (metres).
WORLD_SIGMA_M = 0.1
#: Most one joint adds to the term (in units of ``(d / WORLD_SIGMA_M)^2``, before the 0.5 and the weight).
WORLD_CAP = 9.0
#: A warm-started fit that misses the landmarks by more than this (RMS, metres) is redone from
#: every heading of :data:`mocap.body.ik.FIT_START_YAWS_DEG` (about 0.6 s here, against about 50 ms
#: for the warm fit). MediaPipe's proportions are not the calibrated body's: on renders of CMU
#: subject 14 the warm fits missed by 41 mm RMS at the median and 53 mm at the 90th percentile.
REFIT_RMS_M = 0.08
#: The arm joints the term compares (shoulders, elbows, wrists).
ARM_JOINTS = np.array([JOINT_INDEX[n] for n in ("r_shoulder", "r_elbow", "r_wrist",
                                                "l_shoulder", "l_elbow", "l_wrist")])


def about_shoulders(joints: np.ndarray) -> np.ndarray:
    """The six arm joints of ``joints`` (10, 3) about their shoulders' midpoint, shape (6, 3)."""
    arms = np.asarray(joints, dtype=np.float64)[ARM_JOINTS]
    return arms - 0.5 * (arms[0] + arms[3])


@dataclass(frozen=True, kw_only=True)
class PlacedWorld:
    """A frame's detector 3D placed onto the body.

    Attributes
    ----------
    pose : ndarray, shape (23,), float64
        The fitted pose (its root about the detector's origin, not in the camera).
    arms : ndarray, shape (6, 3), float64, metres
        Its arm joints about the shoulders' midpoint (:func:`about_shoulders`).
    """

    pose: np.ndarray
    arms: np.ndarray

    def energy(self, joints: np.ndarray) -> float:
        """The term before its weight (nats): ``0.5 * sum_j min(d_j^2 / WORLD_SIGMA_M^2, WORLD_CAP)``
        of a candidate's ``joints`` (10, 3; metres, camera coordinates)."""
        d2 = np.sum((about_shoulders(joints) - self.arms) ** 2, axis=1) / WORLD_SIGMA_M ** 2
        return 0.5 * float(np.minimum(d2, WORLD_CAP).sum())


def place_world(keypoints, model: BodyModel, start) -> PlacedWorld | None:
    """A frame's detector 3D placed onto ``model``, or None without it.

    Parameters
    ----------
    keypoints : Keypoints or None
        The frame's keypoints; their :attr:`~mocap.io.keypoints.Keypoints.world` is used.
    model : BodyModel
        The calibrated actor.
    start : array_like, shape (23,)
        Where the fit starts (the leading hypothesis's pose).

    Returns
    -------
    PlacedWorld or None
        None when the keypoints carry no 3D or fewer than :data:`~mocap.body.ik.FIT_MIN_JOINTS`
        joints of it, or without both shoulders.
    """
    if keypoints is None or keypoints.world is None:
        return None
    world = keypoints.world
    present = np.isfinite(world).all(axis=1)
    if present.sum() < FIT_MIN_JOINTS or not present[ARM_JOINTS[[0, 3]]].all():
        return None
    fit = fit_pose_to_joints(world, present, model.skeleton, start=start, headings_deg=())
    if fit.rms_m > REFIT_RMS_M:
        fit = fit_pose_to_joints(world, present, model.skeleton, start=start)
    return PlacedWorld(pose=fit.pose, arms=about_shoulders(model.joint_positions(fit.pose)))


__all__ = ["ARM_JOINTS", "PlacedWorld", "REFIT_RMS_M", "WORLD_CAP", "WORLD_SIGMA_M", "about_shoulders", "place_world"]
