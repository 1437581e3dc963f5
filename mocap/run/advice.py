"""One line on what to try when a run went badly (:func:`what_to_try`), from the run's facts."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["KEYPOINTS_EXTRA_INSTALL", "MOSTLY_FAILED", "RunFacts", "mostly_failed", "what_to_try"]

#: Share of the tracked frames marked failed above which the run ends with advice.
MOSTLY_FAILED = 0.5
#: How the optional extra ``keypoints`` (MediaPipe Pose) is installed from the checkout (as the README).
KEYPOINTS_EXTRA_INSTALL = 'python -m pip install -e ".[keypoints]"'


@dataclass(frozen=True, kw_only=True)
class RunFacts:
    """What the advice looks at.

    Attributes
    ----------
    frames : int
        Frames tracked.
    failures : int
        Frames marked failed.
    keypoints : str or None
        The keypoint cue used, as resolved (``"mediapipe"``, a file; ``--keypoints auto`` gives
        ``"mediapipe"`` or None: :func:`mocap.run.options.resolve_keypoints`), None without.
    keypoints_extra : bool
        MediaPipe Pose (the optional extra ``keypoints``) is installed
        (:func:`mocap.io.mediapipe_keypoints.available`).
    background : str or None
        The background's mode (:data:`mocap.run.options.BACKGROUND_MODES`: ``auto``, ``image``,
        ``frames``, ``none``); None: unknown.
    height_given : bool
        The person's height was given (the absolute scale is known).
    calibration : str or None
        ``given`` or ``automatic``; None: unknown.
    """

    frames: int
    failures: int
    keypoints: str | None = None
    keypoints_extra: bool
    background: str | None = None
    height_given: bool = False
    calibration: str | None = None


def mostly_failed(frames: int, failures: int) -> bool:
    """More than :data:`MOSTLY_FAILED` of ``frames`` (at least one) were marked failed: the run
    ends with advice."""
    return frames > 0 and failures > MOSTLY_FAILED * frames


def what_to_try(facts: RunFacts) -> str | None:
    """One line for a run whose frames mostly failed (:func:`mostly_failed`): the options not
    used yet that most often help, best first (the keypoints extra first where it is not
    installed); None for a run that went well."""
    if not mostly_failed(facts.frames, facts.failures):
        return None
    tries = []
    if facts.keypoints is None and not facts.keypoints_extra:
        tries.append(f"the keypoints extra ({KEYPOINTS_EXTRA_INSTALL}: MediaPipe Pose's 2D keypoints as a further "
                     "cue, used by default once installed)")
    elif facts.keypoints is None:
        tries.append("--keypoints mediapipe (2D keypoints as a further cue)")
    if facts.background in ("auto", "none"):            # no picture of the empty scene given
        tries.append("a background plate (--background IMG, a picture of the empty scene, or "
                     "--background-frames A:B where nobody is in view)")
    if facts.calibration == "automatic" and not facts.height_given:
        tries.append("--height M (the person's height fixes the scale of the automatic calibration)")
    share = f"{facts.failures} of {facts.frames} frames were marked failed"
    if not tries:
        return f"{share}: see docs/own-video.md for what the tracker needs to see"
    return f"{share}; try " + ", or ".join(tries)
