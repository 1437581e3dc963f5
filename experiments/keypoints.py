"""The keypoint sources of the experiments: the oracle (the ground truth's projected joints plus
Gaussian pixel noise) and the run's own detector on the rendered frames.

What the keypoint cue can give at best (a detector's error is larger and not Gaussian): every
joint of :data:`mocap.body.skeleton.JOINT_NAMES` present with confidence 1, each coordinate
displaced by independent N(0, sigma^2) pixels, from a seeded generator (the same seed gives
the same keypoints). :func:`swap_runs` and :func:`swap_labels` simulate a detector that names
the person's left arm the right one on runs of frames (MediaPipe on a figure whose face it does
not see, issue 44). :func:`detector_keypoints` is what a user gets instead: MediaPipe Pose as
``python -m mocap track --keypoints mediapipe`` runs it (image mode, every frame on its own, at
the frames' own size), its errors and left/right labels as they come.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from mocap.io.keypoints import Keypoints
from mocap.render.camera import Camera

#: Noise of the oracle in the experiments, pixels at 160x120 (issue 23).
ORACLE_SIGMA_PX = 2.0
#: The detector's keypoints, kept in a benchmark sequence's folder (:func:`detector_keypoints`).
DETECTOR_FILE = "keypoints-mediapipe.csv"


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


def swap_runs(frames: int, share: float, seed: int = 0, shortest: int = 5, longest: int = 30) -> np.ndarray:
    """Which frames a simulated detector swaps left and right on: runs of ``shortest`` to
    ``longest`` frames (uniform) between runs as long, until about ``share`` of the frames are
    swapped (1: every frame; 0: none).

    Returns
    -------
    ndarray, shape (frames,), bool
    """
    if not 0.0 <= share <= 1.0:
        raise ValueError(f"share must be in [0, 1], got {share}")
    if share in (0.0, 1.0):
        return np.full(frames, share == 1.0)
    rng = np.random.default_rng(seed + 7919)
    mask = np.zeros(frames, bool)
    i = int(rng.integers(shortest, longest + 1))
    while i < frames:
        run = int(rng.integers(shortest, longest + 1))
        mask[i:i + run] = True
        gap = int(round(run * (1.0 - share) / share))
        i += run + max(gap, 1)
    return mask


def swap_labels(keypoints: list[Keypoints], swapped: np.ndarray) -> list[Keypoints]:
    """``keypoints`` with left and right swapped (every ``r_`` joint's row given to its ``l_``
    twin and back, as :meth:`Keypoints.swapped` does; spelt out here so that code from before it
    is measured the same way) on the frames where ``swapped`` is True."""
    from mocap.body.skeleton import JOINT_NAMES

    twin = [JOINT_NAMES.index({"r_": "l_", "l_": "r_"}.get(n[:2], n[:2]) + n[2:]) for n in JOINT_NAMES]
    return [Keypoints(k.uv[twin], k.confidence[twin], None if k.world is None else k.world[twin]) if s else k
            for k, s in zip(keypoints, swapped)]


def offset_keypoints(keypoints: list[Keypoints | None], offset_px: float) -> list[Keypoints | None]:
    """``keypoints`` moved ``offset_px`` to the right (pixels, every present joint of every frame;
    confidences and 3D kept; None frames kept): a null perturbation, far below any detector's
    noise, that shows how far a track moves from nothing (``experiments.tracking --null-offset-px``)."""
    return [None if k is None else Keypoints(k.uv + np.array([offset_px, 0.0]), k.confidence, k.world)
            for k in keypoints]


def detector_keypoints(frames: list[np.ndarray], cache: Path) -> list[Keypoints]:
    """MediaPipe Pose, as the run uses it (:class:`mocap.io.mediapipe_keypoints.MediaPipeKeypoints`,
    image mode), on every frame; read back from ``cache`` (a keypoint file with MediaPipe's world
    joints) when it holds them, else detected and written there (atomically).

    Parameters
    ----------
    frames : list of ndarray, shape (H, W, 3), uint8
        The input frames, RGB, in order.
    cache : Path
        The keypoint file (:data:`DETECTOR_FILE` in the sequence's folder).

    Returns
    -------
    list of Keypoints
        One per frame, input pixels (empty where no person was found).

    Raises
    ------
    ValueError
        When the keypoints extra is not installed (``pip install -e .[keypoints]``).
    """
    from mocap.io.keypoints import read_keypoints, write_keypoints
    from mocap.io.mediapipe_keypoints import MediaPipeKeypoints

    if not cache.is_file():
        with MediaPipeKeypoints() as detector:
            write_keypoints(cache, {i: detector.keypoints(i, frame) for i, frame in enumerate(frames)})
    found = read_keypoints(cache)
    return [found.get(i, Keypoints.empty()) for i in range(len(frames))]
