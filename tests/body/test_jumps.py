"""Kinematic jumps: projections kept exactly, depth changed, involutions, closed-form arm angles."""
import numpy as np
import pytest

from mocap.body import PARAMETER_INDEX as P, BodyModel, JOINT_NAMES, neutral_pose
from mocap.body.jumps import ARM_JUMPS, arm_angles_for_points, arm_jumps, ray_sphere_depths, reflect_on_ray, torso_flip
from mocap.render import Camera

MODEL = BodyModel.build(resolution=8)
SKELETON = MODEL.skeleton
CAMERA = Camera.default(160, 120)
ARM = {side: [JOINT_NAMES.index(f"{side}_{j}") for j in ("shoulder", "elbow", "wrist")] for side in "rl"}


def random_pose(rng):
    """Arms bent and raised, torso turned a little: every jump is then a real change."""
    q = neutral_pose()
    q[P["chest_yaw"]] = rng.uniform(-0.8, 0.8)
    q[P["chest_pitch"]] = rng.uniform(-0.1, 0.3)
    for side in "rl":
        q[P[f"{side}_shoulder_flex"]] = rng.uniform(0.1, 1.4)
        q[P[f"{side}_shoulder_abd"]] = rng.uniform(0.1, 1.2)
        q[P[f"{side}_shoulder_rot"]] = rng.uniform(-0.6, 0.8)
        q[P[f"{side}_elbow_flex"]] = rng.uniform(0.3, 2.0)
        q[P[f"{side}_forearm_twist"]] = rng.uniform(-0.5, 0.5)
    return q


def test_reflection_keeps_the_ray_and_the_distance():
    rng = np.random.default_rng(0)
    for _ in range(50):
        point, pivot = rng.uniform([-1, -1, 1], [1, 1, 3]), rng.uniform([-1, -1, 1], [1, 1, 3])
        r = reflect_on_ray(point, pivot)
        assert np.linalg.norm(np.cross(r, point)) < 1e-12                 # same ray
        assert np.linalg.norm(r - pivot) == pytest.approx(np.linalg.norm(point - pivot), abs=1e-12)
        np.testing.assert_allclose(reflect_on_ray(r, pivot), point, atol=1e-12)
        # both crossings of the ray with the sphere, the original among them
        ray = point / np.linalg.norm(point)
        depths = ray_sphere_depths(ray, pivot, np.linalg.norm(point - pivot))
        assert len(depths) == 2                    # signed distances along the ray
        np.testing.assert_allclose(sorted(depths), sorted([point @ ray, r @ ray]), atol=1e-9)
    assert len(ray_sphere_depths(np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 2.0]), 0.5)) == 0


def test_arm_angles_in_closed_form_reproduce_the_arm():
    rng = np.random.default_rng(1)
    for _ in range(30):
        q = random_pose(rng)
        joints = MODEL.joint_positions(q)
        for side in "rl":
            e, w = joints[ARM[side][1]], joints[ARM[side][2]]
            solved = arm_angles_for_points(q, SKELETON, side, e, w)
            np.testing.assert_allclose(MODEL.joint_positions(solved), joints, atol=1e-9)


@pytest.mark.parametrize("seed", range(8))
def test_every_arm_jump_keeps_the_projections_and_changes_depth(seed):
    rng = np.random.default_rng(seed)
    q = random_pose(rng)
    before = MODEL.joint_positions(q)
    uv_before = CAMERA.project(before)
    for side in "rl":
        jumps = arm_jumps(q, SKELETON, side)
        assert "forearm" in jumps and set(jumps) <= set(ARM_JUMPS)
        for name, jumped in jumps.items():
            after = MODEL.joint_positions(jumped)
            keep = ARM[side]                      # shoulder, elbow and wrist stay on their rays
            np.testing.assert_allclose(CAMERA.project(after[keep]), uv_before[keep], atol=1e-9)
            other = [i for i in range(len(JOINT_NAMES)) if i not in ARM[side] + [ARM[side][2] + 1]]
            np.testing.assert_allclose(after[other], before[other], atol=1e-12)    # the rest untouched
            moved = ARM[side][1] if name != "forearm" else ARM[side][2]
            assert abs(after[moved, 2] - before[moved, 2]) > 1e-3          # depth changed
            # segment lengths kept
            for a, b in ((0, 1), (1, 2)):
                i, j = ARM[side][a], ARM[side][b]
                assert np.linalg.norm(after[i] - after[j]) == pytest.approx(np.linalg.norm(before[i] - before[j]),
                                                                            abs=1e-9)
            # the same jump again gives the original arm back
            back = arm_jumps(jumped, SKELETON, side)[name]
            np.testing.assert_allclose(MODEL.joint_positions(back), before, atol=1e-9)


def test_torso_flip_turns_the_chest_round_and_keeps_the_hands_on_their_rays():
    q = neutral_pose()
    q[P["chest_yaw"]] = np.radians(20.0)
    for side in "rl":                                # arms in front, easy to reach both ways
        q[P[f"{side}_shoulder_flex"]] = np.radians(40.0)
        q[P[f"{side}_shoulder_abd"]] = np.radians(30.0)
        q[P[f"{side}_elbow_flex"]] = np.radians(60.0)
    flipped = torso_flip(q, SKELETON)
    assert flipped[P["chest_yaw"]] == pytest.approx(np.pi - q[P["chest_yaw"]])
    before, after = CAMERA.project(MODEL.joint_positions(q)), CAMERA.project(MODEL.joint_positions(flipped))
    hand = {side: JOINT_NAMES.index(f"{side}_hand") for side in "rl"}
    # each hand now lies near the ray of the other side's hand: a turned torso under perspective
    # is not an exact mirror image, so within 2 px here (not the arm jumps' 1e-9)
    assert np.linalg.norm(after[hand["r"]] - before[hand["l"]]) < 2.0
    assert np.linalg.norm(after[hand["l"]] - before[hand["r"]]) < 2.0
    # shoulders swap places in the image (the torso is left-right symmetric)
    rs, ls = JOINT_NAMES.index("r_shoulder"), JOINT_NAMES.index("l_shoulder")
    assert np.linalg.norm(after[rs] - before[ls]) < 1.5 and np.linalg.norm(after[ls] - before[rs]) < 1.5
    twice = torso_flip(flipped, SKELETON)
    assert twice[P["chest_yaw"]] == pytest.approx(q[P["chest_yaw"]])


def test_turned_mirror_reflects_the_body_through_the_plane_facing_the_camera():
    """Every joint of the turned mirror is the original's reflection z -> 2 z_root - z (the
    joints of the other side), so a far camera sees the same silhouette."""
    from mocap.body.jumps import turned_mirror

    rng = np.random.default_rng(3)
    swap = [JOINT_NAMES.index(n.replace("r_", "l_") if n.startswith("r_") else n.replace("l_", "r_"))
            for n in JOINT_NAMES]
    for _ in range(10):
        q = random_pose(rng)
        q[P["chest_roll"]], q[P["head_turn"]] = rng.uniform(-0.3, 0.3, 2)
        turned = turned_mirror(q)
        a, b = MODEL.joint_positions(q), MODEL.joint_positions(turned)[swap]
        root_z = q[P["root_z"]]
        np.testing.assert_allclose(b, a * [1, 1, -1] + [0, 0, 2 * root_z], atol=1e-9)
        np.testing.assert_allclose(turned_mirror(turned), q, atol=1e-12)
