"""Kinematic jumps: the depth mirrors' geometry against the ray-sphere quadratic, projections kept exactly,
depth changed, involutions, closed-form arm angles."""
import numpy as np
import pytest

from mocap.body import PARAMETER_INDEX as P, BodyModel, JOINT_NAMES, neutral_pose
from mocap.body.jumps import (ARM_JUMPS, arm_angles_for_points, arm_jumps, flipped_arm_joints, ray_sphere_depths,
                              torso_flip)
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


def other_root(ray, parent, length, depth):
    """The independent reference: the two depths ``t`` of ``t * ray`` at ``length`` from ``parent``
    are the roots of ``t**2 - 2 (ray . parent) t + |parent|**2 - length**2``; the one that is not
    ``depth`` (numpy's polynomial roots; None where the ray misses the sphere)."""
    roots = np.roots([1.0, -2.0 * ray @ parent, parent @ parent - length ** 2])
    if np.iscomplexobj(roots) and np.any(np.abs(roots.imag) > 1e-12):
        return None
    roots = roots.real
    return roots[np.argmax(np.abs(roots - depth))]


@pytest.mark.parametrize("side", ["r", "l"])
def test_flipped_arm_joints_are_the_other_root_of_the_ray_and_the_bone_sphere(side):
    """Each flipped bone's child moves to the other crossing of its camera ray with the sphere of
    the bone's length about its parent (the quadratic's other root), each bone below it keeps its
    own side of the crossing about the moved parent: every joint projects where it did, every bone
    keeps its length, the rest of the body stays, and the same flip again gives the joints back."""
    rng = np.random.default_rng(7)
    rows = {j: JOINT_NAMES.index(f"{side}_{j}") for j in ("shoulder", "elbow", "wrist", "hand")}
    chain = [("upper_arm", "shoulder", "elbow"), ("forearm", "elbow", "wrist"), ("hand", "wrist", "hand")]
    checked = 0
    for _ in range(20):
        joints = MODEL.joint_positions(random_pose(rng))
        for flip in (("upper_arm",), ("forearm",), ("upper_arm", "forearm")):
            new = flipped_arm_joints(joints, side, flip)
            expected = joints.copy()
            for bone, parent, child in chain:
                p, c = rows[parent], rows[child]
                ray = joints[c] / np.linalg.norm(joints[c])
                length = np.linalg.norm(joints[c] - joints[p])
                # the original child: which crossing about its original parent (the other root farther?)
                other = other_root(ray, joints[p], length, np.linalg.norm(joints[c]))
                beyond = np.linalg.norm(joints[c]) >= other
                if bone in flip:
                    beyond = not beyond
                roots = np.sort(np.roots([1.0, -2.0 * ray @ expected[p], expected[p] @ expected[p] - length ** 2]))
                if np.iscomplexobj(roots):             # the moved parent leaves the ray out of reach
                    break
                expected[c] = roots[1 if beyond else 0] * ray
            else:
                checked += 1
                np.testing.assert_allclose(new, expected, atol=1e-9)
                np.testing.assert_allclose(CAMERA.project(new), CAMERA.project(joints), atol=1e-9)
                for _, parent, child in chain:
                    assert np.linalg.norm(new[rows[child]] - new[rows[parent]]) == pytest.approx(
                        np.linalg.norm(joints[rows[child]] - joints[rows[parent]]), abs=1e-9)
                np.testing.assert_allclose(flipped_arm_joints(new, side, flip), joints, atol=1e-9)
                first = next(b for b in ("upper_arm", "forearm") if b in flip)        # its parent did not move
                moved = rows["elbow" if first == "upper_arm" else "wrist"]
                assert abs(new[moved, 2] - joints[moved, 2]) > 1e-6
    assert checked >= 30              # (38 of 60 here: elsewhere the moved wrist leaves the hand out of reach)
    # where the ray misses the sphere there is no crossing at all
    assert len(ray_sphere_depths(np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 2.0]), 0.5)) == 0
    with pytest.raises(ValueError, match="side"):
        flipped_arm_joints(joints, "x", ())
    with pytest.raises(ValueError, match="unknown bones"):
        flipped_arm_joints(joints, side, ("femur",))


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
