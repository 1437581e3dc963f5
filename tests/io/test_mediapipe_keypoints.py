"""The MediaPipe keypoint source on a real clip (needs the optional extra ``keypoints``).

CI installs the extra (the ``test`` extra includes it), so there the test runs; elsewhere,
without MediaPipe, it skips with its reason (and without the shared data, as every test that
needs it).
"""
from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import numpy as np
import pytest

from mocap.body.skeleton import JOINT_NAMES

from tests.conftest import need_mediapipe

pytestmark = pytest.mark.shared_data

#: Joints of frame 30 of ``intel_asl_no.mkv`` (640x480), read off the frame by eye (to about
#: 15 px) before MediaPipe was run on it: the person's right arm raised, the left hanging.
ANNOTATED = {"head": (305, 105), "r_shoulder": (225, 185), "l_shoulder": (395, 185), "r_elbow": (160, 300),
             "l_elbow": (455, 300), "r_wrist": (205, 195), "l_wrist": (440, 420)}
#: Stated tolerance: a quarter of the annotated shoulder width (the issue's real-clip measure).
TOLERANCE_PX = 0.25 * (395 - 225)


@pytest.fixture(scope="module")
def mediapipe_available():
    need_mediapipe()


def test_mediapipe_finds_the_visible_joints_of_a_real_clip(shared_data, mediapipe_available, capfd):
    import warnings

    from mocap.io.mediapipe_keypoints import MediaPipeKeypoints
    from mocap.io.video import iter_frames

    capfd.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")             # every warning shown, as `python -W always` would
        with MediaPipeKeypoints() as source:
            for i, frame in enumerate(iter_frames(shared_data / "video" / "intel_asl_no.mkv")):
                k = source.keypoints(i, frame)
                if i == 30:
                    break
    # nothing of MediaPipe's own reaches the terminal: no Python warning (protobuf's deprecation),
    # no native log line (TensorFlow Lite, absl) on the process's stderr
    assert [str(w.message) for w in caught] == []
    assert capfd.readouterr().err == ""
    found = k.as_mapping()
    for name, (u, v) in ANNOTATED.items():
        assert name in found, f"{name} not found"
        assert np.hypot(found[name][0] - u, found[name][1] - v) < TOLERANCE_PX, name
    assert "neck" not in found and len(source.milliseconds) == 31
    assert k.uv.shape == (len(JOINT_NAMES), 2)
    # its 3D (world landmarks) on the camera's axes: the person faces the camera, so their right
    # shoulder is left of their left one (x right), the head above the shoulders (y down), the
    # raised right wrist above the hanging left one; metres (shoulders 0.25-0.5 m apart)
    w = {name: k.world[JOINT_NAMES.index(name)] for name in ANNOTATED}
    assert w["r_shoulder"][0] < w["l_shoulder"][0] and w["head"][1] < min(w["r_shoulder"][1], w["l_shoulder"][1])
    assert w["r_wrist"][1] < w["l_wrist"][1]
    assert 0.25 < np.linalg.norm(w["r_shoulder"] - w["l_shoulder"]) < 0.5
    assert np.isnan(k.world[JOINT_NAMES.index("neck")]).all()


def test_the_detector_in_its_own_process_gives_the_same_keypoints_bit_for_bit(shared_data, mediapipe_available, capfd):
    """:func:`mediapipe_process` (the run's detector) against :class:`MediaPipeKeypoints` (this
    process) on 12 frames of a real clip: the same bytes, 2D and world; nothing of MediaPipe's
    own on stderr; and the parent never imports MediaPipe (a process of its own asked)."""
    import subprocess
    import sys

    from mocap.io.mediapipe_keypoints import MediaPipeKeypoints, mediapipe_process
    from mocap.io.video import iter_frames

    clip = shared_data / "video" / "intel_asl_no.mkv"
    frames = [frame for _, frame in zip(range(12), iter_frames(clip))]
    capfd.readouterr()
    with mediapipe_process(depth=3) as process:
        there = []
        for i, frame in enumerate(frames):
            if process.pending == process.depth:
                there.append(process.take(len(there)))
            process.submit(i, frame)
        while process.pending:
            there.append(process.take(len(there)))
        assert process.description.startswith("mediapipe 0.") and len(process.milliseconds) == 12
    with MediaPipeKeypoints() as source:
        here = [source.keypoints(i, frame) for i, frame in enumerate(frames)]
    assert capfd.readouterr().err == ""
    assert sum(k.present.sum() for k in here) >= 9 * 10
    for a, b in zip(here, there, strict=True):
        assert a.uv.tobytes() == b.uv.tobytes() and a.confidence.tobytes() == b.confidence.tobytes()
        assert a.world.tobytes() == b.world.tobytes()
    script = ("import sys, numpy as np; from mocap.io.mediapipe_keypoints import mediapipe_process; "
              "p = mediapipe_process(); p.keypoints(0, np.zeros((48, 64, 3), np.uint8)); p.close(); "
              "print(sorted(m for m in sys.modules if m.split('.')[0] == 'mediapipe'))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True,
                          cwd=Path(__file__).resolve().parents[2])
    assert done.stdout.strip() == "[]" and done.stderr == ""


def test_missing_extra_is_one_clear_line(monkeypatch):
    import builtins

    from mocap.io.mediapipe_keypoints import MISSING_EXTRA, MediaPipeKeypoints

    real_import = builtins.__import__

    def no_mediapipe(name, *args, **kwargs):
        if name.startswith("mediapipe"):
            raise ImportError("No module named 'mediapipe'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_mediapipe)
    with pytest.raises(ValueError, match="pip install 'mocap\\[keypoints\\]'") as info:
        MediaPipeKeypoints()
    assert "\n" not in str(info.value) and str(info.value) == MISSING_EXTRA
