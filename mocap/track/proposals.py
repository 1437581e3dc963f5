"""Hypothesis proposals: where else the actor might be, beyond the local search.

Two kinds feed the beam (:class:`mocap.track.Tracker`):

* **From the previous poses.** Hand re-acquisition: skin regions of the image that the
  leader's hands and head leave unexplained are taken for a lost hand; each arm is posed to
  reach each such region on its camera ray (:func:`reach_proposals`, inverse kinematics of
  :mod:`mocap.body.ik`). Kinematic jumps (:func:`jump_proposals`): each arm's other depth
  branches and the torso's front/back mirror (:mod:`mocap.body.jumps`).
* **From the current image** (the *proposal stage*). A :class:`ProposalSource` reads the
  frame's observation (:class:`mocap.imaging.PreparedFrame`: class labels, edges, distance
  map; and, where a detector gave them, 2D keypoints) and returns full poses
  (:class:`Proposal`), whatever the previous pose was. The tracker scores every proposal once
  by F, refines the lowest-F ones of each source by a short registration and lets them
  compete in the beam; the decoder decides. The source here: :class:`LifterSource` (the learned
  lifter's whole-body hypotheses from the frame's 2D keypoints, :mod:`mocap.track.lifter`). The
  arms' one-at-a-time inverse kinematics on the keypoints and the silhouette-only sources (hand
  blobs, the k-NN exemplars) were removed: see docs/research-log.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from mocap.body.ik import place_arm, reach_arm
from mocap.body.jumps import SIDES, arm_jumps, ray_sphere_depths, torso_flip
from mocap.body.model import BodyModel
from mocap.body.pose import HEADING, PARAMETER_INDEX, PARAMETER_NAMES, clamp_to_limits
from mocap.body.skeleton import JOINT_INDEX
from mocap.imaging.blobs import label_blobs
from mocap.io.keypoints import Keypoints
from mocap.labels import class_label
from mocap.render.camera import Camera
from mocap.track.config import MAX_REACH_TARGETS, MIN_SKIN_BLOB_PIXELS, TrackerConfig
from mocap.track.lifter import MIN_VISIBLE, LiftedHypotheses, Lifter, relative_joints


#: Most nats the lifter term charges a candidate (before ``lifter_weight``): about the energy of
#: joints 18 cm on average from the nearest hypothesis (:data:`~mocap.track.lifter.DENSITY_SIGMA_M`). The
#: lifter misses some frames (its best of ten is within 10 cm on about nine in ten); there the
#: image's evidence must decide.
LIFTER_ENERGY_CAP = 10.0

#: Hand distances from the shoulder tried when an arm is posed to reach an image point, as
#: fractions of the arm's straight reach (shoulder to hand centre).
REACH_FRACTIONS = (0.95, 0.7)


@dataclass(frozen=True)
class Proposal:
    """A full pose proposed for the current frame.

    Attributes
    ----------
    pose : ndarray, shape (23,), float64
        Metres and radians, the root placed in camera coordinates.
    origin : str
        The source that made it (its ``origin``), written to ``poses.csv``.
    """

    pose: np.ndarray
    origin: str


@dataclass(frozen=True, kw_only=True)
class ProposalContext:
    """What a proposal source may use besides the frame's observation.

    Attributes
    ----------
    lifted : LiftedHypotheses or None
        The learned lifter's hypotheses of the frame's 2D keypoints (:meth:`LifterSource.lift`),
        lifted once per frame for the proposal stage and the score alike; None on frames without
        keypoints or when the configuration does not lift.
    lifted_swapped : LiftedHypotheses or None
        The same of the keypoints with left and right swapped
        (:meth:`mocap.io.keypoints.Keypoints.swapped`): the body the keypoints show if the
        detector named the person's left arm the right one; None where ``lifted`` is, or where
        the labellings are not both scored (``keypoint_weight`` 0).
    keypoints : Keypoints or None
        The frame's 2D keypoints (with the detector's 3D in ``world`` where it gave one).
    pose : ndarray, shape (23,), or None
        The beam leader's pose as the frame starts (the last frame's): where proposals that keep
        the torso take it from.
    """

    lifted: LiftedHypotheses | None = None
    lifted_swapped: LiftedHypotheses | None = None
    keypoints: Keypoints | None = None
    pose: np.ndarray | None = None


class ProposalSource(Protocol):
    """Anything that proposes full poses from one frame's observation."""

    #: Name of the source (``Proposal.origin``).
    origin: str

    def propose(self, prepared, context: ProposalContext) -> list[Proposal]:
        """Poses for this frame (possibly none), from ``prepared``
        (:class:`mocap.imaging.PreparedFrame`) and ``context``."""


def arm_reach_m(pose: np.ndarray, model: BodyModel, side: str) -> float:
    """Distance from shoulder to hand centre with the arm straight (metres)."""
    straight = np.array(pose, dtype=np.float64)
    straight[[i for i, name in enumerate(PARAMETER_NAMES) if name.startswith(f"{side}_")]] = 0.0
    joints = model.joint_positions(straight)
    return float(np.linalg.norm(joints[JOINT_INDEX[f"{side}_hand"]] - joints[JOINT_INDEX[f"{side}_shoulder"]]))


def pixel_ray(camera: Camera, uv) -> np.ndarray:
    """Unit direction (camera coordinates) of the ray through pixel ``uv = (u, v)``."""
    ray = np.linalg.solve(camera.intrinsics(), np.array([uv[0], uv[1], 1.0]))
    return ray / np.linalg.norm(ray)


def skin_blobs_off_head(labels: np.ndarray, joints: np.ndarray, model: BodyModel, camera: Camera,
                        min_pixels: int) -> np.ndarray:
    """Centroids of the skin regions of a label image, but the one nearest the projected head.

    Parameters
    ----------
    labels : ndarray of uint8, shape (H, W)
    joints : ndarray, shape (10, 3), metres
        A pose's joints (the head's projection picks the head's region).
    model : BodyModel
        Its ``skin`` class (none: nothing is returned).
    camera : Camera
    min_pixels : int
        Smaller regions are ignored.

    Returns
    -------
    ndarray, shape (n, 2), float64, pixels
        ``(u, v)`` of each region, largest first.
    """
    if "skin" not in model.class_names or np.any(joints[:, 2] <= 0.0):
        return np.zeros((0, 2))         # (a joint at or behind the camera plane projects nowhere)
    blobs = label_blobs(labels, class_label("skin", model.class_names), min_pixels=min_pixels)
    if len(blobs) == 0:
        return np.zeros((0, 2))
    head = int(np.argmin(np.linalg.norm(blobs.centroids - camera.project(joints)[JOINT_INDEX["head"]], axis=1)))
    return np.delete(blobs.centroids, head, axis=0)


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
        ``reacquisition_distance_px`` (skin regions of at least
        :data:`~mocap.track.config.MIN_SKIN_BLOB_PIXELS`).

    Returns
    -------
    ndarray, shape (n, 2), float64, pixels, n <= MAX_REACH_TARGETS
        ``(u, v)`` of each skin region, other than the one nearest the projected head centre,
        whose centroid is farther than ``reacquisition_distance_px`` from both projected hand
        centres: the :data:`~mocap.track.config.MAX_REACH_TARGETS` largest such.
    """
    blobs = skin_blobs_off_head(labels, joints, model, camera, MIN_SKIN_BLOB_PIXELS)
    if len(blobs) == 0:
        return blobs
    hands = camera.project(joints)[[JOINT_INDEX["r_hand"], JOINT_INDEX["l_hand"]]]
    far = np.linalg.norm(blobs[:, None, :] - hands[None], axis=2).min(axis=1) > config.reacquisition_distance_px
    return blobs[far][:MAX_REACH_TARGETS]       # largest first (skin_blobs_off_head's order)


def reach_proposals(pose: np.ndarray, joints: np.ndarray, targets: np.ndarray, model: BodyModel,
                    camera: Camera) -> list[np.ndarray]:
    """Poses with one arm moved so that its hand projects onto each image point.

    For every target pixel and arm, the hand is put on the camera ray through the pixel at the
    depths where the ray meets the spheres of :data:`REACH_FRACTIONS` of the arm's reach about
    the shoulder (both branches) and at the ray's point nearest the shoulder, by
    :func:`mocap.body.ik.reach_arm`.

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
    return [q for uv, side, reach_m in reach_jobs(pose, targets, model)
            for q in arm_reach_proposals(pose, joints, uv, side, reach_m, model, camera)]


def reach_jobs(pose: np.ndarray, targets: np.ndarray, model: BodyModel) -> list[tuple[np.ndarray, str, float]]:
    """The ``(uv, side, reach_m)`` of each target pixel and arm, in :func:`reach_proposals`' order
    (targets first, then :data:`~mocap.body.jumps.SIDES`): each one call of
    :func:`arm_reach_proposals` (``reach_m``: :func:`arm_reach_m`, metres)."""
    reach = {side: arm_reach_m(pose, model, side) for side in SIDES}
    return [(uv, side, reach[side]) for uv in targets for side in SIDES]


def arm_reach_proposals(pose: np.ndarray, joints: np.ndarray, uv, side: str, reach_m: float, model: BodyModel,
                        camera: Camera) -> list[np.ndarray]:
    """:func:`reach_proposals` of one target pixel ``uv`` (pixels, shape (2,)) and one arm
    (``side`` ``"r"`` or ``"l"``, its reach ``reach_m`` metres: :func:`arm_reach_m`), in its
    order: the tracker runs the pixels and arms on threads of their own."""
    ray = pixel_ray(camera, uv)
    shoulder = joints[JOINT_INDEX[f"{side}_shoulder"]]
    depths = [float(shoulder @ ray)]
    for fraction in REACH_FRACTIONS:
        depths += list(ray_sphere_depths(ray, shoulder, fraction * reach_m))
    return [reach_arm(pose, model.skeleton, side, t * ray) for t in depths if t > 0]


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


class LifterSource:
    """Whole-body proposals from 2D keypoints: the learned lifter's K hypotheses of the frame.

    The source owns the lifting: :meth:`lift` turns a frame's keypoints into the lifter's
    hypotheses (:meth:`mocap.track.lifter.Lifter.lift`: the calibrated body's forward
    kinematics, each hypothesis's root placed by the translation whose projection best fits the
    keypoints, its depth from the body's size and the keypoints' scale). The tracker lifts each
    frame once and hands the result to :meth:`propose` (in :attr:`ProposalContext.lifted`) and to
    its score (:meth:`energy`). :meth:`propose` proposes every hypothesis, most probable first;
    none without keypoints.

    Parameters
    ----------
    lifter : Lifter, optional
        The network (default: :meth:`Lifter.load` of ``path``, loaded at the first frame that is
        lifted; so a tracker that never sees keypoints never reads the file).
    path : str or Path, optional
        The lifter file read when ``lifter`` is not given (default: the shipped one).
    """

    origin: str = "lifter"

    def __init__(self, lifter: Lifter | None = None, path: str | Path | None = None) -> None:
        self._lifter = lifter
        self._path = path

    @property
    def lifter(self) -> Lifter:
        """The network (its file, by default the shipped one, is read here at first use)."""
        if self._lifter is None:
            self._lifter = Lifter.load(self._path)
        return self._lifter

    def lift(self, keypoints, camera: Camera, model: BodyModel) -> LiftedHypotheses | None:
        """The lifter's hypotheses of a frame's keypoints.

        Parameters
        ----------
        keypoints : Keypoints or None
            The frame's 2D keypoints in ``camera``'s pixels (:class:`mocap.io.keypoints.Keypoints`;
            a joint is present where its confidence is positive).
        camera : Camera
        model : BodyModel
            The calibrated actor.

        Returns
        -------
        LiftedHypotheses or None
            None without keypoints or with fewer than :data:`~mocap.track.lifter.MIN_VISIBLE`
            joints present.
        """
        if keypoints is None:
            return None
        present = np.asarray(keypoints.confidence) > 0
        if present.sum() < MIN_VISIBLE:
            return None
        uv = np.where(present[:, None], keypoints.uv, 0.0)
        return self.lifter.lift(uv, present, camera, model)

    def energy(self, lifted: LiftedHypotheses, joints: np.ndarray) -> float:
        """The lifter term of the score before its weight (nats): the lifter's log-density at its
        most probable hypothesis minus that at ``joints`` (10, 3; camera coordinates, metres), at
        most :data:`LIFTER_ENERGY_CAP` (far from every hypothesis the lifter has no say)."""
        return min(lifted.top_log_density - self.lifter.log_density(lifted, relative_joints(joints)), LIFTER_ENERGY_CAP)

    def propose(self, prepared, context: ProposalContext) -> list[Proposal]:
        """Every hypothesis of the frame's lifting, most probable first, then those of the
        swapped labelling's (:attr:`ProposalContext.lifted_swapped`), if any."""
        return [Proposal(np.array(q, dtype=np.float64), self.origin)
                for lifted in (context.lifted, context.lifted_swapped) if lifted is not None for q in lifted.poses]


#: The arm's joints a detector's 3D places, shoulder first (:func:`detector_arm_targets`).
_ARM_CHAIN = ("shoulder", "elbow", "wrist", "hand")


def detector_arm_targets(joints: np.ndarray, world: np.ndarray, side: str) -> np.ndarray | None:
    """Where one arm's elbow, wrist and hand go along the detector's 3D bones, from our shoulder.

    Each of our bones (shoulder-elbow, elbow-wrist, wrist-hand) keeps its length and takes the
    direction of the detector's; a missing hand takes the forearm's direction.

    Parameters
    ----------
    joints : ndarray, shape (10, 3), metres
        Our pose's joints (camera coordinates).
    world : ndarray, shape (10, 3), metres
        The detector's 3D joints (camera axes, its own origin; NaN where absent).
    side : {"r", "l"}

    Returns
    -------
    ndarray, shape (3, 3), metres, or None
        Camera coordinates of the elbow, wrist and hand; None where the detector lacks the
        shoulder, elbow or wrist, or gives a bone of no length.
    """
    chain = [JOINT_INDEX[f"{side}_{j}"] for j in _ARM_CHAIN]
    w = np.array(world[chain], dtype=np.float64)
    if not np.isfinite(w[:3]).all():
        return None
    if not np.isfinite(w[3]).all():
        w[3] = w[2] + (w[2] - w[1])
    bones = np.diff(w, axis=0)
    norms = np.linalg.norm(bones, axis=1)
    if not (norms > 1e-9).all():
        return None
    lengths = np.linalg.norm(np.diff(joints[chain], axis=0), axis=1)
    return joints[chain[0]] + np.cumsum(bones / norms[:, None] * lengths[:, None], axis=0)


@dataclass(frozen=True)
class DetectorArmsSource:
    """Proposals from the keypoint detector's own 3D arms (:attr:`mocap.io.keypoints.Keypoints.world`):
    on a frame whose detector shows the person's front (where its labels are right, issue 49),
    the beam leader's pose with each arm placed along the detector's bones
    (:func:`detector_arm_targets`, :func:`~mocap.body.ik.place_arm`), where the leader too faces
    the camera (its chest heading within 90 degrees of it): the detector's 3D of a front is not
    put on a torso facing away. Nothing elsewhere, and nothing without the detector's 3D."""

    model: BodyModel
    origin: str = "detector3d"

    def propose(self, prepared, context: ProposalContext) -> list[Proposal]:
        keypoints, pose = context.keypoints, context.pose
        if keypoints is None or pose is None or keypoints.world is None or not keypoints.shows_front():
            return []
        if np.cos(pose[PARAMETER_INDEX[HEADING]]) <= 0.0:
            return []
        joints = self.model.joint_positions(pose)
        q, placed = np.array(pose, dtype=np.float64), False
        for side in SIDES:
            targets = detector_arm_targets(joints, keypoints.world, side)
            if targets is not None:
                q, placed = place_arm(q, self.model.skeleton, side, targets).pose, True
        return [Proposal(q, self.origin)] if placed else []
