"""``python -m experiments.fit_score fit``: the score's weights fitted on the records by a conditional logit.

Within each frame the candidates' probabilities are the softmax of minus their scores (linear
in the weights, each weight non-negative), and the loss is the cross-entropy against soft targets
that favour the candidates nearest the truth about the neck (``exp(-(error - best) /
temperature)``), plus a small ridge on the weights (:func:`fit_weights`; convex, L-BFGS-B,
deterministic). The seed draws the frames held out (``--holdout``), on which the fitted and the
default weights' choices are compared (:func:`~experiments.fit_score.candidates.choose`). The
weights are given in the tracker's units (F's weight kept at
:data:`~mocap.track.score.REGION_WEIGHT`) and written (``--write``) as a
:class:`~mocap.track.TrackerConfig` JSON (:func:`tracker_config`); the weights of terms that
never applied in the records (the keypoint and lifter terms of records without keypoints) are
kept at their defaults (:func:`keep_unseen`). The fits measured in full runs are named
configurations of ``experiments.tracking`` (``oracle-fitted``, ``fitted-silhouette``).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from experiments.fit_score.candidates import (TERMS, Candidates, Choice, choose, default_weights, group_min, groups,
                                              informative, load_records, record_paths)
from mocap.track import score

#: Soft target's temperature (mm): a candidate this much worse than the frame's best gets 1/e of its weight.
TEMPERATURE_MM = 10.0
#: Ridge on the standardised weights (per frame of the fit).
RIDGE = 1e-3
#: Default seeds of the records fitted on.
SEEDS = "0,1"


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
    x = np.where(np.isnan(candidates.features), 0.0, candidates.features)     # a term not applied adds nothing
    starts, group = groups(candidates.frame)
    n_frames = len(starts)
    centred = x - (np.add.reduceat(x, starts) / np.diff(np.r_[starts, len(x)])[:, None])[group]
    scale = np.sqrt(np.mean(centred ** 2, axis=0))
    scale = np.where(scale > 0, scale, 1.0)
    z = x / scale
    gap = candidates.error_mm - group_min(candidates.error_mm, starts)[group]
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
    weight over :data:`~mocap.track.score.REGION_WEIGHT`): the data says nothing of them.
    ``defaults``: the weights to keep (default :func:`~experiments.fit_score.candidates.default_weights`)."""
    w = np.array(weights, dtype=np.float64)
    d = default_weights() if defaults is None else np.asarray(defaults, dtype=np.float64)
    unseen = np.all(np.isnan(np.asarray(features, dtype=np.float64)), axis=0)
    w[unseen] = d[unseen] * w[0] / d[0]
    return w


def in_tracker_units(weights) -> np.ndarray:
    """Weights rescaled so that F's is :data:`~mocap.track.score.REGION_WEIGHT` (the tracker's unit)."""
    w = np.asarray(weights, dtype=np.float64)
    if not w[0] > 0:
        raise ValueError("F's weight was fitted to 0: the score has no unit in the tracker")
    return w * (score.REGION_WEIGHT / w[0])


def tracker_config(weights, base=None):
    """The :class:`~mocap.track.TrackerConfig` (``base``, default the defaults) with these weights
    (:data:`TERMS` order, rescaled to the tracker's units) in its score."""
    from mocap.track import TrackerConfig

    return score.with_weights(base if base is not None else TrackerConfig(), in_tracker_units(weights))


def _frames_held_out(candidates: Candidates, share: float, seed: int) -> np.ndarray:
    """Row mask of a random ``share`` of the frames (drawn with ``seed``)."""
    ids = np.unique(candidates.frame)
    rng = np.random.default_rng(seed)
    held = rng.choice(ids, size=int(round(share * len(ids))), replace=False)
    return np.isin(candidates.frame, held)


def _choice_line(name: str, c: Choice) -> str:
    return (f"| {name} | {c.frames} | {c.mean_error_mm:.1f} | {c.mean_camera_error_mm:.1f} | "
            f"{100 * c.failure_rate:.1f} % | {100 * c.miss_rate:.1f} % | {100 * c.best_failure_rate:.1f} % |")


def add_parser(sub) -> argparse.ArgumentParser:
    f = sub.add_parser("fit", help="fit the weights on the records")
    f.add_argument("--seed", type=int, default=0, help="draws the frames held out")
    f.add_argument("--holdout", type=float, default=0.3, help="share of frames held out of the fit")
    f.add_argument("--temperature-mm", type=float, default=TEMPERATURE_MM)
    f.add_argument("--ridge", type=float, default=RIDGE)
    f.add_argument("--write", type=Path, help="TrackerConfig JSON of the weights fitted on every frame")
    return f


def run(args, sequences: list[str], seeds: list[int]) -> int:
    """The subcommand: fit on the records, table the choices and the weights, write the config."""
    paths = record_paths(args.out, sequences, seeds)
    if paths is None:
        return 2
    every = load_records(paths)
    held = _frames_held_out(every, args.holdout, args.seed)
    train = informative(every.subset(~held))
    w_fit = fit_weights(train, temperature_mm=args.temperature_mm, ridge=args.ridge)
    w_all = fit_weights(informative(every), temperature_mm=args.temperature_mm, ridge=args.ridge)
    unseen = np.all(np.isnan(every.features), axis=0)
    defaults = default_weights()
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
    if not (w_fit[0] > 0 and w_all[0] > 0):
        print("error: F's weight was fitted to 0, so the score has no unit in the tracker (too few informative "
              "frames? record more)", file=sys.stderr)
        return 2
    print("\n| term | default | fitted on the rest | fitted on all |\n|---|---|---|---|")
    for j, t in enumerate(TERMS):
        note = " (never applied: the default kept)" if unseen[j] else ""
        print(f"| {t}{note} | {defaults[j]:g} | {in_tracker_units(w_fit)[j]:.4g} | {in_tracker_units(w_all)[j]:.4g} |")
    if args.write:
        tracker_config(w_all).to_json(args.write)
        print(f"\nwrote {args.write}")
    return 0
