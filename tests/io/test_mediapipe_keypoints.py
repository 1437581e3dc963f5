"""The MediaPipe keypoint source on a real clip (needs the optional extra ``keypoints``).

CI installs the extra (the ``test`` extra includes it), so there the test runs; elsewhere,
without MediaPipe, it skips with its reason (and without the shared data, as every test that
needs it).
"""
from __future__ import annotations

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
