"""Procedural motion of the named benchmark sequences.

Motion is built from key poses: a vocabulary of arm gestures (:data:`ARM_GESTURES`), picked at
random per key with a little jitter, reached in a smooth transition and held a moment. All 23
parameters are interpolated through the keys by a monotone cubic (PCHIP: no overshoot, zero
velocity at holds), then overlaid with slow idle sway (sums of low-frequency sinusoids with
random phases: breathing, weight shift, head motion) and, while waving, a 2 Hz elbow
oscillation. Each sequence starts with half a second in a calibration pose (upright, facing or
turned as the sequence wants, arms slightly away from the body). Every random choice comes
from the generator passed in, so a seed fixes the motion; the first frames do not depend on the
number of frames asked for.

Sequences (the paper's Fig. 5):

* ``gestures-1``: moderate arm gestures facing the camera (wave, point, raise, shrug, clap,
  touch the head), the easiest sequence.
* ``gestures-2``: gestures with fast motion in depth: the actor steps towards and away from
  the camera (root depth between about 1.35 and 2.2 m in under a second) and reaches forwards.
* ``gestures-3``: fast, varied gestures with more torso and head motion.
* ``arms-crossing``: forearms crossing in front of the chest (either on top), a hand reaching
  across to the other shoulder, clapping: arm-arm and arm-torso occlusions.
* ``not-facing``: gestures with the torso held turned 30-45 degrees from the camera.
* ``turning``: the actor turns around himself (a full chest-yaw turn, then back part of the way).

Joint limits always hold: the result is clamped to :data:`~mocap.body.pose.JOINT_LIMITS`
and the chest yaw wrapped into [-180, 180) degrees. Hands and forearms that a transition would
drive into the torso are lifted forwards (:func:`avoid_torso`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType
from typing import Callable

import numpy as np
from scipy.interpolate import PchipInterpolator

from mocap.body.model import BodyModel
from mocap.body.pose import JOINT_LIMITS, N_PARAMETERS, PARAMETER_INDEX
from mocap.body.skeleton import JOINT_NAMES, SEGMENT_NAMES

__all__ = ["ARM_GESTURES", "ARM_PARAMETERS", "MOTIONS", "MotionStyle", "avoid_torso", "gesture_motion",
           "root_height_for_depth"]

#: The seven arm parameters (without side prefix) in the order of :data:`ARM_GESTURES` rows.
ARM_PARAMETERS: tuple[str, ...] = ("shoulder_flex", "shoulder_abd", "shoulder_rot", "elbow_flex",
                                   "forearm_twist", "wrist_flex", "wrist_dev")
#: Arm key poses, degrees, in :data:`ARM_PARAMETERS` order (the same for either arm: the
#: parameters are mirrored by the kinematics).
ARM_GESTURES = MappingProxyType({
    "rest": (5.0, 12.0, 0.0, 15.0, 0.0, 0.0, 0.0),
    "calibration": (5.0, 20.0, 0.0, 10.0, 0.0, 0.0, 0.0),
    "wave": (0.0, 85.0, 85.0, 90.0, 0.0, 0.0, 0.0),
    "point_forward": (85.0, 5.0, 0.0, 5.0, 0.0, 10.0, 0.0),
    "point_side": (10.0, 85.0, 0.0, 5.0, 0.0, 0.0, 0.0),
    "raise": (155.0, 15.0, 0.0, 20.0, 0.0, 0.0, 0.0),
    "hand_to_chest": (30.0, 0.0, -55.0, 105.0, 0.0, 0.0, 0.0),
    "cross": (40.0, -5.0, -60.0, 115.0, 0.0, 0.0, 0.0),
    "across_shoulder": (55.0, -15.0, -55.0, 130.0, 0.0, 10.0, 0.0),
    "clap": (65.0, 5.0, -30.0, 60.0, 0.0, 0.0, 0.0),
    "touch_head": (100.0, 50.0, 30.0, 130.0, 0.0, 0.0, 0.0),
    "shrug": (20.0, 45.0, 30.0, 30.0, 40.0, 0.0, 0.0),
    "reach_forward": (90.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    "hips": (-10.0, 40.0, -40.0, 100.0, 0.0, 0.0, 0.0),
})
#: Typical framing: chest-base height below the optical axis per metre of depth, so that the
#: chest base sits near the bottom of the image (webcam framing of the upper body).
_ROOT_Y_PER_Z = 0.33


def root_height_for_depth(z: float) -> float:
    """Chest-base height (camera y, metres) that frames the upper body at depth ``z`` metres."""
    return _ROOT_Y_PER_Z * z


def _idx(name: str) -> int:
    return PARAMETER_INDEX[name]


@dataclass(frozen=True)
class MotionStyle:
    """How one procedural sequence moves (times in seconds, angles in degrees, lengths in metres).

    Attributes
    ----------
    pairs : tuple of ((right gesture, left gesture), weight)
        Key-pose vocabulary: which gestures the two arms take together, with relative weights.
    transition : (float, float)
        Range of the time to move from one key pose to the next.
    hold : (float, float)
        Range of the time a key pose is held.
    jitter_deg : float
        Standard deviation of the random change of every key angle.
    sway : dict of str to float
        Amplitude (degrees, or metres for root parameters) of the idle sway per parameter.
    depth_range : (float, float)
        Range of the root depth; ``depth_steps`` moves between its ends.
    depth_steps : bool
        Step towards and away from the camera (fast motion in depth) at every key.
    yaw_hold : (float, float) or None
        Hold the chest yaw at a random magnitude in this range (random side).
    turns : bool
        Turn around: a full chest-yaw turn, then back part of the way, and so on.
    """

    pairs: tuple[tuple[tuple[str, str], float], ...]
    transition: tuple[float, float] = (0.6, 1.0)
    hold: tuple[float, float] = (0.3, 1.0)
    jitter_deg: float = 7.0
    sway: tuple[tuple[str, float], ...] = (("chest_yaw", 5.0), ("chest_roll", 2.5), ("chest_pitch", 2.0),
                                           ("head_turn", 10.0), ("head_flex", 5.0), ("head_tilt", 3.0),
                                           ("root_x", 0.03), ("root_z", 0.04), ("root_y", 0.01))
    depth_range: tuple[float, float] = (1.6, 1.8)
    depth_steps: bool = False
    yaw_hold: tuple[float, float] | None = None
    turns: bool = False


def _sym(a: str, b: str | None = None) -> tuple[str, str]:
    return (a, a if b is None else b)


_GESTURE_PAIRS = (
    (_sym("rest"), 1.0), (_sym("wave", "rest"), 1.0), (_sym("rest", "wave"), 0.6),
    (_sym("point_forward", "rest"), 0.8), (_sym("rest", "point_side"), 0.8), (_sym("point_side"), 0.5),
    (_sym("raise", "rest"), 0.7), (_sym("rest", "raise"), 0.5), (_sym("shrug"), 0.6), (_sym("clap"), 0.5),
    (_sym("touch_head", "rest"), 0.5), (_sym("hand_to_chest", "rest"), 0.4), (_sym("hips"), 0.3),
)

#: The style of every procedural sequence.
STYLES = MappingProxyType({
    "gestures-1": MotionStyle(_GESTURE_PAIRS, transition=(0.8, 1.3), hold=(0.4, 1.2)),
    "gestures-2": MotionStyle(
        ((_sym("reach_forward"), 1.0), (_sym("point_forward", "rest"), 1.0), (_sym("clap"), 0.8),
         (_sym("rest"), 0.8), (_sym("rest", "reach_forward"), 0.8), (_sym("shrug"), 0.5), (_sym("wave", "rest"), 0.5)),
        transition=(0.45, 0.8), hold=(0.2, 0.7), depth_range=(1.35, 2.2), depth_steps=True),
    "gestures-3": MotionStyle(
        _GESTURE_PAIRS + ((_sym("raise"), 0.5), (_sym("point_side", "point_forward"), 0.6),
                          (_sym("wave"), 0.4), (_sym("hand_to_chest", "point_side"), 0.4)),
        transition=(0.4, 0.75), hold=(0.1, 0.6), jitter_deg=10.0,
        sway=(("chest_yaw", 12.0), ("chest_roll", 5.0), ("chest_pitch", 4.0), ("head_turn", 20.0),
              ("head_flex", 10.0), ("head_tilt", 6.0), ("root_x", 0.06), ("root_z", 0.06), ("root_y", 0.015))),
    "arms-crossing": MotionStyle(
        ((_sym("cross"), 2.0), (_sym("rest"), 1.0), (_sym("across_shoulder", "rest"), 0.8),
         (_sym("rest", "across_shoulder"), 0.8), (_sym("hand_to_chest"), 0.8), (_sym("clap"), 0.6),
         (_sym("cross", "hand_to_chest"), 0.6), (_sym("point_side"), 0.3)),
        transition=(0.6, 1.0), hold=(0.4, 1.1)),
    "not-facing": MotionStyle(_GESTURE_PAIRS, yaw_hold=(30.0, 45.0),
                              sway=(("chest_yaw", 3.0), ("chest_roll", 2.5), ("chest_pitch", 2.0),
                                    ("head_turn", 12.0), ("head_flex", 5.0), ("head_tilt", 3.0),
                                    ("root_x", 0.03), ("root_z", 0.04), ("root_y", 0.01))),
    "turning": MotionStyle(
        ((_sym("rest"), 1.5), (_sym("point_side"), 0.5), (_sym("shrug"), 0.5), (_sym("hips"), 0.5),
         (_sym("raise", "rest"), 0.4), (_sym("reach_forward", "rest"), 0.4)),
        transition=(0.7, 1.2), hold=(0.4, 1.0), turns=True,
        sway=(("chest_roll", 2.0), ("chest_pitch", 2.0), ("head_turn", 6.0), ("head_flex", 4.0),
              ("root_x", 0.02), ("root_z", 0.03), ("root_y", 0.01))),
})


def _arm_values(gesture: str, rng: np.random.Generator, jitter: float) -> np.ndarray:
    g = np.asarray(ARM_GESTURES[gesture], dtype=np.float64)
    j = rng.normal(0.0, jitter, size=g.shape)
    j[4:] *= 0.5                          # forearm twist and wrist: small changes only
    return np.deg2rad(g + j)


def _set_arm(pose: np.ndarray, side: str, values: np.ndarray) -> None:
    for k, name in enumerate(ARM_PARAMETERS):
        pose[_idx(f"{side}_{name}")] = values[k]


def _sway(rng: np.random.Generator, t: np.ndarray, amplitude: float, *, n_waves: int = 3,
          freq: tuple[float, float] = (0.08, 0.45)) -> np.ndarray:
    """Smooth random wobble: a sum of sinusoids of random frequency and phase, peak ~amplitude."""
    out = np.zeros_like(t)
    for _ in range(n_waves):
        f = rng.uniform(*freq)
        out += np.sin(2.0 * np.pi * f * t + rng.uniform(0.0, 2.0 * np.pi))
    return amplitude * out / math.sqrt(n_waves)


def _turn_schedule(rng: np.random.Generator, duration: float, start: float) -> tuple[list[float], list[float]]:
    """Key times and chest yaws (radians, unwrapped) of a turning-around actor."""
    times, yaws = [0.0, start], [0.0, 0.0]
    t, yaw = start, 0.0
    direction = 1.0 if rng.uniform() < 0.5 else -1.0
    first = True
    while t < duration + 2.0:
        amount = 2.0 * np.pi if first else np.deg2rad(rng.uniform(120.0, 240.0))
        speed = np.deg2rad(rng.uniform(55.0, 80.0))          # degrees per second while turning
        t += amount / speed
        yaw += direction * amount
        times.append(t)
        yaws.append(yaw)
        t += rng.uniform(0.6, 1.4)                           # face the new way for a moment
        times.append(t)
        yaws.append(yaw)
        direction = -direction
        first = False
    return times, yaws


def gesture_motion(style: MotionStyle, rng: np.random.Generator, n_frames: int, fps: float) -> np.ndarray:
    """Poses of a procedural sequence.

    Parameters
    ----------
    style : MotionStyle
    rng : numpy.random.Generator
        Source of every random choice.
    n_frames : int
        Frames to produce (>= 1).
    fps : float
        Frames per second.

    Returns
    -------
    ndarray, shape (n_frames, 23), float64
        Metres and radians, within the joint limits.
    """
    duration = n_frames / fps
    # independent streams, so that a longer sequence starts exactly like a shorter one
    rng, sway_rng, turn_rng = rng.spawn(3)
    calib = 0.5                                              # seconds in the calibration pose
    z0 = rng.uniform(*style.depth_range) if not style.depth_steps else float(np.mean(style.depth_range))
    x0 = rng.uniform(-0.08, 0.08)
    yaw0 = 0.0
    if style.yaw_hold is not None:
        yaw0 = np.deg2rad(rng.uniform(*style.yaw_hold)) * (1.0 if rng.uniform() < 0.5 else -1.0)
    base = np.zeros(N_PARAMETERS)
    base[_idx("root_x")], base[_idx("root_y")], base[_idx("root_z")] = x0, root_height_for_depth(z0), z0
    base[_idx("chest_yaw")] = yaw0
    first = base.copy()
    for side in ("r", "l"):
        _set_arm(first, side, np.deg2rad(ARM_GESTURES["calibration"]))
    times, keys, waves = [0.0, calib], [first, first], [(0.0, 0.0), (0.0, 0.0)]
    names = [p[0] for p in style.pairs]
    weights = np.array([p[1] for p in style.pairs], dtype=np.float64)
    weights /= weights.sum()
    t = calib
    near = rng.uniform() < 0.5
    while t < duration + 1.5:                                # keys past the end keep the tail smooth
        right, left = names[rng.choice(len(names), p=weights)]
        if rng.uniform() < 0.5 and right != left:            # either arm may lead
            right, left = left, right
        key = base.copy()
        _set_arm(key, "r", _arm_values(right, rng, style.jitter_deg))
        _set_arm(key, "l", _arm_values(left, rng, style.jitter_deg))
        if style.depth_steps:
            lo, hi = style.depth_range
            z = rng.uniform(lo, lo + 0.15) if near else rng.uniform(hi - 0.15, hi)
            near = not near
            key[_idx("root_z")] = z
            key[_idx("root_y")] = root_height_for_depth(float(np.mean(style.depth_range)))
            key[_idx("chest_pitch")] = np.deg2rad(rng.uniform(5.0, 20.0) if z < np.mean(style.depth_range) else 0.0)
        key[_idx("head_flex")] += np.deg2rad(rng.normal(0.0, 4.0))
        key[_idx("head_turn")] += np.deg2rad(rng.normal(0.0, 8.0))
        t += rng.uniform(*style.transition)
        times.append(t)
        keys.append(key)
        waves.append((float(right == "wave"), float(left == "wave")))
        t += rng.uniform(*style.hold)
        times.append(t)
        keys.append(key)
        waves.append(waves[-1])
    tt = np.arange(n_frames) / fps
    poses = PchipInterpolator(np.array(times), np.array(keys), axis=0)(tt)
    wave = PchipInterpolator(np.array(times), np.array(waves), axis=0)(tt)
    # overlays: sway everywhere but in the calibration pose, waving while waving
    ramp = np.clip((tt - calib) / 0.5, 0.0, 1.0)
    for name, amp in style.sway:
        scale = amp if name.startswith("root_") else np.deg2rad(amp)
        poses[:, _idx(name)] += ramp * _sway(sway_rng, tt, scale)
    for k, side in enumerate(("r", "l")):
        phase = sway_rng.uniform(0.0, 2.0 * np.pi)
        poses[:, _idx(f"{side}_elbow_flex")] += wave[:, k] * np.deg2rad(22.0) * np.sin(2.0 * np.pi * 2.2 * tt + phase)
    if style.turns:
        kt, ky = _turn_schedule(turn_rng, duration, calib + turn_rng.uniform(0.3, 0.8))
        turn = PchipInterpolator(np.array(kt), np.array(ky))
        poses[:, _idx("chest_yaw")] += turn(tt)
        # the head leads the turn a little
        poses[:, _idx("head_turn")] += np.clip(turn.derivative()(tt) * 0.15, -0.35, 0.35)
    if style.yaw_hold is not None:                          # the sway stays inside the held range
        lo, hi = np.deg2rad(style.yaw_hold)
        poses[:, _idx("chest_yaw")] = np.sign(yaw0) * np.clip(np.abs(poses[:, _idx("chest_yaw")]), lo, hi)
    poses[:, _idx("chest_yaw")] = (poses[:, _idx("chest_yaw")] + np.pi) % (2.0 * np.pi) - np.pi
    return np.clip(poses, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])


def avoid_torso(poses: np.ndarray, model: BodyModel, *, margin_m: float = 0.02, step_deg: float = 4.0,
                max_steps: int = 25) -> np.ndarray:
    """Lift arms out of the torso: raise shoulder flexion until elbow, wrist and hand clear it.

    The torso is approximated by an elliptic cylinder in the chest frame (half-axes half its
    width and depth plus ``margin_m``, from the chest base to the neck).

    Parameters
    ----------
    poses : ndarray, shape (N, 23)
    model : BodyModel
        The actor (its dimensions and kinematics).

    Returns
    -------
    ndarray, shape (N, 23)
        A corrected copy, within the joint limits.
    """
    out = np.array(poses, dtype=np.float64)
    torso = model.dims["torso"]
    a, b = 0.5 * torso.width + margin_m, 0.5 * torso.depth + margin_m
    chest = SEGMENT_NAMES.index("chest")
    sides = {side: [JOINT_NAMES.index(f"{side}_{j}") for j in ("elbow", "wrist", "hand")] for side in ("r", "l")}
    hi = JOINT_LIMITS[_idx("r_shoulder_flex"), 1]
    for i in range(out.shape[0]):
        for side, rows in sides.items():
            k = _idx(f"{side}_shoulder_flex")
            for _ in range(max_steps):
                t = model.segment_transforms(out[i])
                joints = model.joint_positions(out[i])[rows]
                local = (joints - t[chest, :, 3]) @ t[chest, :, :3]
                inside = ((local[:, 0] / a) ** 2 + (local[:, 2] / b) ** 2 < 1.0) & (local[:, 1] < 0.0) \
                    & (local[:, 1] > -torso.length)
                if not inside.any() or out[i, k] >= hi:
                    break
                out[i, k] = min(out[i, k] + np.deg2rad(step_deg), hi)
    return out


#: Motion generator of every procedural sequence: ``f(rng, n_frames, fps) -> poses``.
MOTIONS: MappingProxyType[str, Callable[[np.random.Generator, int, float], np.ndarray]] = MappingProxyType({
    name: (lambda rng, n, fps, _s=style: gesture_motion(_s, rng, n, fps)) for name, style in STYLES.items()
})
