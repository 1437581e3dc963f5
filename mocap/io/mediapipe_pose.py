"""MediaPipe Pose's landmarks of a frame, as plain arrays: what a detector process runs.

The part of :mod:`mocap.io.mediapipe_keypoints` that touches MediaPipe itself, kept light (it
imports NumPy and nothing of the body model) so that the detector's own process
(:mod:`mocap.io.keypoint_process`) starts with MediaPipe's import and nothing else.
:class:`PoseLandmarks` opens MediaPipe Pose's legacy solution (``mediapipe.solutions.pose``,
model complexity 1, image mode by default) and gives each frame's 33 landmarks, normalised to
the frame, and its 33 world landmarks, in metres, with their visibilities, as float64 arrays
(the values MediaPipe's result holds, widened from float32 to float64 as Python's floats are);
:func:`mocap.io.mediapipe_keypoints.keypoints_of_landmarks` makes the model's joints of them.

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
import warnings
from contextlib import contextmanager

import numpy as np

__all__ = ["MISSING_EXTRA", "NATIVE_NOISE", "N_LANDMARKS", "PoseLandmarks", "describe", "mediapipe_version"]

#: What to install for ``--keypoints mediapipe``.
MISSING_EXTRA = ("--keypoints mediapipe needs MediaPipe Pose, the optional extra 'keypoints': "
                 "pip install 'mocap[keypoints]' (or give a keypoint file: --keypoints FILE.csv)")
#: Number of MediaPipe Pose landmarks.
N_LANDMARKS = 33
#: Lines MediaPipe's native code writes to stderr when its graph starts (regular expressions).
NATIVE_NOISE = (r"INFO: Created TensorFlow Lite XNNPACK delegate",
                r"WARNING: All log messages before absl::InitializeLog\(\) is called",
                r"W\d{4} .*inference_feedback_manager\.cc:\d+\] Feedback manager requires")


def mediapipe_version() -> str | None:
    """The installed MediaPipe's version, read from its package metadata (no import), or None."""
    from importlib import metadata

    try:
        return metadata.version("mediapipe")
    except metadata.PackageNotFoundError:
        return None


def describe(image_mode: bool) -> str:
    """What ``run.json`` ``settings.keypoints`` says of MediaPipe Pose in this mode."""
    return f"mediapipe {mediapipe_version()} pose, model complexity 1, {'image' if image_mode else 'video'} mode"


class PoseLandmarks:
    """MediaPipe Pose, frame by frame (see the module); call :meth:`close` at the end.

    Parameters
    ----------
    image_mode : bool
        Image mode (every frame on its own: exact resumes), else video mode (frames in order).

    Raises
    ------
    ValueError
        When MediaPipe does not import (:data:`MISSING_EXTRA`).
    """

    def __init__(self, *, image_mode: bool = True) -> None:
        try:
            from mediapipe.python.solutions import pose as mp_pose
        except ImportError:
            raise ValueError(MISSING_EXTRA) from None

        # protobuf 4's deprecation of what MediaPipe's result conversion calls (every frame)
        warnings.filterwarnings("ignore", message=r"SymbolDatabase\.GetPrototype\(\) is deprecated",
                                category=UserWarning, module=r"google\.protobuf\.symbol_database")

        with _native_noise_dropped():       # the graph opens its calculators on threads of its own: waited for
            self._pose = mp_pose.Pose(static_image_mode=image_mode, model_complexity=1)
            self._pose._graph.wait_until_idle()

    def detect(self, image: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
        """One frame's landmarks.

        Parameters
        ----------
        image : ndarray, shape (H, W, 3), uint8
            RGB.

        Returns
        -------
        landmarks : ndarray, shape (33, 4), float64, or None
            ``x, y`` normalised to the frame (``u = x W``), ``z``, ``visibility``; None when no
            person was found.
        world : ndarray, shape (33, 4), float64, or None
            ``x, y, z`` in metres about the hips' midpoint, ``visibility``; None without.
        """
        if image is None or image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise ValueError(f"MediaPipe needs an RGB uint8 frame (H, W, 3), got "
                             f"{getattr(image, 'shape', None)} {getattr(image, 'dtype', None)}")
        result = self._pose.process(np.ascontiguousarray(image))
        return _array(result.pose_landmarks), _array(result.pose_world_landmarks)

    def close(self) -> None:
        """Release MediaPipe's graph."""
        self._pose.close()


def _array(landmarks) -> np.ndarray | None:
    """A landmark list's ``(x, y, z, visibility)`` rows, float64 (33, 4), or None."""
    if landmarks is None:
        return None
    return np.array([(p.x, p.y, p.z, p.visibility) for p in landmarks.landmark], dtype=np.float64)


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
