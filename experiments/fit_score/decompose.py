"""``python -m experiments.fit_score decompose``: where each record's failing frames come from.

A failing frame (the decided pose over 100 mm about the neck) is lost in one of four places
(:func:`decompose`): no lifter hypothesis within; one within but none of the refined candidates;
a candidate within but not the frame's lowest score (at the default weights, the motion from the
previous best-path hypothesis); the lowest score within but not the decided pose. On the frames
the score missed it also says which terms favour the chosen candidate over the one nearest the
truth, and the chosen candidate's error per joint.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np

from experiments.fit_score.candidates import (K_SAVED, TERMS, Candidates, default_weights, group_min, groups,
                                              load_records, lowest, record_paths, scores)

#: Default seeds of the records decomposed.
SEEDS = "41"


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
    starts, _ = groups(candidates.frame)
    first = lowest(candidates, scores(candidates, weights))
    frames = candidates.frame[starts]
    best = np.full(n, np.inf)
    best[frames] = group_min(candidates.error_mm, starts)
    chosen = np.full(n, np.inf)
    chosen[frames] = candidates.error_mm[first]
    fail = tracked_error_mm > threshold_mm
    lifter_in, cand_in, chosen_in = (a <= threshold_mm for a in (lifter_best_mm, best, chosen))
    parts = (fail & ~lifter_in, fail & lifter_in & ~cand_in, fail & lifter_in & cand_in & ~chosen_in,
             fail & lifter_in & cand_in & chosen_in)
    return Remains(frames=n, failing=float(fail.mean()), lifter_misses=float(parts[0].mean()),
                   not_refined=float(parts[1].mean()), score_misses=float(parts[2].mean()),
                   decoder_misses=float(parts[3].mean()))


def score_miss_frames(candidates: Candidates, lifter_best_mm: np.ndarray, tracked_error_mm: np.ndarray, weights,
                      threshold_mm: float = 100.0) -> np.ndarray:
    """Frame indices of :class:`Remains`' ``score_misses`` part (see :func:`decompose`)."""
    starts, _ = groups(candidates.frame)
    first = lowest(candidates, scores(candidates, weights))
    frames = candidates.frame[starts]
    best, chosen = group_min(candidates.error_mm, starts), candidates.error_mm[first]
    keep = ((np.asarray(tracked_error_mm)[frames] > threshold_mm) & (np.asarray(lifter_best_mm)[frames] <= threshold_mm)
            & (best <= threshold_mm) & (chosen > threshold_mm))
    return frames[keep]


def _remains_line(name: str, r: Remains) -> str:
    return (f"| {name} | {r.frames} | {100 * r.failing:.1f} % | {100 * r.lifter_misses:.1f} % | "
            f"{100 * r.not_refined:.1f} % | {100 * r.score_misses:.1f} % | {100 * r.decoder_misses:.1f} % |")


def add_parser(sub) -> argparse.ArgumentParser:
    return sub.add_parser("decompose", help="where each record's failing frames come from, at the default weights")


def run(args, sequences: list[str], seeds: list[int]) -> int:
    """The subcommand: one table row per record and pooled, then the score's misses in detail."""
    paths = record_paths(args.out, sequences, seeds)
    if paths is None:
        return 2
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
            score = scores(one, default_weights())
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
