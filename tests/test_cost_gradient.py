"""Gradients of the matching costs (issue 30): against a slow NumPy twin and against central
finite differences of the real cost on smoothed inputs."""
import numpy as np
import pytest
from scipy import ndimage

from mocap.body import PARAMETER_INDEX as P, BodyModel, neutral_pose
from mocap.cost import EdgeCost
from mocap.render import Camera, render
from tests.naive import naive_edge_gradient

MODEL = BodyModel.build(resolution=8)
CAMERA = Camera.default()


def _target_pose():
    q = neutral_pose()
    for name, deg in (("r_shoulder_flex", 35), ("r_shoulder_abd", 50), ("r_elbow_flex", 60),
                      ("l_shoulder_flex", 15), ("l_shoulder_abd", 30), ("l_elbow_flex", 45), ("chest_yaw", 10)):
        q[P[name]] = np.deg2rad(deg)
    return q


def _smooth_edge_cost(sigma_px=3.0):
    """Edge cost of the target pose's own edges, the distance map blurred (sigma in pixels)."""
    edges = render(_target_pose(), MODEL, CAMERA).edges
    distance = ndimage.gaussian_filter(ndimage.distance_transform_edt(~edges), sigma_px)
    return EdgeCost(distance.astype(np.float32), MODEL, CAMERA), distance


def _start_pose(seed):
    rng = np.random.default_rng(seed)
    return _target_pose() + rng.normal(0.0, 0.05, 23) * np.r_[0.3, 0.3, 0.3, np.ones(20)]


@pytest.fixture(scope="module")
def smooth_cost():
    return _smooth_edge_cost()


@pytest.mark.parametrize("seed", [0, 1])
def test_edge_gradient_matches_the_naive_twin(smooth_cost, seed):
    cost, distance = smooth_cost
    q = _start_pose(seed)
    got = cost.gradient(q)
    value, grad, samples = naive_edge_gradient(q, MODEL, CAMERA, distance.astype(np.float32), cost.edge_gap)
    assert got.samples == samples > 100
    assert got.contour_value == pytest.approx(value, rel=1e-9)
    # the twin differentiates the kinematics by central differences (h = 1e-6: error ~1e-9 relative)
    np.testing.assert_allclose(got.gradient, grad, rtol=1e-5, atol=1e-6 * np.abs(grad).max())
    assert got.value == pytest.approx(cost(q))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_edge_gradient_matches_finite_differences_of_eq2_on_a_smoothed_map(smooth_cost, seed):
    # Eq. (2) counts whole pixels, so it is a staircase in the pose; its central differences are
    # meaningful only over steps that move the contour by about a pixel or more (1 cm of root,
    # 0.03 rad of a joint: ~0.8-1.5 px at 1.8 m) and on a distance map smooth at that scale
    # (blurred, sigma 3 px). Then over the ~500 edge pixels the staircase averages out: the
    # gradient of the contour mean and the differences of the real cost agree closely (measured
    # over 8 such start poses: cosine 0.988-0.999, norm ratio 0.90-1.06; the ratio is the
    # noisier, as the staircase steps add to the differences); the tolerances (cosine > 0.97,
    # ratio within 15 %) leave room for the staircase and the differences' own O(h^2) error,
    # and still fail for a wrong sign, axis or pivot of any sizeable parameter.
    cost, _ = smooth_cost
    q = _start_pose(seed)
    got = cost.gradient(q)
    h = np.r_[np.full(3, 0.01), np.full(20, 0.03)]
    fd = np.array([(cost(q + h[k] * e) - cost(q - h[k] * e)) / (2 * h[k]) for k, e in enumerate(np.eye(23))])
    cosine = got.gradient @ fd / np.linalg.norm(got.gradient) / np.linalg.norm(fd)
    assert cosine > 0.97
    assert np.linalg.norm(got.gradient) / np.linalg.norm(fd) == pytest.approx(1.0, abs=0.15)
    assert abs(got.value - got.contour_value) < 0.5                  # the two are one function, near enough


def test_edge_gradient_without_a_visible_contour_is_zero_and_the_penalty(smooth_cost):
    cost, distance = smooth_cost
    q = neutral_pose()
    q[P["root_x"]] = 5.0                                            # far out of view
    got = cost.gradient(q)
    assert got.samples == 0 and not got.gradient.any()
    assert got.value == got.contour_value == pytest.approx(float(distance.astype(np.float32).max()))
    # the buffers were left clean: the next value is right
    assert cost(_target_pose()) == pytest.approx(cost.gradient(_target_pose()).value)


def test_edge_gradient_checks_the_pose(smooth_cost):
    with pytest.raises(ValueError):
        smooth_cost[0].gradient(np.zeros(22))


# ------------------------------------------------------------------ the gradient step
def test_gauss_newton_lowers_eq2_within_its_bounds_and_budget(smooth_cost):
    from mocap.body import JOINT_LIMITS
    from mocap.optimize import minimize_edge_gauss_newton

    cost, _ = smooth_cost
    lower, upper = JOINT_LIMITS[:, 0].copy(), JOINT_LIMITS[:, 1].copy()
    scale = np.r_[np.full(3, 0.05), np.full(20, np.deg2rad(20.0))]
    target = cost(_target_pose())
    for seed in (0, 1):
        q = _start_pose(seed)
        got = minimize_edge_gauss_newton(cost, q, lower, upper, budget=15, scale=scale)
        assert got.start_fun == pytest.approx(cost(q))
        # within 15 renders it gets at least 90 % of the way down to the target pose's eq. (2)
        # (measured: below the target's own value from all of 4 start poses)
        assert got.fun == pytest.approx(cost(got.x)) and got.fun < target + 0.1 * (got.start_fun - target)
        assert 2 <= got.evaluations <= 15 and got.accepted >= 1
    # a box that pins the right elbow: the result never leaves it
    q = _start_pose(0)
    k = P["r_elbow_flex"]
    lower[k], upper[k] = q[k] - 0.01, q[k] + 0.01
    got = minimize_edge_gauss_newton(cost, q, lower, upper, budget=10, scale=scale)
    assert lower[k] <= got.x[k] <= upper[k]
    assert (got.x >= lower).all() and (got.x <= upper).all()
    # scored with F as well: every point takes two renders, and the score never rises
    region = _region_cost(MODEL)
    guarded = minimize_edge_gauss_newton(cost, q, lower, upper, budget=9, scale=scale, region_cost=region,
                                         region_weight=25.0)
    assert guarded.evaluations % 2 == 0 and guarded.evaluations <= 9
    assert guarded.fun + 25.0 * region(guarded.x) <= guarded.start_fun + 25.0 * region(q) + 1e-12
    with pytest.raises(ValueError, match="at least 1"):
        minimize_edge_gauss_newton(cost, q, lower, upper, budget=0, scale=scale)
    with pytest.raises(ValueError, match="EdgeCost"):
        minimize_edge_gauss_newton(object(), q, lower, upper, budget=3, scale=scale)


def test_registration_gradient_step_takes_its_share_and_never_raises_eq2():
    from mocap.cost import RegionCost
    from mocap.track import TrackerConfig, register
    from mocap.track.config import gradient_budget

    cost, _ = _smooth_edge_cost()
    region = RegionCost(render(_target_pose(), MODEL, CAMERA).labels, MODEL, CAMERA)
    config = TrackerConfig.paper(evaluations=300, gradient_step=True)
    assert TrackerConfig.from_dict(config.to_dict()).gradient_step is True
    with pytest.raises(ValueError, match="gradient_step"):
        TrackerConfig(gradient_step="yes")
    got = register(region, cost, _start_pose(2), config)
    n_gradient = gradient_budget(150)
    assert n_gradient == 15 and gradient_budget(30) == 0                # too few to take a step: none
    assert got.gradient is not None and 2 <= got.gradient.evaluations <= n_gradient
    assert got.edge.evaluations <= 150 - n_gradient
    assert got.evaluations <= 300
    assert got.edge_residual == pytest.approx(got.gradient.fun) and got.gradient.fun <= got.gradient.start_fun
    assert got.gradient.start_fun == pytest.approx(cost(got.edge.x))
    assert register(region, cost, _start_pose(2), TrackerConfig.paper(evaluations=300)).gradient is None


# ------------------------------------------------------------------ eq. 1
PAPER_MODEL = BodyModel.build(MODEL.dims.without_extensions(), resolution=8)


def _region_cost(model):
    from mocap.cost import RegionCost
    return RegionCost(render(_target_pose(), model, CAMERA).labels, model, CAMERA)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_region_gradient_matches_finite_differences_of_eq1(seed):
    # F counts whole pixels; its central differences over steps that move the boundary by about
    # a pixel (as for eq. 2) average that staircase over the ~400 boundary pixels. On the paper's
    # two-class model (large classes: F is smooth enough at that scale) the two agree (measured
    # over 8 start poses: cosine 0.966-0.999, norm ratio 1.00-1.06, one pose near the optimum at
    # 1.36: there F's ratios of small mismatch counts are far from linear over the step). The
    # four-class model's hair class is a few dozen pixels, too small for differences of one
    # pixel's motion to be a derivative (cosine 0.81-0.999 over the same poses).
    cost = _region_cost(PAPER_MODEL)
    q = _start_pose(seed)
    got = cost.gradient(q)
    assert got.value == pytest.approx(cost(q)) and got.samples > 100
    h = np.r_[np.full(3, 0.01), np.full(20, 0.03)]
    fd = np.array([(cost(q + h[k] * e) - cost(q - h[k] * e)) / (2 * h[k]) for k, e in enumerate(np.eye(23))])
    cosine = got.gradient @ fd / np.linalg.norm(got.gradient) / np.linalg.norm(fd)
    assert cosine > 0.97
    assert np.linalg.norm(got.gradient) / np.linalg.norm(fd) == pytest.approx(1.0, abs=0.15)


def test_region_gradient_is_flat_where_no_boundary_moves():
    from mocap.cost import RegionCost

    cost = _region_cost(MODEL)
    q = neutral_pose()
    q[P["root_x"]] = 5.0                                            # out of view: no boundary at all
    got = cost.gradient(q)
    assert got.value == pytest.approx(cost(q)) and got.samples == 0 and not got.gradient.any()
    exact = cost.gradient(_target_pose())                           # F = 0: a minimum, gradient 0
    assert exact.value == 0.0 and not exact.gradient.any()
    blank = RegionCost(np.zeros(CAMERA.shape, np.uint8), MODEL, CAMERA)
    assert not blank.gradient(_start_pose(0)).gradient.any()        # F = 1 whatever the model does


@pytest.mark.parametrize("seed", [0, 3])
def test_region_gradient_matches_the_naive_twin(seed):
    from tests.naive import naive_region_gradient

    cost = _region_cost(MODEL)                                      # four classes: contours and seams
    q = _start_pose(seed)
    got = cost.gradient(q)
    value, grad, samples = naive_region_gradient(q, MODEL, CAMERA, render(_target_pose(), MODEL, CAMERA).labels,
                                                 cost.gradient_args().edge_gap)
    assert got.samples == samples > 100
    assert got.value == pytest.approx(value, rel=1e-12)
    # the twin differentiates the kinematics by central differences and reads the depth as
    # float32 metres (the kernel: float32 inverse depth): agreement to ~1e-6 relative
    np.testing.assert_allclose(got.gradient, grad, rtol=1e-4, atol=1e-5 * np.abs(grad).max())
