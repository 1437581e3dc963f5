"""Inverse kinematics: one arm's angles that put the hand at a 3D point (:func:`reach_arm`) or its
elbow, wrist and hand on three (:func:`place_arm`; the tracker's depth alternatives,
:mod:`mocap.track.branches`).

Stateless, like :mod:`mocap.body.kinematics`: the pose and the model data go in, a new pose
comes out. The tracker's hand re-acquisition (:mod:`mocap.track`) uses it to turn a hand seen
in the image (a point on a camera ray, at a chosen depth) into a candidate pose.

The solver is a bounded Levenberg–Marquardt on the four angles that place the hand (shoulder
flexion, abduction, rotation and elbow flexion; the forearm twist and the wrist stay as they
are), with a weak pull towards the starting angles that picks, among the many arm postures
reaching the point, one close to where the arm was.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mocap._numba import jit
from mocap.body.kinematics import (ARM_SIDES, Skeleton, apply_transforms_into, arm_transforms_into, joint_positions,
                                   segment_transforms_into)
from mocap.body.pose import JOINT_LIMITS, PARAMETER_INDEX, check_pose
from mocap.body.skeleton import JOINT_NAMES

#: Arm angles the solver moves, in the order of its internal vector.
REACH_PARAMETERS: tuple[str, ...] = ("shoulder_flex", "shoulder_abd", "shoulder_rot", "elbow_flex")
#: Residual scale of the hand position (metres): a 1 cm miss weighs as much as ``1 / sqrt(weight)``
#: radians of change.
REACH_SCALE_M = 0.01
#: Default weight of the pull towards the starting angles (per radian squared, in units of
#: ``REACH_SCALE_M`` squared).
REACH_REGULARIZATION = 0.0025
#: Levenberg–Marquardt iterations (each evaluates the arm five times).
REACH_ITERATIONS = 30
#: A hand this close to its target (metres) is taken as reached (no second start).
REACH_TOLERANCE_M = 0.01
#: Further starting postures of the reaching angles (shoulder flexion, abduction, rotation,
#: elbow flexion; degrees), tried in turn while the hand misses by more than
#: :data:`REACH_TOLERANCE_M`: the bounded solver can stall against a limit (a straight elbow
#: above all) from the current arm.
REACH_STARTS_DEG = ((45.0, 45.0, 0.0, 90.0), (120.0, 30.0, 0.0, 30.0), (0.0, 90.0, 45.0, 60.0),
                    (60.0, 0.0, -45.0, 120.0))


@jit
def _points(pose, offsets, side, segments, local, transforms, points):
    arm_transforms_into(pose, offsets, side, transforms)
    apply_transforms_into(transforms, segments, local, points)


@jit
def _reach(pose, offsets, side, segments, local, active, lower, upper, targets, scale, regularization,
           iterations):
    """Bounded Levenberg–Marquardt putting the body points ``(segments, local)`` of arm ``side``
    (0: right, 1: left; only the chest's and that arm's transforms are computed) on ``targets``
    (shape (k, 3)); returns the new pose (a copy of ``pose``)."""
    n = active.shape[0]
    k = targets.shape[0]
    q = pose.copy()
    start = np.empty(n)
    for i in range(n):
        start[i] = q[active[i]]
    transforms = np.empty((offsets.shape[0], 3, 4))
    point = np.empty((k, 3))
    m = 3 * k + n
    residual = np.empty(m)
    jac = np.empty((m, n))
    trial_res = np.empty(m)
    sqrt_reg = np.sqrt(regularization)

    def fill(qv, out):
        _points(qv, offsets, side, segments, local, transforms, point)
        for p in range(k):
            for r in range(3):
                out[3 * p + r] = (point[p, r] - targets[p, r]) / scale
        for i in range(n):
            out[3 * k + i] = sqrt_reg * (qv[active[i]] - start[i])

    fill(q, residual)
    cost = np.sum(residual ** 2)
    lam = 1e-2
    h = 1e-6
    for _ in range(iterations):
        for i in range(n):
            a_i = active[i]
            saved = q[a_i]
            q[a_i] = saved + h
            fill(q, trial_res)
            for r in range(m):
                jac[r, i] = (trial_res[r] - residual[r]) / h
            q[a_i] = saved
        jtj = jac.T @ jac
        g = jac.T @ residual
        improved = False
        for _try in range(8):
            a = jtj.copy()
            for i in range(n):
                a[i, i] += lam * (1.0 + jtj[i, i])
            step = np.linalg.solve(a, -g)
            trial = q.copy()
            for i in range(n):
                a_i = active[i]
                trial[a_i] = min(max(q[a_i] + step[i], lower[i]), upper[i])
            fill(trial, trial_res)
            trial_cost = np.sum(trial_res ** 2)
            if trial_cost < cost:
                q = trial
                residual[:] = trial_res
                cost = trial_cost
                lam = max(lam * 0.3, 1e-7)
                improved = True
                break
            lam *= 10.0
        if not improved:
            break
    return q


def reach_arm(pose, skeleton: Skeleton, side: str, target, *, regularization: float = REACH_REGULARIZATION,
              iterations: int = REACH_ITERATIONS, limits: np.ndarray = JOINT_LIMITS) -> np.ndarray:
    """Pose with one arm moved so that its hand centre is as close as it gets to ``target``.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Starting pose (metres, radians); everything but the four reaching angles of ``side``
        is kept.
    skeleton : Skeleton
        The actor's kinematic constants (``model.skeleton``).
    side : {"r", "l"}
        The actor's right or left arm.
    target : array_like, shape (3,), metres
        Camera coordinates of the point for the hand centre (the ``*_hand`` joint).
    regularization : float
        Weight of the pull towards the starting angles (see :data:`REACH_REGULARIZATION`);
        0 leaves the choice among reaching postures to the solver's path.
    iterations : int
        Levenberg–Marquardt iterations at most.
    limits : ndarray, shape (23, 2)
        Joint limits (radians); the result stays within them.

    Returns
    -------
    ndarray, shape (23,), float64
        When the point is out of reach, the arm points at it as far as the limits allow.
    """
    if side not in ("r", "l"):
        raise ValueError(f"side must be 'r' or 'l', got {side!r}")
    q = check_pose(pose)
    t = np.asarray(target, dtype=np.float64)
    if t.shape != (3,) or not np.all(np.isfinite(t)):
        raise ValueError(f"target must be 3 finite coordinates in metres, got {target!r}")
    if regularization < 0 or not np.isfinite(regularization):
        raise ValueError(f"regularization must be finite and non-negative, got {regularization!r}")
    active = np.array([PARAMETER_INDEX[f"{side}_{p}"] for p in REACH_PARAMETERS], dtype=np.int64)
    lower, upper = limits[active, 0].astype(np.float64), limits[active, 1].astype(np.float64)
    hand = JOINT_NAMES.index(f"{side}_hand")
    segment, local = skeleton.joint_segment[hand:hand + 1], skeleton.joint_local[hand:hand + 1]
    best, best_miss = None, np.inf
    for start in (q[active], *np.radians(REACH_STARTS_DEG)):
        s = q.copy()
        s[active] = np.clip(start, lower, upper)
        out = _reach(s, skeleton.offsets, ARM_SIDES.index(side), segment, local, active, lower, upper, t[None, :],
                     REACH_SCALE_M, float(regularization), int(iterations))
        miss = float(np.linalg.norm(joint_positions(out, skeleton)[hand] - t))
        if miss < best_miss:
            best, best_miss = out, miss
        if best_miss <= REACH_TOLERANCE_M:
            break
    return best


#: Arm angles :func:`place_arm` moves: all seven of one arm.
ARM_PARAMETERS: tuple[str, ...] = ("shoulder_flex", "shoulder_abd", "shoulder_rot", "elbow_flex",
                                   "forearm_twist", "wrist_flex", "wrist_dev")
#: The arm joints :func:`place_arm` puts on their targets, in its targets' order.
ARM_JOINTS: tuple[str, ...] = ("elbow", "wrist", "hand")
#: Default weight of :func:`place_arm`'s pull towards the starting angles (as
#: :data:`REACH_REGULARIZATION`): only decides what the three joints leave free.
PLACE_REGULARIZATION = 1e-4
#: :func:`place_arm` stops trying further starts once every joint is this close (metres).
PLACE_TOLERANCE_M = 0.002


@dataclass(frozen=True, kw_only=True)
class ArmPlacement:
    """One arm's elbow, wrist and hand put on 3D points (:func:`place_arm`).

    Attributes
    ----------
    pose : ndarray, shape (23,), float64
        The pose with that arm's seven angles changed (inside the joint limits).
    miss_m : float
        Largest distance of the three joints from their targets (metres); above
        :data:`PLACE_TOLERANCE_M` the limits (or the bone lengths) did not let the arm reach.
    """

    pose: np.ndarray
    miss_m: float


def _wrap(angle: float) -> float:
    """The same angle in (-pi, pi]."""
    return float(np.angle(np.exp(1j * angle)))


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _violation(values, lower, upper) -> float:
    v = np.asarray(values, dtype=np.float64)
    return float(np.sum(np.maximum(lower - v, 0.0) + np.maximum(v - upper, 0.0)))


#: Forearm twists (as fractions of its range) :func:`_arm_angles` tries when the start's twist
#: leaves the wrist's angles outside their limits.
_TWIST_STEPS = np.linspace(0.0, 1.0, 17)


def _arm_angles(q: np.ndarray, skeleton: Skeleton, side: str, targets: np.ndarray, limits: np.ndarray) -> np.ndarray:
    """The seven arm angles that put the elbow, wrist and hand on ``targets`` in closed form, each
    bone's direction taken from the targets (its length from the skeleton), clipped to the limits.

    The rotations are those of :func:`mocap.body.kinematics.segment_transforms_into`: the upper arm's
    axis fixes the shoulder's flexion and abduction (two solutions; the one inside the limits and
    nearest ``q`` wins), the forearm's the elbow's flexion and the shoulder's rotation, the hand's
    the wrist's flexion and deviation at the start's forearm twist (or the nearest twist that
    keeps them inside the limits).
    """
    k = 0 if side == "r" else 1
    m = 1.0 if k == 0 else -1.0
    base = 9 + 7 * k
    transforms = np.empty((skeleton.offsets.shape[0], 3, 4))
    segment_transforms_into(q, skeleton.offsets, transforms)
    chest, shoulder = transforms[0, :, :3], transforms[2 + 3 * k, :, 3]
    elbow, wrist, hand = targets
    upper = elbow - shoulder
    upper = upper / np.linalg.norm(upper)
    u = chest.T @ upper
    phi = float(np.arcsin(np.clip(-u[0], -1.0, 1.0)))
    options = [(_wrap(np.arctan2(-u[2], u[1])), _wrap(m * phi)),
               (_wrap(np.arctan2(u[2], -u[1])), _wrap(m * (np.pi - phi)))]
    fore = wrist - elbow
    fore = fore / np.linalg.norm(fore)
    bend = float(np.arccos(np.clip(upper @ fore, -1.0, 1.0)))
    lo, hi = limits[base:base + 3, 0], limits[base:base + 3, 1]
    shoulders = []
    for flex, abd in options:
        b = chest @ _rx(-flex) @ _rz(m * abd)
        v = b.T @ fore
        rot = m * float(np.arctan2(-v[0], -v[2])) if np.sin(bend) > 1e-6 else float(q[base + 2])
        angles = (flex, abd, rot)
        change = float(np.sum(np.abs(np.subtract(angles, q[base:base + 3]))))
        shoulders.append((round(_violation(angles, lo, hi), 9), change, angles, b))
    _, _, (flex, abd, rot), b = min(shoulders, key=lambda o: o[:2])
    c = b @ _ry(m * rot) @ _rx(-bend)
    palm = hand - wrist
    h = c.T @ (palm / np.linalg.norm(palm))
    lo, hi = limits[base + 5:base + 7, 0], limits[base + 5:base + 7, 1]
    t_lo, t_hi = limits[base + 4]

    twists = np.concatenate([[q[base + 4]], t_lo + _TWIST_STEPS * (t_hi - t_lo)])
    cos, sin = np.cos(m * twists), np.sin(m * twists)
    g = np.stack([cos * h[0] - sin * h[2], np.full_like(twists, h[1]), sin * h[0] + cos * h[2]], axis=1)
    wrists = np.stack([np.angle(np.exp(1j * np.arctan2(-g[:, 2], g[:, 1]))),
                       m * np.arcsin(np.clip(-g[:, 0], -1.0, 1.0))], axis=1)
    violation = np.round(np.sum(np.maximum(lo - wrists, 0.0) + np.maximum(wrists - hi, 0.0), axis=1), 9)
    best = np.lexsort((np.abs(twists - twists[0]), violation))[0]     # the start's twist when it fits
    twist, angles = twists[best], wrists[best]
    out = np.array([flex, abd, rot, bend, twist, *angles])
    return np.clip(out, limits[base:base + 7, 0], limits[base:base + 7, 1])


def place_arm(pose, skeleton: Skeleton, side: str, targets, *, regularization: float = PLACE_REGULARIZATION,
              iterations: int = REACH_ITERATIONS, limits: np.ndarray = JOINT_LIMITS,
              polish_within_m: float = np.inf) -> ArmPlacement:
    """Pose with one arm's seven angles moved so that its elbow, wrist and hand lie on ``targets``.

    First in closed form (each bone's direction gives its angles, clipped to the limits); when that
    misses by more than :data:`PLACE_TOLERANCE_M` (a limit was hit), a bounded Levenberg–Marquardt
    (the kernel of :func:`reach_arm`) on the three joints' positions from the closed form takes
    the arm as close as the limits allow; the closer of the two is returned. The torso, head and other arm are kept,
    so the shoulder stays where ``pose`` has it.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Starting pose (metres, radians).
    skeleton : Skeleton
        The actor's kinematic constants (``model.skeleton``).
    side : {"r", "l"}
        The actor's right or left arm.
    targets : array_like, shape (3, 3), metres
        Camera coordinates of the elbow, wrist and hand centre (:data:`ARM_JOINTS` order).
    regularization : float
        Weight of the pull towards the starting angles (see :data:`PLACE_REGULARIZATION`).
    iterations : int
        Levenberg–Marquardt iterations per start at most.
    limits : ndarray, shape (23, 2)
        Joint limits (radians); the result stays within them.
    polish_within_m : float, metres
        The Levenberg–Marquardt polish runs only when the closed form misses by at most this
        (a caller that prunes farther misses anyway saves its time).

    Returns
    -------
    ArmPlacement
    """
    if side not in ("r", "l"):
        raise ValueError(f"side must be 'r' or 'l', got {side!r}")
    q = check_pose(pose)
    t = np.asarray(targets, dtype=np.float64)
    if t.shape != (len(ARM_JOINTS), 3) or not np.all(np.isfinite(t)):
        raise ValueError(f"targets must be {len(ARM_JOINTS)} rows of 3 finite coordinates in metres, got {targets!r}")
    if regularization < 0 or not np.isfinite(regularization):
        raise ValueError(f"regularization must be finite and non-negative, got {regularization!r}")
    active = np.array([PARAMETER_INDEX[f"{side}_{p}"] for p in ARM_PARAMETERS], dtype=np.int64)
    lower, upper = limits[active, 0].astype(np.float64), limits[active, 1].astype(np.float64)
    rows = np.array([JOINT_NAMES.index(f"{side}_{j}") for j in ARM_JOINTS])
    segments, local = skeleton.joint_segment[rows], skeleton.joint_local[rows]
    closed = q.copy()
    closed[active] = _arm_angles(q, skeleton, side, t, limits)
    best = closed
    best_miss = float(np.max(np.linalg.norm(joint_positions(closed, skeleton)[rows] - t, axis=1)))
    if best_miss <= PLACE_TOLERANCE_M or best_miss > polish_within_m:
        return ArmPlacement(pose=best, miss_m=best_miss)
    out = _reach(closed, skeleton.offsets, ARM_SIDES.index(side), segments, local, active, lower, upper, t,
                 REACH_SCALE_M, float(regularization), int(iterations))
    miss = float(np.max(np.linalg.norm(joint_positions(out, skeleton)[rows] - t, axis=1)))
    if miss < best_miss:
        best, best_miss = out, miss
    return ArmPlacement(pose=best, miss_m=best_miss)


__all__ = ["ARM_JOINTS", "ARM_PARAMETERS", "ArmPlacement", "REACH_PARAMETERS", "place_arm", "reach_arm"]
