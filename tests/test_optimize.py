import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from mocap.body import JOINT_LIMITS, BodyDimensions, BodyModel, clamp_to_limits, neutral_pose
from mocap.cost import EdgeCost, KeypointCost, RegionCost
from mocap.optimize import coefficients, initial_simplex, minimize, minimize_cost
from mocap.render import Camera, render
from tests.naive import naive_nelder_mead

#: Accuracy asked of the test minima (parameter units).
X_TOL = 1e-4


def rosenbrock(x):
    return float(np.sum(100.0 * (x[1:] - x[:-1] ** 2) ** 2 + (1.0 - x[:-1]) ** 2))


class Recorder:
    """A cost that remembers every point it was asked about."""

    def __init__(self, f):
        self.f, self.points = f, []

    def __call__(self, x):
        self.points.append(np.array(x))
        return self.f(x)


def box(n, lo=-2.0, hi=2.0):
    return np.full(n, lo), np.full(n, hi)


@pytest.mark.parametrize("n", [2, 3, 5])
def test_finds_minimum_of_bounded_quadratic(n):
    lower, upper = box(n)
    centre = np.linspace(-1.0, 1.5, n)
    f = lambda x: float(np.sum((np.arange(1, n + 1)) * (x - centre) ** 2))
    res = minimize(f, initial_simplex(np.zeros(n), np.full(n, 0.5), lower, upper), lower, upper,
                   budget=5000, ftol=1e-14)
    assert res.converged
    np.testing.assert_allclose(res.x, centre, atol=X_TOL)


def test_minimum_outside_the_box_ends_on_the_bound():
    lower, upper = box(3, -1.0, 1.0)
    target = np.array([3.0, 0.2, -5.0])
    f = lambda x: float(np.sum((x - target) ** 2))
    res = minimize(f, initial_simplex(np.zeros(3), np.full(3, 0.3), lower, upper), lower, upper,
                   budget=4000, ftol=1e-14)
    np.testing.assert_allclose(res.x, [1.0, 0.2, -1.0], atol=X_TOL)


@pytest.mark.parametrize("n", [2, 4])
def test_finds_minimum_of_rosenbrock(n):
    lower, upper = box(n)
    res = minimize(rosenbrock, initial_simplex(np.full(n, -0.5), np.full(n, 0.5), lower, upper), lower, upper,
                   budget=20000, ftol=1e-16)
    np.testing.assert_allclose(res.x, np.ones(n), atol=1e-3)
    assert res.fun < 1e-8


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 150), st.integers(2, 6), st.integers(0, 1000))
def test_never_outside_bounds_and_stops_exactly_at_budget(budget, n, seed):
    rng = np.random.default_rng(seed)
    lower, upper = -rng.uniform(0.1, 1.0, n), rng.uniform(0.1, 1.0, n)
    # a minimum far outside the box keeps pushing trial points against the bounds
    target = rng.uniform(-5, 5, n)
    cost = Recorder(lambda x: float(np.sum((x - target) ** 2) + 0.1 * np.sin(5 * x).sum()))
    start = rng.uniform(lower, upper)
    res = minimize(cost, initial_simplex(start, np.full(n, 2.0), lower, upper), lower, upper, budget=budget, ftol=0.0)
    pts = np.array(cost.points)
    assert len(pts) == res.evaluations <= budget
    # ftol 0: only the budget stops it, or a simplex collapsed onto a corner of the box
    assert res.evaluations == budget or (res.converged and np.ptp(res.values) == 0)
    assert np.all(pts >= lower) and np.all(pts <= upper)
    assert res.fun == min(cost.f(p) for p in pts)


@pytest.mark.parametrize("budget", [1, 2, 3, 4, 7, 10, 33, 100, 257])
def test_stops_exactly_at_its_budget_even_inside_a_shrink(budget):
    lower, upper = box(5)
    cost = Recorder(lambda x: float(np.sum(np.abs(x - 0.1)) + 0.3 * np.sin(9 * x).sum()))
    res = minimize(cost, initial_simplex(np.full(5, 0.5), np.full(5, 1.0), lower, upper), lower, upper,
                   budget=budget, ftol=0.0)
    assert len(cost.points) == res.evaluations == budget


@pytest.mark.parametrize("adaptive", [False, True])
def test_follows_the_textbook_twin_point_by_point(adaptive):
    n = 4
    lower, upper = box(n, -1.5, 1.5)
    simplex = initial_simplex(np.array([-1.0, 0.5, 0.3, -0.2]), np.full(n, 0.4), lower, upper)
    cost = Recorder(rosenbrock)
    minimize(cost, simplex, lower, upper, budget=400, ftol=1e-9, adaptive=adaptive)
    twin = naive_nelder_mead(rosenbrock, simplex, lower, upper, 400, 1e-9, tuple(coefficients(n, adaptive)))
    assert len(twin) == len(cost.points)
    np.testing.assert_array_equal(np.array(twin), np.array(cost.points))


def test_hand_off_returns_the_final_simplex_with_its_values():
    n = 3
    lower, upper = box(n)
    f = lambda x: float(np.sum((x - 0.3) ** 2))
    first = minimize(f, initial_simplex(np.zeros(n), np.full(n, 0.5), lower, upper), lower, upper, budget=40, ftol=0.0)
    assert first.simplex.shape == (n + 1, n)
    for v, value in zip(first.simplex, first.values):
        if np.isfinite(value):
            assert value == f(v)
    assert first.fun == np.min(first.values[np.isfinite(first.values)])
    # the final simplex is smaller than the initial one and continuing from it improves further
    assert np.ptp(first.simplex, axis=0).max() < 0.5
    second = minimize(f, first.simplex, lower, upper, budget=200, ftol=1e-12)
    assert second.fun <= first.fun
    np.testing.assert_allclose(second.x, 0.3, atol=1e-3)


def test_convergence_uses_the_relative_spread_of_values():
    lower, upper = box(2)
    f = lambda x: float(100.0 + np.sum(x ** 2))   # large constant: relative spread is small early
    loose = minimize(f, initial_simplex(np.ones(2), np.full(2, 0.1), lower, upper), lower, upper, budget=1000, ftol=1e-2)
    assert loose.converged and loose.evaluations == 3   # spread (100.4 - 102) / 101 < 1e-2 at once
    tight = minimize(f, initial_simplex(np.ones(2), np.full(2, 0.1), lower, upper), lower, upper, budget=1000, ftol=1e-12)
    assert tight.evaluations > 50


def test_initial_simplex_stays_inside_and_is_not_degenerate():
    lower, upper = np.array([0.0, 0.0]), np.array([1.0, 1.0])
    s = initial_simplex(np.array([1.0, 0.0]), np.array([0.3, 0.3]), lower, upper)
    np.testing.assert_allclose(s, [[1.0, 0.0], [0.7, 0.0], [1.0, 0.3]])
    assert abs(np.linalg.det(s[1:] - s[0])) > 0


@pytest.mark.parametrize("call, match", [
    (lambda: initial_simplex([0.0], [0.0], [-1.0], [1.0]), "steps"),
    (lambda: initial_simplex([0.0], [0.1], [1.0], [-1.0]), "lower bound"),
    (lambda: initial_simplex([np.nan], [0.1], [-1.0], [1.0]), "finite"),
    (lambda: minimize(rosenbrock, np.zeros((2, 2)), [-1, -1], [1, 1], budget=10), "shape"),
    (lambda: minimize(rosenbrock, np.zeros((3, 2)), [-1, -1], [1, 1], budget=-1), "budget"),
    (lambda: minimize(rosenbrock, np.zeros((3, 2)), [-1, -1], [1, 1], budget=10, ftol=-1), "ftol"),
    (lambda: minimize(lambda x: float("nan"), np.zeros((3, 2)), [-1, -1], [1, 1], budget=10), "NaN"),
    (lambda: minimize_cost(rosenbrock, np.zeros((3, 2)), [-1, -1], [1, 1], budget=10), "RegionCost"),
])
def test_bad_input_raises(call, match):
    with pytest.raises(ValueError, match=match):
        call()


#: The paper's two-class model: on a frame rendered by the model itself, the four-class default's
#: lower body and hair match exactly whatever the arms do, and eq. (1)'s product is then 0.
PAPER_MODEL = BodyModel.build(BodyDimensions().without_extensions(), resolution=6)


def test_compiled_cost_loop_equals_python_loop():
    model, camera = PAPER_MODEL, Camera.default(80, 60)
    q = neutral_pose()
    cost = RegionCost(render(q, model, camera).labels, model, camera)
    start = q.copy()
    start[9:16] += 0.2
    start = clamp_to_limits(start)
    simplex = initial_simplex(start, np.r_[np.full(3, 0.02), np.full(20, 0.1)], JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
    a = minimize_cost(cost, simplex, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], budget=150)
    b = minimize(cost, simplex, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], budget=150)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.simplex, b.simplex)
    assert a.evaluations == b.evaluations <= 150 and a.iterations == b.iterations
    assert a.fun < cost(start)


def test_compiled_loop_with_keypoints_equals_python_loop_on_the_sum():
    model, camera = PAPER_MODEL, Camera.default(80, 60)
    q = neutral_pose()
    rendered = render(q, model, camera)
    truth_uv = camera.project(model.joint_positions(q))
    keypoints = KeypointCost(truth_uv + 0.7, np.linspace(0.2, 1.0, 10), model, camera)
    start = q.copy()
    start[9:16] += 0.2
    start = clamp_to_limits(start)
    simplex = initial_simplex(start, np.r_[np.full(3, 0.02), np.full(20, 0.1)], JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
    for cost in (RegionCost(rendered.labels, model, camera),
                 EdgeCost(ndimage_distance(rendered.edges), model, camera)):
        a = minimize_cost(cost, simplex, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], budget=120,
                          keypoint_cost=keypoints, keypoint_weight=0.05)
        b = minimize(lambda x: cost(x) + 0.05 * keypoints(x), simplex, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1],
                     budget=120)
        np.testing.assert_array_equal(a.x, b.x)
        assert a.fun == b.fun and a.evaluations == b.evaluations
        plain = minimize_cost(cost, simplex, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], budget=120)
        zero = minimize_cost(cost, simplex, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], budget=120,
                             keypoint_cost=keypoints, keypoint_weight=0.0)
        np.testing.assert_array_equal(plain.x, zero.x)


def ndimage_distance(edges):
    from scipy import ndimage

    return ndimage.distance_transform_edt(~edges).astype(np.float32)
