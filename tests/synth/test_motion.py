"""Procedural motion of the named sequences: limits, smoothness, what each sequence promises."""
import math

import numpy as np
import pytest

from mocap.body import JOINT_LIMITS, JOINT_NAMES, PARAMETER_INDEX, BodyModel, neutral_pose
from mocap.render import Camera
from mocap.synth.motion import ARM_GESTURES, ARM_PARAMETERS, MOTIONS, avoid_torso
from mocap.synth.sequence import FPS, SEQUENCES

J = {name: i for i, name in enumerate(JOINT_NAMES)}
MODEL = BodyModel.build()


@pytest.fixture(scope="module")
def motions():
    """Default-length motion of every sequence, for two seeds."""
    return {(name, seed): avoid_torso(MOTIONS[name](np.random.default_rng(seed), SEQUENCES[name].frames, FPS), MODEL)
            for name in MOTIONS for seed in (0, 1)}


def _joints(poses):
    return np.stack([MODEL.joint_positions(q) for q in poses])


def test_every_sequence_has_a_motion():
    assert set(MOTIONS) == set(SEQUENCES)


def test_limits_hold_and_motion_is_smooth(motions):
    for (name, seed), poses in motions.items():
        assert poses.shape == (SEQUENCES[name].frames, 23)
        assert np.isfinite(poses).all()
        assert (poses >= JOINT_LIMITS[:, 0]).all() and (poses <= JOINT_LIMITS[:, 1]).all(), name
        step = np.abs(np.diff(poses, axis=0))
        yaw = PARAMETER_INDEX["chest_yaw"]
        step[:, yaw] = np.abs(np.diff(np.unwrap(poses[:, yaw])))
        assert np.degrees(step[:, 3:].max()) < 30.0, name              # under 750 degrees per second
        assert step[:, :3].max() < 0.12, name                           # under 3 m/s


def test_starts_in_the_calibration_pose(motions):
    for (name, _), poses in motions.items():
        for side in "rl":
            for k, param in enumerate(ARM_PARAMETERS):
                assert math.degrees(poses[0, PARAMETER_INDEX[f"{side}_{param}"]]) == pytest.approx(
                    ARM_GESTURES["calibration"][k]), (name, param)


def test_head_stays_in_view(motions):
    camera = Camera.default(160, 120)
    for (name, _), poses in motions.items():
        uv = camera.project(_joints(poses)[:, J["head"]])
        assert (uv[:, 0] > 0).all() and (uv[:, 0] < 160).all() and (uv[:, 1] > 0).all() and (uv[:, 1] < 120).all()
        assert (poses[:, 2] > 1.3).all() and (poses[:, 2] < 2.3).all(), name


def test_arms_crossing_crosses_the_forearms_in_front_of_the_chest(motions):
    for seed in (0, 1):
        poses = motions[("arms-crossing", seed)]
        joints = _joints(poses)
        # the actor's right is -x: crossed, his right wrist is on the +x side of his left one
        crossed = (joints[:, J["r_wrist"], 0] > joints[:, J["l_wrist"], 0] + 0.02) \
            & (joints[:, J["r_wrist"], 2] < poses[:, 2] - 0.05) & (joints[:, J["l_wrist"], 2] < poses[:, 2] - 0.05)
        assert crossed.mean() > 0.15


def test_not_facing_holds_the_turn(motions):
    for seed in (0, 1):
        yaw = np.degrees(np.abs(motions[("not-facing", seed)][:, PARAMETER_INDEX["chest_yaw"]]))
        assert (yaw >= 30.0 - 1e-9).all() and (yaw <= 45.0 + 1e-9).all()


def test_turning_turns_all_the_way_round(motions):
    for seed in (0, 1):
        yaw = np.degrees(np.unwrap(motions[("turning", seed)][:, PARAMETER_INDEX["chest_yaw"]]))
        assert np.ptp(yaw) >= 359.0


def test_gestures_2_moves_fast_in_depth(motions):
    for seed in (0, 1):
        z = motions[("gestures-2", seed)][:, PARAMETER_INDEX["root_z"]]
        assert np.ptp(z) > 0.6
        assert np.abs(np.diff(z)).max() * FPS > 1.0                      # metres per second


def test_a_longer_sequence_starts_like_a_shorter_one():
    for name, motion in MOTIONS.items():
        long = motion(np.random.default_rng(3), 200, FPS)
        short = motion(np.random.default_rng(3), 60, FPS)
        np.testing.assert_array_equal(long[:60], short)


def test_avoid_torso_lifts_a_hand_out_of_the_chest():
    pose = neutral_pose((0.0, 0.6, 1.7))
    for name, deg in (("r_shoulder_flex", 0.0), ("r_shoulder_abd", 5.0), ("r_shoulder_rot", -70.0),
                      ("r_elbow_flex", 90.0)):
        pose[PARAMETER_INDEX[name]] = math.radians(deg)
    torso = MODEL.dims["torso"]

    def inside(q):
        t = MODEL.segment_transforms(q)
        local = (MODEL.joint_positions(q)[[J["r_elbow"], J["r_wrist"], J["r_hand"]]] - t[0, :, 3]) @ t[0, :, :3]
        return ((local[:, 0] / (torso.width / 2)) ** 2 + (local[:, 2] / (torso.depth / 2)) ** 2 < 1).any()

    assert inside(pose)
    fixed = avoid_torso(pose[None], MODEL)[0]
    assert not inside(fixed)
    assert fixed[PARAMETER_INDEX["r_shoulder_flex"]] > 0.0
    changed = np.flatnonzero(fixed != pose)
    assert changed.tolist() == [PARAMETER_INDEX["r_shoulder_flex"]]
