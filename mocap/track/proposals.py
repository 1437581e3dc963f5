"""Hypothesis proposals: where else the actor might be, beyond the local search.

* **Hand re-acquisition**: skin regions of the image that the model's hands and head leave
  unexplained are taken for a lost hand; each arm is posed to reach each such region on its
  camera ray (:func:`reach_proposals`, inverse kinematics of :mod:`mocap.body.ik`).
* **Kinematic jumps** (:func:`jump_proposals`): each arm's other depth branches and the
  torso's front/back mirror (:mod:`mocap.body.jumps`), clamped to the joint limits.
"""
from __future__ import annotations

import math

import numpy as np

from mocap.body.ik import reach_arm
from mocap.body.jumps import SIDES, arm_jumps, torso_flip
from mocap.body.model import BodyModel
from mocap.body.pose import PARAMETER_NAMES, clamp_to_limits
from mocap.body.skeleton import JOINT_NAMES
from mocap.imaging.blobs import label_blobs
from mocap.labels import class_label
from mocap.render.camera import Camera
from mocap.track.config import TrackerConfig

#: Row of each named joint in the joint arrays.
_JOINT = {name: i for i, name in enumerate(JOINT_NAMES)}


#: Hand depths tried by hand re-acquisition, as fractions of the arm's reach (shoulder to hand
#: centre, arm straight): the hand on the camera ray at that distance from the shoulder, nearer
#: and farther than the shoulder (the two depth branches), plus the point of the ray nearest
#: the shoulder.
REACQUISITION_REACH = (0.95, 0.7)


def unexplained_hands(labels: np.ndarray, joints: np.ndarray, model: BodyModel, camera: Camera,
                      config: TrackerConfig) -> np.ndarray:
    """Centroids of the image's skin regions that the model's hands and head do not account for.

    Parameters
    ----------
    labels : ndarray of uint8, shape (H, W)
        The frame's label image.
    joints : ndarray, shape (10, 3), metres
        The registered model's joints (:data:`mocap.body.JOINT_NAMES` order).
    model : BodyModel
        Its ``skin`` colour class is the hands' (none: nothing is returned).
    camera : Camera
    config : TrackerConfig
        ``reacquisition_min_pixels`` and ``reacquisition_distance_px``.

    Returns
    -------
    ndarray, shape (n, 2), float64, pixels
        ``(u, v)`` of each skin region, other than the one nearest the projected head centre,
        whose centroid is farther than ``reacquisition_distance_px`` from both projected hand
        centres.
    """
    if "skin" not in model.class_names or np.any(joints[:, 2] <= 0.0):
        return np.zeros((0, 2))         # (a joint at or behind the camera plane projects nowhere)
    blobs = label_blobs(labels, class_label("skin", model.class_names), min_pixels=config.reacquisition_min_pixels)
    if len(blobs) == 0:
        return np.zeros((0, 2))
    projected = camera.project(joints)
    head = int(np.argmin(np.linalg.norm(blobs.centroids - projected[_JOINT["head"]], axis=1)))
    hands = projected[[_JOINT["r_hand"], _JOINT["l_hand"]]]
    far = np.linalg.norm(blobs.centroids[:, None, :] - hands[None], axis=2).min(axis=1) > config.reacquisition_distance_px
    far[head] = False
    return blobs.centroids[far]


def reach_proposals(pose: np.ndarray, joints: np.ndarray, targets: np.ndarray, model: BodyModel,
                    camera: Camera) -> list[np.ndarray]:
    """Poses with one arm moved so that its hand projects onto each image point.

    For every target pixel and arm, the hand is put on the camera ray through the pixel at the
    depths of :data:`REACQUISITION_REACH` (both branches where the ray passes within reach) and
    at the ray's point nearest the shoulder, by :func:`mocap.body.ik.reach_arm`.

    Parameters
    ----------
    pose : ndarray, shape (23,)
        Registered pose (metres, radians); the rest of the body is kept.
    joints : ndarray, shape (10, 3), metres
        Its joints.
    targets : ndarray, shape (n, 2), pixels
    model : BodyModel
    camera : Camera

    Returns
    -------
    list of ndarray, shape (23,)
    """
    reach = {}
    for side in "rl":                      # shoulder to hand centre with the arm straight
        straight = pose.copy()
        straight[[i for i, name in enumerate(PARAMETER_NAMES) if name.startswith(f"{side}_")]] = 0.0
        straight_joints = model.joint_positions(straight)
        reach[side] = float(np.linalg.norm(straight_joints[_JOINT[f"{side}_hand"]]
                                           - straight_joints[_JOINT[f"{side}_shoulder"]]))
    out = []
    k_inv = np.linalg.inv(camera.intrinsics())
    for uv in targets:
        ray = k_inv @ np.array([uv[0], uv[1], 1.0])
        ray /= np.linalg.norm(ray)
        for side in "rl":
            shoulder = joints[_JOINT[f"{side}_shoulder"]]
            nearest = float(shoulder @ ray)
            miss = float(np.linalg.norm(shoulder - nearest * ray))
            depths = [nearest]
            for fraction in REACQUISITION_REACH:
                if fraction * reach[side] > miss:
                    half = math.sqrt((fraction * reach[side]) ** 2 - miss ** 2)
                    depths += [nearest - half, nearest + half]
            out += [reach_arm(pose, model.skeleton, side, t * ray) for t in depths if t > 0]
    return out


def jump_proposals(pose: np.ndarray, model: BodyModel) -> list[tuple[str, np.ndarray]]:
    """The kinematic jumps of a pose, clamped to the joint limits.

    Parameters
    ----------
    pose : ndarray, shape (23,)
        Metres and radians.
    model : BodyModel

    Returns
    -------
    list of (str, ndarray of shape (23,))
        ``("r_forearm", pose)`` and so on for each side and :data:`~mocap.body.jumps.ARM_JUMPS`
        entry that is possible, then ``("torso_flip", pose)``.
    """
    out = []
    for side in SIDES:
        for name, q in arm_jumps(pose, model.skeleton, side).items():
            out.append((f"{side}_{name}", clamp_to_limits(q)))
    out.append(("torso_flip", torso_flip(pose, model.skeleton)))
    return out
