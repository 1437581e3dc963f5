"""The proposal stage: sources that read the current frame, placement, and their way into the beam."""
from __future__ import annotations

import numpy as np

from mocap.body import JOINT_INDEX, PARAMETER_INDEX as P, PARAMETER_NAMES, neutral_pose, within_limits
from mocap.imaging import PreparedFrame
from mocap.io.pose_table import PoseTable
from mocap.render import render
from mocap.track import BlobArmSource, ProposalContext, Tracker, TrackerConfig, place_by_silhouette
from tests.test_track import CAMERA, MODEL, joint_error, lost_arm_frame


def reaching_forward_frame():
    """A clean frame of the right arm reaching forward and out (both depth branches of its hand
    are inside the joint limits), and a start with that arm hanging."""
    truth = neutral_pose()
    for name, degrees in (("r_shoulder_flex", 40.0), ("r_shoulder_abd", 30.0), ("r_elbow_flex", 30.0)):
        truth[P[name]] = np.radians(degrees)
    lost = truth.copy()
    lost[[P["r_shoulder_flex"], P["r_shoulder_abd"], P["r_elbow_flex"]]] = 0.0
    r = render(truth, MODEL, CAMERA)
    return truth, lost, PreparedFrame(r.labels, r.labels != 0, r.edges, np.zeros(r.labels.shape, np.float32), False, {})


def test_blob_arm_proposals_put_the_hand_on_the_blob_on_both_branches():
    truth, lost, frame = reaching_forward_frame()
    proposals = BlobArmSource().propose(frame, ProposalContext(MODEL, CAMERA, lost))
    assert proposals and all(p.origin == "blob" for p in proposals)
    true_hand = CAMERA.project(MODEL.joint_positions(truth)[JOINT_INDEX["r_hand"]])
    branches = set()
    for p in proposals:
        assert within_limits(p.pose)
        joints = MODEL.joint_positions(p.pose)
        if np.linalg.norm(CAMERA.project(joints[JOINT_INDEX["r_hand"]]) - true_hand) < 1.5:   # pixels: on the blob
            branches.add(bool(joints[JOINT_INDEX["r_hand"], 2] < joints[JOINT_INDEX["r_shoulder"], 2]))
    assert branches == {True, False}                  # the hand nearer and farther than the shoulder
    assert min(joint_error(p.pose, truth) for p in proposals) < 0.03


def test_placement_brings_a_shifted_pose_back_over_the_silhouette():
    truth, _, frame = lost_arm_frame()
    shifted = truth.copy()
    shifted[P["root_x"]] += 0.12
    shifted[P["root_y"]] -= 0.08
    placed = place_by_silhouette(shifted, frame.foreground, MODEL, CAMERA)
    assert abs(placed[P["root_x"]] - truth[P["root_x"]]) < 0.01       # metres
    assert abs(placed[P["root_y"]] - truth[P["root_y"]]) < 0.01
    assert placed[P["root_z"]] == shifted[P["root_z"]]


def test_the_blob_source_refinds_a_lost_arm_in_the_beam_and_says_so():
    truth, lost, frame = lost_arm_frame()
    errors = {}
    for on in (False, True):
        config = TrackerConfig(hand_reacquisition=False, blob_arms=on, beam=1, jumps=False, lag=0, prior_weight=0.0)
        result, = Tracker(MODEL, CAMERA, config, lost).push(0, frame)
        errors[on] = joint_error(result.pose, truth)
        assert (result.origin == "blob") == on
    assert errors[False] > 0.1 and errors[True] < 0.035


def test_origin_column_round_trips(tmp_path):
    table = PoseTable([0, 1], np.zeros((2, 23)), np.zeros((2, 10, 3)),
                      {"score": np.array([1.5, 2.0]), "origin": np.array(["tracked", "exemplar"])})
    table.write(tmp_path / "poses.csv")
    back = PoseTable.read(tmp_path / "poses.csv")
    assert list(back.extra["origin"]) == ["tracked", "exemplar"]
    np.testing.assert_array_equal(back.extra["score"], [1.5, 2.0])


def test_started_facing_away_with_the_arms_down_the_exemplars_bring_the_tracker_back():
    """A clean frame of the four-class model (hair tells the back of the head from the face); the
    tracker starts turned round with both arms hanging. With the exemplar source it is within
    10 cm of the truth within six frames; without it (the kinematic jumps alone) it stays lost."""
    from scipy import ndimage

    from mocap.body import BodyDimensions, BodyModel
    from mocap.body.jumps import turned_mirror

    model = BodyModel.build(BodyDimensions(), resolution=8)
    truth = neutral_pose()
    for name, degrees in (("r_shoulder_abd", 70), ("r_elbow_flex", 60), ("l_shoulder_flex", 50),
                          ("l_shoulder_abd", 20), ("chest_yaw", 25)):
        truth[P[name]] = np.radians(degrees)
    r = render(truth, model, CAMERA)
    frame = PreparedFrame(r.labels, r.labels != 0, r.edges,
                          np.minimum(ndimage.distance_transform_edt(~r.edges), 20.0).astype(np.float32), False, {})
    start = turned_mirror(truth)
    start[[P[name] for name in PARAMETER_NAMES if name[:2] in ("r_", "l_")]] = 0.0   # both arms hanging
    error = lambda q: float(np.linalg.norm(model.joint_positions(q) - model.joint_positions(truth), axis=1).mean())
    assert error(start) > 0.4
    final = {}
    for exemplars in (False, True):
        tracker = Tracker(model, CAMERA, TrackerConfig(exemplars=exemplars, lag=0), start)
        for i in range(6):
            result, = tracker.push(i, frame)
        final[exemplars] = error(result.pose)
    assert final[True] < 0.1 and final[False] > 0.15                   # metres
