"""``python -m experiments.beam_origins [--seeds 0] [--keypoints mediapipe|oracle] [--out DIR]``:
which stage of the beam made each decided pose, and what each stage costs (issue 50, item 6).

The default tracker runs every benchmark sequence (full length, 160x120, true calibration) given
MediaPipe's keypoints on the rendered frames (:func:`experiments.keypoints.detector_keypoints`) or
the oracle's (the true joints projected plus 2 px). For every decided frame its
:attr:`~mocap.track.FrameResult.origin` names the stage whose candidate the decoder chose on that
frame (``tracked``: a hypothesis of the beam refined; ``jump``, ``lifter``, ``reacquisition``,
``recovery``, ``mirror``). Beside it, from :attr:`mocap.track.Tracker.scored`, the candidates each
stage gave per frame, and their budget: the evaluations the configuration grants each candidate of
that stage (the leader's ``evaluations``, the beam's others' ``hypothesis_evaluations``, a jump's
``jump_evaluations``, a proposal's ``proposal_evaluations``, a re-acquisition's
``hypothesis_evaluations``, recovery's ``evaluations``, a mirror's ``mirror_evaluations``; a simplex
that converges early spends less, and the unrefined evaluations that rank proposals are left out).

A stage that spends much and is rarely chosen is where an adaptive budget would cut. Writes
``OUT/beam_origins.json`` and prints a table.
"""
from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from dataclasses import asdict, dataclass
from pathlib import Path

from experiments import RESULTS_DIR
from mocap.synth import SEQUENCE_NAMES
from mocap.track import TrackerConfig


@dataclass(frozen=True)
class StageShare:
    """One stage of the beam over the frames measured.

    Attributes
    ----------
    origin : str
        The stage (:attr:`mocap.track.FrameResult.origin`).
    chosen_rate : float
        The share of decided frames whose pose this stage made, in [0, 1].
    candidates_per_frame : float
        Its candidates per tracked frame.
    budget_per_frame : float, evaluations
        Their granted evaluations per tracked frame (see the module).
    budget_share : float
        That budget over every stage's, in [0, 1].
    """

    origin: str
    chosen_rate: float
    candidates_per_frame: float
    budget_per_frame: float
    budget_share: float


def candidate_budget(origin: str, rank: int, config: TrackerConfig) -> int:
    """The evaluations ``config`` grants one candidate of ``origin`` (``rank``: its place among
    the frame's ``tracked`` candidates, 0 the leader)."""
    budgets = {"jump": config.jump_evaluations, "lifter": config.proposal_evaluations,
               "reacquisition": config.hypothesis_evaluations, "recovery": config.evaluations,
               "mirror": config.mirror_evaluations}
    if origin == "tracked":
        return config.evaluations if rank == 0 else config.hypothesis_evaluations
    if origin not in budgets:
        raise ValueError(f"unknown origin {origin!r}")
    return budgets[origin]


def stage_shares(chosen: list[str], candidates: list[list[str]], config: TrackerConfig) -> list[StageShare]:
    """Each stage's share of the decided frames and of the budget.

    Parameters
    ----------
    chosen : list of str
        The origin of each decided frame (empty frames left out).
    candidates : list of list of str
        Each tracked frame's candidates' origins, in the tracker's order (the leader first).
    config : TrackerConfig

    Returns
    -------
    list of StageShare
        One per origin seen, the most chosen first.
    """
    if not chosen or not candidates:
        raise ValueError("no frame to count")
    picked = Counter(chosen)
    counts: Counter = Counter()
    budget: Counter = Counter()
    for frame in candidates:
        rank = 0
        for origin in frame:
            counts[origin] += 1
            budget[origin] += candidate_budget(origin, rank, config)
            rank += origin == "tracked"
    total = sum(budget.values()) or 1
    origins = sorted(set(picked) | set(counts), key=lambda o: (-picked[o], o))
    return [StageShare(o, picked[o] / len(chosen), counts[o] / len(candidates), budget[o] / len(candidates),
                       budget[o] / total) for o in origins]


def measure(seeds: list[int], keypoints: str, root: Path, progress=print) -> dict:
    """Track every benchmark sequence of ``seeds`` with ``keypoints`` (``mediapipe`` or
    ``oracle``); every frame's origins (see the module)."""
    from experiments.ambiguity import benchmark_sequence
    from experiments.keypoints import DETECTOR_FILE, detector_keypoints, oracle_keypoints
    from mocap.track import Tracker

    config = TrackerConfig()
    chosen: list[str] = []
    candidates: list[list[str]] = []
    for seed in seeds:
        for sequence in SEQUENCE_NAMES:
            loaded, prepared = benchmark_sequence(sequence, root, seed)
            camera = loaded.calibration.camera
            given = (detector_keypoints(loaded.frames[: len(prepared)], loaded.folder / DETECTOR_FILE)
                     if keypoints == "mediapipe" else
                     oracle_keypoints(loaded.ground_truth.joints[: len(prepared)], camera, 2.0, seed))
            tracker = Tracker(loaded.model, camera, config, loaded.calibration.initial_pose)
            results = []
            for i, frame in enumerate(prepared):
                results += tracker.push(i, frame, given[i])
                if not frame.is_empty:
                    candidates.append([c.origin for c in tracker.scored])
            results += tracker.finish()
            chosen += [r.origin for r in results if not r.empty]
            progress(f"{sequence} seed {seed}: {len(results)} frames")
    return {"seeds": seeds, "keypoints": keypoints, "frames": len(chosen),
            "stages": [asdict(s) for s in stage_shares(chosen, candidates, config)]}


def table(result: dict) -> str:
    """The Markdown table of a :func:`measure` result."""
    lines = [f"{result['frames']} frames, seeds {', '.join(map(str, result['seeds']))}, {result['keypoints']} keypoints",
             "", "| stage | decided frames | candidates a frame | budget a frame (evaluations) | share of the budget |",
             "|---|---|---|---|---|"]
    for s in result["stages"]:
        lines.append(f"| {s['origin']} | {100 * s['chosen_rate']:.1f} % | {s['candidates_per_frame']:.2f} | "
                     f"{s['budget_per_frame']:.0f} | {100 * s['budget_share']:.1f} % |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.beam_origins", description=__doc__.splitlines()[0])
    p.add_argument("--seeds", default="0", help="comma-separated generator seeds (default 0)")
    p.add_argument("--keypoints", choices=("mediapipe", "oracle"), default="mediapipe")
    p.add_argument("--out", type=Path, default=RESULTS_DIR / "beam_origins")
    args = p.parse_args(argv)
    try:
        seeds = [int(s) for s in args.seeds.split(",") if s]
    except ValueError:
        p.error(f"--seeds must be integers separated by commas, got {args.seeds!r}")
    if args.keypoints == "mediapipe":
        from mocap.io import mediapipe_keypoints

        if not mediapipe_keypoints.available():
            print("error: --keypoints mediapipe needs the optional extra: pip install 'mocap[keypoints]'",
                  file=sys.stderr)
            return 2
    result = measure(seeds, args.keypoints, RESULTS_DIR / "tracking")      # the benchmark's sequences, shared
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "beam_origins.json").write_text(json.dumps(result, indent=1) + "\n")
    print(table(result), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
