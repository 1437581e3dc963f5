"""``python -m experiments.fit_score``: the tracker's score weights fitted on recorded candidates.

The tracker scores every candidate of a frame (the beam's hypotheses extended, recovery,
re-acquisition, jumps and the lifter's refined proposals) by a weighted sum of terms
(:class:`mocap.track.tracker.ScoredCandidate`): F, the edge distance, the keypoint distance, the
pose prior's and the lifter's energies, and the motion term from the previous frame. The weights
were chosen by hand. This script fits them on data, in two steps:

``record``
    Tracks benchmark sequences (:func:`experiments.ambiguity.benchmark_sequence`: full length,
    160x120, true calibration) with the oracle's 2D keypoints (projected truth plus
    ``--sigma-px`` of noise, :func:`experiments.keypoints.oracle_keypoints`) and a tracker
    configuration (default: the defaults), and writes every frame's candidates with each term's
    value (before the weights; the motion term from the previous frame's best-path hypothesis)
    and their error against the truth: MPJPE about the neck and in the camera, millimetres. One
    ``.npz`` per (sequence, seed) under ``--out`` (default ``experiments/results/fit_score``,
    git-ignored), written atomically (a crash leaves the finished sequences; a second run skips
    them); also each candidate's joints, the truth, the lifter's hypotheses and the decided
    poses. ``--no-keypoints`` tracks the silhouette alone.
``decompose``
    Splits each record's failing frames (the decided pose over 100 mm about the neck) into where
    they come from (:func:`decompose`): no lifter hypothesis within; one within but none of the
    refined candidates; a candidate within but not the frame's lowest score; the lowest score
    within but not the decided pose.
``fit``
    Reads the records and fits the weights offline by a conditional logit: within each frame
    the candidates' probabilities are the softmax of minus their scores (linear in the weights,
    each weight non-negative), and the loss is the cross-entropy against soft targets that favour
    the candidates nearest the truth about the neck (``exp(-(error - best) / temperature)``),
    plus a small ridge on the weights (:func:`fit_weights`; convex, L-BFGS-B, deterministic).
    The seed draws the frames held out (``--holdout``), on which the fitted and the default
    weights' choices are compared (:func:`choose`). The weights are given in the tracker's units
    (F's weight kept at :data:`~mocap.track.config.REGION_WEIGHT`) and written (``--write``) as
    a :class:`~mocap.track.TrackerConfig` JSON: on records without keypoints into the
    ``silhouette_*`` weights (the keypoint and lifter weights, whose terms never applied, kept).
    The fits measured in full runs are named configurations of ``experiments.tracking``
    (``oracle-fitted``, ``fitted-silhouette``).
``decode``
    An offline Viterbi through every recorded candidate (:func:`decode_offline`) at several
    motion weights, caps and lifter weights, against the tracker's own decisions.
``depth``
    The decided poses moved along the neck's ray to a median depth over frames
    (:func:`smooth_depth`), and the true depth's bound.

The fit chooses per frame with the motion from the previous frame's best-path hypothesis; the
tracker decodes paths (``lag`` frames later), and the refinements change with the keypoint
weight. So the fitted weights are confirmed by full tracking runs on a seed never used.
"""
from __future__ import annotations

import argparse
import io
import json
import math
import sys
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from experiments import RESULTS_DIR

#: The terms of the score, in the order of the feature columns (:class:`ScoredCandidate`'s names).
TERMS: tuple[str, ...] = ("region", "edge", "keypoint", "prior", "lifter", "motion")
#: The :class:`~mocap.track.TrackerConfig` field of each term's weight (``region``: the constant unit).
WEIGHT_FIELDS = {"edge": "edge_weight", "keypoint": "keypoint_weight", "prior": "prior_weight",
                 "lifter": "lifter_weight", "motion": "motion_weight"}
#: The fields of the weights on frames without keypoints (the keypoint and lifter terms never apply there).
SILHOUETTE_FIELDS = {"edge": "silhouette_edge_weight", "prior": "silhouette_prior_weight",
                     "motion": "silhouette_motion_weight"}
#: Candidates whose errors about the neck all lie within this (mm) of each other leave nothing to choose:
#: such frames are left out of the fit.
MIN_SPREAD_MM = 5.0
#: Soft target's temperature (mm): a candidate this much worse than the frame's best gets 1/e of its weight.
TEMPERATURE_MM = 10.0
#: Lifter hypotheses kept per frame in a record (their joints about the neck and probabilities).
K_SAVED = 10
#: Ridge on the standardised weights (per frame of the fit).
RIDGE = 1e-3


@dataclass(frozen=True, kw_only=True)
class Candidates:
    """Recorded candidates, every frame's rows together.

    Attributes
    ----------
    frame : ndarray of int64, shape (n,)
        A frame's id, unique over the records read together (rows of one frame are adjacent).
    features : ndarray of float64, shape (n, len(TERMS))
        Each term's value before its weight (NaN: the term did not apply).
    error_mm : ndarray of float64, shape (n,)
        MPJPE about the neck against the truth, millimetres.
    camera_error_mm : ndarray of float64, shape (n,)
        MPJPE in the camera (root included), millimetres.
    origin : ndarray of str, shape (n,)
    """

    frame: np.ndarray
    features: np.ndarray
    error_mm: np.ndarray
    camera_error_mm: np.ndarray
    origin: np.ndarray

    def __len__(self) -> int:
        return len(self.frame)

    def subset(self, rows: np.ndarray) -> "Candidates":
        """The rows ``rows`` (boolean mask or indices)."""
        return Candidates(frame=self.frame[rows], features=self.features[rows], error_mm=self.error_mm[rows],
                          camera_error_mm=self.camera_error_mm[rows], origin=self.origin[rows])


@dataclass(frozen=True, kw_only=True)
class Choice:
    """What a weight vector chooses per frame (:func:`choose`).

    Attributes
    ----------
    frames : int
    mean_error_mm, mean_camera_error_mm : float
        Mean error of the chosen candidates about the neck and in the camera.
    failure_rate : float
        Share of frames whose chosen candidate is over 100 mm about the neck.
    miss_rate : float
        Share of frames whose chosen candidate is over 100 mm about the neck while one of the
        frame's candidates is within.
    best_failure_rate : float
        Share of frames without a candidate within 100 mm about the neck (the oracle's).
    """

    frames: int
    mean_error_mm: float
    mean_camera_error_mm: float
    failure_rate: float
    miss_rate: float
    best_failure_rate: float


def default_weights(silhouette: bool = False) -> np.ndarray:
    """The shipped weights, :data:`TERMS` order, shape (6,): of frames with keypoints, or
    (``silhouette``) without (their keypoint and lifter weights apply to no term there)."""
    from mocap.track import TrackerConfig
    from mocap.track.config import REGION_WEIGHT

    c = TrackerConfig()
    fields = {**WEIGHT_FIELDS, **SILHOUETTE_FIELDS} if silhouette else WEIGHT_FIELDS
    return np.array([REGION_WEIGHT] + [getattr(c, fields[t]) for t in TERMS[1:]], dtype=np.float64)


def _groups(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start of each run of equal ``frame`` values and the run of each row."""
    starts = np.flatnonzero(np.r_[True, frame[1:] != frame[:-1]])
    return starts, np.cumsum(np.r_[False, frame[1:] != frame[:-1]])


def _group_min(values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    return np.minimum.reduceat(values, starts)


def _filled(features: np.ndarray) -> np.ndarray:
    """NaN terms as 0 (a term that does not apply adds nothing, as in the tracker)."""
    return np.where(np.isnan(features), 0.0, features)


def choose(candidates: Candidates, weights, threshold_mm: float = 100.0) -> Choice:
    """The candidate of lowest score ``features @ weights`` per frame (ties: the first), measured.

    Parameters
    ----------
    candidates : Candidates
    weights : array_like, shape (len(TERMS),)
    """
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (len(TERMS),):
        raise ValueError(f"weights must have shape ({len(TERMS)},), got {w.shape}")
    if len(candidates) == 0:
        raise ValueError("no candidates to choose from")
    starts, group = _groups(candidates.frame)
    score = _filled(candidates.features) @ w
    order = np.lexsort((np.arange(len(score)), score, group))      # by frame, then score, then row
    first = order[np.r_[True, group[order][1:] != group[order][:-1]]]
    err, cam = candidates.error_mm[first], candidates.camera_error_mm[first]
    best = _group_min(candidates.error_mm, starts)
    return Choice(frames=len(starts), mean_error_mm=float(err.mean()), mean_camera_error_mm=float(cam.mean()),
                  failure_rate=float(np.mean(err > threshold_mm)),
                  miss_rate=float(np.mean((err > threshold_mm) & (best <= threshold_mm))),
                  best_failure_rate=float(np.mean(best > threshold_mm)))


def informative(candidates: Candidates, min_spread_mm: float = MIN_SPREAD_MM) -> Candidates:
    """The frames with at least two candidates whose errors about the neck differ by ``min_spread_mm``."""
    starts, group = _groups(candidates.frame)
    spread = np.maximum.reduceat(candidates.error_mm, starts) - _group_min(candidates.error_mm, starts)
    return candidates.subset(spread[group] >= min_spread_mm)


def fit_weights(candidates: Candidates, *, temperature_mm: float = TEMPERATURE_MM, ridge: float = RIDGE,
                fixed: dict[int, float] | None = None) -> np.ndarray:
    """Fit the score's weights by a conditional logit over each frame's candidates.

    Minimises, over non-negative weights ``w``, the mean over frames of the cross-entropy
    ``-sum_c q_c log p_c`` with ``p = softmax(-features @ w)`` over the frame's candidates and soft
    targets ``q ∝ exp(-(error - best error) / temperature_mm)``, plus ``ridge`` times the squared
    norm of the weights in units of each feature's within-frame spread. Convex; solved by
    L-BFGS-B from the zero vector, so the result depends on the data only.

    Parameters
    ----------
    candidates : Candidates
        Frames with one candidate add nothing (use :func:`informative` first to drop frames
        that leave nothing to choose).
    temperature_mm : float
    ridge : float
    fixed : dict of int to float, optional
        Weights held at a value (column index to weight), e.g. a term that never varies.

    Returns
    -------
    ndarray, shape (len(TERMS),), float64
        The weights in the features' units (the score's overall scale is its sharpness: see
        :func:`in_tracker_units`).
    """
    from scipy.optimize import minimize

    if not (math.isfinite(temperature_mm) and temperature_mm > 0):
        raise ValueError(f"temperature_mm must be positive, got {temperature_mm!r}")
    if len(candidates) == 0:
        raise ValueError("no candidates to fit on")
    x = _filled(candidates.features)
    starts, group = _groups(candidates.frame)
    n_frames = len(starts)
    centred = x - (np.add.reduceat(x, starts) / np.diff(np.r_[starts, len(x)])[:, None])[group]
    scale = np.sqrt(np.mean(centred ** 2, axis=0))
    scale = np.where(scale > 0, scale, 1.0)
    z = x / scale
    gap = candidates.error_mm - _group_min(candidates.error_mm, starts)[group]
    q = np.exp(-gap / temperature_mm)
    q /= np.add.reduceat(q, starts)[group]
    fixed = dict(fixed or {})
    free = np.array([j not in fixed for j in range(x.shape[1])])
    base = np.zeros(x.shape[1])
    for j, v in fixed.items():
        base[j] = v * scale[j]

    def loss(v):
        u = base.copy()
        u[free] = v
        s = -(z @ u)
        top = np.maximum.reduceat(s, starts)
        e = np.exp(s - top[group])
        total = np.add.reduceat(e, starts)
        p = e / total[group]
        log_z = top + np.log(total)
        value = float(np.sum(q * (log_z[group] - s)) / n_frames + ridge * np.sum(u[free] ** 2))
        grad = (z.T @ (q - p)) / n_frames          # d/du of sum q (log Z - s), s = -z u
        return value, grad[free] + 2.0 * ridge * u[free]

    result = minimize(loss, np.zeros(int(free.sum())), jac=True, method="L-BFGS-B",
                      bounds=[(0.0, None)] * int(free.sum()), options={"maxiter": 2000, "gtol": 1e-10})
    u = base.copy()
    u[free] = result.x
    return u / scale


def keep_unseen(weights, features: np.ndarray, defaults=None) -> np.ndarray:
    """``weights`` with the terms that never applied (NaN on every row of ``features``, e.g. the
    keypoint and lifter terms without keypoints) set to their default, on the same scale (F's
    weight over :data:`~mocap.track.config.REGION_WEIGHT`): the data says nothing of them.
    ``defaults``: the weights to keep (default :func:`default_weights`)."""
    w = np.array(weights, dtype=np.float64)
    d = default_weights() if defaults is None else np.asarray(defaults, dtype=np.float64)
    unseen = np.all(np.isnan(np.asarray(features, dtype=np.float64)), axis=0)
    w[unseen] = d[unseen] * w[0] / d[0]
    return w


def in_tracker_units(weights) -> np.ndarray:
    """Weights rescaled so that F's is :data:`~mocap.track.config.REGION_WEIGHT` (the tracker's unit)."""
    from mocap.track.config import REGION_WEIGHT

    w = np.asarray(weights, dtype=np.float64)
    if not w[0] > 0:
        raise ValueError("F's weight was fitted to 0: the score has no unit in the tracker")
    return w * (REGION_WEIGHT / w[0])


def tracker_config(weights, base=None, silhouette: bool = False):
    """The :class:`~mocap.track.TrackerConfig` with these weights (in the tracker's units) in its score:
    of frames with keypoints, or (``silhouette``) of frames without (edge, prior and motion only)."""
    from mocap.track import TrackerConfig

    w = in_tracker_units(weights)
    fields = SILHOUETTE_FIELDS if silhouette else WEIGHT_FIELDS
    return replace(base if base is not None else TrackerConfig(),
                   **{fields[t]: float(w[j]) for j, t in enumerate(TERMS) if t in fields})


# -- recording ---------------------------------------------------------------------------------
def record_path(out: Path, sequence: str, seed: int) -> Path:
    return out / "records" / f"{sequence}-s{seed}.npz"


def record_sequence(sequence: str, seed: int, out: Path, config, sigma_px: float | None, data_root: Path,
                    max_frames: int | None = None) -> Path:
    """Track one sequence with oracle keypoints (``sigma_px`` None: without keypoints) and write its
    candidates (see the module); ``max_frames``: only its first frames."""
    from experiments.ambiguity import benchmark_sequence
    from experiments.keypoints import oracle_keypoints
    from mocap.io.files import write_bytes_atomic
    from mocap.metrics import mpjpe, root_relative_mpjpe
    from mocap.track import Tracker

    loaded, prepared = benchmark_sequence(sequence, data_root, seed)
    prepared = prepared[:max_frames]
    camera = loaded.calibration.camera
    truth = loaded.ground_truth.joints
    keypoints = ([None] * len(prepared) if sigma_px is None
                 else oracle_keypoints(truth[: len(prepared)], camera, sigma_px, seed))
    tracker = Tracker(loaded.model, camera, config, loaded.calibration.initial_pose)
    rows: dict[str, list] = {k: [] for k in ("frame", "features", "error_mm", "camera_error_mm", "origin", "joints")}
    lifter_best, results, lifted_joints, lifted_p = [], [], [], []
    for i, frame in enumerate(prepared):
        results += tracker.push(i, frame, keypoints[i])
        scored = tracker.scored
        if scored:
            joints = np.array([c.joints for c in scored])
            t = np.repeat(truth[i:i + 1], len(scored), axis=0)
            rows["frame"] += [i] * len(scored)
            rows["features"] += [[c.region, c.edge, c.keypoint, c.prior, c.lifter, c.motion[0]] for c in scored]
            rows["error_mm"] += list(root_relative_mpjpe(joints, t, per_frame=True))
            rows["camera_error_mm"] += list(mpjpe(joints, t, per_frame=True))
            rows["origin"] += [c.origin for c in scored]
            rows["joints"] += list(joints)
        lifted = tracker.lifted
        lifted_joints.append(np.full((K_SAVED, 10, 3), np.nan) if lifted is None else lifted.joints[:K_SAVED])
        lifted_p.append(np.full(K_SAVED, np.nan) if lifted is None else lifted.probabilities[:K_SAVED])
        lifter_best.append(math.inf if lifted is None else float(np.min(root_relative_mpjpe(
            lifted.joints, np.repeat(truth[i:i + 1], len(lifted), axis=0), per_frame=True))))
    results += tracker.finish()
    tracked = np.array([r.joints for r in results])
    buffer = io.BytesIO()
    np.savez_compressed(buffer, frame=np.array(rows["frame"], dtype=np.int64),
                        features=np.array(rows["features"], dtype=np.float64).reshape(-1, len(TERMS)),
                        error_mm=np.array(rows["error_mm"]), camera_error_mm=np.array(rows["camera_error_mm"]),
                        origin=np.array(rows["origin"], dtype=str), lifter_best_mm=np.array(lifter_best),
                        joints=np.array(rows["joints"], dtype=np.float64).reshape(-1, 10, 3),
                        truth=truth[: len(prepared)], lifted_joints=np.array(lifted_joints),
                        lifted_probabilities=np.array(lifted_p),
                        tracked_joints=tracked, tracked_poses=np.array([r.pose for r in results]),
                        tracked_error_mm=root_relative_mpjpe(tracked, truth[: len(tracked)], per_frame=True),
                        tracked_camera_error_mm=mpjpe(tracked, truth[: len(tracked)], per_frame=True),
                        config=np.array(json.dumps(config.to_dict(), sort_keys=True)), sigma_px=np.array(np.nan if sigma_px is None else sigma_px))
    path = record_path(out, sequence, seed)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bytes_atomic(path, buffer.getvalue())
    return path


def load_records(paths: list[Path]) -> Candidates:
    """Read records (:func:`record_sequence`) into one :class:`Candidates`, frame ids made unique."""
    parts, offset = [], 0
    for path in paths:
        with np.load(path) as f:
            frame = f["frame"] + offset
            parts.append(Candidates(frame=frame, features=f["features"], error_mm=f["error_mm"],
                                    camera_error_mm=f["camera_error_mm"], origin=f["origin"]))
            offset = int(frame.max()) + 1 if len(frame) else offset
    if not parts:
        raise ValueError("no records given")
    return Candidates(**{k: np.concatenate([getattr(p, k) for p in parts])
                         for k in ("frame", "features", "error_mm", "camera_error_mm", "origin")})


@dataclass(frozen=True, kw_only=True)
class Remains:
    """Where the tracker's failing frames (over 100 mm about the neck) come from (:func:`decompose`);
    shares of all frames, the four parts adding up to ``failing``.

    Attributes
    ----------
    frames : int
    failing : float
        The tracked (decided) pose over the threshold about the neck.
    lifter_misses : float
        ...and none of the lifter's hypotheses (unrefined) within it: what covering must gain.
    not_refined : float
        ...a lifter hypothesis within, but none of the frame's scored candidates (after refinement):
        lost by which proposals are refined, or by their refinement.
    score_misses : float
        ...a candidate within, but not the frame's lowest score (the weights given, the motion
        from the previous best-path hypothesis): the score's choice.
    decoder_misses : float
        ...the frame's lowest score within, the decided pose not: the decoder (or the beam) lost it.
    """

    frames: int
    failing: float
    lifter_misses: float
    not_refined: float
    score_misses: float
    decoder_misses: float


def decompose(candidates: Candidates, lifter_best_mm: np.ndarray, tracked_error_mm: np.ndarray, weights,
              threshold_mm: float = 100.0) -> Remains:
    """Split the failing frames of one record (frame ids ``0 .. N-1``, every frame scored) into
    :class:`Remains`' parts.

    Parameters
    ----------
    candidates : Candidates
        One record's candidates; ``frame`` indexes the next two arrays.
    lifter_best_mm : ndarray, shape (N,)
        The best lifter hypothesis's error about the neck per frame (``inf`` where none).
    tracked_error_mm : ndarray, shape (N,)
        The tracker's decided pose's error about the neck per frame.
    weights : array_like, shape (len(TERMS),)
    """
    lifter_best_mm, tracked_error_mm = np.asarray(lifter_best_mm), np.asarray(tracked_error_mm)
    n = len(tracked_error_mm)
    if lifter_best_mm.shape != (n,) or len(candidates) == 0 or candidates.frame.max() >= n:
        raise ValueError("need one lifter error and one tracked error per frame of the candidates")
    starts, group = _groups(candidates.frame)
    score = _filled(candidates.features) @ np.asarray(weights, dtype=np.float64)
    order = np.lexsort((np.arange(len(score)), score, group))
    first = order[np.r_[True, group[order][1:] != group[order][:-1]]]
    frames = candidates.frame[starts]
    best = np.full(n, np.inf)
    best[frames] = _group_min(candidates.error_mm, starts)
    chosen = np.full(n, np.inf)
    chosen[frames] = candidates.error_mm[first]
    fail = tracked_error_mm > threshold_mm
    lifter_in, cand_in, chosen_in = (a <= threshold_mm for a in (lifter_best_mm, best, chosen))
    parts = (fail & ~lifter_in, fail & lifter_in & ~cand_in, fail & lifter_in & cand_in & ~chosen_in,
             fail & lifter_in & cand_in & chosen_in)
    return Remains(frames=n, failing=float(fail.mean()), lifter_misses=float(parts[0].mean()),
                   not_refined=float(parts[1].mean()), score_misses=float(parts[2].mean()),
                   decoder_misses=float(parts[3].mean()))


def decode_offline(candidates: Candidates, joints: np.ndarray, weights, motion_cap: float) -> np.ndarray:
    """The best path (Viterbi, :func:`mocap.track.decode.viterbi`) through every scored candidate of
    one record, the motion term recomputed between every pair of consecutive frames' candidates
    from their joints (not only the beam the tracker kept); returns the chosen row of each frame.

    Parameters
    ----------
    candidates : Candidates
        One record's rows, frames in order.
    joints : ndarray, shape (n, 10, 3), metres
        Each row's joints.
    weights : array_like, shape (len(TERMS),)
        The last (motion) multiplies the truncated quadratic of
        :data:`~mocap.track.config.MOTION_SIGMA_M`, capped at ``motion_cap``.
    """
    from mocap.track.config import MOTION_SIGMA_M
    from mocap.track.decode import viterbi

    w = np.asarray(weights, dtype=np.float64)
    starts, _ = _groups(candidates.frame)
    rows = np.split(np.arange(len(candidates)), starts[1:])
    x = _filled(candidates.features)
    unary = [x[r, :-1] @ w[:-1] for r in rows]
    transition = [np.zeros((1, len(rows[0])))]
    for a, b in zip(rows[:-1], rows[1:]):
        squared = ((joints[a][:, None] - joints[b][None]) ** 2).sum(axis=3).mean(axis=2)
        transition.append(w[-1] * np.minimum(0.5 * squared / MOTION_SIGMA_M ** 2, motion_cap))
    path, _ = viterbi(unary, transition)
    return np.array([r[k] for r, k in zip(rows, path)])


def score_miss_frames(candidates: Candidates, lifter_best_mm: np.ndarray, tracked_error_mm: np.ndarray, weights,
                      threshold_mm: float = 100.0) -> np.ndarray:
    """Frame indices of :class:`Remains`' ``score_misses`` part (see :func:`decompose`)."""
    starts, group = _groups(candidates.frame)
    score = _filled(candidates.features) @ np.asarray(weights, dtype=np.float64)
    order = np.lexsort((np.arange(len(score)), score, group))
    first = order[np.r_[True, group[order][1:] != group[order][:-1]]]
    frames = candidates.frame[starts]
    best, chosen = _group_min(candidates.error_mm, starts), candidates.error_mm[first]
    keep = ((np.asarray(tracked_error_mm)[frames] > threshold_mm) & (np.asarray(lifter_best_mm)[frames] <= threshold_mm)
            & (best <= threshold_mm) & (chosen > threshold_mm))
    return frames[keep]


def smooth_depth(joints: np.ndarray, window: int, joint: int = 1) -> np.ndarray:
    """Each frame's body moved along the camera ray through ``joint`` (default the neck) to the
    median depth of that joint over a centred window of ``window`` frames (odd; shorter at the
    ends): the root's depth taken over frames, the projection of ``joint`` kept.

    Parameters
    ----------
    joints : ndarray, shape (N, 10, 3), metres, camera coordinates (depth ``z`` > 0)
    window : int
        Frames, odd, at least 1 (1 returns the joints unchanged).

    Returns
    -------
    ndarray, shape (N, 10, 3)
    """
    joints = np.asarray(joints, dtype=np.float64)
    if window < 1 or window % 2 == 0:
        raise ValueError(f"window must be an odd number of frames, got {window}")
    if joints.ndim != 3 or joints.shape[2] != 3 or np.any(joints[:, joint, 2] <= 0):
        raise ValueError("joints must be (N, J, 3) with the joint in front of the camera")
    z = joints[:, joint, 2]
    h = window // 2
    smoothed = np.array([np.median(z[max(0, i - h): i + h + 1]) for i in range(len(z))])
    shift = joints[:, joint] * (smoothed / z - 1.0)[:, None]
    return joints + shift[:, None, :]


def _frames_held_out(candidates: Candidates, share: float, seed: int) -> np.ndarray:
    """Row mask of a random ``share`` of the frames (drawn with ``seed``)."""
    ids = np.unique(candidates.frame)
    rng = np.random.default_rng(seed)
    held = rng.choice(ids, size=int(round(share * len(ids))), replace=False)
    return np.isin(candidates.frame, held)


def _remains_line(name: str, r: Remains) -> str:
    return (f"| {name} | {r.frames} | {100 * r.failing:.1f} % | {100 * r.lifter_misses:.1f} % | "
            f"{100 * r.not_refined:.1f} % | {100 * r.score_misses:.1f} % | {100 * r.decoder_misses:.1f} % |")


def _choice_line(name: str, c: Choice) -> str:
    return (f"| {name} | {c.frames} | {c.mean_error_mm:.1f} | {c.mean_camera_error_mm:.1f} | "
            f"{100 * c.failure_rate:.1f} % | {100 * c.miss_rate:.1f} % | {100 * c.best_failure_rate:.1f} % |")


def main(argv=None) -> int:
    from mocap.synth import SEQUENCE_NAMES

    p = argparse.ArgumentParser(prog="python -m experiments.fit_score", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("record", help="track sequences with oracle keypoints and record every frame's candidates")
    r.add_argument("--seeds", default="0,1")
    r.add_argument("--sequences", default=",".join(SEQUENCE_NAMES))
    r.add_argument("--sigma-px", type=float, default=2.0, help="the oracle keypoints' noise (pixels)")
    r.add_argument("--no-keypoints", action="store_true", help="track without keypoints (the silhouette only)")
    r.add_argument("--config-file", type=Path, help="TrackerConfig JSON to record with (default: the defaults)")
    r.add_argument("--max-frames", type=int, help="only the first frames of each sequence (a smoke test)")
    r.add_argument("--data", type=Path, default=RESULTS_DIR / "tracking",
                   help="where the generated sequences are (made there when missing)")
    dsub = sub.add_parser("decompose", help="where each record's failing frames come from, at the default weights")
    dsub.add_argument("--seeds", default="41")
    dsub.add_argument("--sequences", default=",".join(SEQUENCE_NAMES))
    vsub = sub.add_parser("decode", help="offline Viterbi through every recorded candidate, motion weights and caps")
    vsub.add_argument("--seeds", default="2,3")
    vsub.add_argument("--sequences", default=",".join(SEQUENCE_NAMES))
    vsub.add_argument("--motion-weights", default="0,0.3,1,3")
    vsub.add_argument("--caps", default="8,20")
    vsub.add_argument("--lifter-weights", default="0.5,2")
    rsub = sub.add_parser("depth", help="the decided poses' depth taken over frames (a centred median), measured")
    rsub.add_argument("--seeds", default="0,1")
    rsub.add_argument("--sequences", default=",".join(SEQUENCE_NAMES))
    rsub.add_argument("--windows", default="1,5,9,17,33")
    f = sub.add_parser("fit", help="fit the weights on the records")
    f.add_argument("--seeds", default="0,1")
    f.add_argument("--sequences", default=",".join(SEQUENCE_NAMES))
    f.add_argument("--seed", type=int, default=0, help="draws the frames held out")
    f.add_argument("--holdout", type=float, default=0.3, help="share of frames held out of the fit")
    f.add_argument("--temperature-mm", type=float, default=TEMPERATURE_MM)
    f.add_argument("--ridge", type=float, default=RIDGE)
    f.add_argument("--write", type=Path, help="TrackerConfig JSON of the weights fitted on every frame")
    for q in (r, f, dsub, vsub, rsub):
        q.add_argument("--out", type=Path, default=RESULTS_DIR / "fit_score")
    args = p.parse_args(argv)
    try:
        seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    except ValueError:
        seeds = []
    sequences = [s for s in args.sequences.split(",") if s]
    if not seeds or not sequences or any(s not in SEQUENCE_NAMES for s in sequences):
        print(f"error: need seeds and sequences of {', '.join(SEQUENCE_NAMES)}", file=sys.stderr)
        return 2
    if args.command == "record":
        from mocap.track import TrackerConfig

        config = TrackerConfig.from_json(args.config_file) if args.config_file else TrackerConfig()
        for seed in seeds:
            for sequence in sequences:
                if record_path(args.out, sequence, seed).is_file():
                    continue
                print(f"recording {sequence} seed {seed}", flush=True)
                record_sequence(sequence, seed, args.out, config, None if args.no_keypoints else args.sigma_px, args.data,
                                args.max_frames)
        return 0
    paths = [record_path(args.out, q, s) for s in seeds for q in sequences]
    missing = [str(x) for x in paths if not x.is_file()]
    if missing:
        print(f"error: no record {', '.join(missing)} (run record first)", file=sys.stderr)
        return 2
    if args.command == "decompose":
        print("| record | frames | > 100 mm about the neck | no lifter hypothesis within | within, not among the refined "
              "candidates | a candidate within, not the lowest score | the lowest score within, not decided |\n"
              + "|---" * 7 + "|")
        total = []
        for path in paths:
            with np.load(path) as z:
                one = load_records([path])
                part = decompose(one, z["lifter_best_mm"], z["tracked_error_mm"], default_weights())
            total.append(part)
            print(_remains_line(path.stem, part))
        n = sum(x.frames for x in total)
        pooled = Remains(frames=n, **{k: sum(getattr(x, k) * x.frames for x in total) / n
                                      for k in ("failing", "lifter_misses", "not_refined", "score_misses",
                                                "decoder_misses")})
        print(_remains_line("all, pooled", pooled))
        ranks, top_within, p_nearest, p_top, higher, joint_error = [], [], [], [], [], []
        for path in paths:
            with np.load(path) as z:
                if "lifted_joints" not in z.files:
                    continue
                one = load_records([path])
                frames = score_miss_frames(one, z["lifter_best_mm"], z["tracked_error_mm"], default_weights())
                score = _filled(one.features) @ default_weights()
                for t in frames:
                    rows = np.flatnonzero(one.frame == t)
                    chosen, best = rows[np.argmin(score[rows])], rows[np.argmin(one.error_mm[rows])]
                    higher.append(one.features[best] > one.features[chosen])
                    about = z["joints"][chosen] - z["joints"][chosen][1]
                    joint_error.append(1e3 * np.linalg.norm(about - (z["truth"][t] - z["truth"][t][1]), axis=1))
                truth = z["truth"][frames] - z["truth"][frames][:, 1:2]
                lifted, prob = z["lifted_joints"][frames], z["lifted_probabilities"][frames]
                error = 1e3 * np.linalg.norm(lifted - truth[:, None], axis=3).mean(axis=2)     # (frames, K)
                nearest = np.argmin(error, axis=1)
                ranks += list(nearest)
                top_within += list(error[:, 0] <= 100.0)
                p_nearest += list(prob[np.arange(len(frames)), nearest])
                p_top += list(prob[:, 0])
        if ranks:
            print(f"\nOn the {len(ranks)} frames the score missed: the lifter's hypothesis nearest the truth has "
                  f"probability rank (0: top) {np.bincount(ranks, minlength=K_SAVED).tolist()}, median probability "
                  f"{np.median(p_nearest):.3f} (the top's {np.median(p_top):.3f}); the top hypothesis is within "
                  f"100 mm about the neck on {100 * np.mean(top_within):.0f} % of them.")
            from mocap.body import JOINT_NAMES
            share = np.mean(higher, axis=0)
            print("The candidate nearest the truth has the higher term than the chosen one on: "
                  + ", ".join(f"{t} {100 * share[j]:.0f} %" for j, t in enumerate(TERMS)) + " of them.")
            print("The chosen candidate's median error about the neck per joint (mm): "
                  + ", ".join(f"{n} {v:.0f}" for n, v in zip(JOINT_NAMES, np.median(joint_error, axis=0))))
        return 0
    if args.command == "depth":
        from mocap.metrics import mpjpe

        tracks = []
        for path in paths:
            with np.load(path) as z:
                if "tracked_joints" not in z.files:
                    print(f"error: {path} has no tracked joints (recorded before they were kept)", file=sys.stderr)
                    return 2
                tracks.append((z["tracked_joints"], z["truth"][: len(z["tracked_joints"])]))
        print(f"records: seeds {args.seeds}; {len(paths)} sequences\n\n| window (frames) | mean MPJPE mm | median of "
              "the sequences' MPJPE mm | > 100 mm |\n|---|---|---|---|")
        for window in (int(v) for v in args.windows.split(",")):
            errors = [mpjpe(smooth_depth(j, window), t, per_frame=True) for j, t in tracks]
            every = np.concatenate(errors)
            print(f"| {window} | {every.mean():.1f} | {np.median([e.mean() for e in errors]):.1f} | "
                  f"{100 * np.mean(every > 100):.1f} % |")
        bound = []
        for j, t in tracks:      # the neck moved along its ray to the true neck's depth: what depth alone can give
            bound.append(mpjpe(j + (j[:, 1] * (t[:, 1, 2] / j[:, 1, 2] - 1.0)[:, None])[:, None], t, per_frame=True))
        every = np.concatenate(bound)
        print(f"| the true depth (a bound) | {every.mean():.1f} | {np.median([e.mean() for e in bound]):.1f} | "
              f"{100 * np.mean(every > 100):.1f} % |")
        return 0
    if args.command == "decode":
        loaded = []
        for path in paths:
            with np.load(path) as z:
                if "joints" not in z.files:
                    print(f"error: {path} has no joints (recorded before they were kept)", file=sys.stderr)
                    return 2
                loaded.append((load_records([path]), z["joints"], z["tracked_error_mm"], z["tracked_camera_error_mm"]))
        tracked = np.concatenate([t for *_, t, _ in loaded])
        tracked_cam = np.concatenate([c for *_, c in loaded])
        print(f"records: seeds {args.seeds}; {len(paths)} sequences, {len(tracked)} frames\n")
        print("| decoding | motion weight | cap | lifter weight | mean error about the neck mm | > 100 mm about the neck | "
              "mean in the camera mm | > 100 mm in the camera |\n" + "|---" * 8 + "|")
        print(f"| the tracker (online, lag 8, its beam) | 1 | 8 | 0.5 | {tracked.mean():.1f} | "
              f"{100 * np.mean(tracked > 100):.1f} % | {tracked_cam.mean():.1f} | {100 * np.mean(tracked_cam > 100):.1f} % |")
        for m in (float(v) for v in args.motion_weights.split(",")):
            for cap in (float(v) for v in args.caps.split(",")):
                for lw in (float(v) for v in args.lifter_weights.split(",")):
                    w = default_weights()
                    w[TERMS.index("lifter")], w[TERMS.index("motion")] = lw, m
                    err = np.concatenate([c.error_mm[decode_offline(c, j, w, cap)] for c, j, *_ in loaded])
                    cam = np.concatenate([c.camera_error_mm[decode_offline(c, j, w, cap)] for c, j, *_ in loaded])
                    print(f"| offline, every candidate | {m:g} | {cap:g} | {lw:g} | {err.mean():.1f} | "
                          f"{100 * np.mean(err > 100):.1f} % | {cam.mean():.1f} | {100 * np.mean(cam > 100):.1f} % |")
        return 0
    every = load_records(paths)
    held = _frames_held_out(every, args.holdout, args.seed)
    train = informative(every.subset(~held))
    w_fit = fit_weights(train, temperature_mm=args.temperature_mm, ridge=args.ridge)
    w_all = fit_weights(informative(every), temperature_mm=args.temperature_mm, ridge=args.ridge)
    unseen = np.all(np.isnan(every.features), axis=0)
    silhouette = bool(unseen[TERMS.index("keypoint")])        # recorded without keypoints
    defaults = default_weights(silhouette)
    w_fit, w_all = (keep_unseen(w, every.features, defaults) for w in (w_fit, w_all))
    head = "| weights | frames | chosen's error about the neck mm (mean) | in the camera mm | > 100 mm about the neck | missed (another within) | no candidate within |"
    print(f"records: seeds {args.seeds}; {len(sequences)} sequences; {len(np.unique(every.frame))} frames, "
          f"{len(every)} candidates; fitted on {len(np.unique(train.frame))} informative frames of "
          f"{int(np.sum(~held))} rows; held out {len(np.unique(every.frame[held]))} frames (seed {args.seed})\n")
    print(head + "\n" + "|---" * 7 + "|")
    held_c = every.subset(held)
    print(_choice_line("default, held-out frames", choose(held_c, defaults)))
    print(_choice_line("fitted on the rest, held-out frames", choose(held_c, w_fit)))
    print(_choice_line("default, all frames", choose(every, defaults)))
    print(_choice_line("fitted on all, all frames", choose(every, w_all)))
    print("\n| term | default | fitted on the rest | fitted on all |\n|---|---|---|---|")
    for j, t in enumerate(TERMS):
        note = " (never applied: the default kept)" if unseen[j] else ""
        print(f"| {t}{note} | {defaults[j]:g} | {in_tracker_units(w_fit)[j]:.4g} | {in_tracker_units(w_all)[j]:.4g} |")
    if args.write:
        tracker_config(w_all, silhouette=silhouette).to_json(args.write)
        print(f"\nwrote {args.write}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
