"""The score's table (mocap.track.score): one place for the terms, read by the tracker's record,
the config's validation and the weights; the sums and the motion term against plain loops."""
import dataclasses
import math

import numpy as np
import pytest

from mocap.track.smooth import SmootherConfig
from mocap.track import ScoredCandidate, TrackerConfig
from mocap.track.score import (MOTION, MOTION_CAP, MOTION_SIGMA_M, REGION_WEIGHT, TERM_NAMES, TERMS, TURN_CAP,
                               TURN_SIGMA_DEG, UNARY_TERMS, WEIGHT_FIELDS, motion_term, transition_term, turn_term,
                               weighted_sum, weights, with_weights)


def test_every_term_is_an_attribute_of_a_scored_candidate_and_its_weight_a_validated_config_field():
    fields = {f.name for f in dataclasses.fields(ScoredCandidate)}
    assert set(TERM_NAMES) <= fields
    # everything else a scored candidate holds is not a term
    assert fields - set(TERM_NAMES) == {"origin", "pose", "joints", "unary"}
    config_fields = {f.name for f in dataclasses.fields(TrackerConfig)}
    assert set(WEIGHT_FIELDS) <= config_fields
    assert not any(name.startswith("silhouette_") and name.endswith("_weight") for name in config_fields)
    for name in WEIGHT_FIELDS:
        for bad in (-1.0, math.nan, math.inf, True):
            with pytest.raises(ValueError):
                TrackerConfig(**{name: bad})
    assert TERMS[MOTION].pairwise and [t.name for t in UNARY_TERMS] == list(TERM_NAMES[:len(UNARY_TERMS)])
    assert [t.weight_field for t in TERMS].count(None) == 1                     # F's weight is the unit


def test_the_weights_of_a_config_in_the_tables_order_and_back():
    config = TrackerConfig(edge_weight=3.0, keypoint_weight=1.5, prior_weight=0.1, lifter_weight=0.7,
                           labelling_weight=0.4, motion_weight=0.25)
    w = weights(config)
    np.testing.assert_array_equal(w, [REGION_WEIGHT, 3.0, 1.5, 0.1, 0.7, 0.4, 0.25])
    assert with_weights(TrackerConfig(beam=4), w) == dataclasses.replace(config, beam=4)
    with pytest.raises(ValueError):
        with_weights(config, w[:5])


def test_a_scored_candidates_values_follow_the_table():
    c = ScoredCandidate.from_terms("tracked", np.zeros(23), np.zeros((10, 3)), [0.1, 2.0, math.nan, 3.0, 4.0, 0.5],
                                   np.array([5.0, 6.0]), 7.0)
    assert (c.region, c.edge, c.prior, c.lifter, c.labelling, c.unary) == (0.1, 2.0, 3.0, 4.0, 0.5, 7.0)
    assert math.isnan(c.keypoint)
    np.testing.assert_array_equal(c.values(), [0.1, 2.0, math.nan, 3.0, 4.0, 0.5, 5.0])
    np.testing.assert_array_equal(c.values(previous=1)[MOTION], 6.0)
    assert math.isnan(c.values(previous=2)[MOTION])
    with pytest.raises(ValueError):
        ScoredCandidate.from_terms("tracked", np.zeros(23), np.zeros((10, 3)), [0.1, 2.0], np.zeros(1), 0.0)


def test_the_weighted_sum_leaves_out_what_does_not_apply_and_is_the_same_float_alone_or_in_an_array():
    rng = np.random.default_rng(5)
    values = rng.uniform(0, 10, size=(40, len(UNARY_TERMS)))
    values[::3, 2] = np.nan                                   # no keypoints
    values[::4, 3:5] = np.nan                                 # no prior, not lifted
    w = np.array([50.0, 2.0, 1.5, 0.05, 0.5, 1.0, 1.0])
    together = weighted_sum(values, w)
    for row, total in zip(values, together):
        expected = 0.0
        for j in range(len(row)):                             # the loop the tracker ran, term by term
            if not math.isnan(row[j]):
                expected += w[j] * row[j]
        assert weighted_sum(row, w) == expected == total      # bit for bit
    assert isinstance(weighted_sum(values[0], w), float)
    with pytest.raises(ValueError):
        weighted_sum(np.ones(8), w)


def test_the_motion_term_is_half_the_mean_squared_displacement_truncated():
    rng = np.random.default_rng(6)
    a = rng.normal(0, 0.05, size=(3, 10, 3))
    b = rng.normal(0, 0.05, size=(4, 10, 3))
    b[0] = a[1] + 0.4                                         # far: capped
    b[1] = a[2]                                               # the same joints: 0
    m = motion_term(a, b)
    assert m.shape == (3, 4)
    for i in range(3):
        for j in range(4):
            squared = np.mean([np.sum((a[i, k] - b[j, k]) ** 2) for k in range(10)])
            assert m[i, j] == pytest.approx(min(0.5 * squared / MOTION_SIGMA_M ** 2, MOTION_CAP), rel=1e-12)
    assert m[1, 0] == MOTION_CAP and m[2, 1] == 0.0
    assert motion_term(a, b, cap=1e9)[1, 0] == pytest.approx(0.5 * 3 * 0.4 ** 2 / MOTION_SIGMA_M ** 2)
    with pytest.raises(ValueError):
        motion_term(a, b[:, :5])


def test_the_turn_term_is_half_the_squared_heading_change_on_the_circle_truncated():
    # by hand in degrees: the change taken the short way round, (b - a + 180) mod 360 - 180
    previous = np.radians([0.0, 170.0, -90.0])
    current = np.radians([10.0, -170.0, 90.0, 370.0, 180.0])
    t = turn_term(previous, current)
    assert t.shape == (3, 5)
    for i, a in enumerate(np.degrees(previous)):
        for j, b in enumerate(np.degrees(current)):
            change = (b - a + 180.0) % 360.0 - 180.0
            assert t[i, j] == pytest.approx(min(0.5 * (change / TURN_SIGMA_DEG) ** 2, TURN_CAP), rel=1e-9, abs=1e-12)
    assert t[0, 3] == pytest.approx(t[0, 0]) and t[1, 1] == pytest.approx(4 * t[0, 0])   # 370 is 10; 170 -> -170 is 20 the short way
    assert t[0, 4] == pytest.approx(0.5 * (180.0 / TURN_SIGMA_DEG) ** 2)           # turned round: an arm's jump more
    assert t[0, 4] >= MOTION_CAP
    with pytest.raises(ValueError):
        turn_term(previous[:, None], current)


def test_the_decoders_motion_term_adds_the_joints_and_the_heading():
    rng = np.random.default_rng(7)
    a, b = rng.normal(0, 0.05, size=(2, 10, 3)), rng.normal(0, 0.05, size=(3, 10, 3))
    ha, hb = rng.uniform(-np.pi, np.pi, 2), rng.uniform(-np.pi, np.pi, 3)
    np.testing.assert_allclose(transition_term(a, b, ha, hb), motion_term(a, b) + turn_term(ha, hb), rtol=1e-15)


def test_the_papers_method_switches_off_the_terms_beyond_the_paper():
    paper = TrackerConfig.paper()
    assert (paper.keypoint_weight, paper.prior_weight, paper.lifter_weight, paper.labelling_weight) == (0.0,) * 4
    assert (paper.edge_weight, paper.motion_weight) == (TrackerConfig().edge_weight, TrackerConfig().motion_weight)
    assert paper == TrackerConfig(recovery=False, hand_reacquisition=False, beam=1, jumps=False, lag=0,
                                  gradient_step=False, mirrors=False, prior_weight=0.0, keypoint_weight=0.0,
                                  lifter_weight=0.0, labelling_weight=0.0, smoothing=SmootherConfig(on=False))


def test_the_labelling_term_prices_a_swapped_reading_only_where_the_detector_shows_the_front():
    """The frame's front price for a swapped reading; nothing for the detector's own reading, or
    where it shows no front (price 0); NaN without keypoints."""
    from mocap.track.score import labelling_term

    assert labelling_term(3.5, True) == 3.5
    assert labelling_term(3.5, False) == labelling_term(0.0, True) == labelling_term(0.0, False) == 0.0
    assert math.isnan(labelling_term(None, True)) and math.isnan(labelling_term(None, False))


@pytest.mark.parametrize("ratio, nats", [(0.0, 1.18), (0.39, 1.18), (0.4, 1.39), (0.6, 2.61), (0.75, 3.17),
                                         (0.85, 3.69), (0.95, 6.11), (1.0, 6.30), (1.4, 6.30), (math.nan, 1.18),
                                         (-1.0, 1.18)])
def test_the_front_price_grows_as_the_shoulders_are_seen_square_on(ratio, nats):
    """The table's bins (lower edges inclusive), by hand; a ratio that cannot be read pays the least."""
    from mocap.track.score import front_price

    assert front_price(ratio) == nats


def test_the_tracker_prices_a_front_claim_by_its_shoulders_over_the_leaders_seen_square_on():
    """The leader's shoulders (metres) projected square-on at their mean depth, by hand, against
    the keypoints' shoulder distance (pixels)."""
    from mocap.body import BodyModel
    from mocap.body.pose import neutral_pose
    from mocap.body.skeleton import JOINT_INDEX
    from mocap.io.keypoints import Keypoints
    from mocap.render.camera import Camera
    from mocap.track import Tracker
    from mocap.track.score import front_price

    model, camera = BodyModel.build(), Camera(160, 120, 140.0, 140.0, 80.0, 60.0)
    pose = neutral_pose()
    tracker = Tracker(model, camera, TrackerConfig(), pose)
    joints = model.joint_positions(pose)
    r, l = joints[JOINT_INDEX["r_shoulder"]], joints[JOINT_INDEX["l_shoulder"]]
    square_on = 140.0 * np.linalg.norm(r - l) / ((r[2] + l[2]) / 2)
    for share in (0.5, 0.85, 0.95, 1.2):                              # inside the bins
        uv = np.full((10, 2), 60.0)
        uv[JOINT_INDEX["r_shoulder"], 0], uv[JOINT_INDEX["l_shoulder"], 0] = 60.0, 60.0 + share * square_on
        keypoints = Keypoints(uv, np.ones(10))
        assert tracker._front_price(keypoints) == front_price(share)
        assert tracker._front_price(keypoints.swapped()) == 0.0            # no front shown: no price


def test_keypoints_show_the_front_when_the_left_shoulder_is_on_the_images_right():
    from mocap.body.skeleton import JOINT_INDEX
    from mocap.io.keypoints import Keypoints

    uv = np.full((10, 2), 50.0)
    uv[JOINT_INDEX["l_shoulder"], 0], uv[JOINT_INDEX["r_shoulder"], 0] = 70.0, 30.0
    front = Keypoints(uv, np.ones(10))
    assert front.shows_front() and not front.swapped().shows_front()
    confidence = np.ones(10)
    confidence[JOINT_INDEX["r_shoulder"]] = 0.0
    assert not Keypoints(uv, confidence).shows_front()                   # it cannot tell
    assert not Keypoints.empty().shows_front()
