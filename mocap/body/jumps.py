"""Kinematic jumps: poses that look the same to one camera but differ in depth.

Sminchisescu & Triggs, *Kinematic jump processes for monocular 3D human tracking* (CVPR 2003):
under a pinhole camera the distal joint of a limb segment can sit at two depths on its camera
ray at the segment's length from the proximal joint — the two points where the ray meets the
sphere about the proximal joint. They are mirror images about the plane through the proximal
joint perpendicular to the ray, so reflecting the distal joint in that plane keeps its
projection exactly and changes its depth. A tracker that holds one branch can *jump* to the
other instead of hoping a local search crosses the ridge between them.

For an arm this gives (stateless: pose and skeleton in, new poses out):

* ``"forearm"``: the wrist reflected about the plane through the elbow perpendicular to the
  ray through the wrist (shoulder, elbow and wrist project where they did);
* ``"upper_arm"``: the elbow reflected about the plane through the shoulder perpendicular to
  the ray through the elbow, the wrist kept on its ray on the same side of the new elbow's
  nearest ray point as before (so the forearm keeps its own branch; impossible when the wrist's
  ray passes out of the forearm's reach of the new elbow);
* ``"both"``: one after the other.

The forearm twist and the wrist angles are kept; the four arm angles that place elbow and wrist
(shoulder flexion, abduction, rotation, elbow flexion) are solved in closed form
(:func:`arm_angles_for_points`). The torso's front/back mirror (:func:`torso_flip`) turns the
chest to the heading whose silhouette mirrors the current one about the image-plane direction,
swaps the arms' roles and re-poses each arm so its hand lies on the camera ray of the hand it
replaces.

The jumped poses are not clamped to the joint limits here; the tracker clamps and refines them.
"""
from __future__ import annotations

import math

import numpy as np

from mocap.body.ik import reach_arm
from mocap.body.kinematics import Skeleton, joint_positions, segment_transforms
from mocap.body.pose import JOINT_LIMITS, PARAMETER_INDEX, check_pose, clamp_to_limits
from mocap.body.skeleton import JOINT_INDEX, SEGMENT_NAMES

#: Names of the arm jumps, in the order :func:`arm_jumps` returns them.
ARM_JUMPS: tuple[str, ...] = ("upper_arm", "forearm", "both")
#: Sides of the body, as in the parameter names.
SIDES: tuple[str, ...] = ("r", "l")
_SEGMENT = {name: i for i, name in enumerate(SEGMENT_NAMES)}


def ray_sphere_depths(direction, centre, radius: float) -> np.ndarray:
    """Distances along a camera ray at which it meets a sphere.

    Parameters
    ----------
    direction : array_like, shape (3,)
        Unit direction of the ray from the camera centre (camera coordinates).
    centre : array_like, shape (3,), metres
    radius : float, metres

    Returns
    -------
    ndarray, shape (0,) or (2,), metres
        The two depths, nearest first, symmetric about ``direction @ centre``; empty when the
        ray misses the sphere.
    """
    d, c = np.asarray(direction, dtype=np.float64), np.asarray(centre, dtype=np.float64)
    mid = float(d @ c)
    disc = mid * mid - float(c @ c) + radius * radius
    if disc < 0.0:
        return np.zeros(0)
    half = math.sqrt(disc)
    return np.array([mid - half, mid + half])


def reflect_on_ray(point, pivot) -> np.ndarray:
    """Reflect ``point`` about the plane through ``pivot`` perpendicular to the ray through ``point``.

    Parameters
    ----------
    point, pivot : array_like, shape (3,), metres, camera coordinates

    Returns
    -------
    ndarray, shape (3,), metres
        On the same camera ray as ``point`` (same projection) and the same distance from
        ``pivot``: the ray's other crossing of the sphere about ``pivot``.
    """
    p, c = np.asarray(point, dtype=np.float64), np.asarray(pivot, dtype=np.float64)
    n = p / np.linalg.norm(p)
    return p - 2.0 * float((p - c) @ n) * n


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


#: The four arm angles :func:`arm_angles_for_points` sets.
ARM_ANGLES: tuple[str, ...] = ("shoulder_flex", "shoulder_abd", "shoulder_rot", "elbow_flex")
#: The angles whose limits choose between its two solutions for the kinematic jumps (the tracker's
#: measured behaviour: judging all four changed 17 % of random jumps and, on the unseen seed 17,
#: the default tracker's median from 115 to 145 mm).
JUMP_JUDGED_ANGLES: tuple[str, ...] = ("shoulder_flex", "shoulder_abd")


def arm_angles_for_points(pose, skeleton: Skeleton, side: str, elbow, wrist, *,
                          judged: tuple[str, ...] = JUMP_JUDGED_ANGLES) -> np.ndarray:
    """Pose with one arm's shoulder and elbow angles set to put its elbow and wrist at two points.

    Closed form, from the chain of :func:`mocap.body.kinematics.segment_transforms`: in the
    chest frame the upper arm's direction is ``(-sin b, cos b cos f, -cos b sin f)`` for
    flexion ``f`` and (mirrored) abduction ``b``, and the forearm's, in the frame of the upper
    arm before its rotation ``r``, is ``(-sin e sin r, cos e, -sin e cos r)`` for elbow flexion
    ``e``. Of the two solutions (flexion, abduction and with them the rotation) the one whose
    ``judged`` angles are inside the joint limits (else the one less outside, then the one nearer
    the current flexion and abduction) is taken; with a straight elbow the rotation is kept.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Metres and radians; everything but the four angles is kept.
    skeleton : Skeleton
    side : {"r", "l"}
    elbow, wrist : array_like, shape (3,), metres
        Targets in camera coordinates; they must be the segment lengths apart from the shoulder
        and from each other (as the jumps make them), else the directions are matched.
    judged : tuple of str
        Names among :data:`ARM_ANGLES` (without the side) whose joint limits decide between the
        two solutions (:data:`JUMP_JUDGED_ANGLES` for the jumps).

    Returns
    -------
    ndarray, shape (23,), float64
        Not clamped to the joint limits.
    """
    if side not in SIDES:
        raise ValueError(f"side must be one of {SIDES}, got {side!r}")
    q = check_pose(pose).copy()
    mirror = 1.0 if side == "r" else -1.0
    unknown = set(judged) - set(ARM_ANGLES)
    if unknown:
        raise ValueError(f"judged must name arm angles among {ARM_ANGLES}, got {sorted(unknown)}")
    names = {k: PARAMETER_INDEX[f"{side}_{k}"] for k in ARM_ANGLES}
    transforms = segment_transforms(q, skeleton)
    chest = transforms[_SEGMENT["chest"], :, :3]
    shoulder = transforms[_SEGMENT[f"{side}_upper_arm"], :, 3]
    u = chest.T @ _unit(np.asarray(elbow, dtype=np.float64) - shoulder)
    b1 = math.asin(max(-1.0, min(1.0, -u[0])))
    lim = JOINT_LIMITS
    candidates = []
    for b in (b1, math.pi - b1 if b1 >= 0 else -math.pi - b1):
        cb = math.cos(b)
        f = math.atan2(-u[2] / cb, u[1] / cb) if abs(cb) > 1e-12 else q[names["shoulder_flex"]]
        rx = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(-f), -math.sin(-f)], [0.0, math.sin(-f), math.cos(-f)]])
        rz = np.array([[math.cos(b), -math.sin(b), 0.0], [math.sin(b), math.cos(b), 0.0], [0.0, 0.0, 1.0]])
        w = (chest @ rx @ rz).T @ _unit(np.asarray(wrist, dtype=np.float64) - np.asarray(elbow, dtype=np.float64))
        e = math.acos(max(-1.0, min(1.0, w[1])))
        r = mirror * math.atan2(-w[0], -w[2]) if math.sin(e) > 1e-9 else q[names["shoulder_rot"]]
        candidates.append({"shoulder_flex": f, "shoulder_abd": mirror * b, "shoulder_rot": r, "elbow_flex": e})

    def badness(angles):
        outside = sum(max(0.0, lim[names[k], 0] - angles[k]) + max(0.0, angles[k] - lim[names[k], 1]) for k in judged)
        return outside, abs(angles["shoulder_flex"] - q[names["shoulder_flex"]]) + abs(
            angles["shoulder_abd"] - q[names["shoulder_abd"]])

    for k, v in min(candidates, key=badness).items():
        q[names[k]] = v
    return q


def arm_jumps(pose, skeleton: Skeleton, side: str) -> dict[str, np.ndarray]:
    """The depth branches of one arm other than the current one (see the module).

    Parameters
    ----------
    pose : array_like, shape (23,)
    skeleton : Skeleton
    side : {"r", "l"}

    Returns
    -------
    dict of str to ndarray, shape (23,)
        Keyed by :data:`ARM_JUMPS`; a jump that is impossible (the wrist's ray out of the
        forearm's reach of the new elbow) is left out. Not clamped to the joint limits.
    """
    q = check_pose(pose)
    joints = joint_positions(q, skeleton)
    s, e, w = (joints[JOINT_INDEX[f"{side}_{j}"]] for j in ("shoulder", "elbow", "wrist"))
    out = {}
    w_forearm = reflect_on_ray(w, e)
    out["forearm"] = arm_angles_for_points(q, skeleton, side, e, w_forearm)
    e_upper = reflect_on_ray(e, s)
    ray_w = _unit(w)
    forearm_length = float(np.linalg.norm(w - e))
    depths = ray_sphere_depths(ray_w, e_upper, forearm_length)
    if len(depths):
        near_side = float(ray_w @ w) < float(ray_w @ e)          # wrist nearer than the elbow's ray point
        w_upper = depths[0 if near_side else 1] * ray_w
        out["upper_arm"] = arm_angles_for_points(q, skeleton, side, e_upper, w_upper)
        out["both"] = arm_angles_for_points(q, skeleton, side, e_upper, reflect_on_ray(w_upper, e_upper))
    return {name: out[name] for name in ARM_JUMPS if name in out}


#: Parameters whose sign flips under the torso's front/back mirror (besides the chest heading).
_MIRRORED_SIGNS = ("chest_roll", "head_tilt", "head_turn")


def turned_mirror(pose) -> np.ndarray:
    """The torso's front/back mirror without re-posing: the body reflected through the plane
    facing the camera at its root (its silhouette under an orthographic camera is unchanged).

    The chest heading ``yaw`` becomes ``pi - yaw`` (or ``-pi - yaw``, whichever is nearer); the
    sideways lean and the head's tilt and turn change sign; each arm takes the other arm's angles.

    Parameters
    ----------
    pose : array_like, shape (23,)

    Returns
    -------
    ndarray, shape (23,), float64
        Inside the joint limits.
    """
    q = check_pose(pose)
    out = q.copy()
    yaw = q[PARAMETER_INDEX["chest_yaw"]]
    out[PARAMETER_INDEX["chest_yaw"]] = min((math.pi - yaw, -math.pi - yaw), key=lambda y: abs(y - yaw))
    for name in _MIRRORED_SIGNS:
        out[PARAMETER_INDEX[name]] = -q[PARAMETER_INDEX[name]]
    for name, i in PARAMETER_INDEX.items():
        if name.startswith("r_"):
            j = PARAMETER_INDEX["l_" + name[2:]]
            out[i], out[j] = q[j], q[i]
    return clamp_to_limits(out)


def torso_flip(pose, skeleton: Skeleton) -> np.ndarray:
    """The torso's front/back mirror: the heading seen the other way round, arms re-posed.

    :func:`turned_mirror`, then each arm is re-posed (:func:`mocap.body.ik.reach_arm`) towards
    the camera ray of the hand it replaces, at the depth the mirrored body gives it, when that
    brings the hand nearer. Under a pinhole camera a turned torso is not the mirror image of the
    original, so unlike the arm jumps this one keeps the projections only approximately (to a
    pixel or two at 160x120).

    Parameters
    ----------
    pose : array_like, shape (23,)
    skeleton : Skeleton

    Returns
    -------
    ndarray, shape (23,), float64
        Inside the joint limits.
    """
    q = check_pose(pose)
    old_hands = {side: joint_positions(q, skeleton)[JOINT_INDEX[f"{side}_hand"]] for side in SIDES}
    out = turned_mirror(q)
    mirrored_hands = joint_positions(out, skeleton)
    for side, other in (("r", "l"), ("l", "r")):
        hand = JOINT_INDEX[f"{side}_hand"]
        ray = _unit(old_hands[other])
        target = float(ray @ mirrored_hands[hand]) * ray
        moved = reach_arm(out, skeleton, side, target)
        miss = lambda pose: float(np.linalg.norm(joint_positions(pose, skeleton)[hand] - target))
        if miss(moved) < miss(out):             # the arm's limits may not let it reach the ray
            out = moved
    return out
