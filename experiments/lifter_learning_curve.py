"""``python -m experiments.lifter_learning_curve``: the lifter's coverage against its training steps.

Held-out subjects (``--hold-out``, default :data:`HOLD_OUT`) are left out of the training
together: each run trains the shipped network (:data:`experiments.fit_lifter.HIDDEN`, its batch,
noise and cosine schedule, seed 0, one thread) on the poses of every trial of the other subjects
for a budget of steps (``--budgets``), and measures along the way (every ``--every`` steps, the
run's own schedule still going) and at its end the coverage of each held-out subject's poses
(:func:`experiments.lifter_coverage.held_out_queries`: random heading, body and place before the
benchmark's camera, 160x120, oracle 2D + 2 px): the share of poses on which the top hypothesis
(M = 1) or one of the ten (M = 10) is within 100 mm of the truth, joints about the neck. A run's
end is what a lifter trained for that budget gives; the points along a run are what its
unfinished schedule gives (a lower bound for a run of that budget).

Holding out two subjects at once instead of each of the nine in turn keeps the curve within
about half an hour of one core; the coverage is then measured with one subject fewer in the
training than leave-one-subject-out would have (a little pessimistic).

One file per run, ``run_<budget>.json`` in ``--out`` (default ``experiments/lifter_learning_curve``),
rewritten atomically after every measurement (a crash leaves the measurements made so far;
a finished run is not trained again), so runs may go in separate processes; then the figure
(:mod:`experiments.figures.ext_lifter_learning_curve`) from every run file there.
``--figure-only`` redraws it.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from experiments import EXPERIMENTS_DIR

#: Subjects held out by default: everyday arm motion (14) and dance with high arms (49).
HOLD_OUT = ("14", "49")
#: Training budgets (steps) by default, and the spacing of the measurements along a run.
BUDGETS = (4000, 12000)
EVERY = 2000
#: Held-out poses queried per subject.
QUERIES = 1000
OUT = EXPERIMENTS_DIR / "lifter_learning_curve"


def run_file(out: Path, budget: int) -> Path:
    return out / f"run_{budget}.json"


def read_runs(out: Path) -> list[dict]:
    """Every run file in ``out``, by budget."""
    runs = [json.loads(p.read_text()) for p in sorted(out.glob("run_*.json"))]
    return sorted(runs, key=lambda r: r["budget"])


def run(train_dir: Path, out: Path, budget: int, hold_out: tuple[str, ...], every: int, seed: int,
        queries: int, hidden: tuple[int, ...], command: str) -> dict:
    """Train one run of ``budget`` steps without ``hold_out`` and measure it (see the module docstring)."""
    import torch

    from experiments.fit_lifter import BATCH, THREADS, KeypointNoise, export_weights, train, training_poses
    from experiments.lifter_coverage import coverage, held_out_errors, held_out_queries
    from mocap.io.files import write_json
    from mocap.track.lifter import Lifter

    path = run_file(out, budget)
    if path.exists():
        done = json.loads(path.read_text())
        if done.get("finished") and done.get("hold_out") == list(hold_out) and done.get("hidden") == list(hidden):
            print(f"{path.name}: already finished", file=sys.stderr)
            return done
    poses, subjects = training_poses(train_dir)
    unknown = sorted(set(hold_out) - {str(s) for s in subjects})
    if unknown:
        raise ValueError(f"held-out subjects not in {train_dir}: {unknown}")
    held = np.isin(subjects, list(hold_out))
    probes = {s: held_out_queries(poses[subjects == s], s, seed, queries) for s in hold_out}
    record = {"budget": budget, "hold_out": list(hold_out), "hidden": list(hidden), "seed": seed, "batch": BATCH,
              "threads": THREADS, "torch": torch.__version__, "queries_per_subject": queries,
              "training_subjects": sorted({str(s) for s in subjects[~held]}), "training_poses": int((~held).sum()),
              "command": command, "load_average_at_start": [round(v, 2) for v in os.getloadavg()],
              "points": [], "finished": False}
    started = time.perf_counter()

    def measure(step: int, net) -> None:
        lifter = Lifter(export_weights(net))
        row = {"step": step, "train_s": round(time.perf_counter() - started, 1)}
        for s, q in probes.items():
            c = coverage(held_out_errors(lifter, q))
            row[s] = {"top1": c["coverage_at_1"], "best_of_10": c["coverage_at_10"],
                      "median_top1_mm": c["median_top1_mm"], "median_best_mm": c["median_best_mm"]}
        record["points"].append(row)
        write_json(path, record)
        print(f"budget {budget} step {step}: " + ", ".join(
            f"{s} {100 * row[s]['top1']:.1f} / {100 * row[s]['best_of_10']:.1f} %" for s in probes), file=sys.stderr)

    net = train(poses[~held], seed=seed, hidden=hidden, steps=budget, batch=BATCH, noise=KeypointNoise.read(),
                progress=False, on_step=measure, every=every if every > 0 else budget)
    if not record["points"] or record["points"][-1]["step"] != budget:
        measure(budget, net)
    record["finished"] = True
    record["wall_s"] = round(time.perf_counter() - started, 1)
    write_json(path, record)
    return record


def main(argv=None) -> int:
    from experiments.fit_pose_prior import TRAIN_DIR, positive_integers

    p = argparse.ArgumentParser(prog="python -m experiments.lifter_learning_curve",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("--train", type=Path, default=TRAIN_DIR)
    p.add_argument("--out", type=Path, default=OUT)
    p.add_argument("--hold-out", default=",".join(HOLD_OUT), help="CMU subjects left out together (comma-separated)")
    p.add_argument("--budgets", default=",".join(map(str, BUDGETS)), help="training steps of each run")
    p.add_argument("--every", type=int, default=EVERY, help="measure every this many steps along a run (0: at its end)")
    p.add_argument("--queries", type=int, default=QUERIES, help="held-out poses per subject")
    p.add_argument("--hidden", default=None, help="hidden layer widths (default the shipped network's)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--figure-only", action="store_true", help="redraw the figure from the run files in --out")
    args = p.parse_args(argv)
    from experiments.figures import ext_lifter_learning_curve

    if args.figure_only:
        runs = read_runs(args.out)
        if not runs:
            print(f"error: no run files in {args.out}", file=sys.stderr)
            return 2
        print("\n".join(str(f) for f in ext_lifter_learning_curve.main(runs, args.out)))
        return 0
    from experiments.fit_lifter import HIDDEN

    budgets = positive_integers(args.budgets)
    hidden = positive_integers(args.hidden) if args.hidden else HIDDEN
    hold_out = tuple(s.strip() for s in args.hold_out.split(",") if s.strip())
    if not budgets or not hidden or not hold_out or args.every < 0 or args.queries < 1:
        print("error: --budgets and --hidden take positive integers, --hold-out subjects, --every >= 0, "
              "--queries >= 1", file=sys.stderr)
        return 2
    if not args.train.is_dir():
        print(f"error: no training folder {args.train}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    from experiments.fit_lifter import command_line

    command = command_line("python -m experiments.lifter_learning_curve", argv if argv is not None else sys.argv[1:])
    for budget in budgets:
        try:
            run(args.train, args.out, budget, hold_out, args.every, args.seed, args.queries, tuple(hidden), command)
        except ValueError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
    print("\n".join(str(f) for f in ext_lifter_learning_curve.main(read_runs(args.out), args.out)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
