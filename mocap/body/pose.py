"""The 23-parameter pose vector: names, units, neutral pose and biomechanical joint limits.

Layout (docs/design.md section 2): three root positions in metres (camera coordinates, x right,
y down, z forward), then 20 joint angles in radians.

Angle conventions (all rotations right-handed about the parent segment's axes; with every
angle zero the actor stands upright facing the camera, arms hanging):

=====================  ========================================================
parameter              positive direction
=====================  ========================================================
chest_yaw              torso turns towards the actor's right (face moves to -x)
chest_pitch            torso leans forwards (towards the camera)
chest_roll             torso leans towards the actor's left
head_flex              chin down (nod forward)
head_tilt              head tilts towards the actor's left shoulder (Rz)
head_turn              face turns towards the actor's right
*_shoulder_flex        arm raised forwards (towards the camera)
*_shoulder_abd         arm raised sideways, away from the body
*_shoulder_rot         rotation about the upper arm's long axis
*_elbow_flex           forearm bends forwards
*_forearm_twist        rotation about the forearm's long axis
*_wrist_flex           hand bends forwards (palm side)
*_wrist_dev            hand deviates sideways
=====================  ========================================================

Joint limits are the normal active ranges of motion of adult joints from the American Academy
of Orthopaedic Surgeons (AAOS, *Joint Motion: Method of Measuring and Recording*, 1965; the
values as tabulated in Norkin & White, *Measurement of Joint Motion*, 5th ed., 2016,
Appendix A), rounded to 5 degrees. The chest (global torso orientation) is not a joint: its yaw
covers two full turns either way so that an actor turning around is followed continuously
(no wrap at ±180°); its pitch and roll allow leaning.
"""
from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

#: Parameter names in vector order.
PARAMETER_NAMES: tuple[str, ...] = (
    "root_x", "root_y", "root_z",
    "chest_yaw", "chest_pitch", "chest_roll",
    "head_flex", "head_tilt", "head_turn",
    "r_shoulder_flex", "r_shoulder_abd", "r_shoulder_rot",
    "r_elbow_flex", "r_forearm_twist",
    "r_wrist_flex", "r_wrist_dev",
    "l_shoulder_flex", "l_shoulder_abd", "l_shoulder_rot",
    "l_elbow_flex", "l_forearm_twist",
    "l_wrist_flex", "l_wrist_dev",
)
#: Number of pose parameters.
N_PARAMETERS: int = len(PARAMETER_NAMES)
#: Index of each parameter by name (read-only).
PARAMETER_INDEX = MappingProxyType({name: i for i, name in enumerate(PARAMETER_NAMES)})
#: Names of the three position parameters (metres); the rest are angles (radians).
POSITION_NAMES: tuple[str, ...] = PARAMETER_NAMES[:3]
ANGLE_NAMES: tuple[str, ...] = PARAMETER_NAMES[3:]

# Limits in the unit people read: metres for positions, degrees for angles.
_ARM_LIMITS_DEG = {
    "shoulder_flex": (-60.0, 180.0),   # extension 60, flexion 180 (AAOS)
    "shoulder_abd": (-30.0, 180.0),    # adduction across the body 30, abduction 180
    "shoulder_rot": (-70.0, 90.0),     # internal 70, external 90
    "elbow_flex": (0.0, 150.0),        # flexion 150
    "forearm_twist": (-80.0, 80.0),    # pronation / supination 80
    "wrist_flex": (-70.0, 80.0),       # extension 70, flexion 80
    "wrist_dev": (-20.0, 30.0),        # radial 20, ulnar 30
}
_LIMITS_HUMAN: dict[str, tuple[float, float]] = {
    "root_x": (-3.0, 3.0),
    "root_y": (-3.0, 3.0),
    "root_z": (0.3, 10.0),
    "chest_yaw": (-720.0, 720.0),     # global orientation: two full turns each way, so that a
                                       # turning actor is followed without a jump at +-180
    "chest_pitch": (-30.0, 60.0),
    "chest_roll": (-40.0, 40.0),
    "head_flex": (-50.0, 60.0),        # cervical extension 50 (limited by the head), flexion 60 (AAOS 45-60)
    "head_tilt": (-45.0, 45.0),        # lateral flexion 45
    "head_turn": (-80.0, 80.0),        # rotation 80
}
for _side in ("r", "l"):
    for _joint, _lim in _ARM_LIMITS_DEG.items():
        _LIMITS_HUMAN[f"{_side}_{_joint}"] = _lim


def _limits_array() -> np.ndarray:
    out = np.empty((N_PARAMETERS, 2))
    for i, name in enumerate(PARAMETER_NAMES):
        lo, hi = _LIMITS_HUMAN[name]
        if name in ANGLE_NAMES:
            lo, hi = np.deg2rad(lo), np.deg2rad(hi)
        out[i] = lo, hi
    out.setflags(write=False)
    return out


#: Joint limits, float64 array of shape (23, 2): lower and upper bound per parameter
#: (metres for positions, radians for angles). Read-only.
JOINT_LIMITS: np.ndarray = _limits_array()

#: Default position of the chest base in camera coordinates, metres.
DEFAULT_ROOT = (0.0, 0.25, 1.8)


def neutral_pose(root: tuple[float, float, float] = DEFAULT_ROOT) -> np.ndarray:
    """The neutral pose: upright, facing the camera, arms slightly away from the body.

    Parameters
    ----------
    root : tuple of 3 float, metres
        Chest-base position in camera coordinates.

    Returns
    -------
    pose : ndarray, shape (23,), float64
        Positions in metres, angles in radians.
    """
    pose = np.zeros(N_PARAMETERS)
    pose[:3] = root
    pose[PARAMETER_INDEX["r_shoulder_abd"]] = np.deg2rad(15.0)
    pose[PARAMETER_INDEX["l_shoulder_abd"]] = np.deg2rad(15.0)
    pose[PARAMETER_INDEX["r_elbow_flex"]] = np.deg2rad(10.0)
    pose[PARAMETER_INDEX["l_elbow_flex"]] = np.deg2rad(10.0)
    return check_pose(pose)


def check_pose(pose, *, name: str = "pose") -> np.ndarray:
    """Validate a pose vector and return it as a float64 array.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Positions in metres, angles in radians.

    Returns
    -------
    ndarray, shape (23,), float64
        A new contiguous array.

    Raises
    ------
    ValueError
        If the shape is not (23,) or a value is NaN or infinite.
    """
    try:
        arr = np.array(pose, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be {N_PARAMETERS} numbers: {exc}") from None
    if arr.shape != (N_PARAMETERS,):
        raise ValueError(f"{name} must have shape ({N_PARAMETERS},), got {arr.shape}")
    # the sum is NaN or infinite when a value is (a cheap test: 0.4 µs against 1.2; it may also
    # overflow on huge finite values, which the exact test below then lets through)
    if math.isfinite(sum(arr.tolist())):
        return arr
    bad = ~np.isfinite(arr)
    if bad.any():
        names = ", ".join(PARAMETER_NAMES[i] for i in np.flatnonzero(bad))
        raise ValueError(f"{name} has non-finite values in: {names}")
    return arr


def clamp_to_limits(pose, limits: np.ndarray = JOINT_LIMITS) -> np.ndarray:
    """Clamp every parameter into its joint limits.

    Parameters
    ----------
    pose : array_like, shape (23,)
    limits : ndarray, shape (23, 2)

    Returns
    -------
    ndarray, shape (23,), float64
    """
    return np.clip(check_pose(pose), limits[:, 0], limits[:, 1])


def within_limits(pose, limits: np.ndarray = JOINT_LIMITS) -> bool:
    """Whether every parameter of ``pose`` lies inside its limits (inclusive)."""
    arr = check_pose(pose)
    return bool(np.all(arr >= limits[:, 0]) and np.all(arr <= limits[:, 1]))


#: The chest's heading: the one angle that turns the whole body about the vertical (unwrapped).
HEADING: str = "chest_yaw"


def nearest_heading(yaw, reference):
    """The 2π-equivalent of a chest heading nearest a reference heading, inside the heading's limits.

    Headings 2π apart put every joint in the same place; the tracker keeps the heading unwrapped
    (limits ±720°) so that a turning actor is followed continuously, and a heading that comes
    wrapped (a lifter's proposal, a jump) must be brought next to the heading it continues
    (issue 44). A tie (exactly π away) goes to the even number of turns (``numpy.round``).

    Parameters
    ----------
    yaw : float or array_like
        Headings, radians.
    reference : float or array_like
        Headings to come nearest (broadcast against ``yaw``), radians.

    Returns
    -------
    float or ndarray, radians
        ``yaw + 2πk`` with integer ``k``: nearest ``reference`` among those inside the limits of
        :data:`HEADING` (:data:`JOINT_LIMITS`; a ``yaw`` outside them is first brought inside).
    """
    lo, hi = JOINT_LIMITS[PARAMETER_INDEX[HEADING]]
    y, r = np.asarray(yaw, dtype=np.float64), np.asarray(reference, dtype=np.float64)
    out = y + 2.0 * math.pi * np.round((r - y) / (2.0 * math.pi))
    out = np.where(out > hi, out - 2.0 * math.pi * np.ceil((out - hi) / (2.0 * math.pi)), out)
    out = np.where(out < lo, out + 2.0 * math.pi * np.ceil((lo - out) / (2.0 * math.pi)), out)
    return float(out) if out.ndim == 0 else out


def heading_near(pose, reference: float) -> np.ndarray:
    """A pose with its chest heading brought to the 2π-equivalent nearest ``reference``.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Metres and radians.
    reference : float
        The heading it continues (the parent hypothesis's, a prediction's), radians.

    Returns
    -------
    ndarray, shape (23,), float64
        A new array; only :data:`HEADING` changes, by a whole number of turns
        (:func:`nearest_heading`), so every joint stays where it was.
    """
    out = check_pose(pose)
    i = PARAMETER_INDEX[HEADING]
    out[i] = nearest_heading(out[i], reference)
    return out


def pose_to_dict(pose, *, degrees: bool = False) -> dict[str, float]:
    """Pose as ``{name: value}``; angles in degrees when ``degrees`` (for files people read)."""
    arr = check_pose(pose)
    if degrees:
        arr = arr.copy()
        arr[3:] = np.rad2deg(arr[3:])
    return {name: float(v) for name, v in zip(PARAMETER_NAMES, arr)}


def pose_from_dict(values: dict[str, float], *, degrees: bool = False) -> np.ndarray:
    """Inverse of :func:`pose_to_dict`. Every name must be present; unknown names are an error."""
    unknown = set(values) - set(PARAMETER_NAMES)
    if unknown:
        raise ValueError(f"unknown pose parameters: {', '.join(sorted(unknown))}")
    missing = [n for n in PARAMETER_NAMES if n not in values]
    if missing:
        raise ValueError(f"missing pose parameters: {', '.join(missing)}")
    arr = np.array([float(values[n]) for n in PARAMETER_NAMES])
    if degrees:
        arr[3:] = np.deg2rad(arr[3:])
    return check_pose(arr)
