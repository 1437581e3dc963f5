"""The proposal stage: what its poses carry into poses.csv."""
from __future__ import annotations

import numpy as np

from mocap.io.pose_table import PoseTable


def test_origin_column_round_trips(tmp_path):
    table = PoseTable([0, 1], np.zeros((2, 23)), np.zeros((2, 10, 3)),
                      {"score": np.array([1.5, 2.0]), "origin": np.array(["tracked", "lifter"])})
    table.write(tmp_path / "poses.csv")
    back = PoseTable.read(tmp_path / "poses.csv")
    assert list(back.extra["origin"]) == ["tracked", "lifter"]
    np.testing.assert_array_equal(back.extra["score"], [1.5, 2.0])


def test_the_detectors_3d_arms_are_placed_from_our_shoulders():
    """A detector whose 3D is a target pose's joints (shifted and scaled: its own origin and
    bone lengths) proposes, from a leader with other arms, the target's arms; nothing on a frame
    without the front shown or without 3D. Reference: the target pose's own joints."""
    from mocap.body import BodyModel, neutral_pose
    from mocap.body.pose import PARAMETER_INDEX as P
    from mocap.body.skeleton import JOINT_INDEX, JOINT_NAMES
    from mocap.io.keypoints import Keypoints
    from mocap.render import Camera
    from mocap.track.proposals import DetectorArmsSource, ProposalContext, detector_arm_targets

    model, camera = BodyModel.build(resolution=8), Camera.default()
    leader = neutral_pose()
    target = leader.copy()
    for name, degrees in (("r_shoulder_flex", 40.0), ("r_elbow_flex", 60.0), ("l_shoulder_abd", 50.0),
                          ("l_elbow_flex", 30.0)):
        target[P[name]] = np.radians(degrees)
    truth = model.joint_positions(target)
    world = 1.3 * (truth - truth[JOINT_INDEX["neck"]]) + [0.1, -0.2, 0.05]
    for side in ("r", "l"):
        rows = [JOINT_INDEX[f"{side}_{j}"] for j in ("elbow", "wrist", "hand")]
        np.testing.assert_allclose(detector_arm_targets(model.joint_positions(leader), world, side), truth[rows],
                                   atol=1e-9)
    front_uv = camera.project(truth)
    assert Keypoints(front_uv, np.ones(len(JOINT_NAMES))).shows_front()
    source = DetectorArmsSource(model)
    proposals = source.propose(None, ProposalContext(keypoints=Keypoints(front_uv, np.ones(10), world), pose=leader))
    assert [p.origin for p in proposals] == ["detector3d"]
    np.testing.assert_allclose(model.joint_positions(proposals[0].pose), truth, atol=2e-3)
    # no front shown (the image mirrored), no 3D, no leader: nothing
    mirrored = front_uv * (-1.0, 1.0) + (camera.width, 0.0)
    for keypoints, pose in ((Keypoints(mirrored, np.ones(10), world), leader), (Keypoints(front_uv, np.ones(10)), leader),
                            (Keypoints(front_uv, np.ones(10), world), None), (None, leader)):
        assert source.propose(None, ProposalContext(keypoints=keypoints, pose=pose)) == []
