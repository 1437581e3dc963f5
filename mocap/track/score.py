"""The tracker's score: its terms in one table, their weights, and the motion term.

Every candidate of a frame gets a **unary score**: the sum over the unary terms of
:data:`TERMS` of each term's weight times its value, a term whose value is NaN (it does not
apply: the keypoint distance on a frame without keypoints, the prior with ``prior_weight`` 0,
the lifter's energy on a frame not lifted) left out (:func:`weighted_sum`). Between consecutive
frames the **motion term** (:func:`transition_term`: the joints' :func:`motion_term` plus the
heading's :func:`turn_term`) links every hypothesis of the previous frame to every candidate of
this one; ``motion_weight`` multiplies it in the decoder. F's weight is the
constant :data:`REGION_WEIGHT`, the score's unit; every other weight is a field of
:class:`~mocap.track.config.TrackerConfig`, named in the table, and the same weights score every
frame, with keypoints or without.

The table is the one place the terms are spelled: :class:`ScoredCandidate` (what
:attr:`mocap.track.Tracker.scored` holds) has one attribute per term, ``TrackerConfig``
validates the weight fields it names, and ``experiments.fit_score`` records and fits the
weights in its column order.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

#: Score of a candidate per unit of F (the region residual): the score's unit.
REGION_WEIGHT = 50.0
#: Motion term between hypotheses of consecutive frames: half the mean squared joint
#: displacement over ``MOTION_SIGMA_M**2`` (metres)...
MOTION_SIGMA_M = 0.05
#: ...at most this much (a truncated quadratic): a jump between branches or to a re-acquired arm
#: costs a fixed price that a clearly better fit pays.
MOTION_CAP = 8.0
#: Turn term between hypotheses of consecutive frames: half the squared change of the chest's
#: heading (on the circle) over ``TURN_SIGMA_DEG**2`` (degrees)...
TURN_SIGMA_DEG = 45.0
#: ...at most this much. A body turned round between two frames (a front/back switch, which the
#: keypoints' labellings cannot tell apart) pays 8 besides the joints' motion term (at most
#: :data:`MOTION_CAP`, what an arm's jump pays); a 30° step pays 0.22 (docs/research-log.md,
#: 2026-11-29).
TURN_CAP = 40.0
#: The labelling term's price of reading the keypoints swapped on a frame whose detector shows the
#: front (:meth:`mocap.io.keypoints.Keypoints.shows_front`), by how square-on the shoulders are
#: seen: the claim's shoulder distance over the body's own seen square-on at its depth
#: (:func:`front_price`). Lower edges of the bins and the ln odds (add-one) that MediaPipe's
#: front claim is right in each, counted on the benchmark's seeds 0-4 against the true chest
#: heading (5,584 claims, 116 wrong; docs/research-log.md, 2026-11-30): near profile a claim is
#: worth a nat, squarely seen six. A body turned round with the labels read swapped projects as
#: the right one does: this is what tells them apart.
FRONT_SWAP_NATS_BY_WIDTH: tuple[tuple[float, float], ...] = (
    (0.0, 1.18), (0.4, 1.39), (0.55, 2.61), (0.7, 3.17), (0.8, 3.69), (0.9, 6.11), (1.0, 6.30))


def front_price(width_ratio: float) -> float:
    """The price (nats) of reading swapped a front claim whose shoulders are seen ``width_ratio``
    of their square-on width (:data:`FRONT_SWAP_NATS_BY_WIDTH`; NaN or negative: the lowest)."""
    price = FRONT_SWAP_NATS_BY_WIDTH[0][1]
    for edge, nats in FRONT_SWAP_NATS_BY_WIDTH:
        if width_ratio >= edge:
            price = nats
    return price


@dataclass(frozen=True)
class Term:
    """One term of the score.

    Attributes
    ----------
    name : str
        Its name: :class:`ScoredCandidate`'s attribute and ``experiments.fit_score``'s column.
    weight_field : str or None
        The :class:`~mocap.track.config.TrackerConfig` field of its weight (None: the constant
        :data:`REGION_WEIGHT`).
    unit : str
        The unit of its value.
    pairwise : bool
        Between consecutive frames' hypotheses (the motion term), not of one candidate.
    beyond_paper : bool
        Added by this toolkit: :meth:`~mocap.track.config.TrackerConfig.paper` sets its weight to
        0 (the motion term is kept: with the paper's single hypothesis it changes nothing).
    """

    name: str
    weight_field: str | None
    unit: str
    pairwise: bool = False
    beyond_paper: bool = False


#: The score's terms, in the order of every weight vector and feature column.
TERMS: tuple[Term, ...] = (
    Term("region", None, "F, in [0, 1]"),                   # the region residual (eq. 1)
    Term("edge", "edge_weight", "pixels"),                  # mean edge distance (eq. 2)
    Term("keypoint", "keypoint_weight", "pixels", beyond_paper=True),     # keypoint distance D_k
    Term("prior", "prior_weight", "nats", beyond_paper=True),             # the pose prior's energy
    Term("lifter", "lifter_weight", "nats", beyond_paper=True),           # the lifter's energy at the joints
    Term("labelling", "labelling_weight", "nats", beyond_paper=True),     # the detector's front against the swap
    Term("motion", "motion_weight", "truncated quadratic", pairwise=True),
)
#: The terms' names, :data:`TERMS` order.
TERM_NAMES: tuple[str, ...] = tuple(t.name for t in TERMS)
#: The unary terms (all but the motion term), a prefix of :data:`TERMS`.
UNARY_TERMS: tuple[Term, ...] = tuple(t for t in TERMS if not t.pairwise)
#: The config's fields of the weights, :data:`TERMS` order (F's constant left out).
WEIGHT_FIELDS: tuple[str, ...] = tuple(t.weight_field for t in TERMS if t.weight_field is not None)
#: Column of the motion term.
MOTION = TERM_NAMES.index("motion")
#: The config's fields of the weights the paper's method sets to 0 (the terms beyond the paper).
BEYOND_PAPER_FIELDS: tuple[str, ...] = tuple(t.weight_field for t in TERMS if t.beyond_paper)

if TERMS[: len(UNARY_TERMS)] != UNARY_TERMS:          # the unary terms' vector is a prefix of the weights'
    raise ImportError("the motion term must come after every unary term")


def weights(config) -> np.ndarray:
    """The score's weights of a :class:`~mocap.track.config.TrackerConfig` (any object with the
    :data:`WEIGHT_FIELDS`), :data:`TERMS` order, shape (len(TERMS),), float64: F's is
    :data:`REGION_WEIGHT`."""
    return np.array([REGION_WEIGHT if t.weight_field is None else float(getattr(config, t.weight_field))
                     for t in TERMS], dtype=np.float64)


def with_weights(config, w):
    """``config`` (a frozen dataclass, e.g. :class:`~mocap.track.config.TrackerConfig`) with its
    weight fields set from ``w`` (shape (len(TERMS),), :data:`TERMS` order; F's is not a field
    and is ignored)."""
    w = np.asarray(w, dtype=np.float64)
    if w.shape != (len(TERMS),):
        raise ValueError(f"weights must have shape ({len(TERMS)},), got {w.shape}")
    return dataclasses.replace(config, **{t.weight_field: float(w[j]) for j, t in enumerate(TERMS)
                                          if t.weight_field is not None})


def weighted_sum(values, w):
    """The score of terms' values: ``sum_j w[j] * values[..., j]``, a NaN value left out (it does
    not apply), accumulated term by term in :data:`TERMS` order (so one candidate's score is the
    same float whether computed alone or in an array).

    Parameters
    ----------
    values : array_like, shape (..., n), the terms' values before their weights
        ``n`` the leading terms of :data:`TERMS` (the unary ones: ``len(UNARY_TERMS)``; all).
    w : array_like, shape (n,) or at least (n,)
        Weights, :data:`TERMS` order; only the first ``n`` are read.

    Returns
    -------
    float or ndarray of shape (...), float64
    """
    x = np.asarray(values, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    if x.ndim == 0 or x.shape[-1] > len(w):
        raise ValueError(f"values must end in at most {len(w)} terms, got shape {x.shape}")
    if x.ndim == 1:                                       # one candidate: plain floats (as fast as spelt out)
        total = 0.0
        for value, weight in zip(x.tolist(), w.tolist()):
            if not math.isnan(value):
                total += weight * value
        return total
    total = np.zeros(x.shape[:-1])
    for j in range(x.shape[-1]):
        total = total + np.where(np.isnan(x[..., j]), 0.0, w[j] * x[..., j])
    return total


def labelling_term(front: float | None, swapped: bool) -> float:
    """A candidate's labelling term before its weight (nats): the frame's front price ``front``
    (:func:`front_price`; 0 where the detector does not show the front) when it reads the
    keypoints swapped, else 0; NaN on a frame without keypoints (``front`` None)."""
    if front is None:
        return math.nan
    return front if swapped else 0.0


def turn_term(previous, current) -> np.ndarray:
    """The turn term between every pair (previous, current) of chest headings: half the squared
    change on the circle over ``TURN_SIGMA_DEG**2``, at most :data:`TURN_CAP`.

    Parameters
    ----------
    previous : array_like, shape (P,), radians
    current : array_like, shape (C,), radians

    Returns
    -------
    ndarray, shape (P, C), float64
    """
    a = np.asarray(previous, dtype=np.float64)
    b = np.asarray(current, dtype=np.float64)
    if a.ndim != 1 or b.ndim != 1:
        raise ValueError(f"need headings of shape (P,) and (C,), got {a.shape} and {b.shape}")
    change = np.angle(np.exp(1j * (b[None] - a[:, None])))
    return np.minimum(0.5 * (change / np.radians(TURN_SIGMA_DEG)) ** 2, TURN_CAP)


def transition_term(previous_joints, current_joints, previous_headings, current_headings) -> np.ndarray:
    """The motion term of the decoder between every pair (previous, current) of hypotheses before
    ``motion_weight``: the joints' :func:`motion_term` plus the chest headings' :func:`turn_term`.

    Parameters
    ----------
    previous_joints : array_like, shape (P, J, 3), metres
    current_joints : array_like, shape (C, J, 3), metres
    previous_headings : array_like, shape (P,), radians
    current_headings : array_like, shape (C,), radians

    Returns
    -------
    ndarray, shape (P, C), float64
    """
    return motion_term(previous_joints, current_joints) + turn_term(previous_headings, current_headings)


def motion_term(previous, current, cap: float = MOTION_CAP) -> np.ndarray:
    """The motion term between every pair (previous, current) of joint sets before
    ``motion_weight``: half the mean squared joint displacement over ``MOTION_SIGMA_M**2``, at
    most ``cap``.

    Parameters
    ----------
    previous : array_like, shape (P, J, 3), metres
    current : array_like, shape (C, J, 3), metres
    cap : float
        The truncation (default :data:`MOTION_CAP`).

    Returns
    -------
    ndarray, shape (P, C), float64
    """
    a = np.asarray(previous, dtype=np.float64)
    b = np.asarray(current, dtype=np.float64)
    if a.ndim != 3 or b.ndim != 3 or a.shape[1:] != b.shape[1:] or a.shape[2] != 3:
        raise ValueError(f"need joint sets of shape (P, J, 3) and (C, J, 3), got {a.shape} and {b.shape}")
    squared = ((a[:, None] - b[None]) ** 2).sum(axis=3).mean(axis=2)
    return np.minimum(0.5 * squared / MOTION_SIGMA_M ** 2, cap)


@dataclass(frozen=True, kw_only=True)
class ScoredCandidate:
    """One candidate of a frame with every term of its score before the weights (one attribute
    per term of :data:`TERMS`).

    What :attr:`mocap.track.Tracker.scored` holds for the frame just tracked
    (``experiments.fit_score`` records it to fit the weights). Its unary score is
    :func:`weighted_sum` of :meth:`values` and the config's :func:`weights`, and the motion
    term from the previous frame's hypothesis ``k`` is ``motion_weight * motion[k]``.

    Attributes
    ----------
    origin : str
        What produced it (``tracked``, ``recovery``, ``reacquisition``, ``jump``, ``lifter``).
    pose : ndarray, shape (23,), float64
        Metres and radians.
    joints : ndarray, shape (10, 3), float64, metres
        Camera coordinates.
    region : float
        F, the region residual (in [0, 1]).
    edge : float, pixels
        Mean edge distance.
    keypoint : float, pixels
        Keypoint distance D_k; NaN on frames without keypoints or with ``keypoint_weight`` 0.
    prior : float, nats
        The pose prior's energy; NaN without a prior (``prior_weight`` 0).
    lifter : float, nats
        The lifter term (:meth:`~mocap.track.proposals.LifterSource.energy`); NaN on frames not lifted.
    labelling : float, nats
        :func:`labelling_term`; NaN on frames without keypoints.
    motion : ndarray, shape (K_prev,), float64
        The motion term (:func:`motion_term`) from each hypothesis of the previous frame's beam.
    unary : float
        The weighted sum the tracker scored it with.
    """

    origin: str
    pose: np.ndarray
    joints: np.ndarray
    region: float
    edge: float
    keypoint: float
    prior: float
    lifter: float
    labelling: float
    motion: np.ndarray
    unary: float

    @classmethod
    def from_terms(cls, origin: str, pose: np.ndarray, joints: np.ndarray, unary_values, motion: np.ndarray,
                   unary: float) -> "ScoredCandidate":
        """From the unary terms' values (shape (len(UNARY_TERMS),), :data:`TERMS` order)."""
        return cls(origin=origin, pose=pose, joints=joints, motion=motion, unary=unary,
                   **{t.name: float(v) for t, v in zip(UNARY_TERMS, unary_values, strict=True)})

    def values(self, previous: int = 0) -> np.ndarray:
        """Every term's value, :data:`TERMS` order, shape (len(TERMS),): the motion term's from the
        previous frame's hypothesis ``previous`` (NaN when there was none)."""
        motion = float(self.motion[previous]) if 0 <= previous < len(self.motion) else math.nan
        return np.array([motion if t.pairwise else getattr(self, t.name) for t in TERMS], dtype=np.float64)
