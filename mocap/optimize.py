"""Bounded downhill simplex (Nelder–Mead) with an exact evaluation budget and simplex hand-off.

Why not ``scipy.optimize.minimize(method="Nelder-Mead")``: its ``maxfev`` is checked once per
iteration, so a shrink step can overrun the budget by up to n evaluations; its stopping test is
absolute (``xatol``/``fatol``), not the paper's relative spread of the simplex values; and its
Python loop adds about 13 µs per evaluation, a quarter of a 50 µs cost evaluation. Here the
algorithm is an ask/tell state machine in compiled kernels, driven either by a compiled loop
that calls the mocap costs directly (no Python per evaluation) or by a Python loop for any
callable; both run the very same steps.

The method (Nelder & Mead 1965, as in Numerical Recipes' ``amoeba``): reflection, expansion,
outside/inside contraction, shrink. Coefficients are the standard (1, 2, 1/2, 1/2) or the
dimension-adaptive ones of Gao & Han (2012). Every trial point is clipped into the bounds
before it is evaluated, so the cost is never evaluated outside them. Convergence is the
paper's test on the spread of the simplex values:
``2 |f_high - f_low| <= ftol * (|f_high| + |f_low| + 1e-12)``.
The budget counts cost evaluations, including the n + 1 of the initial simplex; the run stops
exactly when it is spent, even inside a shrink (vertices not yet re-evaluated then carry
``inf``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from mocap._numba import jit
from mocap.body.pose import N_PARAMETERS

# phases of the state machine
_INIT, _REFLECT, _EXPAND, _CONTRACT_OUT, _CONTRACT_IN, _SHRINK, _DONE = 0, 1, 2, 3, 4, 5, 6
# integer state slots
_PHASE, _K, _HIGH, _SECOND, _LOW, _ITER, _EVALS, _CONVERGED = range(8)
# float state slots
_FR, _BEST, _FTOL = range(3)
# rows of the work array
_CENTROID, _XR, _TRIAL, _BEST_X = range(4)


@jit
def _clip(x, lower, upper):
    for i in range(x.shape[0]):
        x[i] = min(max(x[i], lower[i]), upper[i])


@jit
def _set_trial(work, base, direction_from, scale, lower, upper):
    """trial = clip(base + scale * (base - direction_from))."""
    for i in range(work.shape[1]):
        work[_TRIAL, i] = base[i] + scale * (base[i] - direction_from[i])
    _clip(work[_TRIAL], lower, upper)


@jit
def _begin_iteration(simplex, values, lower, upper, coef, work, ist, fst):
    n = simplex.shape[1]
    low, high = 0, 0
    for i in range(n + 1):
        if values[i] < values[low]:
            low = i
        if values[i] > values[high]:
            high = i
    second = low
    for i in range(n + 1):
        if i != high and values[i] >= values[second]:
            second = i
    ist[_LOW], ist[_HIGH], ist[_SECOND] = low, high, second
    fl, fh = values[low], values[high]
    if 2.0 * abs(fh - fl) <= fst[_FTOL] * (abs(fh) + abs(fl) + 1e-12):
        ist[_PHASE] = _DONE
        ist[_CONVERGED] = 1
        return
    for j in range(n):
        s = 0.0
        for i in range(n + 1):
            if i != high:
                s += simplex[i, j]
        work[_CENTROID, j] = s / n
    _set_trial(work, work[_CENTROID], simplex[high], coef[0], lower, upper)
    ist[_PHASE] = _REFLECT


@jit
def _replace_high(simplex, values, ist, point, value):
    h = ist[_HIGH]
    simplex[h, :] = point
    values[h] = value
    ist[_ITER] += 1


@jit
def _start_shrink(simplex, values, lower, upper, coef, work, ist):
    n = simplex.shape[1]
    low = ist[_LOW]
    for i in range(n + 1):
        if i != low:
            for j in range(n):
                simplex[i, j] = simplex[low, j] + coef[3] * (simplex[i, j] - simplex[low, j])
            _clip(simplex[i], lower, upper)
            values[i] = np.inf
    ist[_PHASE] = _SHRINK
    ist[_K] = 1 if low == 0 else 0
    work[_TRIAL, :] = simplex[ist[_K]]


@jit
def _nm_tell(simplex, values, lower, upper, coef, work, ist, fst, f):
    """Consume the cost ``f`` of the current trial point and prepare the next one."""
    n = simplex.shape[1]
    ist[_EVALS] += 1
    if f < fst[_BEST]:
        fst[_BEST] = f
        work[_BEST_X, :] = work[_TRIAL]
    phase = ist[_PHASE]
    if phase == _INIT:
        k = ist[_K]
        values[k] = f
        if k < n:
            ist[_K] = k + 1
            work[_TRIAL, :] = simplex[k + 1]
        else:
            _begin_iteration(simplex, values, lower, upper, coef, work, ist, fst)
    elif phase == _REFLECT:
        fst[_FR] = f
        work[_XR, :] = work[_TRIAL]
        if f < values[ist[_LOW]]:
            # expansion: c + beta * (xr - c) = c + alpha * beta * (c - x_high)
            _set_trial(work, work[_CENTROID], simplex[ist[_HIGH]], coef[0] * coef[1], lower, upper)
            ist[_PHASE] = _EXPAND
        elif f < values[ist[_SECOND]]:
            _replace_high(simplex, values, ist, work[_XR], f)
            _begin_iteration(simplex, values, lower, upper, coef, work, ist, fst)
        elif f < values[ist[_HIGH]]:
            # outside contraction: c + gamma * (xr - c)
            _set_trial(work, work[_CENTROID], simplex[ist[_HIGH]], coef[0] * coef[2], lower, upper)
            ist[_PHASE] = _CONTRACT_OUT
        else:
            # inside contraction: c - gamma * (c - x_high)
            _set_trial(work, work[_CENTROID], simplex[ist[_HIGH]], -coef[2], lower, upper)
            ist[_PHASE] = _CONTRACT_IN
    elif phase == _EXPAND:
        if f < fst[_FR]:
            _replace_high(simplex, values, ist, work[_TRIAL], f)
        else:
            _replace_high(simplex, values, ist, work[_XR], fst[_FR])
        _begin_iteration(simplex, values, lower, upper, coef, work, ist, fst)
    elif phase == _CONTRACT_OUT or phase == _CONTRACT_IN:
        accept = f <= fst[_FR] if phase == _CONTRACT_OUT else f < values[ist[_HIGH]]
        if accept:
            _replace_high(simplex, values, ist, work[_TRIAL], f)
            _begin_iteration(simplex, values, lower, upper, coef, work, ist, fst)
        else:
            _start_shrink(simplex, values, lower, upper, coef, work, ist)
    elif phase == _SHRINK:
        k = ist[_K]
        values[k] = f
        k += 1
        if k == ist[_LOW]:
            k += 1
        if k <= n:
            ist[_K] = k
            work[_TRIAL, :] = simplex[k]
        else:
            ist[_ITER] += 1
            _begin_iteration(simplex, values, lower, upper, coef, work, ist, fst)


@jit
def _nm_run_costs(kind, region_args, edge_args, keypoint_args, keypoint_weight, simplex, values, lower, upper, coef,
                  work, ist, fst, budget):
    """Drive the state machine with a mocap cost: kind 0 region (eq. 1), 1 edge (eq. 2), plus
    ``keypoint_weight`` times the keypoint distance when that weight is positive."""
    while ist[_EVALS] < budget and ist[_PHASE] != _DONE:
        if kind == 0:
            f = region_cost_kernel(work[_TRIAL], region_args)
        else:
            f = edge_cost_kernel(work[_TRIAL], edge_args)
        if keypoint_weight > 0.0:
            f += keypoint_weight * keypoint_cost_kernel(work[_TRIAL], keypoint_args)
        _nm_tell(simplex, values, lower, upper, coef, work, ist, fst, f)


@jit
def _gn_run_edge(args, region_args, region_weight, q, lower, upper, scale, budget, lam0, best, info):
    """Levenberg–Marquardt on the contour's mean squared distance (see :func:`minimize_edge_gauss_newton`).

    ``q`` (23,) is the start (clipped into the bounds, then the current point); ``best`` (23,)
    receives the evaluated point of lowest score; ``info`` (4,) float: eq. (2) at the best,
    at the start, evaluations, accepted steps. With ``region_weight`` > 0 every point also
    renders F (``region_args``, one more evaluation) and the score is eq. (2) +
    ``region_weight`` F for the choice of the best and for accepting a step."""
    n = q.shape[0]
    grad = np.zeros(n)
    rhs, normal = np.zeros(n), np.zeros((n, n))
    t_rhs, t_normal = np.zeros(n), np.zeros((n, n))
    trial = np.empty(n)
    a = np.empty((n, n))
    for k in range(n):
        q[k] = min(max(q[k], lower[k]), upper[k])
    value, _, square, samples = edge_normal_equations_kernel(q, args, grad, rhs, normal)
    evaluations, accepted = 1, 0
    score = value
    if region_weight > 0.0:
        score += region_weight * region_cost_kernel(q, region_args)
        evaluations += 1
    best[:] = q
    best_value, best_score = value, score
    info[1] = value
    lam = lam0
    per_point = 2 if region_weight > 0.0 else 1
    while evaluations + per_point <= budget and samples > 0 and lam < 1e10:
        top = 0.0
        for k in range(n):
            top = max(top, normal[k, k])
        for k in range(n):
            for j in range(n):
                a[k, j] = normal[k, j]
            a[k, k] += lam * normal[k, k] + 1e-9 * top + 1e-12
        delta = np.linalg.solve(a, -rhs)
        # a trust region of one simplex step per parameter, then the bounds
        shrink = 1.0
        for k in range(n):
            shrink = max(shrink, abs(delta[k]) / scale[k])
        moved = 0.0
        for k in range(n):
            trial[k] = min(max(q[k] + delta[k] / shrink, lower[k]), upper[k])
            moved = max(moved, abs(trial[k] - q[k]) / scale[k])
        if moved < 1e-6:
            break                                       # converged (or pinned by the bounds)
        t_value, _, t_square, t_samples = edge_normal_equations_kernel(trial, args, grad, t_rhs, t_normal)
        evaluations += 1
        t_score = t_value
        if region_weight > 0.0:
            t_score += region_weight * region_cost_kernel(trial, region_args)
            evaluations += 1
        if t_score < best_score:
            best_value, best_score = t_value, t_score
            best[:] = trial
        if t_samples > 0 and (t_square < square if region_weight == 0.0 else t_score < score):
            q[:] = trial
            square, samples, score = t_square, t_samples, t_score
            rhs[:] = t_rhs
            normal[:, :] = t_normal
            lam = max(lam * 0.3, 1e-7)
            accepted += 1
        else:
            lam *= 10.0
    info[0], info[2], info[3] = best_value, evaluations, accepted


from mocap.cost import (EdgeKernelArgs, KeypointKernelArgs, RegionKernelArgs,  # noqa: E402  (compiled into the loops above)
                        edge_cost_kernel, edge_normal_equations_kernel, keypoint_cost_kernel, region_cost_kernel)


# ----------------------------------------------------------------------------- public API
@dataclass(frozen=True)
class SimplexResult:
    """Outcome of one bounded downhill-simplex run.

    Attributes
    ----------
    x : ndarray, shape (n,), float64
        Best point evaluated (same units as the parameters).
    fun : float
        Its cost.
    simplex : ndarray, shape (n + 1, n), float64
        Final simplex (hand it to the next step as its initial simplex).
    values : ndarray, shape (n + 1,), float64
        Costs of the simplex vertices (``inf`` for vertices a budget stop left unevaluated).
    evaluations : int
        Cost evaluations used (never more than the budget).
    iterations : int
        Completed Nelder–Mead iterations.
    converged : bool
        Whether the spread test stopped the run (rather than the budget).
    """

    x: np.ndarray
    fun: float
    simplex: np.ndarray
    values: np.ndarray
    evaluations: int
    iterations: int
    converged: bool


def coefficients(n: int, adaptive: bool = False) -> np.ndarray:
    """Reflection, expansion, contraction and shrink coefficients for dimension ``n``.

    Standard: (1, 2, 1/2, 1/2). Adaptive (Gao & Han 2012): (1, 1 + 2/n, 3/4 - 1/(2n), 1 - 1/n).
    """
    if adaptive:
        return np.array([1.0, 1.0 + 2.0 / n, 0.75 - 0.5 / n, 1.0 - 1.0 / n])
    return np.array([1.0, 2.0, 0.5, 0.5])


def initial_simplex(x0, steps, lower, upper) -> np.ndarray:
    """Simplex of x0 and, for each parameter i, x0 moved by ``steps[i]`` along axis i.

    The move goes towards whichever bound leaves room for it (a full step if possible), so
    every vertex lies inside the bounds and the simplex is not degenerate.

    Parameters
    ----------
    x0, steps, lower, upper : array_like, shape (n,)
        ``steps`` > 0, in parameter units.

    Returns
    -------
    ndarray, shape (n + 1, n), float64
    """
    x0, steps, lower, upper = (np.asarray(a, dtype=np.float64) for a in (x0, steps, lower, upper))
    _check_bounds(x0, lower, upper)
    if steps.shape != x0.shape or not np.all(np.isfinite(steps)) or np.any(steps <= 0):
        raise ValueError("steps must be finite, positive and one per parameter")
    x0 = np.clip(x0, lower, upper)
    simplex = np.tile(x0, (len(x0) + 1, 1))
    for i in range(len(x0)):
        up, down = upper[i] - x0[i], x0[i] - lower[i]
        simplex[i + 1, i] += min(steps[i], up) if up >= down else -min(steps[i], down)
    return simplex


def _check_bounds(x0, lower, upper) -> None:
    if x0.ndim != 1 or lower.shape != x0.shape or upper.shape != x0.shape:
        raise ValueError(f"x0, lower and upper must be 1-D of one length, got {x0.shape}, {lower.shape}, {upper.shape}")
    if not (np.all(np.isfinite(x0)) and np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
        raise ValueError("x0 and bounds must be finite")
    if np.any(lower >= upper):
        raise ValueError("every lower bound must be below its upper bound")


class _State:
    """Arrays of one run of the state machine."""

    def __init__(self, simplex, lower, upper, ftol, adaptive, values=None):
        simplex = np.array(simplex, dtype=np.float64)
        n = simplex.shape[1] if simplex.ndim == 2 else -1
        if simplex.ndim != 2 or simplex.shape[0] != n + 1 or n < 1:
            raise ValueError(f"simplex must have shape (n + 1, n), got {simplex.shape}")
        lower, upper = np.asarray(lower, np.float64), np.asarray(upper, np.float64)
        _check_bounds(simplex[0], lower, upper)
        if not np.all(np.isfinite(simplex)):
            raise ValueError("simplex must be finite")
        if not (np.isfinite(ftol) and ftol >= 0):
            raise ValueError(f"ftol must be finite and non-negative, got {ftol}")
        self.simplex = np.clip(simplex, lower, upper)
        self.values = np.full(n + 1, np.inf)
        self.lower, self.upper = lower, upper
        self.coef = coefficients(n, adaptive)
        self.work = np.zeros((4, n))
        self.work[_TRIAL] = self.simplex[0]
        self.work[_BEST_X] = self.simplex[0]
        self.ist = np.zeros(8, np.int64)
        self.fst = np.array([np.inf, np.inf, ftol])

    def args(self):
        return (self.simplex, self.values, self.lower, self.upper, self.coef, self.work, self.ist, self.fst)

    def result(self) -> SimplexResult:
        return SimplexResult(self.work[_BEST_X].copy(), float(self.fst[_BEST]), self.simplex.copy(),
                             self.values.copy(), int(self.ist[_EVALS]), int(self.ist[_ITER]),
                             bool(self.ist[_CONVERGED]))


def _check_budget(budget: int) -> int:
    if isinstance(budget, bool) or not isinstance(budget, (int, np.integer)) or budget < 0:
        raise ValueError(f"the evaluation budget must be a non-negative integer, got {budget!r}")
    return int(budget)


def minimize(fun: Callable[[np.ndarray], float], simplex, lower, upper, *, budget: int,
             ftol: float = 1e-3, adaptive: bool = False) -> SimplexResult:
    """Minimise a Python callable by bounded downhill simplex.

    Parameters
    ----------
    fun : callable
        ``fun(x) -> float`` with x an (n,) float64 array (do not keep it: it is reused).
    simplex : array_like, shape (n + 1, n)
        Initial simplex (see :func:`initial_simplex`, or a previous result's ``simplex``).
    lower, upper : array_like, shape (n,)
        Bounds; no point outside them is ever evaluated.
    budget : int
        Most cost evaluations, including the n + 1 of the initial simplex.
    ftol : float
        Relative spread of the simplex values at which to stop (the paper's test).
    adaptive : bool
        Dimension-adaptive coefficients (Gao & Han 2012) instead of the standard ones.

    Returns
    -------
    SimplexResult
    """
    budget = _check_budget(budget)
    st = _State(simplex, lower, upper, ftol, adaptive)
    args = st.args()
    x = np.empty(st.simplex.shape[1])
    while st.ist[_EVALS] < budget and st.ist[_PHASE] != _DONE:
        x[:] = st.work[_TRIAL]
        f = float(fun(x))
        if np.isnan(f):
            raise ValueError(f"the cost returned NaN at {x}")
        _nm_tell(*args, f)
    return st.result()


def minimize_cost(cost, simplex, lower, upper, *, budget: int, ftol: float = 1e-3, keypoint_cost=None,
                  keypoint_weight: float = 0.0) -> SimplexResult:
    """As :func:`minimize` for a :class:`~mocap.cost.RegionCost` or :class:`~mocap.cost.EdgeCost`
    over the whole pose vector, with the loop compiled (no Python per evaluation).

    With a :class:`~mocap.cost.KeypointCost` and a positive ``keypoint_weight`` the function
    minimised is ``cost(q) + keypoint_weight * keypoint_cost(q)``.

    Parameters
    ----------
    cost : RegionCost or EdgeCost
    simplex : ndarray, shape (24, 23)
        Initial simplex (metres and radians).
    lower, upper : ndarray, shape (23,)
        Bounds (the joint limits).
    budget : int
        Cost evaluations at most.
    ftol : float
        Stop when the relative spread of the simplex values falls below it.
    keypoint_cost : KeypointCost, optional
    keypoint_weight : float
        Units of ``cost`` per pixel of keypoint distance (>= 0; 0: the term is off).
    """
    from mocap.cost import EdgeCost, KeypointCost, RegionCost

    budget = _check_budget(budget)
    st = _State(simplex, lower, upper, ftol, False)
    if isinstance(cost, RegionCost):
        kind, region_args, edge_args = 0, cost.kernel_args(), _DummyArgs.edge(cost)
    elif isinstance(cost, EdgeCost):
        kind, region_args, edge_args = 1, _DummyArgs.region(cost), cost.kernel_args()
    else:
        raise ValueError(f"minimize_cost takes a RegionCost or EdgeCost, got {type(cost).__name__}; "
                         "use minimize() for other callables")
    if st.simplex.shape[1] != N_PARAMETERS:
        raise ValueError(f"mocap costs take {N_PARAMETERS} parameters: the simplex has {st.simplex.shape[1]} columns")
    if not (np.isfinite(keypoint_weight) and keypoint_weight >= 0):
        raise ValueError(f"keypoint_weight must be finite and non-negative, got {keypoint_weight!r}")
    if keypoint_cost is None or (isinstance(keypoint_cost, KeypointCost) and keypoint_cost.empty):
        keypoint_args, keypoint_weight = _DummyArgs.keypoint(cost), 0.0
    elif not isinstance(keypoint_cost, KeypointCost):
        raise ValueError(f"keypoint_cost must be a KeypointCost, got {type(keypoint_cost).__name__}")
    else:
        keypoint_args = keypoint_cost.kernel_args()
    _nm_run_costs(kind, region_args, edge_args, keypoint_args, float(keypoint_weight), *st.args(), budget)
    return st.result()


@dataclass(frozen=True)
class GaussNewtonResult:
    """Outcome of :func:`minimize_edge_gauss_newton`.

    Attributes
    ----------
    x : ndarray, shape (23,), float64
        The evaluated pose of lowest eq. (2), the start included (metres, radians).
    fun : float, pixels
        Its mean edge distance (eq. 2).
    start_fun : float, pixels
        Eq. (2) at the start.
    evaluations : int
        Renders (each gives the value, the gradient and the normal equations; with a region
        weight, a second render gives F), the start's included.
    accepted : int
        Steps that lowered the contour's mean squared distance.
    """

    x: np.ndarray
    fun: float
    start_fun: float
    evaluations: int
    accepted: int


#: Initial Levenberg–Marquardt damping of :func:`minimize_edge_gauss_newton` (relative to the
#: normal matrix's diagonal).
GAUSS_NEWTON_DAMPING = 1e-2


def minimize_edge_gauss_newton(cost, x0, lower, upper, *, budget: int, scale, region_cost=None,
                               region_weight: float = 0.0) -> GaussNewtonResult:
    """Bounded Gauss–Newton (Levenberg–Marquardt) refinement of eq. (2), compiled.

    The residuals are the distance map at the visible occluding-contour samples of
    :class:`~mocap.cost.EdgeGradient` (r_s, pixels) and their Jacobian the analytic one; each
    iteration renders once (:func:`~mocap.cost.edge_normal_equations_kernel`) and solves
    ``(J^T J + lam diag(J^T J)) delta = -J^T r``. The step is shortened so that no parameter
    moves by more than its ``scale``, then clipped into the bounds; it is kept when it lowers
    the mean squared contour distance (damping / 0.3), else the damping grows tenfold. Every
    evaluated point is scored by eq. (2) itself and the lowest is returned. With a
    ``region_cost`` and a positive ``region_weight`` every point also renders F (one more
    evaluation) and the score, for accepting a step and for the result, is eq. (2) +
    ``region_weight`` F.

    Parameters
    ----------
    cost : EdgeCost
    x0 : array_like, shape (23,)
        Start (metres, radians); clipped into the bounds.
    lower, upper : array_like, shape (23,)
        Bounds (the joint limits).
    budget : int
        Renders at most (>= 1; the start is always evaluated, so with a region weight a budget
        of 1 still takes its 2 renders).
    scale : array_like, shape (23,)
        Largest move per step of each parameter (> 0; metres, radians).
    region_cost : RegionCost, optional
    region_weight : float
        Pixels of eq. (2) per unit of F in the score (0: eq. 2 alone).

    Returns
    -------
    GaussNewtonResult
    """
    from mocap.cost import EdgeCost

    if not isinstance(cost, EdgeCost):
        raise ValueError(f"minimize_edge_gauss_newton takes an EdgeCost, got {type(cost).__name__}")
    budget = _check_budget(budget)
    if budget < 1:
        raise ValueError("the Gauss-Newton budget must be at least 1 render")
    x0, lower, upper, scale = (np.array(a, dtype=np.float64) for a in (x0, lower, upper, scale))
    _check_bounds(x0, lower, upper)
    if x0.shape != (N_PARAMETERS,):
        raise ValueError(f"mocap costs take {N_PARAMETERS} parameters, got {x0.shape}")
    if scale.shape != x0.shape or not np.all(np.isfinite(scale)) or np.any(scale <= 0):
        raise ValueError("scale must be finite, positive and one per parameter")
    best, info = np.empty(N_PARAMETERS), np.zeros(4)
    if region_cost is None or region_weight == 0.0:
        region_args, region_weight = _DummyArgs.region(cost), 0.0
    else:
        from mocap.cost import RegionCost
        if not isinstance(region_cost, RegionCost) or not (np.isfinite(region_weight) and region_weight > 0):
            raise ValueError("region_cost must be a RegionCost and region_weight finite and positive")
        region_args = region_cost.kernel_args()
    _gn_run_edge(cost.gradient_args(), region_args, float(region_weight), x0, lower, upper, scale, budget,
                 GAUSS_NEWTON_DAMPING, best, info)
    return GaussNewtonResult(best, float(info[0]), float(info[1]), int(info[2]), int(info[3]))


class _DummyArgs:
    """Type-correct placeholder arguments for the cost kind a compiled run does not use."""

    @staticmethod
    def region(cost) -> RegionKernelArgs:
        args = cost.kernel_args()
        return RegionKernelArgs(args.scene, args.buffers, np.zeros(0, np.uint8), np.zeros(1, np.int64), 0,
                                np.zeros(1, np.int64), np.zeros(1, np.int64), True)

    @staticmethod
    def keypoint(cost) -> KeypointKernelArgs:
        """No keypoint (the loop never evaluates it: its weight is 0); arrays of the real one's types."""
        scene = cost.kernel_args().scene
        return KeypointKernelArgs(scene.offsets, np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 2)),
                                  np.zeros(0), scene.camera, np.zeros((len(scene.offsets), 3, 4)), 0.0, np.zeros(0),
                                  False, np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros(0, np.int64))

    @staticmethod
    def edge(cost) -> EdgeKernelArgs:
        args = cost.kernel_args()
        return EdgeKernelArgs(args.scene, args.buffers, np.zeros(0, np.float32), np.zeros(0, np.bool_), 0.0, 0.0)
