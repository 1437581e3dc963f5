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

What MediaPipe and its dependencies print about themselves does not reach the terminal: the
Python warning of protobuf's deprecated ``SymbolDatabase.GetPrototype`` (ignored by a filter on
that message and module alone, set where MediaPipe is imported) and the lines its native code
writes to the process's stderr when its graph opens (TensorFlow Lite's delegate, absl's
logging notice, the feedback manager's warning: :data:`NATIVE_NOISE`, dropped from what is
written there while the graph opens, which the constructor waits for; any other line is passed
on).
"""
from __future__ import annotations

import os
import re
import sys
import tempfile
import time
import warnings
from contextlib import contextmanager
from types import MappingProxyType

import numpy as np

from mocap.body.skeleton import JOINT_NAMES
from mocap.io.keypoints import Keypoints

#: MediaPipe Pose landmark indices averaged into each joint (absent joints have none).
MEDIAPIPE_LANDMARKS = MappingProxyType({
    "head": (7, 8),
    "r_shoulder": (12,), "r_elbow": (14,), "r_wrist": (16,), "r_hand": (16, 18, 20),
    "l_shoulder": (11,), "l_elbow": (13,), "l_wrist": (15,), "l_hand": (15, 17, 19),
})
#: What to install for ``--keypoints mediapipe``.
MISSING_EXTRA = ("--keypoints mediapipe needs MediaPipe Pose, the optional extra 'keypoints': "
                 "pip install 'mocap[keypoints]' (or give a keypoint file: --keypoints FILE.csv)")


#: Number of MediaPipe Pose landmarks.
N_LANDMARKS = 33
#: Least visibility of a world landmark taken as present by :func:`world_joints`.
MIN_WORLD_VISIBILITY = 0.5


def world_joints(world_landmarks, visibility, min_visibility: float = MIN_WORLD_VISIBILITY
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The model's joints from MediaPipe Pose's 3D world landmarks (``pose_world_landmarks``).

    MediaPipe gives them in metres about the midpoint of the hips, on the image's axes (x right,
    y down, z away from the camera), which are the camera's up to a translation: what
    :func:`mocap.body.ik.fit_pose_to_joints` takes. Joints as :data:`MEDIAPIPE_LANDMARKS` (the
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
    """Whether MediaPipe Pose (the optional extra ``keypoints``) imports here: what
    ``--keypoints auto`` asks (an import of about 2 s the first time)."""
    try:
        from mediapipe.python.solutions import pose  # noqa: F401
    except ImportError:
        return False
    return True


class MediaPipeKeypoints:
    """A :class:`~mocap.io.keypoints.KeypointSource` running MediaPipe Pose on each frame.

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
        try:
            from mediapipe.python.solutions import pose as mp_pose
        except ImportError:
            raise ValueError(MISSING_EXTRA) from None
        from mediapipe import __version__

        # protobuf 4's deprecation of what MediaPipe's result conversion calls (every frame)
        warnings.filterwarnings("ignore", message=r"SymbolDatabase\.GetPrototype\(\) is deprecated",
                                category=UserWarning, module=r"google\.protobuf\.symbol_database")

        with _native_noise_dropped():       # the graph opens its calculators on threads of its own: waited for
            self._pose = mp_pose.Pose(static_image_mode=image_mode, model_complexity=1)
            self._pose._graph.wait_until_idle()
        self.milliseconds: list[float] = []
        mode = "image" if image_mode else "video"
        self.description = f"mediapipe {__version__} pose, model complexity 1, {mode} mode"

    def keypoints(self, frame_index: int, image: np.ndarray | None) -> Keypoints:
        """Keypoints of one frame.

        Parameters
        ----------
        frame_index : int
            Unused (video mode relies on the frames' order).
        image : ndarray, shape (H, W, 3), uint8
            The input-resolution RGB frame.

        Returns
        -------
        Keypoints
            Input pixels; empty when no person was found. Their ``world`` holds MediaPipe's
            world joints (:func:`world_joints`; all NaN when no person was found).
        """
        if image is None or image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise ValueError(f"MediaPipe needs an RGB uint8 frame (H, W, 3), got "
                             f"{getattr(image, 'shape', None)} {getattr(image, 'dtype', None)}")
        height, width = image.shape[:2]
        started = time.perf_counter()
        result = self._pose.process(np.ascontiguousarray(image))
        self.milliseconds.append(1e3 * (time.perf_counter() - started))
        none = np.full((len(JOINT_NAMES), 3), np.nan)     # the world columns: none this frame
        if result.pose_landmarks is None:
            empty = Keypoints.empty()
            return Keypoints(empty.uv, empty.confidence, none)
        landmarks = result.pose_landmarks.landmark
        joints = {}
        for name, indices in MEDIAPIPE_LANDMARKS.items():
            points = np.array([(landmarks[i].x * width, landmarks[i].y * height) for i in indices])
            confidence = min(float(np.clip(landmarks[i].visibility, 0.0, 1.0)) for i in indices)
            joints[name] = (*points.mean(axis=0), confidence)
        flat = Keypoints.from_mapping(joints)
        if result.pose_world_landmarks is None:
            return Keypoints(flat.uv, flat.confidence, none)
        world = result.pose_world_landmarks.landmark
        xyz, _ = world_joints([(p.x, p.y, p.z) for p in world], [p.visibility for p in world])
        return Keypoints(flat.uv, flat.confidence, xyz)

    def close(self) -> None:
        """Release MediaPipe's graph."""
        self._pose.close()

    def __enter__(self) -> "MediaPipeKeypoints":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


#: Lines MediaPipe's native code writes to stderr when its graph starts (regular expressions).
NATIVE_NOISE = (r"INFO: Created TensorFlow Lite XNNPACK delegate",
                r"WARNING: All log messages before absl::InitializeLog\(\) is called",
                r"W\d{4} .*inference_feedback_manager\.cc:\d+\] Feedback manager requires")


@contextmanager
def _native_noise_dropped():
    """Within the block, what is written to file descriptor 2 (native code's stderr, and
    Python's) goes to a temporary file; after it, the lines that are not :data:`NATIVE_NOISE`
    are written to ``sys.stderr`` (nothing is lost, only delayed)."""
    noise = re.compile("|".join(NATIVE_NOISE))
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as caught:
        os.dup2(caught.fileno(), 2)
        try:
            yield
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            caught.seek(0)
            kept = [line for line in caught.read().decode("utf-8", "replace").splitlines(keepends=True)
                    if not noise.search(line)]
            if kept:
                sys.stderr.write("".join(kept))
                sys.stderr.flush()
