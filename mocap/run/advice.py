"""One line on what to try when a run went badly (:func:`what_to_try`), from the run's facts."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["MOSTLY_FAILED", "RunFacts", "what_to_try"]

#: Share of the tracked frames marked failed above which the run ends with advice.
MOSTLY_FAILED = 0.5


@dataclass(frozen=True)
class RunFacts:
    """What the advice looks at.

    Attributes
    ----------
    frames : int
        Frames tracked.
    failures : int
        Frames marked failed.
    keypoints : str or None
        The keypoint cue used (``"mediapipe"``, a file), None without.
    background : str or None
        How the background was found (``image``, ``frames``, ``estimated``, ``none``); None: unknown.
    height_given : bool
        The person's height was given (the absolute scale is known).
    calibration : str or None
        ``given`` or ``automatic``; None: unknown.
    """

    frames: int
    failures: int
    keypoints: str | None = None
    background: str | None = None
    height_given: bool = False
    calibration: str | None = None


def what_to_try(facts: RunFacts) -> str | None:
    """One line for a run whose frames mostly failed (more than :data:`MOSTLY_FAILED` of them):
    the options not used yet that most often help, best first; None for a run that went well."""
    if facts.frames == 0 or facts.failures <= MOSTLY_FAILED * facts.frames:
        return None
    tries = []
    if facts.keypoints is None:
        tries.append("--keypoints mediapipe (2D keypoints as a further cue; optional extra 'keypoints')")
    if facts.background in ("estimated", "none"):
        tries.append("a background plate (--background IMG, a picture of the empty scene, or "
                     "--background-frames A:B where nobody is in view)")
    if facts.calibration == "automatic" and not facts.height_given:
        tries.append("--height M (the person's height fixes the scale of the automatic calibration)")
    share = f"{facts.failures} of {facts.frames} frames were marked failed"
    if not tries:
        return f"{share}: see docs/own-video.md for what the tracker needs to see"
    return f"{share}; try " + ", or ".join(tries)
