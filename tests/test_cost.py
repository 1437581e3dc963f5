import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp
from scipy import ndimage

from mocap.body import JOINT_LIMITS, JOINT_NAMES, PARAMETER_INDEX as P, BodyModel, neutral_pose
from mocap.cost import (EMPTY_REGION_COST, KEYPOINT_NOISE, MIN_KEYPOINT_SCALE_PX, EdgeCost, KeypointCost, LabelRenderer,
                        RegionCost, keypoint_gates, keypoint_scales, mean_edge_distance, robust_distance,
                        non_overlapping_ratio)
from mocap.render import Camera, render
from tests.naive import naive_keypoint_distance, naive_mean_edge_distance, naive_non_overlapping_ratio

MODEL = BodyModel.build(resolution=8)
CAMERA = Camera.default()


def random_pose(rng):
    q = rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
    q[:3] = rng.uniform([-0.3, 0.0, 1.5], [0.3, 0.4, 2.5])
    return q


# ------------------------------------------------------------------ label renderer
def test_label_renderer_matches_render_over_a_sequence_of_poses():
    # each call clears only the previous render's box: a sequence with renders that are
    # empty, small, large and shifted must still equal a fresh render every time
    rng = np.random.default_rng(5)
    renderer = LabelRenderer(MODEL, CAMERA)
    away = neutral_pose()
    away[2] = -2.0                                   # behind the camera: nothing drawn
    near = neutral_pose()
    near[2] = 0.8
    poses = [random_pose(rng), away, near, random_pose(rng), away, away, neutral_pose()]
    poses += [random_pose(rng) for _ in range(10)]
    for q in poses:
        got = renderer(q)
        np.testing.assert_array_equal(got, render(q, MODEL, CAMERA).labels)
    assert got.shape == CAMERA.shape and got.dtype == np.uint8


def test_label_renderer_takes_every_pose_form_and_refuses_non_finite_ones():
    # a plain float64 array takes the compiled check; lists, float32, read-only and strided
    # arrays and huge finite values (whose sum overflows) go through check_pose: same labels
    rng = np.random.default_rng(8)
    renderer = LabelRenderer(MODEL, CAMERA)
    q = random_pose(rng)
    expected = render(q, MODEL, CAMERA).labels
    read_only = q.copy()
    read_only.setflags(write=False)
    strided = np.repeat(q, 2)[::2]
    for form in (q, list(q), read_only, strided):
        np.testing.assert_array_equal(renderer(form), expected)
    np.testing.assert_array_equal(renderer(q.astype(np.float32)), render(q.astype(np.float32), MODEL, CAMERA).labels)
    huge = neutral_pose()
    huge[3], huge[4] = 1e308, 1e308                 # finite: rendered as render() renders it
    np.testing.assert_array_equal(renderer(huge), render(huge, MODEL, CAMERA).labels)
    for value in (np.nan, np.inf):
        bad = q.copy()
        bad[5] = value
        with pytest.raises(ValueError, match="non-finite"):
            renderer(bad)
    np.testing.assert_array_equal(renderer(q), expected)      # nothing was drawn by the refused poses


def test_label_renderer_output_is_read_only():
    got = LabelRenderer(MODEL, CAMERA)(neutral_pose())
    assert got.any()
    with pytest.raises(ValueError):
        got[0, 0] = 1


# ------------------------------------------------------------------ non-overlapping ratio
def test_ratio_identical_is_zero_and_disjoint_is_one():
    a = np.zeros((4, 6), np.uint8)
    a[:2, :2] = 1
    a[2:, :2] = 2
    assert non_overlapping_ratio(a, a, 2) == 0.0
    b = np.zeros_like(a)
    b[:2, 4:] = 1
    b[2:, 4:] = 2
    assert non_overlapping_ratio(a, b, 2) == 1.0


def test_ratio_hand_computed_example():
    # class 1: image 4 px, model 4 px, 2 shared -> union 6 -> (6 - 2) / 6 = 2/3
    # class 2: image 2 px, model 2 px, 1 shared -> union 3 -> (3 - 1) / 3 = 2/3
    # F = (2/3 * 2/3) ** (1/2) = 2/3
    a = np.zeros((3, 6), np.uint8)
    b = np.zeros_like(a)
    a[0, 0:4] = 1
    b[0, 2:6] = 1
    a[2, 0:2] = 2
    b[2, 1:3] = 2
    assert non_overlapping_ratio(a, b, 2) == pytest.approx(2 / 3)
    # unknown (255) and background pixels never count
    a[1, :] = 255
    assert non_overlapping_ratio(a, b, 2) == pytest.approx(2 / 3)


def test_ratio_empty_unions_are_documented():
    a = np.zeros((3, 3), np.uint8)
    assert non_overlapping_ratio(a, a, 2) == EMPTY_REGION_COST == 1.0
    a[0, 0] = 1
    b = a.copy()
    b[1, 1] = 1                    # class 2 absent from both: dropped, F = class-1 term = 1/2
    assert non_overlapping_ratio(a, b, 2) == pytest.approx(0.5)


@settings(max_examples=50, deadline=None)
@given(hnp.arrays(np.uint8, (6, 7), elements=st.sampled_from([0, 1, 2, 3, 255])),
       hnp.arrays(np.uint8, (6, 7), elements=st.sampled_from([0, 1, 2, 3])), st.integers(1, 3))
def test_ratio_matches_naive_set_twin(a, b, m):
    assert non_overlapping_ratio(a, b, m) == pytest.approx(naive_non_overlapping_ratio(a, b, m), abs=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_region_cost_equals_ratio_of_rendered_labels(seed):
    rng = np.random.default_rng(seed)
    q_true, q = random_pose(rng), random_pose(rng)
    target = render(q_true, MODEL, CAMERA).labels
    cost = RegionCost(target, MODEL, CAMERA)
    assert cost(q_true) == 0.0
    expect = naive_non_overlapping_ratio(target, render(q, MODEL, CAMERA).labels, MODEL.n_classes)
    assert cost(q) == pytest.approx(expect, abs=1e-12)
    assert cost(q) == pytest.approx(expect, abs=1e-12)     # buffers are left clean between calls


def test_region_cost_grows_with_displacement():
    q = neutral_pose()
    cost = RegionCost(render(q, MODEL, CAMERA).labels, MODEL, CAMERA)
    values = [cost(q + np.r_[dx, np.zeros(22)]) for dx in (0.0, 0.02, 0.05, 0.1, 1.5)]
    assert values[0] == 0.0 and np.all(np.diff(values) > 0) and values[-1] == 1.0


def test_region_cost_model_out_of_view():
    target = render(neutral_pose(), MODEL, CAMERA).labels
    q = neutral_pose()
    q[2] = -1.0                                   # behind the camera: nothing drawn
    assert RegionCost(target, MODEL, CAMERA)(q) == 1.0
    assert RegionCost(np.zeros_like(target), MODEL, CAMERA)(q) == EMPTY_REGION_COST


# ------------------------------------------------------------------ mean edge distance
def test_edge_distance_zero_on_own_edges_and_equal_to_naive():
    rng = np.random.default_rng(7)
    q = random_pose(rng)
    edges = render(q, MODEL, CAMERA).edges
    dist = ndimage.distance_transform_edt(~edges).astype(np.float32)
    cost = EdgeCost(dist, MODEL, CAMERA)
    assert cost(q) == 0.0
    for _ in range(5):
        q2 = random_pose(rng)
        expect = naive_mean_edge_distance(dist, render(q2, MODEL, CAMERA).edges, dist.max())
        assert cost(q2) == pytest.approx(expect, rel=1e-6)


@pytest.mark.parametrize("k", [1, 2, 5])
def test_edge_distance_equals_known_shift(k):
    # straight horizontal image edges; model edges k rows below them: D = k exactly
    image_edges = np.zeros((40, 60), bool)
    image_edges[10, :] = True
    image_edges[30, :] = True
    dist = ndimage.distance_transform_edt(~image_edges)
    model_edges = np.roll(image_edges, k, axis=0)
    assert mean_edge_distance(dist, model_edges) == pytest.approx(k)
    assert naive_mean_edge_distance(dist, model_edges, 0) == pytest.approx(k)


def test_edge_distance_of_shifted_body_is_bounded_by_shift():
    q = neutral_pose()
    edges = render(q, MODEL, CAMERA).edges
    for k in (1, 3):
        shifted = np.zeros_like(edges)
        shifted[:, k:] = edges[:, :-k]
        dist = ndimage.distance_transform_edt(~shifted).astype(np.float32)
        d = EdgeCost(dist, MODEL, CAMERA)(q)
        assert 0.3 * k < d <= k


def test_edge_cost_without_model_edges_returns_penalty():
    dist = np.full(CAMERA.shape, 4.0, np.float32)
    q = neutral_pose()
    q[2] = -2.0
    assert EdgeCost(dist, MODEL, CAMERA)(q) == 4.0
    assert EdgeCost(dist, MODEL, CAMERA, no_edge_penalty=30.0)(q) == 30.0


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("make, match", [
    (lambda: RegionCost(np.zeros((120, 161), np.uint8), MODEL, CAMERA), "shape"),
    (lambda: RegionCost(np.zeros((120, 160), np.int32), MODEL, CAMERA), "uint8"),
    (lambda: RegionCost([[0]], MODEL, CAMERA), "shape"),
    (lambda: EdgeCost(np.zeros((10, 10)), MODEL, CAMERA), "shape"),
    (lambda: EdgeCost(np.full((120, 160), np.nan), MODEL, CAMERA), "finite"),
    (lambda: EdgeCost(-np.ones((120, 160)), MODEL, CAMERA), "non-negative"),
    (lambda: EdgeCost(np.ones((120, 160)), MODEL, CAMERA, no_edge_penalty=float("inf")), "penalty"),
    (lambda: non_overlapping_ratio(np.zeros((2, 2)), np.zeros((2, 3)), 2), "shape"),
    (lambda: mean_edge_distance(np.zeros((2, 2)), np.zeros((3, 2), bool)), "shape"),
])
def test_bad_cost_input_raises(make, match):
    with pytest.raises(ValueError, match=match):
        make()


@settings(max_examples=30, deadline=None)
@given(hnp.arrays(np.float64, st.integers(0, 30), elements=st.floats(allow_nan=True, allow_infinity=True)))
def test_cost_calls_with_bad_pose_raise_not_crash(values):
    cost = RegionCost(np.zeros(CAMERA.shape, np.uint8), MODEL, CAMERA)
    edge = EdgeCost(np.ones(CAMERA.shape, np.float32), MODEL, CAMERA)
    if values.shape == (23,) and np.isfinite(values).all():
        assert 0.0 <= cost(values) <= 1.0 and edge(values) >= 0.0
    else:
        with pytest.raises(ValueError):
            cost(values)
        with pytest.raises(ValueError):
            edge(values)


def test_pose_far_outside_limits_still_renders_finitely():
    q = neutral_pose()
    q[P["r_elbow_flex"]] = 1e6
    q[0] = 1e3
    target = render(neutral_pose(), MODEL, CAMERA).labels
    assert np.isfinite(RegionCost(target, MODEL, CAMERA)(q))


def test_unknown_pixels_count_on_neither_side_by_default():
    # class 1: image 2 px + 2 unknown px; the model covers all 4 -> literally (4 - 2) / 4 = 1/2,
    # ignoring the unknown pixels the model covers: union 2, overlap 2 -> 0
    a = np.zeros((2, 4), np.uint8)
    a[0, :2] = 1
    a[0, 2:] = 255
    b = np.zeros_like(a)
    b[0, :] = 1
    assert non_overlapping_ratio(a, b, 1) == 0.0
    assert non_overlapping_ratio(a, b, 1, ignore_unknown=False) == pytest.approx(0.5)
    assert naive_non_overlapping_ratio(a, b, 1, ignore_unknown=False) == pytest.approx(0.5)


@pytest.mark.parametrize("ignore", [True, False])
def test_region_cost_with_unknown_pixels_matches_the_twin(ignore):
    rng = np.random.default_rng(11)
    q_true, q = random_pose(rng), random_pose(rng)
    target = render(q_true, MODEL, CAMERA).labels.copy()
    target[rng.random(target.shape) < 0.2] = 255          # a fifth of the image unexplained
    cost = RegionCost(target, MODEL, CAMERA, ignore_unknown=ignore)
    for pose in (q_true, q):
        expect = naive_non_overlapping_ratio(target, render(pose, MODEL, CAMERA).labels, MODEL.n_classes,
                                             ignore_unknown=ignore)
        assert cost(pose) == pytest.approx(expect, abs=1e-12)


def test_one_class_matched_exactly_does_not_zero_the_product():
    """Hair matched pixel for pixel while the clothes are half off: F stays the clothes' mismatch,
    with the exact class at 1 / (union + 1) (a product of eq. 1 would be 0)."""
    target = np.zeros((4, 8), np.uint8)
    target[0, :3] = 3                       # hair: 3 pixels, matched exactly
    target[2, :4] = 2                       # clothes: 4 pixels, the model covers 2 of them and 2 more
    model = target.copy()
    model[2, :4] = 0
    model[2, 2:6] = 2
    clothes_term = (6 - 2) / 6
    expect = (clothes_term * (1 / (3 + 1))) ** 0.5
    assert non_overlapping_ratio(target, model, 3) == pytest.approx(expect)
    assert naive_non_overlapping_ratio(target, model, 3) == pytest.approx(expect)
    assert non_overlapping_ratio(target, target, 3) == 0.0


# ------------------------------------------------------------------ keypoint distance
def test_keypoint_cost_equals_its_twin_on_random_poses():
    rng = np.random.default_rng(11)
    for trial in range(20):
        uv = rng.uniform([0, 0], [CAMERA.width, CAMERA.height], (10, 2))
        conf = rng.uniform(0, 1, 10)
        conf[rng.uniform(size=10) < 0.3] = 0.0                    # some absent
        uv[rng.uniform(size=10) < 0.1] = np.nan                    # some NaN: absent too
        scale = rng.uniform(1.0, 8.0, 10)
        swap = trial % 2 == 1
        plain = KeypointCost(uv, conf, MODEL, CAMERA, scale=np.full(10, np.inf))
        robust = KeypointCost(uv, conf, MODEL, CAMERA, scale=scale, swap=swap)
        for _ in range(5):
            q = random_pose(rng)
            assert plain(q) == pytest.approx(naive_keypoint_distance(q, MODEL, CAMERA, uv, conf), rel=1e-12, abs=1e-12)
            assert robust(q) == pytest.approx(naive_keypoint_distance(q, MODEL, CAMERA, uv, conf, scale, swap),
                                              rel=1e-12, abs=1e-12)
            direct, swapped = robust.labellings(q)
            assert direct == pytest.approx(naive_keypoint_distance(q, MODEL, CAMERA, uv, conf, scale), rel=1e-12,
                                           abs=1e-12)
            assert robust.labelling(q) == (swap and swapped < direct)


def test_keypoint_cost_is_zero_on_the_models_own_projections_and_grows_with_a_shift():
    rng = np.random.default_rng(3)
    q = random_pose(rng)
    uv = CAMERA.project(MODEL.joint_positions(q))
    conf = rng.uniform(0.1, 1.0, 10)
    assert KeypointCost(uv, conf, MODEL, CAMERA)(q) == pytest.approx(0.0, abs=1e-9)
    assert KeypointCost(uv + [3.0, 4.0], conf, MODEL, CAMERA, scale=np.full(10, np.inf))(q) == pytest.approx(5.0)
    # robust: 5 px at a 2 px scale is 2 log(1 + 5 / 2) pixels (a scale given)
    assert KeypointCost(uv + [3.0, 4.0], conf, MODEL, CAMERA, scale=np.full(10, 2.0))(q) == pytest.approx(
        2.0 * np.log(3.5))


def test_robust_distance_is_the_distance_near_a_keypoint_and_its_pull_falls_off():
    assert robust_distance(0.0, 3.0) == 0.0
    assert robust_distance(0.01, 3.0) == pytest.approx(0.01, rel=2e-3)       # slope 1 at the keypoint
    assert robust_distance(50.0, 3.0) == pytest.approx(3.0 * np.log(53.0 / 3.0))
    slope = (robust_distance(50.01, 3.0) - robust_distance(50.0, 3.0)) / 0.01
    assert slope == pytest.approx(3.0 / 53.0, rel=1e-3)
    assert robust_distance(7.0, np.inf) == 7.0


def test_keypoint_scales_follow_the_persons_size_and_keep_a_floor():
    uv = CAMERA.project(MODEL.joint_positions(neutral_pose()))
    small = keypoint_scales(uv, np.ones(10))
    assert np.all(small >= MIN_KEYPOINT_SCALE_PX)
    spread = np.sqrt(((uv - uv.mean(axis=0)) ** 2).sum(axis=1).mean())
    factor = 2.0 * MIN_KEYPOINT_SCALE_PX / (spread * min(KEYPOINT_NOISE.values()))
    big = keypoint_scales(uv * factor, np.ones(10))          # a person that large: the measured noise rules
    np.testing.assert_allclose(big, [factor * spread * KEYPOINT_NOISE[n] for n in JOINT_NAMES])


def test_keypoint_gates_weigh_down_a_joint_off_the_silhouette():
    fg = np.zeros(CAMERA.shape, bool)
    fg[40:80, 60:100] = True
    uv = np.array([[70.5, 50.5], [101.5, 50.5], [150.5, 50.5], [80.0, -20.0]])
    gates = keypoint_gates(uv, fg, margin=3.0)
    assert gates[0] == 1.0 and gates[1] == 1.0                  # on it, and 2 px off it (within the margin)
    assert gates[2] == pytest.approx(1.0 / (1.0 + ((51.0 - 3.0) / 3.0) ** 2))   # 51 px to the nearest column
    assert gates[3] < 0.01                                      # above the image: 60 px off
    np.testing.assert_array_equal(keypoint_gates(uv, np.zeros(CAMERA.shape, bool)), 1.0)
    with pytest.raises(ValueError, match="margin"):
        keypoint_gates(uv, fg, margin=0.0)
    # a gated joint hardly counts: the cost is about the others' alone
    q = neutral_pose()
    truth = CAMERA.project(MODEL.joint_positions(q))
    labels = render(q, MODEL, CAMERA).labels
    wrong = truth.copy()
    wrong[JOINT_NAMES.index("r_hand")] += [0.0, 45.0]              # thrown below the silhouette
    gated = KeypointCost(wrong, np.ones(10), MODEL, CAMERA, foreground=labels != 0)
    ungated = KeypointCost(wrong, np.ones(10), MODEL, CAMERA)
    assert gated(q) < 0.05 * ungated(q)


def test_keypoint_value_and_labelling_are_the_cost_and_its_labelling():
    """One evaluation of both labellings gives what ``cost(pose)`` and ``labelling(pose)`` give,
    bit for bit, with ``swap`` off and on (the keypoints read swapped on half the poses)."""
    rng = np.random.default_rng(11)
    q = neutral_pose()
    uv = CAMERA.project(MODEL.joint_positions(q))
    swapped_uv = uv[[JOINT_NAMES.index(n.replace("r_", "#").replace("l_", "r_").replace("#", "l_")) for n in JOINT_NAMES]]
    seen = set()
    for swap in (False, True):
        for points in (uv, swapped_uv):
            cost = KeypointCost(points + rng.normal(0.0, 2.0, (10, 2)), rng.uniform(0.3, 1.0, 10), MODEL, CAMERA,
                                swap=swap)
            for _ in range(4):
                pose = np.clip(q + rng.normal(0.0, 0.2, 23) * (np.arange(23) >= 6), *JOINT_LIMITS.T)
                value, taken = cost.value_and_labelling(pose)
                assert value == cost(pose) and taken == cost.labelling(pose)
                seen.add(taken)
    assert seen == {False, True}


def test_keypoint_cost_for_another_body_is_a_new_cost_of_that_body():
    """``for_model`` (the calibration's trial bodies) gives, bit for bit, what a KeypointCost built
    on the other body gives (gates, scales and both labellings kept), and leaves the first one's
    value alone."""
    from mocap.body import BodyDimensions

    rng = np.random.default_rng(5)
    q = neutral_pose()
    uv = CAMERA.project(MODEL.joint_positions(q)) + rng.normal(0.0, 3.0, (10, 2))
    uv[JOINT_NAMES.index("r_hand")] += [0.0, 45.0]                  # gated: off the silhouette
    conf = rng.uniform(0.3, 1.0, 10)
    foreground = render(q, MODEL, CAMERA).labels != 0
    other = BodyModel.build(BodyDimensions().scaled(1.15, parts=("r_upper_arm", "l_forearm", "torso")), resolution=8)
    for swap in (False, True):
        first = KeypointCost(uv, conf, MODEL, CAMERA, foreground=foreground, swap=swap)
        fresh = KeypointCost(uv, conf, other, CAMERA, foreground=foreground, swap=swap)
        moved = first.for_model(other)
        for pose in (q, *(np.clip(q + rng.normal(0.0, 0.3, 23) * (np.arange(23) >= 6), *JOINT_LIMITS.T)
                          for _ in range(5))):
            before = first(pose)
            assert moved(pose) == fresh(pose)
            assert np.array_equal(moved.labellings(pose), fresh.labellings(pose), equal_nan=True)
            assert first(pose) == before and first(pose) != fresh(pose)


def test_region_cost_for_another_body_is_a_new_cost_of_that_body():
    """``RegionCost.for_model`` (the calibration's trial bodies) gives, bit for bit, what a
    RegionCost built on the other body gives, leaves the first one's value alone, and refuses a
    body with another number of colour classes."""
    from mocap.body import BodyDimensions

    rng = np.random.default_rng(6)
    q = neutral_pose()
    target = render(q, MODEL, CAMERA).labels.copy()
    target[rng.random(target.shape) < 0.05] = 255                  # some unknown pixels
    other = MODEL.with_dimensions(BodyDimensions().scaled(1.15, parts=("r_upper_arm", "l_forearm", "torso")))
    first = RegionCost(target, MODEL, CAMERA)
    fresh = RegionCost(target, other, CAMERA)
    moved = first.for_model(other)
    for pose in (q, *(np.clip(q + rng.normal(0.0, 0.3, 23) * (np.arange(23) >= 6), *JOINT_LIMITS.T)
                      for _ in range(5))):
        before = first(pose)
        assert moved(pose) == fresh(pose)
        assert first(pose) == before
    assert first(q) != fresh(q)
    with pytest.raises(ValueError, match="colour classes"):
        first.for_model(MODEL.with_class_names(MODEL.class_names[:2]))


def test_keypoint_cost_without_keypoints_is_zero_and_joints_behind_the_camera_cost_the_diagonal():
    q = neutral_pose()
    assert KeypointCost(np.full((10, 2), np.nan), np.zeros(10), MODEL, CAMERA)(q) == 0.0
    behind = q.copy()
    behind[2] = -1.0
    uv = CAMERA.project(MODEL.joint_positions(q))
    assert KeypointCost(uv, np.ones(10), MODEL, CAMERA, scale=np.full(10, np.inf))(behind) == pytest.approx(np.hypot(160, 120))
    with pytest.raises(ValueError, match="shape"):
        KeypointCost(uv[:3], np.ones(3), MODEL, CAMERA)
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        KeypointCost(uv, np.full(10, 2.0), MODEL, CAMERA)
