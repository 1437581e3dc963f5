"""The hand-size cue (issue 46): analytic perspective, the hand's points on the model, the audit's plumbing."""
import math

import numpy as np
import pytest

from experiments.hand_size import (CUE_KINDS, FLIP_KINDS, KNUCKLE_ALONG, NOISE_PX, hand_cue, hand_local_points,
                                   hand_points, measure_sequence, predicted_hand_px, spans, summarise, tables)
from mocap.body import BodyDimensions, BodyModel, PARAMETER_INDEX as P, neutral_pose
from mocap.body.skeleton import JOINT_INDEX
from mocap.render import Camera
from mocap.track.branches import depth_alternatives

MODEL = BodyModel.build(BodyDimensions(), resolution=8)
CAMERA = Camera.default(640, 480)


def facing_hand(z: float, x: float = 0.0, y: float = 0.0) -> np.ndarray:
    """The right hand's three points, palm square to the optical axis, wrist at (x, y, z) metres."""
    return hand_local_points(MODEL, "r") + np.array([x, y, z])


def test_span_is_focal_times_size_over_depth():
    size = MODEL.dims["r_hand"]
    for z in (1.5, 2.3, 3.0):
        width, length = spans(CAMERA.project(facing_hand(z, 0.1, -0.2)))
        assert width == pytest.approx(CAMERA.fx * size.width / z, rel=1e-12)
        assert length == pytest.approx(CAMERA.fy * KNUCKLE_ALONG * size.length / z, rel=1e-12)


def test_hand_moved_along_its_ray_changes_the_span_cue_by_f_s_over_z():
    """A hand moved along the camera ray through its wrist by a known depth: its span cue against
    the first is exactly f * s * |1/z - 1/z'| for both spans, and the points cue is positive."""
    size = MODEL.dims["r_hand"]
    z, dz = 2.3, 0.3
    near = facing_hand(z - dz, 0.0, 0.0)
    far = facing_hand(z, 0.0, 0.0)
    observed, predicted = CAMERA.project(far), CAMERA.project(near)
    s = size.width + KNUCKLE_ALONG * size.length
    expected = CAMERA.fx * s * abs(1.0 / (z - dz) - 1.0 / z)
    assert hand_cue(observed, predicted, "span") == pytest.approx(expected, rel=1e-12)
    assert hand_cue(observed, observed, "span") == 0.0
    assert hand_cue(observed, predicted, "points") > 0.0
    # the arithmetic: 30 cm nearer at 2.3 m, about 15 % larger
    assert spans(predicted)[0] / spans(observed)[0] == pytest.approx(z / (z - dz))


def test_hand_cue_broadcasts_and_rejects_unknown_kind():
    obs = CAMERA.project(facing_hand(2.0))
    stacked = np.stack([obs, obs + 1.0])
    assert hand_cue(stacked, obs[None], "points").tolist() == pytest.approx([0.0, math.sqrt(2.0)])
    with pytest.raises(ValueError):
        hand_cue(obs, obs, "area")


@pytest.mark.parametrize("side", ["r", "l"])
def test_the_mean_of_the_hand_points_is_the_model_hand_joint(side):
    rng = np.random.default_rng(1)
    q = neutral_pose()
    for name in ("shoulder_flex", "shoulder_abd", "elbow_flex", "forearm_twist", "wrist_flex"):
        q[P[f"{side}_{name}"]] = rng.uniform(0.1, 0.8)
    points = hand_points(q, MODEL, side)
    assert points.mean(axis=0) == pytest.approx(MODEL.joint_positions(q)[JOINT_INDEX[f"{side}_hand"]], abs=1e-12)
    assert points[0] == pytest.approx(MODEL.joint_positions(q)[JOINT_INDEX[f"{side}_wrist"]], abs=1e-12)
    assert np.linalg.norm(points[1] - points[2]) == pytest.approx(MODEL.dims[f"{side}_hand"].width)


def test_an_exact_mirror_moves_the_hand_points_and_the_truth_wins_without_noise():
    q = neutral_pose()
    for name, degrees in (("r_shoulder_flex", 30), ("r_shoulder_abd", 20), ("r_elbow_flex", 90)):
        q[P[name]] = np.radians(degrees)
    working = Camera.default(160, 120)
    alternatives = [a for a in depth_alternatives(q, MODEL, working) if a.side == "r"]
    assert alternatives
    truth_px = predicted_hand_px(q, MODEL, CAMERA, "r")
    for a in alternatives:
        alt_px = predicted_hand_px(a.pose, MODEL, CAMERA, "r")
        # the hand joint keeps its projection (within the builder's 0.5 px at 160x120), the hand points do not
        assert np.linalg.norm(alt_px.mean(axis=0) - truth_px.mean(axis=0)) < 4 * 0.5 + 1e-9
        assert hand_cue(truth_px, alt_px, "points") > hand_cue(truth_px, truth_px, "points") == 0.0


@pytest.fixture(scope="module")
def unit():
    """Every 40th frame of one sequence, the motion only (nothing rendered)."""
    return measure_sequence("gestures-1", 0, stride=40)


def test_measure_sequence_shapes_and_the_noise_free_upper_bound(unit):
    n = len(unit["frame"])
    assert n > 0 and int(unit["frames"]) == 5
    for cue in CUE_KINDS:
        assert unit[f"truth_{cue}"].shape == unit[f"alt_{cue}"].shape == (n, len(NOISE_PX))
        assert np.all(unit[f"truth_{cue}"][:, 0] == 0.0)
    assert set(unit["kind"].tolist()) <= set(range(len(FLIP_KINDS)))
    assert np.all(np.isnan(unit["truth_score"]))             # not rendered: no score
    assert np.all(np.isfinite(unit["truth_prior"]))


def test_summary_and_tables(unit, tmp_path):
    from experiments.figures import ext_hand_size

    units = {("gestures-1", 0): unit, ("gestures-1", 83): unit}
    s = summarise(units)
    assert s["groups"]["fit"]["pooled"]["pairs"] == len(unit["frame"])
    assert s["groups"]["fit"]["pooled"]["points"][0] == 1.0          # noise 0: the truth always wins
    assert sum(b["pairs"] for b in s["groups"]["fit"]["per_depth"]) == len(unit["frame"])
    assert [r["base"] for r in s["combined"]] == ["prior"] * (2 * len(NOISE_PX))   # no score measured
    assert "pooled" in tables(s)
    written = ext_hand_size.main(s, tmp_path)
    assert any(p.suffix == ".png" for p in written)
