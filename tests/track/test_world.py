"""MediaPipe's 3D as evidence of the tracker's score (mocap.track.world; issue 34, item 2).

References: a known pose (its own joints as the detector's 3D must give its arms back), the
term's formula computed by hand, and the ground truth of a still clip (the tracker started with
both arms mirrored in depth comes back at the default weights).
"""
from __future__ import annotations

import numpy as np
import pytest

from mocap.body.jumps import arm_jumps
from mocap.body.skeleton import JOINT_INDEX
from mocap.io.keypoints import Keypoints
from mocap.track import Tracker, TrackerConfig
from mocap.track.world import WORLD_CAP, WORLD_SIGMA_M, about_shoulders, place_world
from tests.track.test_lifter_in_tracker import BACK_M, CAMERA, MODEL, reaching_pose, still_clip

#: The placed pose's arm joints this close to the truth's (metres; the fit's own tolerance is 5 mm).
PLACED_TOL_M = 0.01


def with_world(keypoints: Keypoints, joints: np.ndarray, origin=(0.1, -0.3, 2.0)) -> Keypoints:
    """The keypoints carrying ``joints`` (10, 3) as the detector's 3D, about another origin, the neck absent."""
    world = np.asarray(joints, dtype=np.float64) - np.asarray(origin)
    world[JOINT_INDEX["neck"]] = np.nan
    return Keypoints(keypoints.uv, keypoints.confidence, world)


def test_a_known_poses_3d_is_placed_back_onto_the_body():
    truth = reaching_pose()
    joints = MODEL.joint_positions(truth)
    (_, (keypoints, *_)) = still_clip(truth, 1)
    # from the truth (one fit) and from the right arm mirrored in depth (the fit misses: every heading again)
    for start in (truth, arm_jumps(truth, MODEL.skeleton, "r")["both"]):
        placed = place_world(with_world(keypoints, joints), MODEL, start)
        np.testing.assert_allclose(placed.arms, about_shoulders(joints), atol=PLACED_TOL_M)
        assert placed.energy(joints) < 0.5 * 6 * (PLACED_TOL_M / WORLD_SIGMA_M) ** 2
    # no 3D, no keypoints, too few joints or a shoulder missing: no evidence
    assert place_world(keypoints, MODEL, truth) is None and place_world(None, MODEL, truth) is None
    missing = with_world(keypoints, joints)
    world = np.array(missing.world)
    world[JOINT_INDEX["l_shoulder"]] = np.nan
    assert place_world(Keypoints(keypoints.uv, keypoints.confidence, world), MODEL, truth) is None
    # a joint absent in 2D is absent in 3D too (the keypoint file's rows are the 2D joints')
    hidden = np.array(keypoints.confidence)
    hidden[JOINT_INDEX["r_wrist"]] = 0.0
    k = Keypoints(keypoints.uv, hidden, missing.world)
    assert np.isnan(k.world[JOINT_INDEX["r_wrist"]]).all()


def test_the_term_is_half_the_capped_squared_distances_about_the_shoulders():
    truth = reaching_pose()
    joints = MODEL.joint_positions(truth)
    (_, (keypoints, *_)) = still_clip(truth, 1)
    placed = place_world(with_world(keypoints, joints), MODEL, truth)
    base = placed.energy(joints)
    assert placed.energy(joints + np.array([0.3, -0.2, 1.0])) == pytest.approx(base, abs=1e-9)   # translation-free
    moved = joints.copy()
    moved[JOINT_INDEX["r_wrist"]] += (0.0, 0.0, 0.1)           # one joint 1 sigma off
    d = about_shoulders(moved) - placed.arms
    expect = 0.5 * np.minimum(np.sum(d ** 2, axis=1) / WORLD_SIGMA_M ** 2, WORLD_CAP).sum()
    assert placed.energy(moved) == pytest.approx(expect, rel=1e-12)
    assert placed.energy(moved) == pytest.approx(base + 0.5, abs=0.05)
    far = joints.copy()
    far[JOINT_INDEX["l_wrist"]] += (0.0, 0.0, 2.0)             # far off: the cap
    assert placed.energy(far) == pytest.approx(0.5 * WORLD_CAP, abs=0.05)


def test_the_config_switches_the_term():
    assert TrackerConfig().world_weight > 0 and TrackerConfig.paper().world_weight == 0
    with pytest.raises(ValueError, match="world_weight"):
        TrackerConfig(world_weight=-1.0)


@pytest.mark.slow
def test_started_with_both_arms_mirrored_the_3d_brings_the_tracker_back_at_the_default_weights():
    """A still clip with keypoints (1 px noise) that carry the detector's 3D (the truth's joints):
    started with both arms mirrored in depth (the same silhouette and 2D), the tracker at the
    default settings is within 10 cm of the truth (about the neck) from the third frame on;
    with ``world_weight`` 0 it is not back by the end (the lifter's default weight keeps the tie)."""
    truth = reaching_pose()
    start = arm_jumps(arm_jumps(truth, MODEL.skeleton, "r")["both"], MODEL.skeleton, "l")["both"]
    frames, keypoints = still_clip(truth, 6)
    joints = MODEL.joint_positions(truth)
    about_neck = lambda j: j - j[1]

    def errors(config):
        tracker = Tracker(MODEL, CAMERA, config, start)
        return np.array([np.linalg.norm(about_neck(tracker.push(i, f, with_world(k, joints))[0].joints)
                                        - about_neck(joints), axis=1).mean()
                         for i, (f, k) in enumerate(zip(frames, keypoints))])

    assert errors(TrackerConfig(lag=0))[2:].max() < BACK_M
    assert errors(TrackerConfig(lag=0, world_weight=0.0)).min() > BACK_M


def test_without_the_detectors_3d_the_term_changes_nothing():
    """Without keypoints, or with keypoints that carry no 3D (a keypoint file of 2D, the oracle),
    ``world_weight`` leaves every pose and score bit-identical (the benchmark without MediaPipe is
    unchanged)."""
    truth = reaching_pose()
    start = arm_jumps(truth, MODEL.skeleton, "l")["both"]
    frames, keypoints = still_clip(truth, 3)

    def track(weight, given):
        tracker = Tracker(MODEL, CAMERA, TrackerConfig(lag=0, world_weight=weight), start)
        return [(r.pose, r.score) for i, (f, k) in enumerate(zip(frames, given)) for r in tracker.push(i, f, k)]

    for given in ([None] * 3, keypoints):
        on, off = track(0.5, given), track(0.0, given)
        for (p, s), (q, t) in zip(on, off):
            np.testing.assert_array_equal(p, q)
            assert s == t
