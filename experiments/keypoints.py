"""The oracle keypoint source: the ground truth's projected joints plus Gaussian pixel noise.

What the keypoint cue can give at best (a detector's error is larger and not Gaussian): every
joint of :data:`mocap.body.skeleton.JOINT_NAMES` present with confidence 1, each coordinate
displaced by independent N(0, sigma^2) pixels, from a seeded generator (the same seed gives
the same keypoints).
"""
from __future__ import annotations

import numpy as np

from mocap.io.keypoints import Keypoints
from mocap.render.camera import Camera

#: Noise of the oracle in the experiments, pixels at 160x120 (issue 23).
ORACLE_SIGMA_PX = 2.0


def oracle_keypoints(joints: np.ndarray, camera: Camera, sigma_px: float = ORACLE_SIGMA_PX,
                     seed: int = 0) -> list[Keypoints]:
    """The ground truth's joints projected, plus noise.

    Parameters
    ----------
    joints : ndarray, shape (frames, 10, 3), metres
        True joints in camera coordinates (in front of the camera).
    camera : Camera
        The camera whose pixels the keypoints are in.
    sigma_px : float, pixels
        Standard deviation of the noise of each coordinate (>= 0).
    seed : int
        Seed of the noise.

    Returns
    -------
    list of Keypoints
        One per frame, every joint present with confidence 1.
    """
    if not np.isfinite(sigma_px) or sigma_px < 0:
        raise ValueError(f"sigma_px must be finite and non-negative, got {sigma_px}")
    joints = np.asarray(joints, dtype=np.float64)
    rng = np.random.default_rng(seed)
    uv = camera.project(joints) + rng.normal(0.0, sigma_px, joints.shape[:-1] + (2,))
    ones = np.ones(joints.shape[1])
    return [Keypoints(frame_uv, ones) for frame_uv in uv]
