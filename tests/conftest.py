"""Shared fixtures: the real data in ``../shared/data`` and a few small helpers."""
from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

import pytest

from mocap.io import mediapipe_keypoints

REPO_ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO_ROOT.parent / "shared" / "data"
#: Whether MediaPipe is installed, as the library asks it (kept before the session's patch).
_REAL_AVAILABLE = mediapipe_keypoints.available
#: Why MediaPipe cannot be installed on this Python (pyproject.toml's marker on the extra
#: ``keypoints``), or None where it can.
MEDIAPIPE_UNINSTALLABLE = ("MediaPipe cannot be installed on Python 3.13+: mediapipe==0.10.14, the last release "
                           "with its pose model in the wheel, has wheels up to 3.12 (the extra 'keypoints' installs "
                           "nothing here)") if sys.version_info >= (3, 13) else None


def need_mediapipe() -> None:
    """Skip the calling test unless MediaPipe imports, with the reason: it cannot be installed on
    this Python (:data:`MEDIAPIPE_UNINSTALLABLE`), or it is not installed (CI, which installs it
    with the test extra, fails instead)."""
    if importlib.util.find_spec("mediapipe") is not None:
        return
    if MEDIAPIPE_UNINSTALLABLE is not None:
        pytest.skip(MEDIAPIPE_UNINSTALLABLE)
    reason = "MediaPipe is not installed (optional extra 'keypoints': pip install 'mocap[keypoints]')"
    if os.environ.get("CI"):
        pytest.fail(reason + "; CI installs it with the test extra")
    pytest.skip(reason)


#: Test files that share a session fixture costing a minute (the tiny sweep of
#: tests/experiments/conftest.py): one pytest-xdist group, so that one worker makes it once.
SHARED_SESSION_GROUPS = {f"tests/experiments/{name}.py": "tiny-sweep"
                         for name in ("test_figures", "test_sweep", "test_sweep_cluster")}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Under pytest-xdist's ``--dist loadgroup`` (pyproject.toml's addopts), a test file's tests
    run on one worker, in order (its module fixtures are made once; the docs' blocks of a file
    build on each other), and the files of :data:`SHARED_SESSION_GROUPS` together."""
    for item in items:
        name = Path(str(item.fspath)).resolve().relative_to(REPO_ROOT).as_posix()
        item.add_marker(pytest.mark.xdist_group(SHARED_SESSION_GROUPS.get(name, name)))


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


@pytest.fixture(autouse=True, scope="session")
def bare_install_keypoints():
    """The whole session (module- and session-scoped fixtures included) sees ``--keypoints auto``
    (the commands' default) as on an install without the optional extra ``keypoints``: no
    MediaPipe run unless a test asks (marker ``mediapipe``: :func:`real_keypoints_extra`).

    (Processes a test starts are not reached: they get ``--keypoints none``.)"""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(mediapipe_keypoints, "available", lambda: False)
        yield


@pytest.fixture(autouse=True)
def real_keypoints_extra(request, monkeypatch):
    """Tests marked ``mediapipe`` see whether MediaPipe is really installed."""
    if request.node.get_closest_marker("mediapipe") is not None:
        monkeypatch.setattr(mediapipe_keypoints, "available", _REAL_AVAILABLE)

