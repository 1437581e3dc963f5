import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from mocap.body import (JOINT_LIMITS, JOINT_NAMES, PARAMETER_INDEX as P, SEGMENT_NAMES, BodyDimensions,
                        BodyModel, clamp_to_limits, neutral_pose)
from mocap.body.skeleton import SHOULDER_DROP_ARM, SHOULDER_OUT_ARM, SHOULDER_OUT_TORSO, part_spans
from tests.naive import naive_segment_transforms

MODEL = BodyModel.build()
DIMS = MODEL.dims
J = {name: i for i, name in enumerate(JOINT_NAMES)}


def random_pose(rng):
    lo, hi = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    q = rng.uniform(lo, hi)
    q[:3] = rng.uniform([-0.5, -0.5, 1.0], [0.5, 0.5, 3.0])
    return q


def zero_pose(root=(0.0, 0.0, 2.0)):
    q = np.zeros(23)
    q[:3] = root
    return q


def test_matches_naive_scipy_kinematics_on_random_poses():
    rng = np.random.default_rng(1)
    for _ in range(50):
        q = random_pose(rng)
        got = MODEL.segment_transforms(q)
        ref = naive_segment_transforms(q, MODEL.skeleton.offsets)
        for k, name in enumerate(SEGMENT_NAMES):
            np.testing.assert_allclose(got[k, :, :3], ref[name][0], atol=1e-12)
            np.testing.assert_allclose(got[k, :, 3], ref[name][1], atol=1e-12)


def test_one_arms_transforms_are_the_whole_bodys_to_the_bit():
    """``arm_transforms_into`` (what reach_arm's solver computes) fills the chest's and that arm's
    rows exactly as ``segment_transforms_into`` does, and leaves the others as they were."""
    from mocap.body.kinematics import ARM_SIDES, arm_transforms_into, segment_transforms_into

    rng = np.random.default_rng(3)
    for _ in range(20):
        q = random_pose(rng)
        whole = np.empty((len(SEGMENT_NAMES), 3, 4))
        segment_transforms_into(q, MODEL.skeleton.offsets, whole)
        for side_index, side in enumerate(ARM_SIDES):
            arm = np.full_like(whole, np.nan)
            arm_transforms_into(q, MODEL.skeleton.offsets, side_index, arm)
            rows = [SEGMENT_NAMES.index(n) for n in ("chest", f"{side}_upper_arm", f"{side}_forearm", f"{side}_hand")]
            assert arm[rows].tobytes() == whole[rows].tobytes()
            assert np.isnan(np.delete(arm, rows, axis=0)).all()


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_bone_lengths_preserved_under_any_pose(seed):
    q = random_pose(np.random.default_rng(seed))
    j = MODEL.joint_positions(q)
    dist = lambda a, b: np.linalg.norm(j[J[a]] - j[J[b]])
    spans = part_spans(DIMS)
    head_centre = 0.5 * (spans[2, 0] + spans[2, 1])
    for side in "rl":
        assert dist(f"{side}_shoulder", f"{side}_elbow") == pytest.approx(DIMS[f"{side}_upper_arm"].length)
        assert dist(f"{side}_elbow", f"{side}_wrist") == pytest.approx(DIMS[f"{side}_forearm"].length)
        assert dist(f"{side}_wrist", f"{side}_hand") == pytest.approx(DIMS[f"{side}_hand"].length / 2)
        # shoulders are rigid on the chest: their distance to the neck never changes
        ua = DIMS[f"{side}_upper_arm"]
        lateral = SHOULDER_OUT_TORSO * DIMS["torso"].width + SHOULDER_OUT_ARM * ua.width
        assert dist(f"{side}_shoulder", "neck") == pytest.approx(np.hypot(lateral, SHOULDER_DROP_ARM * ua.width))
    assert dist("neck", "head") == pytest.approx(head_centre)
    for k in range(len(SEGMENT_NAMES)):   # every rotation stays orthonormal
        r = MODEL.segment_transforms(q)[k, :, :3]
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)


def test_known_poses_give_hand_computed_joints():
    torso, ua, fa = DIMS["torso"], DIMS["r_upper_arm"], DIMS["r_forearm"]
    sx = 0.5 * torso.width + 0.1 * ua.width            # 0.18 m with default proportions
    sy = -(torso.length - 0.55 * ua.width)             # -0.445 m
    q = zero_pose()
    j = MODEL.joint_positions(q)
    np.testing.assert_allclose(j[J["r_shoulder"]], [-sx, sy, 2.0])
    np.testing.assert_allclose(j[J["l_shoulder"]], [sx, sy, 2.0])
    np.testing.assert_allclose(j[J["r_elbow"]], [-sx, sy + ua.length, 2.0])     # hanging down (+y)
    np.testing.assert_allclose(j[J["neck"]], [0.0, -torso.length, 2.0])
    # abduction 90 degrees: right arm horizontal towards the actor's right (-x)
    q = zero_pose(); q[P["r_shoulder_abd"]] = np.pi / 2
    np.testing.assert_allclose(MODEL.joint_positions(q)[J["r_elbow"]], [-sx - ua.length, sy, 2.0], atol=1e-12)
    q = zero_pose(); q[P["l_shoulder_abd"]] = np.pi / 2
    np.testing.assert_allclose(MODEL.joint_positions(q)[J["l_elbow"]], [sx + ua.length, sy, 2.0], atol=1e-12)
    # flexion 90 degrees: arm points at the camera (-z)
    q = zero_pose(); q[P["r_shoulder_flex"]] = np.pi / 2
    np.testing.assert_allclose(MODEL.joint_positions(q)[J["r_elbow"]], [-sx, sy, 2.0 - ua.length], atol=1e-12)
    # elbow flexion 90 degrees with the arm hanging: forearm points at the camera
    q = zero_pose(); q[P["r_elbow_flex"]] = np.pi / 2
    np.testing.assert_allclose(MODEL.joint_positions(q)[J["r_wrist"]],
                               [-sx, sy + ua.length, 2.0 - fa.length], atol=1e-12)
    # chest yaw 90 degrees: the right shoulder swings back (+z), the left one forward
    q = zero_pose(); q[P["chest_yaw"]] = np.pi / 2
    j = MODEL.joint_positions(q)
    np.testing.assert_allclose(j[J["r_shoulder"]], [0.0, sy, 2.0 + sx], atol=1e-12)
    np.testing.assert_allclose(j[J["l_shoulder"]], [0.0, sy, 2.0 - sx], atol=1e-12)


def test_left_and_right_are_mirror_images():
    rng = np.random.default_rng(3)
    q = random_pose(rng)
    q[3:9] = 0.0                            # symmetric torso and head
    q[:3] = (0.0, 0.2, 2.0)
    q[16:23] = q[9:16]                      # same angles both sides
    j = MODEL.joint_positions(q)
    for name in ("shoulder", "elbow", "wrist", "hand"):
        r, l = j[J[f"r_{name}"]], j[J[f"l_{name}"]]
        np.testing.assert_allclose([-r[0], r[1], r[2]], l, atol=1e-12)


def test_limits_clamp_before_kinematics():
    q = zero_pose()
    q[P["r_elbow_flex"]] = np.deg2rad(300)  # impossible elbow
    c = clamp_to_limits(q)
    j = MODEL.joint_positions(c)
    # clamped to 150 degrees: the wrist is at 150 degrees from the hanging direction
    ua = j[J["r_elbow"]] - j[J["r_shoulder"]]
    fa = j[J["r_wrist"]] - j[J["r_elbow"]]
    cos = ua @ fa / np.linalg.norm(ua) / np.linalg.norm(fa)
    assert np.rad2deg(np.arccos(cos)) == pytest.approx(150.0)


def test_other_dimensions_change_the_skeleton():
    tall = DIMS.scaled(1.2)
    j1 = BodyModel.build(tall).joint_positions(zero_pose())
    j0 = MODEL.joint_positions(zero_pose())
    np.testing.assert_allclose(j1 - [0, 0, 2.0], 1.2 * (j0 - [0, 0, 2.0]), atol=1e-12)


def test_point_jacobians_match_central_differences_of_the_kinematics():
    from mocap.body.kinematics import point_jacobians

    rng = np.random.default_rng(7)
    mesh = MODEL.mesh
    idx = rng.choice(len(mesh.vertices), 60, replace=False)
    seg, local = mesh.vertex_segment[idx], mesh.vertices[idx]

    def points(q):
        t = MODEL.segment_transforms(q)
        return np.einsum("nij,nj->ni", t[seg, :, :3], local) + t[seg, :, 3]

    for _ in range(4):
        q = random_pose(rng)
        got = point_jacobians(q, MODEL.skeleton, seg, local)
        h = 1e-6          # central differences: error ~h^2 * |X'''| + rounding 1e-16 / h, below 1e-8 m
        ref = np.stack([(points(q + h * e) - points(q - h * e)) / (2 * h) for e in np.eye(23)], axis=-1)
        np.testing.assert_allclose(got, ref, atol=1e-8)
    with pytest.raises(ValueError):
        point_jacobians(q, MODEL.skeleton, [8], [[0.0, 0.0, 0.0]])


def test_edge_faces_of_the_body_mesh_and_an_open_mesh():
    from mocap.body.mesh import edge_faces

    tri = MODEL.mesh.triangles
    edges, faces = edge_faces(tri)
    assert len(edges) == 3 * len(tri) // 2                        # closed: every edge in two triangles
    for (a, b), (f, g) in zip(edges[::37], faces[::37]):
        assert f != g and {a, b} <= set(tri[f]) and {a, b} <= set(tri[g])
    with pytest.raises(ValueError, match="not closed"):
        edge_faces(tri[1:])
