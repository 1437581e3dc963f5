"""2D keypoints from MediaPipe Pose (the optional extra ``keypoints``).

MediaPipe Pose's legacy solution (``mediapipe.solutions.pose``, BlazePose GHUM 3D, Apache 2.0)
in image mode (``static_image_mode``) with model complexity 1, whose landmark model ``pose_landmark_full.tflite`` the
pinned wheel (``mediapipe==0.10.14``) bundles: nothing is downloaded at run time. It runs on the
input-resolution RGB frame; landmarks come back normalised to the frame, so ``u = x * width``
and ``v = y * height`` in input pixels, the confidence is the landmark's ``visibility``.

Image mode finds the person afresh in every frame: a frame's keypoints depend on that frame
alone, so a run resumed at any frame (or re-run on another worker) gets the keypoints of an
uninterrupted run, bit for bit. Video mode tracks the person from frame to frame and smooths
the landmarks: its state cannot be rebuilt at a resume point short of replaying every earlier
frame (docs/research-log.md, issue 35: image mode's detector costs 1.4 times video mode's and
its joints are nearer the truth on a synthetic clip). ``image_mode=False`` gives video mode for
comparisons (:mod:`experiments.keypoint_resume`).

Joints (:data:`mocap.body.skeleton.JOINT_NAMES`) from landmarks (the person's left and right, as
MediaPipe's): ``head`` the midpoint of the ears (the centre of the head), shoulders, elbows and
wrists their landmarks, ``*_hand`` the mean of the wrist, index and pinky landmarks (the palm's
centre, where the model's hand joint is). ``neck`` has no landmark and is left absent. A joint
whose landmarks are averaged takes their smallest visibility.

The run's detector works in a process of its own (:func:`mediapipe_process`, a
:class:`~mocap.io.keypoint_process.KeypointProcess` running :class:`~mocap.io.mediapipe_pose.PoseLandmarks`),
so that MediaPipe's import, graph and result conversion do not hold the tracker's interpreter
lock; :class:`MediaPipeKeypoints` is the same detector in this process (the experiments'). Both
make their joints of the same landmarks with :func:`keypoints_of_landmarks`: their keypoints are
the same bit for bit. :func:`available` asks whether MediaPipe is installed without importing it
(about 2 s), so that a run's process never imports it.
"""
from __future__ import annotations

import functools
import importlib.util
import time
from types import MappingProxyType

import numpy as np

from mocap.body.skeleton import JOINT_NAMES
from mocap.io.keypoint_process import KeypointProcess
from mocap.io.keypoints import Keypoints
from mocap.io.mediapipe_pose import MISSING_EXTRA, N_LANDMARKS, NATIVE_NOISE, PoseLandmarks, describe

__all__ = ["MEDIAPIPE_LANDMARKS", "MISSING_EXTRA", "MIN_WORLD_VISIBILITY", "MediaPipeKeypoints", "N_LANDMARKS",
           "NATIVE_NOISE", "available", "keypoints_of_landmarks", "mediapipe_process", "world_joints"]

#: MediaPipe Pose landmark indices averaged into each joint (absent joints have none).
MEDIAPIPE_LANDMARKS = MappingProxyType({
    "head": (7, 8),
    "r_shoulder": (12,), "r_elbow": (14,), "r_wrist": (16,), "r_hand": (16, 18, 20),
    "l_shoulder": (11,), "l_elbow": (13,), "l_wrist": (15,), "l_hand": (15, 17, 19),
})
#: Least visibility of a world landmark taken as present by :func:`world_joints`.
MIN_WORLD_VISIBILITY = 0.5


def world_joints(world_landmarks, visibility, min_visibility: float = MIN_WORLD_VISIBILITY
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The model's joints from MediaPipe Pose's 3D world landmarks (``pose_world_landmarks``).

    MediaPipe gives them in metres about the midpoint of the hips, on the image's axes (x right,
    y down, z away from the camera), which are the camera's up to a translation (recorded in the
    keypoint file's ``x,y,z`` columns; the tracker does not read them). Joints as :data:`MEDIAPIPE_LANDMARKS` (the
    mean of their landmarks); ``neck`` is absent (no landmark), and so is a joint any of whose
    landmarks is less visible than ``min_visibility`` or not finite.

    Parameters
    ----------
    world_landmarks : array_like, shape (33, 3), metres
    visibility : array_like, shape (33,), in [0, 1]
    min_visibility : float

    Returns
    -------
    joints : ndarray, shape (10, 3), float64, metres
        :data:`~mocap.body.skeleton.JOINT_NAMES` order; NaN rows where absent.
    present : ndarray of bool, shape (10,)
    """
    from mocap.body.skeleton import JOINT_NAMES

    points = np.asarray(world_landmarks, dtype=np.float64)
    seen = np.asarray(visibility, dtype=np.float64)
    if points.shape != (N_LANDMARKS, 3) or seen.shape != (N_LANDMARKS,):
        raise ValueError(f"world landmarks must have shape ({N_LANDMARKS}, 3) and visibility ({N_LANDMARKS},), "
                         f"got {points.shape} and {seen.shape}")
    usable = np.all(np.isfinite(points), axis=1) & (np.nan_to_num(seen, nan=0.0) >= min_visibility)
    joints = np.full((len(JOINT_NAMES), 3), np.nan)
    present = np.zeros(len(JOINT_NAMES), dtype=bool)
    for name, indices in MEDIAPIPE_LANDMARKS.items():
        if usable[list(indices)].all():
            k = JOINT_NAMES.index(name)
            joints[k] = points[list(indices)].mean(axis=0)
            present[k] = True
    return joints, present


def available() -> bool:
    """Whether MediaPipe (the optional extra ``keypoints``) is installed here: what
    ``--keypoints auto`` asks. Its package is looked for, not imported (an import of about 2 s,
    which the detector's own process makes)."""
    return _installed()


def _installed() -> bool:
    return importlib.util.find_spec("mediapipe") is not None


def keypoints_of_landmarks(landmarks: tuple[np.ndarray | None, np.ndarray | None], height: int, width: int
                           ) -> Keypoints:
    """The model's keypoints of one frame's MediaPipe landmarks
    (:meth:`mocap.io.mediapipe_pose.PoseLandmarks.detect`).

    Parameters
    ----------
    landmarks : (ndarray (33, 4) or None, ndarray (33, 4) or None)
        The normalised landmarks and the world landmarks (metres), each with its visibility.
    height, width : int, pixels
        The frame's size.

    Returns
    -------
    Keypoints
        Input pixels; empty when no person was found. Their ``world`` holds MediaPipe's
        world joints (:func:`world_joints`; all NaN when no person was found).
    """
    image, world = landmarks
    none = np.full((len(JOINT_NAMES), 3), np.nan)     # the world columns: none this frame
    if image is None:
        empty = Keypoints.empty()
        return Keypoints(empty.uv, empty.confidence, none)
    joints = {}
    for name, indices in MEDIAPIPE_LANDMARKS.items():
        points = np.array([(image[i, 0] * width, image[i, 1] * height) for i in indices])
        confidence = min(float(np.clip(image[i, 3], 0.0, 1.0)) for i in indices)
        joints[name] = (*points.mean(axis=0), confidence)
    flat = Keypoints.from_mapping(joints)
    if world is None:
        return Keypoints(flat.uv, flat.confidence, none)
    xyz, _ = world_joints(world[:, :3], world[:, 3])
    return Keypoints(flat.uv, flat.confidence, xyz)


def mediapipe_process(*, depth: int = 3, image_mode: bool = True) -> KeypointProcess:
    """MediaPipe Pose in a process of its own (the run's detector; see the module), started now:
    its import and graph overlap what the caller does next.

    Parameters
    ----------
    depth : int
        Frames in flight at most (:class:`~mocap.io.keypoint_process.KeypointProcess`).
    image_mode : bool

    Raises
    ------
    ValueError
        When MediaPipe is not installed (:data:`MISSING_EXTRA`), at once.
    """
    if not _installed():
        raise ValueError(MISSING_EXTRA)
    make = PoseLandmarks if image_mode else functools.partial(PoseLandmarks, image_mode=False)
    return KeypointProcess(make, keypoints_of_landmarks, depth=depth, description=describe(image_mode))


class MediaPipeKeypoints:
    """A :class:`~mocap.io.keypoints.KeypointSource` running MediaPipe Pose on each frame, in
    this process (the run's is :func:`mediapipe_process`).

    Image mode by default: every frame on its own (see the module); with ``image_mode=False``,
    video mode, where frames must come in order (MediaPipe tracks the person between them). Use
    as a context manager, or call :meth:`close`.

    Parameters
    ----------
    image_mode : bool
        Image mode (the run's: exact resumes), else video mode.

    Attributes
    ----------
    milliseconds : list of float
        Wall-clock time of each frame's detection (the detector's own cost).

    Raises
    ------
    ValueError
        When the extra is not installed (:data:`MISSING_EXTRA`).
    """

    def __init__(self, *, image_mode: bool = True) -> None:
        self._pose = PoseLandmarks(image_mode=image_mode)
        self.milliseconds: list[float] = []
        self.description = describe(image_mode)

    def keypoints(self, frame_index: int, image: np.ndarray | None) -> Keypoints:
        """Keypoints of one frame (:func:`keypoints_of_landmarks`).

        Parameters
        ----------
        frame_index : int
            Unused (video mode relies on the frames' order).
        image : ndarray, shape (H, W, 3), uint8
            The input-resolution RGB frame.
        """
        started = time.perf_counter()
        landmarks = self._pose.detect(image)
        self.milliseconds.append(1e3 * (time.perf_counter() - started))
        return keypoints_of_landmarks(landmarks, *image.shape[:2])

    def close(self) -> None:
        """Release MediaPipe's graph."""
        self._pose.close()

    def __enter__(self) -> "MediaPipeKeypoints":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
