"""The Viterbi decoder against brute force over every path of small random trellises."""
import itertools

import numpy as np
import pytest

from mocap.track import backtrack, viterbi, viterbi_step


def brute_force(unary, transition):
    best, best_path = np.inf, None
    for path in itertools.product(*[range(len(u)) for u in unary]):
        cost = sum(unary[t][k] for t, k in enumerate(path))
        cost += sum(transition[t][path[t - 1], path[t]] for t in range(1, len(path)))
        if cost < best:
            best, best_path = cost, list(path)
    return best_path, best


@pytest.mark.parametrize("seed", range(25))
def test_viterbi_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 4, size=rng.integers(1, 6))
    unary = [rng.normal(size=k) for k in sizes]
    transition = [np.zeros((1, sizes[0]))] + [rng.exponential(size=(sizes[t - 1], sizes[t]))
                                              for t in range(1, len(sizes))]
    path, cost = viterbi(unary, transition)
    ref_path, ref_cost = brute_force(unary, transition)
    assert cost == pytest.approx(ref_cost, abs=1e-12)
    assert path == ref_path


def test_step_and_backtrack_compose_into_viterbi():
    rng = np.random.default_rng(7)
    unary = [rng.normal(size=3) for _ in range(6)]
    transition = [None] + [rng.exponential(size=(3, 3)) for _ in range(5)]
    cost, backs = unary[0], []
    for t in range(1, 6):
        cost, back = viterbi_step(cost, transition[t], unary[t])
        backs.append(back)
    assert backtrack(backs, int(np.argmin(cost))) == viterbi(unary, [np.zeros((1, 3))] + transition[1:])[0]


def test_bad_trellises_are_rejected():
    with pytest.raises(ValueError, match="empty"):
        viterbi([], [])
    with pytest.raises(ValueError, match="transition"):
        viterbi_step(np.zeros(2), np.zeros((3, 2)), np.zeros(2))
