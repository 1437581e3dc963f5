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
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from mocap.body.model import BodyModel
from mocap.body.pose import JOINT_LIMITS, N_PARAMETERS, check_pose, clamp_to_limits
from mocap.config import JsonConfig
from mocap.cost import EdgeCost, RegionCost
from mocap.optimize import SimplexResult, initial_simplex, minimize_cost
from mocap.render.camera import Camera

#: Total budget below which the ``auto`` policy gives every evaluation to the region step.
AUTO_SPLIT_THRESHOLD = 200
SPLIT_POLICIES = ("auto",)
EDGE_STARTS = ("region_simplex", "fresh")
PREDICTIONS = ("previous", "constant_velocity")


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
        Initial simplex step of the 20 angles.
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
    """

    evaluations: int = 500
    split: str = "auto"
    edge_start: str = "region_simplex"
    prediction: str = "previous"
    position_step_m: float = 0.03
    angle_step_deg: float = 10.0
    fresh_step_scale: float = 3.0
    ftol: float = 1e-3
    adaptive: bool = False
    region_failure_threshold: float = 0.45
    edge_failure_threshold_px: float = 4.0
    recovery: bool = True
    recovery_step_scale: float = 2.5
    mesh_resolution: int = 0
    edge_gap_m: float = 0.03

    def __post_init__(self) -> None:
        if isinstance(self.evaluations, bool) or not isinstance(self.evaluations, int) or self.evaluations < 0:
            raise ValueError(f"evaluations must be a non-negative integer, got {self.evaluations!r}")
        split_budget(self.evaluations, self.split)          # validates the split
        if self.edge_start not in EDGE_STARTS:
            raise ValueError(f"edge_start must be one of {EDGE_STARTS}, got {self.edge_start!r}")
        if self.prediction not in PREDICTIONS:
            raise ValueError(f"prediction must be one of {PREDICTIONS}, got {self.prediction!r}")
        for name in ("position_step_m", "angle_step_deg", "fresh_step_scale", "recovery_step_scale",
                     "edge_failure_threshold_px", "region_failure_threshold"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise ValueError(f"{name} must be a finite positive number, got {v!r}")
        if not (isinstance(self.ftol, (int, float)) and math.isfinite(self.ftol) and self.ftol >= 0):
            raise ValueError(f"ftol must be finite and non-negative, got {self.ftol!r}")
        if not isinstance(self.mesh_resolution, int) or self.mesh_resolution < 0:
            raise ValueError(f"mesh_resolution must be 0 (automatic) or a positive integer, got {self.mesh_resolution!r}")
        if not (isinstance(self.edge_gap_m, (int, float)) and math.isfinite(self.edge_gap_m) and self.edge_gap_m >= 0):
            raise ValueError(f"edge_gap_m must be finite and non-negative, got {self.edge_gap_m!r}")

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
    region : SimplexResult or None
    edge : SimplexResult or None
    """

    pose: np.ndarray
    region_residual: float
    edge_residual: float
    edge_residual_after_region: float
    region: SimplexResult | None
    edge: SimplexResult | None

    @property
    def evaluations(self) -> int:
        return sum(r.evaluations for r in (self.region, self.edge) if r is not None)


def register(region_cost: RegionCost, edge_cost: EdgeCost, start_pose, config: TrackerConfig, *,
             step_scale: float = 1.0, limits: np.ndarray = JOINT_LIMITS) -> Registration:
    """Two-step registration of one frame: region step, then edge step.

    Parameters
    ----------
    region_cost, edge_cost : RegionCost, EdgeCost
        Built from the frame's label image and distance map.
    start_pose : array_like, shape (23,)
        Where the region step's simplex starts (metres, radians).
    config : TrackerConfig
        Budget, split, simplex steps, edge-step start.
    step_scale : float
        Multiplies the initial simplex steps (wider for recovery).

    Returns
    -------
    Registration
    """
    q0 = clamp_to_limits(check_pose(start_pose, name="start pose"), limits)
    lower, upper = limits[:, 0], limits[:, 1]
    n_region, n_edge = split_budget(config.evaluations, config.split)
    steps = config.steps() * step_scale
    pose = q0
    region = edge = None
    if n_region > 0:
        region = minimize_cost(region_cost, initial_simplex(q0, steps, lower, upper), lower, upper,
                               budget=n_region, ftol=config.ftol, adaptive=config.adaptive)
        pose = region.x
    edge_after_region = edge_cost(pose)
    if n_edge > 0:
        if region is not None and config.edge_start == "region_simplex":
            simplex = region.simplex
        else:
            simplex = initial_simplex(pose, steps * config.fresh_step_scale, lower, upper)
        edge = minimize_cost(edge_cost, simplex, lower, upper, budget=n_edge, ftol=config.ftol,
                             adaptive=config.adaptive)
        if edge.evaluations > 0:
            pose = edge.x
    return Registration(pose.copy(), region_cost(pose), edge_cost(pose), edge_after_region, region, edge)


@dataclass
class FrameResult:
    """What the tracker did on one frame (one row of ``poses.csv``).

    ``timings_ms`` has ``prepare``, ``region``, ``edge``, ``recovery`` and ``total``
    (milliseconds; plus the image side's parts ``prepare_*``).
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
        The calibrated actor (its mesh level of detail is used as is).
    camera : Camera
    config : TrackerConfig
    initial_pose : array_like, shape (23,)
        Pose in the first frame (from calibration).
    """

    def __init__(self, model: BodyModel, camera: Camera, config: TrackerConfig, initial_pose) -> None:
        self.model, self.camera, self.config = model, camera, config
        q = clamp_to_limits(check_pose(initial_pose, name="initial pose"))
        self.history: list[np.ndarray] = [q]      # accepted poses, most recent last
        self.last_good = q

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

    def step(self, frame_index: int, prepared) -> FrameResult:
        """Register the model on one prepared frame (a :class:`mocap.imaging.PreparedFrame`)."""
        cfg = self.config
        t0 = time.perf_counter()
        timings = {f"prepare_{k}": 1e3 * v for k, v in prepared.timings.items()}
        timings["prepare"] = sum(timings.values())
        if prepared.is_empty:
            pose = self.history[-1].copy()
            self.history.append(pose)
            timings.update(region=0.0, edge=0.0, recovery=0.0)
            timings["total"] = timings["prepare"] + 1e3 * (time.perf_counter() - t0)
            return FrameResult(frame_index, pose, self.model.joint_positions(pose), math.nan, math.nan, math.nan,
                               False, True, "empty frame: pose kept", 0, 0, 0, timings)
        region_cost = RegionCost(prepared.labels, self.model, self.camera)
        edge_cost = EdgeCost(prepared.distance, self.model, self.camera, edge_gap=cfg.edge_gap_m)
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
        timings["recovery"] = 1e3 * (time.perf_counter() - t2)
        self.history.append(reg.pose)
        if not failed:
            self.last_good = reg.pose
        timings["total"] = timings["prepare"] + 1e3 * (time.perf_counter() - t0)
        return FrameResult(frame_index, reg.pose, self.model.joint_positions(reg.pose), reg.region_residual,
                           reg.edge_residual, reg.edge_residual_after_region, failed, False, action, evaluations,
                           reg.region.iterations if reg.region else 0, reg.edge.iterations if reg.edge else 0,
                           timings)

    def _failed(self, reg: Registration) -> bool:
        cfg = self.config
        edge_checked = reg.edge is not None and reg.edge.evaluations > 0
        return bool(reg.region_residual > cfg.region_failure_threshold
                    or (edge_checked and reg.edge_residual > cfg.edge_failure_threshold_px))


def _share(part: SimplexResult | None, reg: Registration) -> float:
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

    return [tracker.step(first_index + i, p)
            for i, p in enumerate(tqdm(prepared_frames, desc=description, unit="frame", disable=not progress))]
