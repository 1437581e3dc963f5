"""The written trajectory: a fixed-lag Rauch–Tung–Striebel smoother in parameter space.

Each of the 23 pose parameters is a constant-velocity process (state: value and velocity per
frame; a white change of velocity of standard deviation ``*_acceleration`` per frame, the
piecewise-constant acceleration model) observed each frame by the tracker's decoded pose with
noise of standard deviation ``*_noise``. A frame with 2D keypoints divides each parameter's noise
variance by the mean detector confidence of the joints that parameter moves
(:data:`MOVED_JOINTS`; at least :attr:`SmootherConfig.min_weight`), so a joint the detector is
unsure of is smoothed more.

The tracker calls :meth:`Smoother.smooth` when frame ``t - L`` is decided (lag ``L``): with the
frames ``t - L .. t`` of its current best path (tentative poses) it runs the Kalman filter
forward from the filtered state of the last frame decided, then the RTS recursion back to frame
``t - L``, whose smoothed pose is written; the filtered state then moves on by that one frame.
Frames written are never changed. With ``L = 0`` this is the Kalman filter (less smooth);
offline, the whole clip is one window (the RTS smoother of the whole sequence).

A depth branch switch is not blended: where any joint of the decoded path moves more than
:attr:`SmootherConfig.break_m` between consecutive frames, the filter restarts at the new frame
(its pose, velocity 0) and the backward recursion stops there, so no written pose lies between
two branches.

The chest's heading is kept unwrapped (limits ±720°) and a decoded heading may come a whole turn
away from the one before it with the same joints: each observed heading is brought to the
2π-equivalent nearest its prediction (the filtered heading of the frame before, moved on by its
velocity; at a restart too), so the filter never sweeps the body through a turn (issue 44).

:meth:`Smoother.state` and :meth:`Smoother.restore` carry the filtered state exactly (floats in
JSON round-trip bit for bit).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mocap.body.pose import HEADING, JOINT_LIMITS, N_PARAMETERS, PARAMETER_INDEX, PARAMETER_NAMES, nearest_heading
from mocap.body.skeleton import JOINT_INDEX, JOINT_NAMES
from mocap.config import JsonConfig

__all__ = ["MOVED_JOINTS", "Smoother", "SmootherConfig"]

#: Index of the chest's heading in the pose vector.
_HEADING = PARAMETER_INDEX[HEADING]


def _moved(name: str) -> tuple[str, ...]:
    """Joints (:data:`JOINT_NAMES`) a parameter moves: all for the root and chest, the head for
    the head's, the joints below it on its arm for an arm's."""
    side, _, rest = name.partition("_")
    if side not in ("r", "l"):
        return ("head",) if name.startswith("head") else JOINT_NAMES
    below = {"shoulder": ("elbow", "wrist", "hand"), "elbow": ("wrist", "hand"), "forearm": ("wrist", "hand"),
             "wrist": ("hand",)}[rest.split("_")[0]]
    return tuple(f"{side}_{j}" for j in below)


#: The joints whose detector confidence weighs each parameter's observation, by parameter name.
MOVED_JOINTS: dict[str, tuple[str, ...]] = {name: _moved(name) for name in PARAMETER_NAMES}
#: ``_MOVED[p, j]``: 1 / (number of joints parameter ``p`` moves) where it moves joint ``j``.
_MOVED = np.zeros((N_PARAMETERS, len(JOINT_NAMES)))
for _p, _name in enumerate(PARAMETER_NAMES):
    _MOVED[_p, [JOINT_INDEX[j] for j in MOVED_JOINTS[_name]]] = 1.0 / len(MOVED_JOINTS[_name])
_MOVED.setflags(write=False)


@dataclass(frozen=True)
class SmootherConfig(JsonConfig):
    """Settings of the written trajectory's smoother (``TrackerConfig.smoothing``).

    Attributes
    ----------
    on : bool
        Smooth the written poses (False: the decoded poses are written as they are).
    position_noise_m : float, metres
        Standard deviation of a decoded frame's root position.
    angle_noise_deg : float, degrees
        Standard deviation of a decoded frame's joint angle.
    position_acceleration_m : float, metres per frame squared
        Standard deviation of the root's change of velocity from one frame to the next.
    angle_acceleration_deg : float, degrees per frame squared
        The same for the joint angles.
    break_m : float, metres
        A joint moving more than this between consecutive decoded frames is a branch switch:
        the smoother restarts there.
    min_weight : float
        Least weight (share of a fully confident observation) of a parameter on a frame with
        keypoints, in (0, 1].
    """

    on: bool = True
    position_noise_m: float = 0.02
    angle_noise_deg: float = 5.0
    position_acceleration_m: float = 0.003
    angle_acceleration_deg: float = 1.0
    break_m: float = 0.3
    min_weight: float = 0.1

    def __post_init__(self) -> None:
        if not isinstance(self.on, bool):
            raise ValueError(f"smoothing's on must be true or false, got {self.on!r}")
        for name in ("position_noise_m", "angle_noise_deg", "position_acceleration_m", "angle_acceleration_deg",
                     "break_m", "min_weight"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise ValueError(f"smoothing's {name} must be a finite positive number, got {v!r}")
        if self.min_weight > 1:
            raise ValueError(f"smoothing's min_weight must be at most 1, got {self.min_weight!r}")

    def noise(self) -> np.ndarray:
        """Observation standard deviation of each parameter, shape (23,): metres, radians."""
        return np.r_[np.full(3, self.position_noise_m), np.full(N_PARAMETERS - 3, math.radians(self.angle_noise_deg))]

    def acceleration(self) -> np.ndarray:
        """Standard deviation of each parameter's change of velocity per frame, shape (23,)."""
        return np.r_[np.full(3, self.position_acceleration_m),
                     np.full(N_PARAMETERS - 3, math.radians(self.angle_acceleration_deg))]


_F = np.array([[1.0, 1.0], [0.0, 1.0]])


class Smoother:
    """The fixed-lag smoother of one tracked person (see the module).

    Parameters
    ----------
    config : SmootherConfig
    """

    def __init__(self, config: SmootherConfig) -> None:
        self.config = config
        self._r = config.noise() ** 2                                   # (23,)
        a = config.acceleration() ** 2
        self._q = a[:, None, None] * np.array([[0.25, 0.5], [0.5, 1.0]])  # (23, 2, 2)
        self._mean: np.ndarray | None = None    # (23, 2): filtered value and velocity of the last frame written
        self._cov: np.ndarray | None = None     # (23, 2, 2)
        self._joints: np.ndarray | None = None  # (10, 3): that frame's decoded joints
        self._written: np.ndarray | None = None  # (23,): the last pose written (an empty frame's too)

    def weights(self, confidence) -> np.ndarray:
        """Each parameter's observation weight on a frame, shape (23,), in [min_weight, 1]: 1
        without keypoints (``confidence`` None), else the mean confidence of the joints it moves.

        Parameters
        ----------
        confidence : ndarray, shape (10,), in [0, 1], or None
        """
        if confidence is None:
            return np.ones(N_PARAMETERS)
        return np.maximum(_MOVED @ np.asarray(confidence, dtype=np.float64), self.config.min_weight)

    def breaks(self, joints: np.ndarray) -> np.ndarray:
        """Where the decoded path switches branch, shape (n,), bool: ``breaks[k]`` when a joint
        moves more than ``break_m`` from the frame before ``k`` (the last frame written, for
        ``k = 0``; a first frame ever is a start too)."""
        joints = np.asarray(joints, dtype=np.float64)
        chain = joints if self._joints is None else np.concatenate([self._joints[None], joints])
        jumps = np.linalg.norm(np.diff(chain, axis=0), axis=2).max(axis=1) > self.config.break_m
        return jumps if self._joints is not None else np.r_[True, jumps]

    def smooth(self, poses, joints, weights, count: int = 1, empty=None) -> np.ndarray:
        """The written poses of the first ``count`` frames of a window; the state moves past them.

        Parameters
        ----------
        poses : array_like, shape (n, 23)
            The decoded path's poses of the frames not written yet, oldest first (metres, radians).
        joints : array_like, shape (n, 10, 3), metres
            Their joints (for :meth:`breaks`).
        weights : array_like, shape (n, 23)
            Observation weights (:meth:`weights`), in (0, 1].
        count : int
            Frames to write, 1 to n.
        empty : array_like, shape (n,), bool, optional
            Frames with nobody in view: their written pose is the one written before them (the
            pose kept, as the tracker keeps it), while the filter goes on through the kept pose.

        Returns
        -------
        ndarray, shape (count, 23)
            Smoothed, within the joint limits.
        """
        y = np.array(poses, dtype=np.float64)       # a copy: its headings are unwrapped below
        w = np.asarray(weights, dtype=np.float64)
        n = len(y)
        if y.shape != (n, N_PARAMETERS) or w.shape != (n, N_PARAMETERS) or not 1 <= count <= n:
            raise ValueError(f"poses and weights must have shape (n, {N_PARAMETERS}) with n >= count >= 1, got "
                             f"{y.shape}, {w.shape} and count {count}")
        restart = self.breaks(joints)
        filtered_m, filtered_p = np.empty((n, N_PARAMETERS, 2)), np.empty((n, N_PARAMETERS, 2, 2))
        predicted_m, predicted_p = np.empty_like(filtered_m), np.empty_like(filtered_p)
        for k in range(n):
            r = self._r / w[k]
            m0, p0 = (self._mean, self._cov) if k == 0 else (filtered_m[k - 1], filtered_p[k - 1])
            if m0 is not None:      # the observed heading on the circle: nearest its prediction (issue 44)
                y[k, _HEADING] = nearest_heading(y[k, _HEADING], m0[_HEADING, 0] + m0[_HEADING, 1])
            if restart[k]:
                m = np.stack([y[k], np.zeros(N_PARAMETERS)], axis=1)
                p = np.zeros((N_PARAMETERS, 2, 2))
                p[:, 0, 0], p[:, 1, 1] = r, 2.0 * r
            else:
                m = m0 @ _F.T
                p = _F @ p0 @ _F.T + self._q
            predicted_m[k], predicted_p[k] = m, p
            if not restart[k]:              # the update (a restart starts at the observation)
                s = p[:, 0, 0] + r
                gain = p[:, :, 0] / s[:, None]                          # (23, 2)
                m = m + gain * (y[k] - m[:, 0])[:, None]
                p = p - gain[:, :, None] * gain[:, None, :] * s[:, None, None]
            filtered_m[k], filtered_p[k] = m, p
        smoothed = filtered_m[:, :, 0].copy()
        later = filtered_m[n - 1]
        for k in range(n - 2, -1, -1):
            if restart[k + 1]:
                later = filtered_m[k]
                continue
            # C = P_f F^T P_p^-1 (batched over the parameters); m_s = m_f + C (m_s' - m_p')
            c = np.linalg.solve(predicted_p[k + 1], (filtered_p[k] @ _F.T).transpose(0, 2, 1)).transpose(0, 2, 1)
            later = filtered_m[k] + np.einsum("pij,pj->pi", c, later - predicted_m[k + 1])
            smoothed[k] = later[:, 0]
        self._mean, self._cov = filtered_m[count - 1].copy(), filtered_p[count - 1].copy()
        self._joints = np.array(joints[count - 1], dtype=np.float64)
        written = np.clip(smoothed[:count], JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
        kept = np.zeros(n, dtype=bool) if empty is None else np.asarray(empty, dtype=bool)
        if kept.shape != (n,):
            raise ValueError(f"empty must have shape ({n},), got {kept.shape}")
        for k in range(count):
            if kept[k] and self._written is not None:
                written[k] = self._written
            self._written = written[k].copy()
        return written

    # -- exact state -------------------------------------------------------------------------
    def state(self) -> dict:
        """The filtered state of the last frame written, as JSON-able lists (exact)."""
        if self._mean is None:
            return {}
        return {"mean": self._mean.tolist(), "cov": self._cov.tolist(), "joints": self._joints.tolist(),
                "written": self._written.tolist()}

    def restore(self, state: dict) -> None:
        """Continue from a :meth:`state`."""
        if not state:
            self._mean = self._cov = self._joints = self._written = None
            return
        self._mean = np.array(state["mean"], dtype=np.float64).reshape(N_PARAMETERS, 2)
        self._cov = np.array(state["cov"], dtype=np.float64).reshape(N_PARAMETERS, 2, 2)
        self._joints = np.array(state["joints"], dtype=np.float64).reshape(len(JOINT_NAMES), 3)
        self._written = np.array(state["written"], dtype=np.float64).reshape(N_PARAMETERS)
