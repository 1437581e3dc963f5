"""Recorded candidates of ``python -m experiments.fit_score`` and what a weight vector chooses among them.

A record (:mod:`experiments.fit_score.record`) holds, for one (sequence, seed), every frame's
candidates (:class:`mocap.track.ScoredCandidate`) with each term's value before its weight in
the columns of :data:`mocap.track.score.TERMS`, and their errors against the truth. The
subcommands read them back as one :class:`Candidates` (:func:`load_records`).
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.track import score

#: The terms of the score, in the order of the feature columns (:data:`mocap.track.score.TERMS`).
TERMS: tuple[str, ...] = score.TERM_NAMES
#: Lifter hypotheses kept per frame in a record (their joints about the neck and probabilities).
K_SAVED = 10


#: Candidates whose errors about the neck all lie within this (mm) of each other leave nothing to choose:
#: such frames are left out of the fit.
MIN_SPREAD_MM = 5.0


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


def default_weights() -> np.ndarray:
    """The shipped weights, :data:`TERMS` order, shape (len(TERMS),) (:func:`mocap.track.score.weights` of
    the default :class:`~mocap.track.TrackerConfig`; on frames without keypoints the keypoint and
    lifter weights apply to no term)."""
    from mocap.track import TrackerConfig

    return score.weights(TrackerConfig())


def scores(candidates: Candidates, weights) -> np.ndarray:
    """Every row's score under ``weights`` (shape (len(TERMS),)): :func:`mocap.track.score.weighted_sum`,
    a NaN term adding nothing as in the tracker; shape (n,)."""
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (len(TERMS),):
        raise ValueError(f"weights must have shape ({len(TERMS)},), got {w.shape}")
    return np.asarray(score.weighted_sum(candidates.features.reshape(-1, len(TERMS)), w))


def lowest(candidates: Candidates, values: np.ndarray) -> np.ndarray:
    """Row of the lowest ``values`` in each frame (ties: the first row), frames in order."""
    _, group = groups(candidates.frame)
    order = np.lexsort((np.arange(len(values)), values, group))      # by frame, then value, then row
    return order[np.r_[True, group[order][1:] != group[order][:-1]]]


def groups(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start of each run of equal ``frame`` values and the run of each row."""
    starts = np.flatnonzero(np.r_[True, frame[1:] != frame[:-1]])
    return starts, np.cumsum(np.r_[False, frame[1:] != frame[:-1]])


def group_min(values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """The least of ``values`` in each run that starts at ``starts`` (:func:`groups`)."""
    return np.minimum.reduceat(values, starts)


def choose(candidates: Candidates, weights, threshold_mm: float = 100.0) -> Choice:
    """The candidate of lowest score (:func:`scores`) per frame (ties: the first), measured.

    Parameters
    ----------
    candidates : Candidates
    weights : array_like, shape (len(TERMS),)
    """
    if len(candidates) == 0:
        raise ValueError("no candidates to choose from")
    starts, _ = groups(candidates.frame)
    first = lowest(candidates, scores(candidates, weights))
    err, cam = candidates.error_mm[first], candidates.camera_error_mm[first]
    best = group_min(candidates.error_mm, starts)
    return Choice(frames=len(starts), mean_error_mm=float(err.mean()), mean_camera_error_mm=float(cam.mean()),
                  failure_rate=float(np.mean(err > threshold_mm)),
                  miss_rate=float(np.mean((err > threshold_mm) & (best <= threshold_mm))),
                  best_failure_rate=float(np.mean(best > threshold_mm)))


def informative(candidates: Candidates, min_spread_mm: float = MIN_SPREAD_MM) -> Candidates:
    """The frames with at least two candidates whose errors about the neck differ by ``min_spread_mm``."""
    starts, group = groups(candidates.frame)
    spread = np.maximum.reduceat(candidates.error_mm, starts) - group_min(candidates.error_mm, starts)
    return candidates.subset(spread[group] >= min_spread_mm)


def record_path(out: Path, sequence: str, seed: int) -> Path:
    """Where the record of one (sequence, seed) is under ``out``."""
    return out / "records" / f"{sequence}-s{seed}.npz"


def record_paths(out: Path, sequences: list[str], seeds: list[int]) -> list[Path] | None:
    """The records of every (seed, sequence), seeds outer; None (the missing named on stderr)
    when one was not recorded."""
    paths = [record_path(out, q, s) for s in seeds for q in sequences]
    missing = [str(x) for x in paths if not x.is_file()]
    if missing:
        print(f"error: no record {', '.join(missing)} (run record first)", file=sys.stderr)
        return None
    return paths


def record_arrays(out: Path, sequences: list[str], seeds: list[int], names: tuple[str, ...],
                  what: str) -> tuple[list[Path], list[dict[str, np.ndarray]]] | None:
    """The records of every (seed, sequence) (:func:`record_paths`) and the arrays ``names`` of
    each; None, the problem said on stderr in one line, when a record is missing or lacks one of
    them (``what``: those arrays in words, "joints")."""
    paths = record_paths(out, sequences, seeds)
    if paths is None:
        return None
    arrays = []
    for path in paths:
        with np.load(path) as z:
            lacking = [name for name in names if name not in z.files]
            if lacking:
                print(f"error: {path} has no {what} (recorded before they were kept)", file=sys.stderr)
                return None
            arrays.append({name: z[name] for name in names})
    return paths, arrays


def load_records(paths: list[Path]) -> Candidates:
    """Read records (:func:`experiments.fit_score.record.record_sequence`) into one :class:`Candidates`, frame ids made unique."""
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
