"""``python -m experiments.fit_score decode``: an offline Viterbi through every recorded candidate.

The best path through every scored candidate of each record (:func:`decode_offline`), the
motion term recomputed between all pairs of consecutive frames' candidates, at several motion
weights, caps and lifter weights, against the tracker's own online decisions. The records hold
each candidate's joints, not its heading: the joints' :func:`mocap.track.score.motion_term` is
recomputed, without the heading's :func:`mocap.track.score.turn_term` that the tracker adds
since 2026-11-29 (records from before have no turn term in their motion column either).
"""
from __future__ import annotations

import argparse

import numpy as np

from experiments.fit_score.candidates import (TERMS, Candidates, default_weights, groups, load_records,
                                              record_arrays)
from mocap.track import score

#: Default seeds of the records decoded.
SEEDS = "2,3"


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
        The motion term's multiplies :func:`mocap.track.score.motion_term`, capped at ``motion_cap``.
    """
    from mocap.track.decode import viterbi

    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (len(TERMS),):
        raise ValueError(f"weights must have shape ({len(TERMS)},), got {w.shape}")
    starts, _ = groups(candidates.frame)
    rows = np.split(np.arange(len(candidates)), starts[1:])
    unary_columns = len(score.UNARY_TERMS)
    unary = [score.weighted_sum(candidates.features[r, :unary_columns], w) for r in rows]
    transition = [np.zeros((1, len(rows[0])))]
    for a, b in zip(rows[:-1], rows[1:]):
        transition.append(w[score.MOTION] * score.motion_term(joints[a], joints[b], cap=motion_cap))
    path, _ = viterbi(unary, transition)
    return np.array([r[k] for r, k in zip(rows, path)])


def add_parser(sub) -> argparse.ArgumentParser:
    v = sub.add_parser("decode", help="offline Viterbi through every recorded candidate, motion weights and caps")
    v.add_argument("--motion-weights", default="0,0.3,1,3")
    v.add_argument("--caps", default="8,20")
    v.add_argument("--lifter-weights", default="0.5,2")
    return v


def run(args, sequences: list[str], seeds: list[int]) -> int:
    """The subcommand: one table row per (motion weight, cap, lifter weight) and the tracker's own."""
    found = record_arrays(args.out, sequences, seeds, ("joints", "tracked_error_mm", "tracked_camera_error_mm"),
                          "joints")
    if found is None:
        return 2
    paths, arrays = found
    loaded = [(load_records([path]), a["joints"], a["tracked_error_mm"], a["tracked_camera_error_mm"])
              for path, a in zip(paths, arrays)]
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
                w[TERMS.index("lifter")], w[score.MOTION] = lw, m
                err = np.concatenate([c.error_mm[decode_offline(c, j, w, cap)] for c, j, *_ in loaded])
                cam = np.concatenate([c.camera_error_mm[decode_offline(c, j, w, cap)] for c, j, *_ in loaded])
                print(f"| offline, every candidate | {m:g} | {cap:g} | {lw:g} | {err.mean():.1f} | "
                      f"{100 * np.mean(err > 100):.1f} % | {cam.mean():.1f} | {100 * np.mean(cam > 100):.1f} % |")
    return 0
