"""Per-frame two-step registration and tracking over a sequence (paper sections 3.2–3.3, 4, 5).

For every frame: the image side prepares the target (label image, edge distance map); the
**region step** minimises the non-overlapping ratio F(q) by bounded downhill simplex starting
from the predicted pose; the **edge step** minimises the mean edge distance starting from the
region step's final simplex (or, as an option for the paper's Fig. 8, from a fresh large
simplex). The per-frame evaluation budget is split between the two steps by a policy: ``auto``
is the paper's (below 200 evaluations all go to the region step, from 200 on 50/50) or an
explicit ``R:E``. A frame whose residual exceeds its threshold (a "peak") is a failure; the
tracker then retries once from the last good pose with a wider simplex and keeps the better of
the two results, recording what it did.

Beyond the paper, on by default (``hand_reacquisition``): a skin region of the image that the
registered model's hands and head leave unexplained is taken for a hand the tracker lost; each
arm is posed to reach it (inverse kinematics, :mod:`mocap.body.ik`), the frame is registered
again from the best such candidate, and the result is kept when its F is lower.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from mocap.body.ik import reach_arm
from mocap.body.model import BodyModel
from mocap.body.pose import JOINT_LIMITS, N_PARAMETERS, PARAMETER_INDEX, PARAMETER_NAMES, check_pose, clamp_to_limits
from mocap.body.skeleton import JOINT_NAMES
from mocap.config import JsonConfig
from mocap.cost import EdgeCost, RegionCost
from mocap.imaging.blobs import label_blobs
from mocap.labels import class_label
from mocap.optimize import SimplexResult, initial_simplex, minimize_cost
from mocap.render.camera import Camera

#: Total budget below which the ``auto`` policy gives every evaluation to the region step.
AUTO_SPLIT_THRESHOLD = 200
SPLIT_POLICIES = ("auto",)
EDGE_STARTS = ("region_simplex", "fresh")
PREDICTIONS = ("previous", "constant_velocity")
#: Row of each named joint in the joint arrays.
_JOINT = {name: i for i, name in enumerate(JOINT_NAMES)}


@dataclass(frozen=True)
class TrackerConfig(JsonConfig):
    """Settings of the registration (saved in ``run.json``; JSON with unknown keys rejected).

    Attributes
    ----------
    evaluations : int
        Cost evaluations per frame for both steps together (the paper's "iterations").
    split : str
        ``"auto"`` (paper's policy) or ``"R:E"``, e.g. ``"250:250"`` (scaled to ``evaluations``
        when they do not add up to it).
    edge_start : str
        ``"region_simplex"`` (paper) or ``"fresh"`` (a new simplex of ``fresh_step_scale``
        times the initial steps around the region step's best pose).
    prediction : str
        Start of each frame: ``"previous"`` pose or ``"constant_velocity"`` extrapolation.
    position_step_m : float, metres
        Initial simplex step of the three root coordinates.
    angle_step_deg : float, degrees
        Initial simplex step of the 20 angles. The paper gives no sizes; 20 degrees and 5 cm
        were chosen on the six synthetic sequences with three generator seeds each
        (``python -m experiments.ambiguity --seed S --config ...``): against 10 degrees and
        3 cm they lowered MPJPE on 13 of the 18 sequences (mean -27 mm); 5 degrees and 1.5 cm
        was worse everywhere, 30 and 45 degrees no better.
    fresh_step_scale : float
        Size of the fresh edge-step simplex relative to the initial steps.
    ftol : float
        Convergence: relative spread of the simplex values (the paper's test).
    adaptive : bool
        Dimension-adaptive Nelder–Mead coefficients instead of the standard ones.
    region_failure_threshold : float
        A frame with F above this is a region failure (F is in [0, 1]).
    edge_failure_threshold_px : float, pixels
        A frame with mean edge distance above this is an edge failure.
    recovery : bool
        Retry failed frames from the last good pose with a wider simplex.
    recovery_step_scale : float
        Size of the recovery simplex relative to the initial steps.
    mesh_resolution : int
        Mesh level of detail; 0 chooses it from the image size.
    edge_gap_m : float, metres
        Depth step that makes an occluding contour between parts.
    blocks : str
        ``"all"``: one simplex over the 23 parameters (the paper). ``"torso-arms"`` (beyond the
        paper): root, torso and head first, then each arm, each in its own smaller simplex with
        a share of the step's budget proportional to its size; lower-dimensional simplices
        converge in far fewer evaluations and one arm's error cannot leak into the others.
    arm_search : bool
        Beyond the paper: before the region step's arm blocks, score a coarse grid of arm
        postures (:data:`ARM_SEARCH_GRID_DEG`) with F and start the arm's simplex from the best
        one when it beats the predicted arm. Re-finds an arm lost after fast motion; the
        evaluations count against the region budget, and the search is skipped when the arm's
        share of it cannot pay for the grid and a simplex. Needs ``blocks="torso-arms"``.
    prior_weight_region, prior_weight_edge : float
        Weight of a temporal prior added to the region cost (F units) and to the edge cost
        (pixels) while optimising: ``weight * mean(((q - q_predicted) / sigma)**2)``. 0 (the
        default) is the paper's method; the reported residuals never include the prior.
        Beyond the paper: it keeps the weakly observed directions (depth above all) from
        drifting.
    prior_sigma_position_m, prior_sigma_angle_deg : float
        Expected frame-to-frame change of the root position (metres) and of the angles (degrees).
    pose_prior_weight, pose_prior_sigma_deg : float
        Beyond the paper: a weak prior pulling the 20 angles towards the neutral pose,
        ``weight * mean(((angle - neutral) / sigma)**2)``, added to both steps. It breaks the
        monocular forward/backward ties (an arm pointing back looks like one pointing sideways)
        in favour of common postures. 0 is the paper's method.
    posture_weight_region, posture_weight_edge : float
        Beyond the paper: weight (F units, pixels) of the arm posture penalty
        (:func:`mocap.body.posture.arm_behind_penalty`) added to the region and edge costs while
        optimising: elbows and wrists behind the chest plane by more than
        ``posture_margin_m`` cost ``((behind - margin) / posture_sigma_m)**2`` each. It settles
        the forward/backward tie of an arm in favour of the front, where people gesture.
        0 is the paper's method. The defaults, 0.02 and 0.2, lowered the median MPJPE over the
        six synthetic sequences on each of five generator seeds but one (seeds 0-4, 500
        evaluations, with hand re-acquisition: 111/126/117/108/105 mm against
        125/129/124/102/178 mm without the prior) and the error of 25 of the 30 sequences.
    posture_margin_m, posture_sigma_m : float, metres
        Free distance behind the shoulder, and the distance beyond it that costs the weight.
    hand_reacquisition : bool
        Beyond the paper: after a frame's registration, look for skin regions of the image
        that neither of the model's hands (nor its head) is near. For each one, pose either arm
        to reach it (:func:`mocap.body.ik.reach_arm`, hand on the camera ray through the region
        at the depths of :data:`REACQUISITION_REACH`), register again from the candidate of
        lowest F and keep the result when its F is lower. Re-finds an arm that a fast motion left
        behind, which the local simplex cannot; it runs only on frames with such a region.
    reacquisition_distance_px : float, pixels
        A skin region whose centroid is farther than this from both projected hand centres
        triggers re-acquisition.
    reacquisition_min_pixels : int, pixels
        Smaller skin regions are ignored (noise, slivers at boundaries).
    """

    evaluations: int = 500
    split: str = "auto"
    edge_start: str = "region_simplex"
    prediction: str = "previous"
    position_step_m: float = 0.05
    angle_step_deg: float = 20.0
    fresh_step_scale: float = 3.0
    ftol: float = 1e-3
    adaptive: bool = False
    region_failure_threshold: float = 0.45
    edge_failure_threshold_px: float = 4.0
    recovery: bool = True
    recovery_step_scale: float = 2.5
    mesh_resolution: int = 0
    edge_gap_m: float = 0.03
    blocks: str = "all"
    arm_search: bool = False
    prior_weight_region: float = 0.0
    prior_weight_edge: float = 0.0
    prior_sigma_position_m: float = 0.05
    prior_sigma_angle_deg: float = 15.0
    pose_prior_weight: float = 0.0
    pose_prior_sigma_deg: float = 45.0
    posture_weight_region: float = 0.02
    posture_weight_edge: float = 0.2
    posture_margin_m: float = 0.05
    posture_sigma_m: float = 0.1
    hand_reacquisition: bool = True
    reacquisition_distance_px: float = 6.0
    reacquisition_min_pixels: int = 2

    def __post_init__(self) -> None:
        if isinstance(self.evaluations, bool) or not isinstance(self.evaluations, int) or self.evaluations < 0:
            raise ValueError(f"evaluations must be a non-negative integer, got {self.evaluations!r}")
        split_budget(self.evaluations, self.split)          # validates the split
        if self.edge_start not in EDGE_STARTS:
            raise ValueError(f"edge_start must be one of {EDGE_STARTS}, got {self.edge_start!r}")
        block_indices(self.blocks)                           # validates the strategy
        if self.arm_search and self.blocks != "torso-arms":
            raise ValueError("arm_search needs blocks='torso-arms'")
        if self.prediction not in PREDICTIONS:
            raise ValueError(f"prediction must be one of {PREDICTIONS}, got {self.prediction!r}")
        for name in ("position_step_m", "angle_step_deg", "fresh_step_scale", "recovery_step_scale",
                     "edge_failure_threshold_px", "region_failure_threshold", "prior_sigma_position_m",
                     "prior_sigma_angle_deg", "pose_prior_sigma_deg", "posture_sigma_m",
                     "reacquisition_distance_px"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise ValueError(f"{name} must be a finite positive number, got {v!r}")
        if not (isinstance(self.ftol, (int, float)) and math.isfinite(self.ftol) and self.ftol >= 0):
            raise ValueError(f"ftol must be finite and non-negative, got {self.ftol!r}")
        if (isinstance(self.reacquisition_min_pixels, bool) or not isinstance(self.reacquisition_min_pixels, int)
                or self.reacquisition_min_pixels < 1):
            raise ValueError(f"reacquisition_min_pixels must be a positive integer, got {self.reacquisition_min_pixels!r}")
        if not isinstance(self.mesh_resolution, int) or self.mesh_resolution < 0:
            raise ValueError(f"mesh_resolution must be 0 (automatic) or a positive integer, got {self.mesh_resolution!r}")
        for name in ("edge_gap_m", "prior_weight_region", "prior_weight_edge", "pose_prior_weight",
                     "posture_weight_region", "posture_weight_edge", "posture_margin_m"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and non-negative, got {v!r}")

    def prior(self, centre: np.ndarray, weight: float) -> tuple[np.ndarray, np.ndarray] | None:
        """(centre, per-parameter weights) of the quadratic prior of a step, or None if there is none.

        The temporal prior (around ``centre``, the predicted pose, with ``weight``) and the pose
        prior (angles around the neutral pose) add up to one quadratic: its weights are the sum
        and its centre the weighted mean of theirs.
        """
        from mocap.body.pose import neutral_pose

        sigma = np.r_[np.full(3, self.prior_sigma_position_m),
                      np.full(N_PARAMETERS - 3, math.radians(self.prior_sigma_angle_deg))]
        w_time = weight / (N_PARAMETERS * sigma**2)
        w_pose = np.zeros(N_PARAMETERS)
        w_pose[3:] = self.pose_prior_weight / ((N_PARAMETERS - 3) * math.radians(self.pose_prior_sigma_deg) ** 2)
        total = w_time + w_pose
        if not total.any():
            return None
        neutral = neutral_pose()
        centre = np.asarray(centre, dtype=np.float64)
        mixed = np.where(total > 0, (w_time * centre + w_pose * neutral) / np.where(total > 0, total, 1.0), centre)
        return mixed, total

    def steps(self) -> np.ndarray:
        """Initial simplex steps, shape (23,): metres for the root, radians for the angles."""
        return np.r_[np.full(3, self.position_step_m), np.full(N_PARAMETERS - 3, math.radians(self.angle_step_deg))]


def split_budget(total: int, split: str) -> tuple[int, int]:
    """Split a per-frame evaluation budget between the region and the edge step.

    Parameters
    ----------
    total : int
        Evaluations per frame.
    split : str
        ``"auto"``: all to the region step below :data:`AUTO_SPLIT_THRESHOLD`, else half each
        (the paper's policy, section 5). ``"R:E"``: in that proportion (``"1:0"`` all region,
        ``"0:1"`` all edge); ``R + E`` need not equal ``total``.

    Returns
    -------
    (int, int)
        Region and edge evaluations, adding up to ``total``.
    """
    if split == "auto":
        if total < AUTO_SPLIT_THRESHOLD:
            return total, 0
        return total - total // 2, total // 2
    parts = split.split(":") if isinstance(split, str) else []
    try:
        r, e = (float(p) for p in parts)
    except ValueError:
        raise ValueError(f"split must be 'auto' or 'R:E' with two non-negative numbers, got {split!r}") from None
    if not (math.isfinite(r) and math.isfinite(e)) or r < 0 or e < 0 or r + e == 0:
        raise ValueError(f"split must be 'auto' or 'R:E' with two non-negative numbers not both 0, got {split!r}")
    region = int(round(total * r / (r + e)))
    return region, total - region


#: Parameter blocks of the ``"torso-arms"`` strategy: root, torso and head first, then each arm.
PARAMETER_BLOCKS: dict[str, tuple[tuple[str, ...], ...]] = {
    "all": (PARAMETER_NAMES,),
    "torso-arms": (
        tuple(n for n in PARAMETER_NAMES if n.startswith(("root_", "chest_", "head_"))),
        tuple(n for n in PARAMETER_NAMES if n.startswith("r_")),
        tuple(n for n in PARAMETER_NAMES if n.startswith("l_")),
    ),
}


#: TrackerConfig options of the paper's method: every option beyond the paper switched off
#: (``TrackerConfig(**PAPER_METHOD)``), so that their defaults never leak into a reproduction.
PAPER_METHOD = MappingProxyType({
    "prediction": "previous", "adaptive": False, "recovery": False, "blocks": "all", "arm_search": False,
    "prior_weight_region": 0.0, "prior_weight_edge": 0.0, "pose_prior_weight": 0.0,
    "posture_weight_region": 0.0, "posture_weight_edge": 0.0, "hand_reacquisition": False})


@dataclass(frozen=True)
class StepResult:
    """One registration step (region or edge) over one or more parameter blocks.

    Attributes
    ----------
    x : ndarray, shape (23,), float64
        Pose after the step (metres, radians).
    evaluations, iterations : int
        Summed over the blocks.
    converged : bool
        Every block stopped on the spread test.
    blocks : tuple of SimplexResult
        Each block's run; its ``simplex`` is in that block's parameters.
    """

    x: np.ndarray
    evaluations: int
    iterations: int
    converged: bool
    blocks: tuple[SimplexResult, ...]


@dataclass(frozen=True)
class Registration:
    """Result of registering the model on one prepared frame.

    Attributes
    ----------
    pose : ndarray, shape (23,), float64
        Metres and radians.
    region_residual : float
        F(pose), in [0, 1].
    edge_residual : float, pixels
        Mean edge distance at ``pose``.
    edge_residual_after_region : float, pixels
        Mean edge distance at the region step's result (the paper's Fig. 6 grey line).
    region : StepResult or None
    edge : StepResult or None
    """

    pose: np.ndarray
    region_residual: float
    edge_residual: float
    edge_residual_after_region: float
    region: StepResult | None
    edge: StepResult | None

    @property
    def evaluations(self) -> int:
        return sum(r.evaluations for r in (self.region, self.edge) if r is not None)


def block_indices(strategy: str) -> tuple[np.ndarray, ...]:
    """Parameter indices of each block of a block strategy (see :data:`PARAMETER_BLOCKS`)."""
    if strategy not in PARAMETER_BLOCKS:
        raise ValueError(f"blocks must be one of {tuple(PARAMETER_BLOCKS)}, got {strategy!r}")
    return tuple(np.array([PARAMETER_INDEX[n] for n in block]) for block in PARAMETER_BLOCKS[strategy])


def _block_budgets(total: int, blocks: tuple[np.ndarray, ...]) -> list[int]:
    """Split ``total`` evaluations over blocks in proportion to their simplex size (k + 1)."""
    sizes = np.array([len(b) + 1 for b in blocks], dtype=float)
    budgets = np.floor(total * sizes / sizes.sum()).astype(int)
    budgets[0] += total - budgets.sum()
    return budgets.tolist()


#: Arm postures tried by the arm search: shoulder flexion, abduction and elbow flexion (degrees).
ARM_SEARCH_GRID_DEG = {"shoulder_flex": (0.0, 60.0, 120.0, 170.0),
                       "shoulder_abd": (10.0, 60.0, 120.0),
                       "elbow_flex": (20.0, 100.0)}
#: Evaluations of one arm search (the grid and the current arm).
ARM_SEARCH_EVALUATIONS = 1 + int(np.prod([len(v) for v in ARM_SEARCH_GRID_DEG.values()]))


def _arm_candidates(side: str, x: np.ndarray) -> list[np.ndarray]:
    out = []
    for flex in ARM_SEARCH_GRID_DEG["shoulder_flex"]:
        for abd in ARM_SEARCH_GRID_DEG["shoulder_abd"]:
            for elbow in ARM_SEARCH_GRID_DEG["elbow_flex"]:
                q = x.copy()
                q[PARAMETER_INDEX[f"{side}_shoulder_flex"]] = math.radians(flex)
                q[PARAMETER_INDEX[f"{side}_shoulder_abd"]] = math.radians(abd)
                q[PARAMETER_INDEX[f"{side}_elbow_flex"]] = math.radians(elbow)
                out.append(q)
    return out


def _search_arm(cost, x: np.ndarray, block: np.ndarray) -> tuple[np.ndarray, int]:
    """Best of the arm grid and the current arm under ``cost``; returns (pose, evaluations)."""
    side = PARAMETER_NAMES[block[0]][0]
    best, best_f = x, cost.evaluate_unchecked(x)
    candidates = _arm_candidates(side, x)
    for q in candidates:
        f = cost.evaluate_unchecked(q)
        if f < best_f:
            best, best_f = q, f
    return best.copy(), len(candidates) + 1


def _run_step(cost, pose, simplices, budget, config, lower, upper, prior, posture_weight, blocks,
              arm_search=False) -> StepResult:
    x = pose.copy()
    runs = []
    searched = 0
    for block, block_budget, simplex in zip(blocks, _block_budgets(budget, blocks), simplices):
        if simplex is None:
            continue
        if (arm_search and PARAMETER_NAMES[block[0]][:2] in ("r_", "l_")
                and block_budget >= ARM_SEARCH_EVALUATIONS + len(block) + 1):
            x, used = _search_arm(cost, x, block)
            block_budget = max(block_budget - used, 0)
            searched += used
        res = minimize_cost(cost, simplex(x, block) if callable(simplex) else simplex, lower[block], upper[block],
                            budget=block_budget, ftol=config.ftol, adaptive=config.adaptive, prior=prior,
                            active=block, base=x,
                            posture=(posture_weight, config.posture_margin_m, config.posture_sigma_m))
        if res.evaluations > 0:
            x[block] = res.x
        runs.append(res)
    return StepResult(x, searched + sum(r.evaluations for r in runs), sum(r.iterations for r in runs),
                      all(r.converged for r in runs), tuple(runs))


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
    if "skin" not in model.class_names:
        return np.zeros((0, 2))
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


def register(region_cost: RegionCost, edge_cost: EdgeCost, start_pose, config: TrackerConfig, *,
             step_scale: float = 1.0, limits: np.ndarray = JOINT_LIMITS, prior_centre=None) -> Registration:
    """Two-step registration of one frame: region step, then edge step.

    Parameters
    ----------
    region_cost, edge_cost : RegionCost, EdgeCost
        Built from the frame's label image and distance map.
    start_pose : array_like, shape (23,)
        Where the region step's simplex starts (metres, radians).
    config : TrackerConfig
        Budget, split, simplex steps, edge-step start, parameter blocks, prior.
    step_scale : float
        Multiplies the initial simplex steps (wider for recovery).
    prior_centre : array_like, shape (23,), optional
        Centre of the temporal prior (default: ``start_pose``); used when the config's prior
        weights are not 0.

    Returns
    -------
    Registration
    """
    q0 = clamp_to_limits(check_pose(start_pose, name="start pose"), limits)
    prior_centre = q0 if prior_centre is None else check_pose(prior_centre, name="prior centre")
    lower, upper = limits[:, 0], limits[:, 1]
    n_region, n_edge = split_budget(config.evaluations, config.split)
    steps = config.steps() * step_scale
    blocks = block_indices(config.blocks)
    fresh = lambda scale: (lambda x, block: initial_simplex(x[block], steps[block] * scale, lower[block], upper[block]))
    pose = q0
    region = edge = None
    if n_region > 0:
        region = _run_step(region_cost, q0, [fresh(1.0)] * len(blocks), n_region, config, lower, upper,
                           config.prior(prior_centre, config.prior_weight_region), config.posture_weight_region,
                           blocks, config.arm_search)
        pose = region.x
    edge_after_region = edge_cost(pose)
    if n_edge > 0:
        if region is not None and config.edge_start == "region_simplex" and len(region.blocks) == len(blocks):
            simplices = [r.simplex for r in region.blocks]
        else:
            simplices = [fresh(config.fresh_step_scale)] * len(blocks)
        edge = _run_step(edge_cost, pose, simplices, n_edge, config, lower, upper,
                         config.prior(prior_centre, config.prior_weight_edge), config.posture_weight_edge, blocks)
        pose = edge.x
    return Registration(pose.copy(), region_cost(pose), edge_cost(pose), edge_after_region, region, edge)


@dataclass
class FrameResult:
    """What the tracker did on one frame (one row of ``poses.csv``).

    ``timings_ms`` has ``prepare``, ``region``, ``edge``, ``recovery`` (failure recovery and
    hand re-acquisition) and ``total`` (milliseconds; plus the image side's parts ``prepare_*``).
    """

    frame: int
    pose: np.ndarray
    joints: np.ndarray
    region_residual: float
    edge_residual: float
    edge_residual_after_region: float
    failed: bool
    empty: bool
    recovery: str
    evaluations: int
    region_iterations: int
    edge_iterations: int
    timings_ms: dict[str, float] = field(default_factory=dict)


class Tracker:
    """Tracks one actor frame after frame.

    Parameters
    ----------
    model : BodyModel
        The calibrated actor. Its mesh is used as is when ``config.mesh_resolution`` is 0, and
        rebuilt at that level of detail otherwise.
    camera : Camera
    config : TrackerConfig
    initial_pose : array_like, shape (23,)
        Pose in the first frame (from calibration).
    """

    def __init__(self, model: BodyModel, camera: Camera, config: TrackerConfig, initial_pose) -> None:
        if config.mesh_resolution and model.mesh.resolution != config.mesh_resolution:
            model = model.with_resolution(config.mesh_resolution)
        self.model, self.camera, self.config = model, camera, config
        q = clamp_to_limits(check_pose(initial_pose, name="initial pose"))
        self.history: list[np.ndarray] = [q]      # last accepted poses (at most two), most recent last
        self.last_good = q

    #: Accepted poses kept: the prediction needs the last two, nothing else does.
    HISTORY_LENGTH = 2

    def _accept(self, pose: np.ndarray) -> None:
        """Append an accepted pose, keeping only the last :attr:`HISTORY_LENGTH` (bounded memory)."""
        self.history.append(pose)
        del self.history[:-self.HISTORY_LENGTH]

    def predict(self) -> np.ndarray:
        """Start pose of the next frame (previous pose, or constant-velocity extrapolation)."""
        last = self.history[-1]
        if self.config.prediction == "constant_velocity" and len(self.history) >= 2:
            return clamp_to_limits(last + (last - self.history[-2]))
        return last.copy()

    def resume_from(self, poses: np.ndarray, last_good: np.ndarray) -> None:
        """Continue after frames already tracked (``poses`` (N, 23), most recent last)."""
        self.history = [check_pose(p) for p in poses[-2:]]
        self.last_good = check_pose(last_good)

    # -- streaming interface: what the video pipeline and resumable runs use ------------------
    def push(self, frame_index: int, prepared) -> list[FrameResult]:
        """Take one prepared frame; return the frames whose pose is now final (oldest first).

        A tracker that decodes with a lag returns nothing for the first frames and then one
        frame per call; :meth:`finish` returns the rest. Every frame pushed comes out exactly
        once, in order.
        """
        return [self.step(frame_index, prepared)]

    def finish(self) -> list[FrameResult]:
        """Frames still held back at the end of the video (oldest first)."""
        return []

    def state(self) -> dict[str, np.ndarray]:
        """Everything the next :meth:`push` depends on, as named arrays (exact, for resuming).

        Restoring it with :meth:`restore` on a tracker built with the same model, camera and
        config makes the following pushes give bit-identical results.
        """
        return {"history": np.array(self.history[-2:]), "last_good": np.array(self.last_good)}

    def restore(self, state: dict[str, np.ndarray]) -> None:
        """Continue from a :meth:`state` (see there)."""
        self.history = [check_pose(p) for p in np.asarray(state["history"])]
        self.last_good = check_pose(state["last_good"])

    def costs(self, prepared) -> tuple[RegionCost, EdgeCost]:
        """Region and edge costs of one prepared frame, for this tracker's model, camera and config."""
        return (RegionCost(prepared.labels, self.model, self.camera),
                EdgeCost(prepared.distance, self.model, self.camera, edge_gap=self.config.edge_gap_m))

    def step(self, frame_index: int, prepared) -> FrameResult:
        """Register the model on one prepared frame (a :class:`mocap.imaging.PreparedFrame`)."""
        cfg = self.config
        t0 = time.perf_counter()
        timings = {f"prepare_{k}": 1e3 * v for k, v in prepared.timings.items()}
        timings["prepare"] = sum(timings.values())
        if prepared.is_empty:
            pose = self.history[-1].copy()
            self._accept(pose)
            timings.update(region=0.0, edge=0.0, recovery=0.0)
            timings["total"] = timings["prepare"] + 1e3 * (time.perf_counter() - t0)
            return FrameResult(frame_index, pose, self.model.joint_positions(pose), math.nan, math.nan, math.nan,
                               False, True, "empty frame: pose kept", 0, 0, 0, timings)
        region_cost, edge_cost = self.costs(prepared)
        t1 = time.perf_counter()
        reg = register(region_cost, edge_cost, self.predict(), cfg)
        t2 = time.perf_counter()
        timings["region"] = 1e3 * (t2 - t1) * _share(reg.region, reg)
        timings["edge"] = 1e3 * (t2 - t1) - timings["region"]
        action = "none"
        failed = self._failed(reg)
        evaluations = reg.evaluations
        if failed and cfg.recovery:
            retry = register(region_cost, edge_cost, self.last_good, cfg, step_scale=cfg.recovery_step_scale)
            evaluations += retry.evaluations
            if not self._failed(retry):
                reg, failed, action = retry, False, "recovered from last good pose"
            elif retry.region_residual < reg.region_residual:
                reg, action = retry, "recovery tried: kept its lower F, still failing"
            else:
                action = "recovery tried: no better, still failing"
        if cfg.hand_reacquisition and cfg.evaluations > 0:
            reg, failed, action, used = self._reacquire(prepared, region_cost, edge_cost, reg, failed, action)
            evaluations += used
        timings["recovery"] = 1e3 * (time.perf_counter() - t2)
        self._accept(reg.pose)
        if not failed:
            self.last_good = reg.pose
        timings["total"] = timings["prepare"] + 1e3 * (time.perf_counter() - t0)
        return FrameResult(frame_index, reg.pose, self.model.joint_positions(reg.pose), reg.region_residual,
                           reg.edge_residual, reg.edge_residual_after_region, failed, False, action, evaluations,
                           reg.region.iterations if reg.region else 0, reg.edge.iterations if reg.edge else 0,
                           timings)

    def _reacquire(self, prepared, region_cost, edge_cost, reg: Registration, failed: bool, action: str):
        """Hand re-acquisition (see :class:`TrackerConfig`); returns (reg, failed, action, evaluations)."""
        joints = self.model.joint_positions(reg.pose)
        targets = unexplained_hands(prepared.labels, joints, self.model, self.camera, self.config)
        if len(targets) == 0:
            return reg, failed, action, 0
        proposals = reach_proposals(reg.pose, joints, targets, self.model, self.camera)
        if not proposals:
            return reg, failed, action, 0
        values = [region_cost.evaluate_unchecked(q) for q in proposals]
        retry = register(region_cost, edge_cost, proposals[int(np.argmin(values))], self.config)
        used = len(proposals) + retry.evaluations
        if retry.region_residual >= reg.region_residual:
            return reg, failed, action, used
        note = "hand re-acquired"
        return retry, self._failed(retry), note if action == "none" else f"{action}; {note}", used

    def _failed(self, reg: Registration) -> bool:
        cfg = self.config
        edge_checked = reg.edge is not None and reg.edge.evaluations > 0
        return bool(reg.region_residual > cfg.region_failure_threshold
                    or (edge_checked and reg.edge_residual > cfg.edge_failure_threshold_px))


def _share(part: StepResult | None, reg: Registration) -> float:
    """Fraction of the registration's evaluations spent in ``part`` (to apportion its time)."""
    if part is None or reg.evaluations == 0:
        return 0.0
    return part.evaluations / reg.evaluations


def track_prepared(prepared_frames, tracker: Tracker, *, first_index: int = 0, progress: bool = False,
                   description: str = "tracking") -> list[FrameResult]:
    """Track frames already prepared by :func:`mocap.imaging.prepare_frame` (in memory).

    Experiments reuse one image-side pass for many tracker settings this way.

    Parameters
    ----------
    prepared_frames : sequence of PreparedFrame
    tracker : Tracker
        Its state carries over from frame to frame (and from call to call).

    Returns
    -------
    list of FrameResult
    """
    from tqdm import tqdm

    out: list[FrameResult] = []
    for i, p in enumerate(tqdm(prepared_frames, desc=description, unit="frame", disable=not progress)):
        out += tracker.push(first_index + i, p)
    return out + tracker.finish()
