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

import math
from dataclasses import dataclass

import numpy as np

from mocap._numba import jit
from mocap.body.kinematics import Skeleton, apply_transforms_into, segment_transforms_into, joint_positions
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
def _points(pose, offsets, segments, local, transforms, points):
    segment_transforms_into(pose, offsets, transforms)
    apply_transforms_into(transforms, segments, local, points)


@jit
def _reach(pose, offsets, segments, local, active, lower, upper, targets, scale, regularization,
           iterations):
    """Bounded Levenberg–Marquardt putting the body points ``(segments, local)`` on ``targets``
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
        _points(qv, offsets, segments, local, transforms, point)
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
        out = _reach(s, skeleton.offsets, segment, local, active, lower, upper, t[None, :], REACH_SCALE_M,
                     float(regularization), int(iterations))
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


#: Forearm twists (as fractions of its range) :func:`_arm_angles` tries when the start's twist
#: leaves the wrist's angles outside their limits.
_TWIST_STEPS = np.linspace(0.0, 1.0, 17)


@jit
def _wrap(angle):
    """The same angle in (-pi, pi] (radians)."""
    return math.atan2(math.sin(angle), math.cos(angle))


@jit
def _round9(x):
    """``x`` rounded to 9 decimals as NumPy rounds (scaled, rounded half to even, scaled back)."""
    return np.rint(x * 1e9) / 1e9


@jit
def _excess(value, lo, hi):
    """How far ``value`` lies outside ``[lo, hi]`` (0 inside)."""
    return max(lo - value, 0.0) + max(value - hi, 0.0)


@jit
def _rotate_x(r, a):
    """``r @ Rx(a)`` for a 3x3 ``r`` (a new array)."""
    c, s = math.cos(a), math.sin(a)
    out = np.empty((3, 3))
    for i in range(3):
        out[i, 0] = r[i, 0]
        out[i, 1] = r[i, 1] * c + r[i, 2] * s
        out[i, 2] = -r[i, 1] * s + r[i, 2] * c
    return out


@jit
def _rotate_y(r, a):
    """``r @ Ry(a)`` for a 3x3 ``r`` (a new array)."""
    c, s = math.cos(a), math.sin(a)
    out = np.empty((3, 3))
    for i in range(3):
        out[i, 0] = r[i, 0] * c - r[i, 2] * s
        out[i, 1] = r[i, 1]
        out[i, 2] = r[i, 0] * s + r[i, 2] * c
    return out


@jit
def _rotate_z(r, a):
    """``r @ Rz(a)`` for a 3x3 ``r`` (a new array)."""
    c, s = math.cos(a), math.sin(a)
    out = np.empty((3, 3))
    for i in range(3):
        out[i, 0] = r[i, 0] * c + r[i, 1] * s
        out[i, 1] = -r[i, 0] * s + r[i, 1] * c
        out[i, 2] = r[i, 2]
    return out


@jit
def _unit(a, b):
    """``(b - a) / |b - a|`` for 3-vectors."""
    d = np.empty(3)
    for r in range(3):
        d[r] = b[r] - a[r]
    n = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    for r in range(3):
        d[r] /= n
    return d


@jit
def _transposed_times(r, v):
    """``r.T @ v`` for a 3x3 ``r`` and a 3-vector."""
    out = np.empty(3)
    for j in range(3):
        out[j] = r[0, j] * v[0] + r[1, j] * v[1] + r[2, j] * v[2]
    return out


@jit
def _arm_angles(q, offsets, k, targets, limits, active, twist_steps, transforms):
    """The seven arm angles (radians, :data:`ARM_PARAMETERS` order, shape (7,)) that put the elbow,
    wrist and hand on ``targets`` (shape (3, 3), metres) in closed form, each bone's direction
    taken from the targets (its length from the skeleton), clipped to the limits; ``k``: 0 for
    the right arm, 1 for the left; ``active``: the arm's seven pose indices; ``transforms``:
    scratch of shape (segments, 3, 4).

    The rotations are those of :func:`mocap.body.kinematics.segment_transforms_into`: the upper arm's
    axis fixes the shoulder's flexion and abduction (two solutions; the one inside the limits and
    nearest ``q`` wins), the forearm's the elbow's flexion and the shoulder's rotation, the hand's
    the wrist's flexion and deviation at the start's forearm twist (or the nearest twist of
    ``twist_steps``, fractions of its range, that keeps them inside the limits).
    """
    m = 1.0 if k == 0 else -1.0
    segment_transforms_into(q, offsets, transforms)
    chest = transforms[0, :, :3]
    shoulder = transforms[2 + 3 * k, :, 3]
    upper = _unit(shoulder, targets[0])
    u = _transposed_times(chest, upper)
    phi = math.asin(min(max(-u[0], -1.0), 1.0))
    fore = _unit(targets[0], targets[1])
    bend = math.acos(min(max(upper[0] * fore[0] + upper[1] * fore[1] + upper[2] * fore[2], -1.0), 1.0))
    best_violation, best_change = np.inf, np.inf
    flex = abd = rot = 0.0
    b = np.empty((3, 3))
    for option in range(2):         # the two shoulder solutions, the first kept on a tie
        if option == 0:
            f, a = _wrap(math.atan2(-u[2], u[1])), _wrap(m * phi)
        else:
            f, a = _wrap(math.atan2(u[2], -u[1])), _wrap(m * (np.pi - phi))
        bo = _rotate_z(_rotate_x(chest, -f), m * a)
        v = _transposed_times(bo, fore)
        r = m * math.atan2(-v[0], -v[2]) if math.sin(bend) > 1e-6 else q[active[2]]
        change = abs(f - q[active[0]]) + abs(a - q[active[1]]) + abs(r - q[active[2]])
        violation = _round9(_excess(f, limits[active[0], 0], limits[active[0], 1])
                            + _excess(a, limits[active[1], 0], limits[active[1], 1])
                            + _excess(r, limits[active[2], 0], limits[active[2], 1]))
        if violation < best_violation or (violation == best_violation and change < best_change):
            best_violation, best_change = violation, change
            flex, abd, rot = f, a, r
            b[:, :] = bo
    c = _rotate_x(_rotate_y(b, m * rot), -bend)
    h = _transposed_times(c, _unit(targets[1], targets[2]))
    t_lo, t_hi = limits[active[4], 0], limits[active[4], 1]
    twist = w_flex = w_dev = 0.0
    best_violation, best_change = np.inf, np.inf
    for i in range(twist_steps.shape[0] + 1):     # the start's twist first, then the steps
        t = q[active[4]] if i == 0 else t_lo + twist_steps[i - 1] * (t_hi - t_lo)
        cos, sin = math.cos(m * t), math.sin(m * t)
        g0, g1, g2 = cos * h[0] - sin * h[2], h[1], sin * h[0] + cos * h[2]
        wf = _wrap(math.atan2(-g2, g1))
        wd = m * math.asin(min(max(-g0, -1.0), 1.0))
        violation = _round9(_excess(wf, limits[active[5], 0], limits[active[5], 1])
                            + _excess(wd, limits[active[6], 0], limits[active[6], 1]))
        change = abs(t - q[active[4]])
        if violation < best_violation or (violation == best_violation and change < best_change):
            best_violation, best_change = violation, change
            twist, w_flex, w_dev = t, wf, wd
    out = np.array([flex, abd, rot, bend, twist, w_flex, w_dev])
    for i in range(7):
        out[i] = min(max(out[i], limits[active[i], 0]), limits[active[i], 1])
    return out


@jit
def _largest_miss(pose, offsets, segments, local, targets, transforms, points):
    """Largest distance (metres) of the body points ``(segments, local)`` of ``pose`` from
    ``targets`` (shape (k, 3), metres)."""
    _points(pose, offsets, segments, local, transforms, points)
    worst = -np.inf
    for p in range(targets.shape[0]):
        dx, dy, dz = points[p, 0] - targets[p, 0], points[p, 1] - targets[p, 1], points[p, 2] - targets[p, 2]
        worst = max(worst, math.sqrt(dx * dx + dy * dy + dz * dz))
    return worst


@jit
def _place(pose, offsets, segments, local, k, targets, limits, active, twist_steps, regularization, iterations,
           tolerance, polish_within):
    """:func:`place_arm` past its checks: the closed form (:func:`_arm_angles`), then the
    Levenberg–Marquardt polish (:func:`_reach`) when the closed form misses by more than
    ``tolerance`` and at most ``polish_within`` (metres). Returns the pose (shape (23,), float64)
    and its largest miss (metres)."""
    transforms = np.empty((offsets.shape[0], 3, 4))
    points = np.empty((targets.shape[0], 3))
    closed = pose.copy()
    angles = _arm_angles(pose, offsets, k, targets, limits, active, twist_steps, transforms)
    for i in range(active.shape[0]):
        closed[active[i]] = angles[i]
    miss = _largest_miss(closed, offsets, segments, local, targets, transforms, points)
    if miss <= tolerance or miss > polish_within:
        return closed, miss
    lower, upper = np.empty(active.shape[0]), np.empty(active.shape[0])
    for i in range(active.shape[0]):
        lower[i], upper[i] = limits[active[i], 0], limits[active[i], 1]
    out = _reach(closed, offsets, segments, local, active, lower, upper, targets, REACH_SCALE_M, regularization,
                 iterations)
    polished = _largest_miss(out, offsets, segments, local, targets, transforms, points)
    if polished < miss:
        return out, polished
    return closed, miss


def place_arm(pose, skeleton: Skeleton, side: str, targets, *, regularization: float = PLACE_REGULARIZATION,
              iterations: int = REACH_ITERATIONS, limits: np.ndarray = JOINT_LIMITS,
              polish_within_m: float = np.inf) -> ArmPlacement:
    """Pose with one arm's seven angles moved so that its elbow, wrist and hand lie on ``targets``.

    First in closed form (each bone's direction gives its angles, clipped to the limits); when that
    misses by more than :data:`PLACE_TOLERANCE_M` (a limit was hit), a bounded Levenberg–Marquardt
    (the kernel of :func:`reach_arm`) on the three joints' positions from the closed form takes
    the arm as close as the limits allow; the closer of the two is returned. The torso, head and other arm are kept,
    so the shoulder stays where ``pose`` has it. Both run in one compiled kernel; its slow twin
    is ``tests/naive.py``'s ``naive_place_arm``.

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
    limits = np.ascontiguousarray(limits, dtype=np.float64)
    if limits.shape != (len(q), 2):
        raise ValueError(f"limits must have shape ({len(q)}, 2), got {limits.shape}")
    active = np.array([PARAMETER_INDEX[f"{side}_{p}"] for p in ARM_PARAMETERS], dtype=np.int64)
    rows = np.array([JOINT_NAMES.index(f"{side}_{j}") for j in ARM_JOINTS])
    segments, local = skeleton.joint_segment[rows], skeleton.joint_local[rows]
    out, miss = _place(q, skeleton.offsets, segments, local, 0 if side == "r" else 1, np.ascontiguousarray(t), limits,
                       active, _TWIST_STEPS, float(regularization), int(iterations), PLACE_TOLERANCE_M,
                       float(polish_within_m))
    return ArmPlacement(pose=out, miss_m=float(miss))


__all__ = ["ARM_JOINTS", "ARM_PARAMETERS", "ArmPlacement", "REACH_PARAMETERS", "place_arm", "reach_arm"]
