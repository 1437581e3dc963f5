"""Hypothesis proposals: where else the actor might be, beyond the local search.

* **Hand re-acquisition**: skin regions of the image that the model's hands and head leave
  unexplained are taken for a lost hand; each arm is posed to reach each such region on its
  camera ray (:func:`reach_proposals`, inverse kinematics of :mod:`mocap.body.ik`).
* **Kinematic jumps** (:func:`jump_proposals`): each arm's other depth branches and the
  torso's front/back mirror (:mod:`mocap.body.jumps`), clamped to the joint limits.
* **Keypoints** (:class:`KeypointArmSource`): given a frame's 2D keypoints, the torso turned
  to the heading its shoulder keypoints show and each arm posed through its elbow and wrist
  keypoints on every depth branch (:func:`mocap.body.jumps.arm_poses_on_rays`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from mocap.body.ik import reach_arm
from mocap.body.jumps import SIDES, arm_jumps, arm_poses_on_rays, torso_flip
from mocap.body.model import BodyModel
from mocap.body.pose import PARAMETER_INDEX, PARAMETER_NAMES, clamp_to_limits, within_limits
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


@dataclass(frozen=True)
class Proposal:
    """A pose the tracker should consider.

    Attributes
    ----------
    pose : ndarray, shape (23,)
        Metres and radians, root placed.
    origin : str
        What proposed it (``"keypoints"``, ...).
    """

    pose: np.ndarray
    origin: str


@dataclass(frozen=True)
class ProposalContext:
    """What a proposal source may look at besides the prepared frame.

    Attributes
    ----------
    model : BodyModel
    camera : Camera
        The working camera.
    leader : ndarray, shape (23,)
        The leading hypothesis's registered pose this frame.
    keypoints : Keypoints or None
        The frame's 2D keypoints (:class:`mocap.io.keypoints.Keypoints`), working-camera pixels.
    """

    model: BodyModel
    camera: Camera
    leader: np.ndarray
    keypoints: object | None


class ProposalSource(Protocol):
    """Something that proposes poses for a frame."""

    origin: str

    def propose(self, prepared, context: ProposalContext) -> list[Proposal]:
        """Poses to consider for the frame (:class:`mocap.imaging.PreparedFrame`)."""


def camera_ray(camera: Camera, uv) -> np.ndarray:
    """Unit direction (3,) of the camera ray through pixel position ``uv`` (u, v), camera coordinates."""
    ray = np.array([(uv[0] - camera.cx) / camera.fx, (uv[1] - camera.cy) / camera.fy, 1.0])
    return ray / np.linalg.norm(ray)


def torso_on_shoulders(pose: np.ndarray, model: BodyModel, camera: Camera, r_shoulder_uv, l_shoulder_uv) -> np.ndarray:
    """The pose turned and moved so that its shoulders project onto two shoulder keypoints.

    The chest heading starts from the one whose shoulder line, at the shoulders' current depth,
    has the keypoints' projected width (``cos(yaw) = width_px * depth / (fx * shoulder width)``,
    capped at 1), facing the camera when the right shoulder keypoint is left of the left one and
    away otherwise; of the two turns (which shoulder is nearer, which one view cannot tell) the
    one nearer the current heading is taken. The heading is then refined (bounded scalar search,
    scipy) to minimise the shoulders' reprojection distance, the whole body shifted at its depth
    so that the shoulders' midpoint projects onto the keypoints' midpoint. Pitch, roll, head and
    arm angles are kept.

    Parameters
    ----------
    pose : ndarray, shape (23,)
        Metres and radians; its shoulders in front of the camera.
    model : BodyModel
    camera : Camera
    r_shoulder_uv, l_shoulder_uv : array_like, shape (2,), pixels

    Returns
    -------
    ndarray, shape (23,), inside the joint limits
    """
    from scipy.optimize import minimize_scalar

    rows = [_JOINT["r_shoulder"], _JOINT["l_shoulder"]]
    target_uv = np.array([r_shoulder_uv, l_shoulder_uv], dtype=np.float64)
    target_mid = camera_ray(camera, target_uv.mean(axis=0))          # unit ray through the 2D midpoint
    yaw_index = PARAMETER_INDEX["chest_yaw"]

    def placed(yaw: float) -> np.ndarray:
        q = pose.copy()
        q[yaw_index] = yaw
        q = clamp_to_limits(q)
        mid = model.joint_positions(q)[rows].mean(axis=0)
        q[:3] += target_mid * (mid[2] / target_mid[2]) - mid
        for _ in range(3):             # the 3D midpoint does not project onto the 2D midpoint: correct
            joints = model.joint_positions(q)[rows]
            if np.any(joints[:, 2] <= 0):
                break
            off = target_uv.mean(axis=0) - camera.project(joints).mean(axis=0)
            depth = float(joints[:, 2].mean())
            q[0] += off[0] * depth / camera.fx
            q[1] += off[1] * depth / camera.fy
        return clamp_to_limits(q)

    def miss(yaw: float) -> float:
        joints = model.joint_positions(placed(yaw))[rows]
        if np.any(joints[:, 2] <= 0):
            return math.inf
        return float(np.linalg.norm(camera.project(joints) - target_uv, axis=1).sum())

    shoulders = model.joint_positions(pose)[rows]
    width_m = float(np.linalg.norm(shoulders[0] - shoulders[1]))
    across = min(1.0, abs(float(target_uv[1, 0] - target_uv[0, 0])) * float(shoulders[:, 2].mean())
                 / (camera.fx * width_m))
    turn = math.acos(across)
    yaw = float(pose[yaw_index])
    facing = target_uv[1, 0] >= target_uv[0, 0]
    headings = (turn, -turn) if facing else (math.pi - turn, -math.pi + turn)
    # the candidate heading (modulo a full turn) nearest the current one
    start = min((h + 2.0 * math.pi * round((yaw - h) / (2.0 * math.pi)) for h in headings), key=lambda h: abs(h - yaw))
    best = minimize_scalar(miss, bounds=(start - 0.5, start + 0.5), method="bounded", options={"xatol": 1e-3})
    return placed(float(best.x) if miss(float(best.x)) < miss(start) else start)


class KeypointArmSource:
    """Proposals from 2D keypoints: each arm on every depth branch, the torso on the shoulders.

    For each arm whose elbow and wrist keypoints are present, every depth branch of
    :func:`mocap.body.jumps.arm_poses_on_rays` from the leader's torso that lies inside the
    joint limits (else the branches clamped to them, when none does) is proposed, the other arm
    as it is. When both shoulder keypoints are present, one more proposal turns and moves the
    torso onto them (:func:`torso_on_shoulders`: a heading from a shoulder line seen nearly
    face-on is ill-conditioned, hence a proposal of its own) with every arm on its branch
    nearest the leader's arm.
    """

    origin = "keypoints"

    def propose(self, prepared, context: ProposalContext) -> list[Proposal]:
        k = context.keypoints
        if k is None:
            return []
        model, camera = context.model, context.camera
        present = np.asarray(k.confidence) > 0
        leader = np.asarray(context.leader, dtype=np.float64)
        out = []
        for side in SIDES:
            out += self._arm_branches(leader, side, k, present, model, camera)
        r_s, l_s = _JOINT["r_shoulder"], _JOINT["l_shoulder"]
        if present[r_s] and present[l_s] and np.all(model.joint_positions(leader)[[r_s, l_s], 2] > 0):
            torso = torso_on_shoulders(leader, model, camera, k.uv[r_s], k.uv[l_s])
            lead_joints = model.joint_positions(leader)
            for side in SIDES:
                branches = self._arm_branches(torso, side, k, present, model, camera)
                if branches:
                    rows = [_JOINT[f"{side}_elbow"], _JOINT[f"{side}_wrist"]]
                    best = min(branches, key=lambda q: float(np.linalg.norm(model.joint_positions(q)[rows]
                                                                            - lead_joints[rows])))
                    arm = [PARAMETER_INDEX[n] for n in PARAMETER_NAMES if n.startswith(f"{side}_")]
                    torso[arm] = best[arm]
            out.append(torso)
        return [Proposal(q, self.origin) for q in out]

    @staticmethod
    def _arm_branches(pose, side, k, present, model: BodyModel, camera: Camera) -> list[np.ndarray]:
        e, w = _JOINT[f"{side}_elbow"], _JOINT[f"{side}_wrist"]
        if not (present[e] and present[w]):
            return []
        branches = list(arm_poses_on_rays(pose, model.skeleton, side, camera_ray(camera, k.uv[e]),
                                          camera_ray(camera, k.uv[w])).values())
        inside = [q for q in branches if within_limits(q)]
        return inside or [clamp_to_limits(q) for q in branches]
