"""The branch audit's plumbing, on a two-frame still clip rendered from a known pose."""
import math

import numpy as np
import pytest
from scipy import ndimage

from experiments.branch_audit import (COLUMNS, DISTINCT_M, SLOTS, audit_frames, depth_order_disagreements,
                                      frame_rates, mirror_alternatives, pairs, stage_pairs, summarise, truth_better)
from mocap.body import BodyDimensions, BodyModel, PARAMETER_INDEX as P, neutral_pose
from mocap.body.skeleton import JOINT_INDEX
from mocap.imaging import PreparedFrame
from mocap.io.keypoints import Keypoints
from mocap.render import Camera, render
from mocap.track import TrackerConfig

MODEL = BodyModel.build(BodyDimensions(), resolution=8)
CAMERA = Camera.default(160, 120)


def reaching_pose():
    """Both forearms raised in front: each whole arm's mirror (alone or with the forearm's) is inside
    the limits; the forearm's alone would bend the elbow backwards (pruned)."""
    q = neutral_pose()
    for name, degrees in (("r_shoulder_flex", 30), ("r_shoulder_abd", 20), ("r_elbow_flex", 90),
                          ("l_shoulder_flex", 30), ("l_shoulder_abd", 20), ("l_elbow_flex", 90)):
        q[P[name]] = np.radians(degrees)
    return q


@pytest.fixture(scope="module")
def audited():
    truth = reaching_pose()
    r = render(truth, MODEL, CAMERA)
    frame = PreparedFrame(r.labels, r.labels != 0, r.edges,
                          np.minimum(ndimage.distance_transform_edt(~r.edges), 20.0).astype(np.float32), False, {})
    uv = CAMERA.project(MODEL.joint_positions(truth))
    rng = np.random.default_rng(0)
    keypoints = [Keypoints(uv + rng.normal(0.0, 2.0, uv.shape), np.ones(len(uv))) for _ in range(2)]
    unit = audit_frames(MODEL, CAMERA, TrackerConfig(), np.array([truth, truth]), [frame, frame], keypoints, 40)
    return truth, unit


def test_the_alternatives_keep_the_projections_and_the_bone_lengths():
    truth = reaching_pose()
    joints = MODEL.joint_positions(truth)
    alternatives = mirror_alternatives(truth, MODEL, CAMERA)
    assert [a.name for a in alternatives] == list(SLOTS[1:])          # every mirror of this pose exists
    assert [a.name for a in alternatives if a.pruned] == ["r_forearm", "l_forearm"]
    from mocap.body.jumps import arm_jumps
    from mocap.body.pose import within_limits
    for side in "rl":                                   # the exact forearm mirror is outside the limits
        assert not within_limits(arm_jumps(truth, MODEL.skeleton, side)["forearm"])
    for a in (a for a in alternatives if not a.pruned):
        assert within_limits(a.pose)
        j = MODEL.joint_positions(a.pose)
        np.testing.assert_allclose(CAMERA.project(j), CAMERA.project(joints), atol=0.05)     # every joint, hands too
        for side in "rl":
            for x, y in (("shoulder", "elbow"), ("elbow", "wrist"), ("wrist", "hand")):
                a_, b_ = JOINT_INDEX[f"{side}_{x}"], JOINT_INDEX[f"{side}_{y}"]
                assert np.linalg.norm(j[b_] - j[a_]) == pytest.approx(np.linalg.norm(joints[b_] - joints[a_]), abs=1e-6)
        assert np.linalg.norm(j - joints, axis=1).max() > DISTINCT_M           # a different branch


def test_unrefined_cues_of_the_exact_mirrors_against_independent_references(audited):
    truth, unit = audited
    u = unit["unrefined"]
    assert unit["exists"].all() and unit["pruned"].sum() == 4
    assert np.isnan(u[unit["pruned"]]).all()           # a pruned mirror is not scored
    k = COLUMNS.index("keypoint")
    kept = ~unit["pruned"][0]
    # a mirror projects onto the same keypoints: its keypoint distance is the truth's
    np.testing.assert_allclose(u[:, kept, k], u[:, :1, k].repeat(kept.sum(), axis=1), atol=0.02)
    # the truth rendered onto its own labels and edges: F is 0, the edge distance near 0
    assert u[0, 0, COLUMNS.index("region")] == pytest.approx(0.0, abs=1e-9)
    assert u[0, 0, COLUMNS.index("edge")] < 0.5
    assert np.isnan(u[..., COLUMNS.index("world")]).all()                 # the oracle has no 3D
    # the tracker's sums of the terms
    from mocap.track.config import REGION_WEIGHT
    cfg = TrackerConfig()
    u = u[:, kept]
    np.testing.assert_allclose(u[..., COLUMNS.index("region_edge")],
                               REGION_WEIGHT * u[..., COLUMNS.index("region")] + cfg.edge_weight * u[..., COLUMNS.index("edge")])
    np.testing.assert_allclose(u[..., COLUMNS.index("score")],
                               u[..., COLUMNS.index("region_edge")] + cfg.keypoint_weight * u[..., k]
                               + cfg.prior_weight * u[..., COLUMNS.index("prior")]
                               + cfg.lifter_weight * u[..., COLUMNS.index("lifter")])


def test_every_candidate_gets_the_same_refinement_budget(audited):
    _, unit = audited
    kept = ~unit["pruned"]
    e = unit["refined_evaluations"][kept]
    assert (e > 0).all() and (e <= 40).all()
    assert np.isfinite(unit["refined"][kept][:, :5]).all()


def test_the_unrefined_region_cost_separates_a_mirror_the_rendering_shows(audited):
    """On a clean rendering of the truth, every distinct mirror has F > 0 = the truth's (depth
    changes the occlusions of a forearm raised in front), so region separates every pair."""
    _, unit = audited
    p = pairs(unit)
    assert len(p["frame"]) == 2 * 4
    assert p["unrefined"][:, COLUMNS.index("region")].all()
    assert frame_rates(2, stage_pairs(p, "unrefined"))["floor"] == 0.0


def test_the_leader_stage_scores_the_refined_truth_and_its_own_mirrors(audited):
    _, unit = audited
    np.testing.assert_array_equal(unit["leader"][:, 0], unit["refined"][:, 0])
    np.testing.assert_array_equal(unit["leader_joints"][:, 0], unit["refined_joints"][:, 0])
    kept = unit["leader_exists"][0] & ~unit["leader_pruned"][0]
    assert kept[1:].any()
    k = COLUMNS.index("keypoint")            # the leader's mirrors project where the leader does
    np.testing.assert_allclose(unit["leader"][:, kept, k], unit["leader"][:, :1, k].repeat(kept.sum(), axis=1),
                               atol=0.02)


def test_ties_and_missing_values_never_separate():
    assert truth_better([1.0, 1.0, 1.0, np.nan], [1.0 + 1e-9, 1.1, 0.9, 2.0]).tolist() == [False, True, False, False]


def test_the_floor_counts_frames_with_a_pair_no_single_cue_separates(tmp_path):
    n, s, c = 3, len(SLOTS), len(COLUMNS)
    truth_joints = np.zeros((n, 10, 3))
    start = np.zeros((n, s, 10, 3))
    start[:, 1:, 4, 2] = 0.2                            # every alternative's wrist 200 mm off: distinct
    start[2, 2:, 4, 2] = 0.0                            # frame 2: only slot 1 is distinct
    values = np.ones((n, s, c))
    values[:, 0] = 0.5                                  # the truth better by every cue ...
    values[1, 3, :] = 0.5                               # ... but on frame 1, slot 3 ties it on every cue
    unit = {"exists": np.ones((n, s), bool), "pruned": np.zeros((n, s), bool), "start_joints": start,
            "refined_joints": start.copy(), "unrefined": values, "refined": values.copy(),
            "truth_joints": truth_joints}
    p = pairs(unit)
    assert len(p["frame"]) == 2 * (s - 1) + 1
    r = frame_rates(n, stage_pairs(p, "unrefined"))
    assert r["frames"] == 3 and r["floor"] == pytest.approx(1 / 3) and r["region"] == pytest.approx(2 / 3)
    summary = summarise({("gestures-1", 0): unit})
    assert summary["pooled"]["refined"]["floor"] == pytest.approx(1 / 3)
    assert summary["pooled"]["unrefined"]["pair_truth_better"]["edge"] == pytest.approx(1 - 1 / 13)
    from experiments.figures import ext_branch_audit
    written = ext_branch_audit.main(summary, tmp_path)
    assert sorted(p.name for p in written) == ["ext_branch_audit.pdf", "ext_branch_audit.png"]


def test_depth_order_disagreements_count_arm_bones():
    j = np.zeros((10, 3))
    j[:, 2] = 2.0                                       # every joint 2 m straight ahead ...
    j[JOINT_INDEX["r_elbow"], 2] = 2.1                  # ... the right elbow 10 cm behind its shoulder,
    j[JOINT_INDEX["r_wrist"], 2] = 2.2                  # the wrist 10 cm behind the elbow
    world = j - 2.0                                     # the detector's own origin
    assert depth_order_disagreements(j, world) == 0.0
    world[JOINT_INDEX["r_elbow"], 2] = -0.1             # in front, by the detector ...
    assert depth_order_disagreements(j, world) == 1.0   # shoulder-elbow disagrees (elbow-wrist: +0.3 agrees)
    world[JOINT_INDEX["r_wrist"], 2] = -0.2             # ... and the wrist in front of it
    assert depth_order_disagreements(j, world) == 2.0
    assert math.isnan(depth_order_disagreements(j, None))


def test_every_depth_mirror_flips_a_branch_sign_along_the_ray():
    """The detector's 3D of the truth (any origin) agrees with the truth on every bone and
    disagrees with each of its depth mirrors on at least one: the sign is read along the child's
    ray, which a mirror flips (the joints' z difference need not flip off the optical axis)."""
    q = reaching_pose()
    truth = MODEL.joint_positions(q)
    world = truth - truth[1]
    assert depth_order_disagreements(truth, world) == 0.0
    kept = [a for a in mirror_alternatives(q, MODEL, CAMERA) if not a.pruned]
    assert kept
    for a in kept:
        assert depth_order_disagreements(MODEL.joint_positions(a.pose), world) >= 1.0, a.name
