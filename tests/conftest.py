"""Shared fixtures: the real data in ``../shared/data`` and a few small helpers."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO_ROOT.parent / "shared" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path of ``../shared/data``.

    Skips with a reason on a machine that lacks it; in CI (``CI`` set) its absence fails.
    """
    if SHARED_DATA.is_dir():
        return SHARED_DATA
    reason = f"real data folder {SHARED_DATA} is absent (it sits beside the repository in CI)"
    if os.environ.get("CI"):
        pytest.fail(reason)
    pytest.skip(reason)


@pytest.fixture(autouse=True)
def bare_install_keypoints(request, monkeypatch):
    """Every test but those marked ``mediapipe`` sees ``--keypoints auto`` (the commands' default)
    as on an install without the optional extra ``keypoints``: no MediaPipe run unless asked.

    (Processes a test starts are not reached: they get ``--keypoints none``.)"""
    if request.node.get_closest_marker("mediapipe") is None:
        from mocap.io import mediapipe_keypoints

        monkeypatch.setattr(mediapipe_keypoints, "available", lambda: False)
