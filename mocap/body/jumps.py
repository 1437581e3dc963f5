"""Kinematic jumps: poses that look the same to one camera but differ in depth.

Sminchisescu & Triggs, *Kinematic jump processes for monocular 3D human tracking* (CVPR 2003):
under a pinhole camera the distal joint of a limb segment can sit at two depths on its camera
ray at the segment's length from the proximal joint — the two points where the ray meets the
sphere about the proximal joint. They are mirror images about the plane through the proximal
joint perpendicular to the ray, so reflecting the distal joint in that plane keeps its
projection exactly and changes its depth. A tracker that holds one branch can *jump* to the
other instead of hoping a local search crosses the ridge between them.

The geometry is :func:`flipped_arm_joints` (also the tracker's exact depth alternatives,
:mod:`mocap.track.branches`). For an arm this gives (stateless: pose and skeleton in, new poses out):

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
from mocap.body.pose import HEADING, JOINT_LIMITS, PARAMETER_INDEX, check_pose, clamp_to_limits, nearest_heading
from mocap.body.skeleton import JOINT_INDEX, SEGMENT_NAMES

#: Names of the arm jumps, in the order :func:`arm_jumps` returns them.
ARM_JUMPS: tuple[str, ...] = ("upper_arm", "forearm", "both")
#: The bones (:data:`ARM_BONES` names) each arm jump flips (:func:`flipped_arm_joints`).
_JUMP_BONES: dict[str, tuple[str, ...]] = {"upper_arm": ("upper_arm",), "forearm": ("forearm",),
                                           "both": ("upper_arm", "forearm")}
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


#: An arm's bones in chain order, each with its parent and child joint (:data:`JOINT_INDEX` names
#: without the side).
ARM_BONES: tuple[tuple[str, str, str], ...] = (("upper_arm", "shoulder", "elbow"), ("forearm", "elbow", "wrist"),
                                               ("hand", "wrist", "hand"))


def flipped_arm_joints(joints, side: str, flipped) -> np.ndarray:
    """The joints with some of one arm's bones taken to their other depth branch (exact geometry).

    Going down the arm (:data:`ARM_BONES`), each child joint is put on its own camera ray (the ray
    from the camera centre through its current position) at its bone's length from its parent's
    new position (:func:`ray_sphere_depths`): on the other crossing than now for a flipped bone,
    on the same one (nearer or farther than the ray's closest point to the parent) for the others.
    For a flipped bone whose parent did not move, that is the child reflected about the plane
    through the parent perpendicular to the child's ray. Where the moved parent leaves the ray out
    of the bone's reach, the child goes to the ray's closest point to the parent (its bone length
    then changes: :func:`arm_jumps` drops such a jump, and
    :func:`mocap.track.branches.depth_alternatives` prunes it by its projection).

    Parameters
    ----------
    joints : array_like, shape (10, 3), metres
        Camera coordinates of the joints (:data:`~mocap.body.skeleton.JOINT_NAMES` order), z > 0.
    side : {"r", "l"}
    flipped : iterable of str
        Bone names of :data:`ARM_BONES`.

    Returns
    -------
    ndarray, shape (10, 3), float64
        Only ``side``'s elbow, wrist and hand rows change.
    """
    return _flip_chain(joints, side, flipped)[0]


def _flip_chain(joints, side: str, flipped) -> tuple[np.ndarray, frozenset[str]]:
    """:func:`flipped_arm_joints`, and the bones whose child's ray missed the bone's sphere."""
    if side not in SIDES:
        raise ValueError(f"side must be 'r' or 'l', got {side!r}")
    flips = set(flipped)
    unknown = flips - {b for b, _, _ in ARM_BONES}
    if unknown:
        raise ValueError(f"unknown bones {sorted(unknown)}; the arm's bones are {[b for b, _, _ in ARM_BONES]}")
    old = np.asarray(joints, dtype=np.float64)
    if old.shape != (len(JOINT_INDEX), 3) or not np.all(np.isfinite(old)) or np.any(old[:, 2] <= 0):
        raise ValueError(f"joints must be ({len(JOINT_INDEX)}, 3) finite points in front of the camera")
    new = old.copy()
    missed = set()
    for bone, parent_name, child_name in ARM_BONES:
        parent, child = JOINT_INDEX[f"{side}_{parent_name}"], JOINT_INDEX[f"{side}_{child_name}"]
        length = float(np.linalg.norm(old[child] - old[parent]))
        distance = float(np.linalg.norm(old[child]))
        ray = old[child] / distance
        far = distance >= float(ray @ old[parent])           # the child beyond the ray's closest point
        if bone in flips:
            far = not far
        depths = ray_sphere_depths(ray, new[parent], length)
        if len(depths):
            new[child] = depths[1 if far else 0] * ray
        else:
            missed.add(bone)
            new[child] = float(ray @ new[parent]) * ray
    return new, frozenset(missed)


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
    elbow, wrist = JOINT_INDEX[f"{side}_elbow"], JOINT_INDEX[f"{side}_wrist"]
    out = {}
    for name, bones in _JUMP_BONES.items():
        moved, missed = _flip_chain(joints, side, bones)
        if name == "forearm" or not missed & {"upper_arm", "forearm"}:   # (the forearm's flip keeps the elbow)
            out[name] = arm_angles_for_points(q, skeleton, side, moved[elbow], moved[wrist])
    return {name: out[name] for name in ARM_JUMPS if name in out}


#: Parameters whose sign flips under the torso's front/back mirror (besides the chest heading).
_MIRRORED_SIGNS = ("chest_roll", "head_tilt", "head_turn")


def turned_mirror(pose) -> np.ndarray:
    """The torso's front/back mirror without re-posing: the body reflected through the plane
    facing the camera at its root (its silhouette under an orthographic camera is unchanged).

    The chest heading ``yaw`` becomes the 2π-equivalent of ``pi - yaw`` nearest ``yaw``
    (:func:`mocap.body.pose.nearest_heading`: the turned body continues the heading it came from,
    whatever number of turns that holds; issue 44); the sideways lean and the head's tilt and turn
    change sign; each arm takes the other arm's angles.

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
    yaw = q[PARAMETER_INDEX[HEADING]]
    out[PARAMETER_INDEX[HEADING]] = nearest_heading(math.pi - yaw, yaw)
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
