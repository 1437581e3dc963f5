"""The keypoint cue in the tracker: arm IK on keypoint rays, keypoint proposals, recovery."""
from __future__ import annotations

import numpy as np
import pytest

from mocap.body import JOINT_LIMITS, JOINT_NAMES, PARAMETER_INDEX as P, BodyModel, neutral_pose
from mocap.body.jumps import arm_poses_on_rays
from mocap.body.pose import within_limits
from mocap.render import Camera
from mocap.track.proposals import KeypointArmSource, ProposalContext, pixel_ray, torso_on_shoulders
from mocap.io.keypoints import Keypoints

MODEL = BodyModel.build(resolution=6)
CAMERA = Camera.default()
J = {name: i for i, name in enumerate(JOINT_NAMES)}


def random_arm_pose(rng, side):
    q = neutral_pose()
    q[P["chest_yaw"]] = rng.uniform(-0.6, 0.6)
    for name in ("shoulder_flex", "shoulder_abd", "shoulder_rot", "elbow_flex"):
        i = P[f"{side}_{name}"]
        lo, hi = JOINT_LIMITS[i]
        q[i] = rng.uniform(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo))
    return q


@pytest.mark.parametrize("side", ["r", "l"])
def test_arm_ik_reproduces_the_keypoints_on_every_branch(side):
    rng = np.random.default_rng(4 if side == "r" else 5)
    both_inside = 0
    for _ in range(40):
        q = random_arm_pose(rng, side)
        truth = MODEL.joint_positions(q)
        uv = CAMERA.project(truth)
        start = neutral_pose()
        start[P["chest_yaw"]] = q[P["chest_yaw"]]
        branches = arm_poses_on_rays(start, MODEL.skeleton, side, pixel_ray(CAMERA, uv[J[f"{side}_elbow"]]),
                                     pixel_ray(CAMERA, uv[J[f"{side}_wrist"]]))
        rows = [J[f"{side}_{j}"] for j in ("shoulder", "elbow", "wrist")]
        exact = {name: b for name, b in branches.items() if "closest" not in name}   # both rays hit
        inside = [name for name, b in exact.items() if within_limits(b)]
        for name in inside:
            got = CAMERA.project(MODEL.joint_positions(branches[name]))[rows]
            np.testing.assert_allclose(got, uv[rows], atol=1e-6, err_msg=name)
        # the true arm is one of the branches
        assert min(np.abs(MODEL.joint_positions(b)[rows] - truth[rows]).max() for b in exact.values()) < 1e-9
        both_inside += len(inside) >= 2
    assert both_inside >= 5                              # the test did see two branches inside the limits


def test_torso_heading_from_the_shoulders():
    truth = neutral_pose()
    truth[P["chest_yaw"]] = 0.5
    truth[0] += 0.1
    uv = CAMERA.project(MODEL.joint_positions(truth))
    got = torso_on_shoulders(neutral_pose(), MODEL, CAMERA, uv[J["r_shoulder"]], uv[J["l_shoulder"]])
    assert got[P["chest_yaw"]] == pytest.approx(0.5, abs=0.05)
    moved = CAMERA.project(MODEL.joint_positions(got))[[J["r_shoulder"], J["l_shoulder"]]]
    assert np.abs(moved - uv[[J["r_shoulder"], J["l_shoulder"]]]).max() < 1.0


def test_the_source_proposes_the_true_arm():
    rng = np.random.default_rng(8)
    q = random_arm_pose(rng, "r")
    uv = CAMERA.project(MODEL.joint_positions(q))
    leader = q.copy()
    leader[[P["r_shoulder_flex"], P["r_elbow_flex"]]] = 0.2, 0.3
    keypoints = Keypoints(uv, np.ones(len(JOINT_NAMES)))
    proposals = KeypointArmSource().propose(None, ProposalContext(MODEL, CAMERA, leader, keypoints))
    assert proposals and all(p.origin == "keypoints" for p in proposals)
    truth = MODEL.joint_positions(q)
    assert min(np.abs(MODEL.joint_positions(p.pose) - truth).max() for p in proposals) < 0.02
    assert KeypointArmSource().propose(None, ProposalContext(MODEL, CAMERA, leader, None)) == []
