"""Temporal decoding: the best path through each frame's hypotheses (Viterbi).

A trellis has, for frame ``t``, the unary costs ``unary[t]`` (shape ``(K_t,)``) of its
hypotheses and the transition costs ``transition[t]`` (shape ``(K_{t-1}, K_t)``) from the
previous frame's hypotheses (``transition[0]`` is unused). The best path minimises the sum of
the unaries of the hypotheses it visits and of the transitions between them. The tracker runs
the forward recursion frame by frame (:func:`viterbi_step`), which is also how its beam ranks
hypotheses, and reads decisions off the back-pointers (:func:`backtrack`) after a fixed lag or
at the end of the sequence.
"""
from __future__ import annotations

import numpy as np


def viterbi_step(previous_cost: np.ndarray, transition: np.ndarray, unary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One step of the forward recursion.

    Parameters
    ----------
    previous_cost : ndarray, shape (K_prev,)
        Cost of the best path ending at each hypothesis of the previous frame.
    transition : ndarray, shape (K_prev, K)
    unary : ndarray, shape (K,)

    Returns
    -------
    cost : ndarray, shape (K,)
        Cost of the best path ending at each hypothesis of this frame.
    back : ndarray of int64, shape (K,)
        The previous frame's hypothesis on that path (ties: the lowest index).
    """
    previous_cost, transition, unary = (np.asarray(a, dtype=np.float64) for a in (previous_cost, transition, unary))
    if transition.shape != (previous_cost.shape[0], unary.shape[0]):
        raise ValueError(f"transition must be ({previous_cost.shape[0]}, {unary.shape[0]}), got {transition.shape}")
    total = previous_cost[:, None] + transition
    back = np.argmin(total, axis=0)
    return unary + total[back, np.arange(unary.shape[0])], back


def backtrack(backs: list[np.ndarray], last: int) -> list[int]:
    """Hypothesis indices of a path, from its last frame's hypothesis back along the pointers.

    Parameters
    ----------
    backs : list of ndarray of int
        ``backs[i]`` maps frame ``i + 1``'s hypotheses to frame ``i``'s (so ``len(backs)`` is the
        number of frames minus one).
    last : int
        The path's hypothesis in the last frame.

    Returns
    -------
    list of int
        One index per frame, first frame first.
    """
    path = [int(last)]
    for back in reversed(backs):
        path.append(int(back[path[-1]]))
    return path[::-1]


def viterbi(unary: list[np.ndarray], transition: list[np.ndarray]) -> tuple[list[int], float]:
    """Best path through a whole trellis (see the module).

    Parameters
    ----------
    unary : list of ndarray, shapes (K_t,)
    transition : list of ndarray, shapes (K_{t-1}, K_t); ``transition[0]`` is ignored

    Returns
    -------
    path : list of int
        The chosen hypothesis of each frame.
    cost : float
        Its total cost.
    """
    if len(unary) == 0:
        raise ValueError("an empty trellis has no path")
    if len(transition) != len(unary):
        raise ValueError(f"need one transition array per frame, got {len(transition)} for {len(unary)} frames")
    cost = np.asarray(unary[0], dtype=np.float64)
    backs = []
    for t in range(1, len(unary)):
        cost, back = viterbi_step(cost, transition[t], unary[t])
        backs.append(back)
    last = int(np.argmin(cost))
    return backtrack(backs, last), float(cost[last])
