"""``python -m experiments.fit_score depth``: the decided poses' depth taken over frames, measured.

Each decided pose moved along the neck's ray to the median depth of the neck over a centred
window of frames (:func:`smooth_depth`), at several windows, and the true depth's bound (the
neck moved to the true neck's depth: what depth alone can give).
"""
from __future__ import annotations

import argparse

import numpy as np

from experiments.fit_score.candidates import record_arrays

#: Default seeds of the records measured.
SEEDS = "0,1"


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


def add_parser(sub) -> argparse.ArgumentParser:
    r = sub.add_parser("depth", help="the decided poses' depth taken over frames (a centred median), measured")
    r.add_argument("--windows", default="1,5,9,17,33")
    return r


def run(args, sequences: list[str], seeds: list[int]) -> int:
    """The subcommand: one table row per window and the true depth's bound."""
    found = record_arrays(args.out, sequences, seeds, ("tracked_joints", "truth"), "tracked joints")
    if found is None:
        return 2
    from mocap.metrics import mpjpe

    paths, arrays = found
    tracks = [(a["tracked_joints"], a["truth"][: len(a["tracked_joints"])]) for a in arrays]
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
