"""One frame's two-step registration (paper sections 3.2-3.3).

The **region step** minimises the non-overlapping ratio F(q) (eq. 1) by bounded downhill
simplex from a start pose; the **edge step** minimises the mean edge distance (eq. 2) starting
from the region step's final simplex (or, for the paper's Fig. 8, from a fresh large simplex).
The evaluation budget is split between the two by :func:`~mocap.track.config.split_budget`.
Given 2D keypoints, both steps add the keypoint distance (:class:`~mocap.cost.KeypointCost`) at
the weights of :meth:`~mocap.track.config.TrackerConfig.keypoint_step_weights`.

Beyond the paper (its stated future work), the **gradient step**
(``TrackerConfig.gradient_step``) refines the edge step's best pose by a compiled, bounded
Gauss–Newton (Levenberg–Marquardt) descent on the analytic gradient of eq. (2)
(:func:`~mocap.optimize.minimize_edge_gauss_newton`, :meth:`EdgeCost.gradient
<mocap.cost.EdgeCost.gradient>`), within the joint limits; it takes
:data:`~mocap.track.config.GRADIENT_SHARE` of the edge step's evaluations (one iteration is one
render, counted as one evaluation, and one more for F) and keeps, of every pose it evaluates and
the edge step's best, the one of lowest eq. (2) + :data:`~mocap.track.config.GRADIENT_REGION_WEIGHT`
F, accepting a step only when it lowers that score. Given keypoints it does not run (its score
has no keypoint term). Descending eq. (2) alone raised F and the frames over the residual
thresholds, and scipy's L-BFGS-B on the same gradient took 9x the simplex's time per frame:
docs/research-log.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mocap.body.pose import JOINT_LIMITS, check_pose, clamp_to_limits
from mocap.cost import EdgeCost, KeypointCost, RegionCost
from mocap.optimize import GaussNewtonResult, SimplexResult, initial_simplex, minimize_cost, minimize_edge_gauss_newton
from mocap.track.config import (EDGE_FAILURE_THRESHOLD_PX, FRESH_STEP_SCALE, GRADIENT_REGION_WEIGHT, GRADIENT_SCALE,
                                KEYPOINT_FAILURE_THRESHOLD_PX, REGION_FAILURE_THRESHOLD, TrackerConfig, gradient_budget, split_budget)


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
    region, edge : SimplexResult or None
        The two simplex runs (None when the step had no budget).
    keypoint_residual : float, pixels
        Keypoint distance at ``pose`` (NaN without keypoints).
    gradient : GaussNewtonResult or None
        The gradient step (None when it did not run).
    """

    pose: np.ndarray
    region_residual: float
    edge_residual: float
    edge_residual_after_region: float
    region: SimplexResult | None
    edge: SimplexResult | None
    keypoint_residual: float = float("nan")
    gradient: GaussNewtonResult | None = None

    @property
    def evaluations(self) -> int:
        return sum(r.evaluations for r in (self.region, self.edge, self.gradient) if r is not None)

    def failed(self, config: TrackerConfig) -> bool:
        """A residual peak. Without keypoints: F above its threshold, or (when the edge step ran)
        the edge distance. With keypoints: the keypoint distance above
        :data:`~mocap.track.config.KEYPOINT_FAILURE_THRESHOLD_PX`, or F and the edge distance at
        the pose (whether or not the edge step ran) both above theirs: a segmentation that gets
        the colours wrong no longer fails a pose that the keypoints and the edges place."""
        edge_checked = self.edge is not None and self.edge.evaluations > 0
        return failed_residuals(self.region_residual, self.edge_residual, self.keypoint_residual, edge_checked)


def failed_residuals(region: float, edge: float, keypoint: float, edge_checked: bool) -> bool:
    """The failure rule of :meth:`Registration.failed` on a pose's residuals: F (in [0, 1]), the
    edge distance and the keypoint distance (pixels; NaN without keypoints); ``edge_checked``:
    the edge step had a budget (without keypoints the edge distance counts only then)."""
    region_peak = region > REGION_FAILURE_THRESHOLD
    if math.isnan(keypoint):
        return bool(region_peak or (edge_checked and edge > EDGE_FAILURE_THRESHOLD_PX))
    return bool(keypoint > KEYPOINT_FAILURE_THRESHOLD_PX or (region_peak and edge > EDGE_FAILURE_THRESHOLD_PX))


def register(region_cost: RegionCost, edge_cost: EdgeCost, start_pose, config: TrackerConfig, *,
             evaluations: int | None = None, step_scale: float = 1.0,
             limits: np.ndarray = JOINT_LIMITS, keypoint_cost: KeypointCost | None = None) -> Registration:
    """Two-step registration of one frame: region step, then edge step.

    Parameters
    ----------
    region_cost, edge_cost : RegionCost, EdgeCost
        Built from the frame's label image and distance map.
    start_pose : array_like, shape (23,)
        Where the region step's simplex starts (metres, radians); clamped to ``limits``.
    config : TrackerConfig
        Split, simplex steps, edge-step start, convergence test.
    evaluations : int, optional
        Budget of both steps together (default ``config.evaluations``).
    step_scale : float
        Multiplies the initial simplex steps (wider for recovery).
    limits : ndarray, shape (23, 2)
    keypoint_cost : KeypointCost, optional
        The frame's keypoint distance, added into both steps (see the module).

    Returns
    -------
    Registration
    """
    q0 = clamp_to_limits(check_pose(start_pose, name="start pose"), limits)
    lower, upper = limits[:, 0], limits[:, 1]
    total = config.evaluations if evaluations is None else int(evaluations)
    n_region, n_edge = split_budget(total, config.split, keypoints=keypoint_cost is not None)
    n_gradient = gradient_budget(n_edge) if config.gradient_step and keypoint_cost is None else 0
    n_edge -= n_gradient
    steps = config.steps() * step_scale
    region_kw, edge_kw = config.keypoint_step_weights() if keypoint_cost is not None else (0.0, 0.0)
    pose = q0
    region = edge = None
    if n_region > 0:
        region = minimize_cost(region_cost, initial_simplex(q0, steps, lower, upper), lower, upper,
                               budget=n_region, ftol=config.ftol, keypoint_cost=keypoint_cost,
                               keypoint_weight=region_kw)
        if region.evaluations > 0:
            pose = region.x.copy()
    edge_after_region = edge_cost(pose)
    moved = False               # by the edge or gradient step: else the edge distance is edge_after_region
    if n_edge > 0:
        if region is not None and config.edge_start == "region_simplex":
            simplex = region.simplex
        else:
            simplex = initial_simplex(pose, steps * FRESH_STEP_SCALE, lower, upper)
        edge = minimize_cost(edge_cost, simplex, lower, upper, budget=n_edge, ftol=config.ftol,
                             keypoint_cost=keypoint_cost, keypoint_weight=edge_kw)
        if edge.evaluations > 0:
            pose, moved = edge.x.copy(), True
    gradient = None
    if n_gradient > 0:
        gradient = minimize_edge_gauss_newton(edge_cost, pose, lower, upper, budget=n_gradient,
                                              scale=steps * GRADIENT_SCALE, region_cost=region_cost,
                                              region_weight=GRADIENT_REGION_WEIGHT)
        pose, moved = gradient.x.copy(), True
    keypoint_residual = keypoint_cost(pose) if keypoint_cost is not None else float("nan")
    return Registration(pose.copy(), region_cost(pose), edge_cost(pose) if moved else edge_after_region,
                        edge_after_region, region, edge, keypoint_residual, gradient)
