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
                           labelling_weight=0.4, detector_3d_weight=0.3, motion_weight=0.25)
    w = weights(config)
    np.testing.assert_array_equal(w, [REGION_WEIGHT, 3.0, 1.5, 0.1, 0.7, 0.4, 0.3, 0.25])
    assert with_weights(TrackerConfig(beam=4), w) == dataclasses.replace(config, beam=4)
    with pytest.raises(ValueError):
        with_weights(config, w[:5])


def test_a_scored_candidates_values_follow_the_table():
    c = ScoredCandidate.from_terms("tracked", np.zeros(23), np.zeros((10, 3)), [0.1, 2.0, math.nan, 3.0, 4.0, 0.5, 0.6],
                                   np.array([5.0, 6.0]), 7.0)
    assert (c.region, c.edge, c.prior, c.lifter, c.labelling, c.detector_3d, c.unary) == (0.1, 2.0, 3.0, 4.0, 0.5, 0.6,
                                                                                           7.0)
    assert math.isnan(c.keypoint)
    np.testing.assert_array_equal(c.values(), [0.1, 2.0, math.nan, 3.0, 4.0, 0.5, 0.6, 5.0])
    np.testing.assert_array_equal(c.values(previous=1)[MOTION], 6.0)
    assert math.isnan(c.values(previous=2)[MOTION])
    with pytest.raises(ValueError):
        ScoredCandidate.from_terms("tracked", np.zeros(23), np.zeros((10, 3)), [0.1, 2.0], np.zeros(1), 0.0)


def test_the_weighted_sum_leaves_out_what_does_not_apply_and_is_the_same_float_alone_or_in_an_array():
    rng = np.random.default_rng(5)
    values = rng.uniform(0, 10, size=(40, len(UNARY_TERMS)))
    values[::3, 2] = np.nan                                   # no keypoints
    values[::4, 3:5] = np.nan                                 # no prior, not lifted
    w = np.array([50.0, 2.0, 1.5, 0.05, 0.5, 1.0, 1.0, 1.0])
    together = weighted_sum(values, w)
    for row, total in zip(values, together):
        expected = 0.0
        for j in range(len(row)):                             # the loop the tracker ran, term by term
            if not math.isnan(row[j]):
                expected += w[j] * row[j]
        assert weighted_sum(row, w) == expected == total      # bit for bit
    assert isinstance(weighted_sum(values[0], w), float)
    with pytest.raises(ValueError):
        weighted_sum(np.ones(9), w)


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
    assert (paper.keypoint_weight, paper.prior_weight, paper.lifter_weight, paper.labelling_weight,
            paper.detector_3d_weight) == (0.0,) * 5
    assert (paper.edge_weight, paper.motion_weight) == (TrackerConfig().edge_weight, TrackerConfig().motion_weight)
    assert paper == TrackerConfig(recovery=False, hand_reacquisition=False, beam=1, jumps=False, lag=0,
                                  gradient_step=False, mirrors=False, prior_weight=0.0, keypoint_weight=0.0,
                                  lifter_weight=0.0, labelling_weight=0.0, detector_3d_weight=0.0,
                                  smoothing=SmootherConfig(on=False))


def test_the_labelling_term_prices_a_swapped_reading_only_where_the_detector_shows_the_front():
    """ln(0.97 / 0.03) nats (the audit's odds that MediaPipe's labels are right where it shows the
    front) for a swapped reading there; nothing for the detector's own reading, or where it shows
    no front; NaN without keypoints."""
    from mocap.track.score import FRONT_SWAP_NATS, labelling_term

    assert FRONT_SWAP_NATS == pytest.approx(math.log(97 / 3))
    assert labelling_term(True, True) == FRONT_SWAP_NATS
    assert labelling_term(True, False) == labelling_term(False, True) == labelling_term(False, False) == 0.0
    assert math.isnan(labelling_term(None, True)) and math.isnan(labelling_term(None, False))


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


def test_the_detector_3d_term_is_the_arms_bone_angles_truncated_and_weighted_by_confidence():
    """Against a NumPy loop by hand: the arms' four bones, half the squared angle over sigma², each
    at most the cap, the mean weighted by the bones' least confidence; the same bones give 0 (any
    scale or offset of the detector's 3D), a joint absent drops its bones, none present is NaN."""
    from mocap.body.skeleton import JOINT_INDEX
    from mocap.track.score import (DETECTOR_3D_BONES, DETECTOR_3D_CAP, DETECTOR_3D_SIGMA_DEG,
                                   detector_3d_term)

    rng = np.random.default_rng(3)
    joints = rng.normal(size=(10, 3))
    assert detector_3d_term(joints, 2.0 * joints + 5.0, np.ones(10)) == pytest.approx(0.0, abs=1e-12)
    world = rng.normal(size=(10, 3))
    confidence = rng.uniform(0.2, 1.0, size=10)
    total = weight_sum = 0.0
    for a, b in DETECTOR_3D_BONES:
        ours = joints[JOINT_INDEX[b]] - joints[JOINT_INDEX[a]]
        theirs = world[JOINT_INDEX[b]] - world[JOINT_INDEX[a]]
        angle = math.degrees(math.acos(np.dot(ours, theirs) / np.linalg.norm(ours) / np.linalg.norm(theirs)))
        w = min(confidence[JOINT_INDEX[a]], confidence[JOINT_INDEX[b]])
        total += w * min(0.5 * (angle / DETECTOR_3D_SIGMA_DEG) ** 2, DETECTOR_3D_CAP)
        weight_sum += w
    assert detector_3d_term(joints, world, confidence) == pytest.approx(total / weight_sum, rel=1e-12)
    flipped = joints.copy()
    flipped[[JOINT_INDEX["r_elbow"], JOINT_INDEX["r_wrist"]]] *= -1.0       # far from every bone's direction
    assert detector_3d_term(flipped, joints, np.ones(10)) <= DETECTOR_3D_CAP
    absent = world.copy()
    absent[JOINT_INDEX["l_elbow"]] = np.nan
    assert np.isfinite(detector_3d_term(joints, absent, confidence))
    assert math.isnan(detector_3d_term(joints, np.full((10, 3), np.nan), confidence))
