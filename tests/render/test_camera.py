import json

import numpy as np
import pytest
from hypothesis import given, strategies as st

from mocap.render import Camera


def test_default_is_a_160x120_webcam_with_60_degree_field_of_view():
    cam = Camera.default()
    assert cam.shape == (120, 160)
    # the image's left and right borders are 30 degrees off axis
    u = cam.project([[np.tan(np.radians(30)), 0.0, 1.0], [-np.tan(np.radians(30)), 0.0, 1.0]])[:, 0]
    np.testing.assert_allclose(u, [160.0, 0.0])


def test_projection_and_scaling():
    cam = Camera(320, 240, 300.0, 310.0, 160.0, 120.0)
    np.testing.assert_allclose(cam.project([0.2, -0.1, 2.0]), [160 + 30.0, 120 - 15.5])
    big = cam.scaled(640, 480)
    np.testing.assert_allclose(big.project([0.2, -0.1, 2.0]), 2 * cam.project([0.2, -0.1, 2.0]))
    with pytest.raises(ValueError, match="behind"):
        cam.project([0.0, 0.0, -1.0])


def test_json_round_trip(tmp_path):
    cam = Camera.default(256, 256)
    cam.to_json(tmp_path / "cam.json")
    assert Camera.from_json(tmp_path / "cam.json") == cam
    with pytest.raises(ValueError, match="unknown camera keys"):
        Camera.from_dict({**json.loads((tmp_path / "cam.json").read_text()), "k1": 0.1})


@given(st.one_of(st.integers(-5, 0), st.integers(16385, 10**6), st.floats(), st.booleans()))
def test_bad_sizes_rejected(bad):
    with pytest.raises(ValueError):
        Camera(bad, 120, 100.0, 100.0, 80.0, 60.0)


@given(st.sampled_from([0.0, -1.0, float("nan"), float("inf")]))
def test_bad_focal_rejected(bad):
    with pytest.raises(ValueError):
        Camera(160, 120, bad, 100.0, 80.0, 60.0)
