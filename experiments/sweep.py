"""``python -m experiments.sweep``: the paper's experiments over region x edge budgets.

Runs, on the named synthetic sequences (and with ``--motion-dir`` on the same actors driven
by every motion-capture clip there), the tracker over the grid of region-step x edge-step
budgets (Figs. 9-12), the converged and limited runs (Figs. 4, 6), the edge-start runs
(Fig. 8), the split policies, the Table 1 timing runs and the Table 2 timings. With
``--gradient`` the grid and Fig. 4's two-step runs are run again with the gradient step on.

Results go to ``--out`` (default ``experiments/results/full`` or ``.../quick``): one file
per finished unit, written atomically, so an interrupted sweep loses nothing and the same
command resumes where it stopped. Work runs on local processes (``--workers``, 2 by default)
or on a Dask distributed cluster (``--scheduler ADDRESS``); a progress bar shows it either way.

Layout of the results folder::

    config.json                 the SweepConfig of the last invocation
    sweep.json                  clips used, and a log of every invocation (wall time, counts)
    data/<sequence key>/        generated sequence folder + prepared.npz (image side, once)
    units/<sequence key>/<run key>.npz   per-frame results of one run unit
    table2.json                 image processing and cost timings per resolution
"""
from __future__ import annotations

import argparse
import concurrent.futures
import json
import multiprocessing
import sys
import time
from dataclasses import asdict, dataclass, field
from datetime import datetime, timezone
from pathlib import Path

from experiments import RESULTS_DIR
from experiments.config import SweepConfig
from experiments.plan import Plan, find_clips, make_plan
from experiments.units import (PREPARED_FILE, data_folder, measure_table2, prepare_data, run_unit,
                               save_unit)
from mocap.io.files import write_text_atomic

#: Names of the result files at the top of a results folder.
CONFIG_FILE, SWEEP_FILE, TABLE2_FILE = "config.json", "sweep.json", "table2.json"


@dataclass
class SweepSummary:
    """What one invocation did.

    Attributes
    ----------
    computed : int
        Units run and written now.
    skipped : int
        Units already in the results folder (resumed).
    remaining : int
        Units left undone (stopped early by ``max_units``).
    errors : list of str
        Units that raised (the sweep goes on without them).
    wall_s : float
        Seconds.
    """

    computed: int = 0
    skipped: int = 0
    remaining: int = 0
    errors: list[str] = field(default_factory=list)
    wall_s: float = 0.0


class _InlineFuture:
    """A finished future (the ``workers=0`` backend runs everything in this process)."""

    def __init__(self, fn, args) -> None:
        self._value = self._error = None
        try:
            self._value = fn(*args)
        except Exception as exc:              # re-raised by result(), as a real future would
            self._error = exc

    def result(self):
        if self._error is not None:
            raise self._error
        return self._value

    def cancel(self) -> bool:
        return False


class _Backend:
    """Submits work to local processes, to this process, or to a Dask cluster."""

    def __init__(self, workers: int, scheduler: str | None) -> None:
        self.client = self.pool = None
        self.description = "inline"
        if scheduler is not None:
            from distributed import Client
            self.client = Client(scheduler)
            self.description = f"dask {scheduler}"
        elif workers > 0:
            self.pool = concurrent.futures.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"))
            self.description = f"{workers} local processes"

    def submit(self, fn, *args):
        if self.client is not None:
            return self.client.submit(fn, *args, pure=False)
        if self.pool is not None:
            return self.pool.submit(fn, *args)
        return _InlineFuture(fn, args)

    def as_completed(self, futures):
        if self.client is not None:
            from distributed import as_completed
            return as_completed(list(futures))
        if self.pool is not None:
            return concurrent.futures.as_completed(list(futures))
        return iter(list(futures))

    def close(self, futures=()) -> None:
        for f in futures:
            f.cancel()
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=True)
        if self.client is not None:
            self.client.close()


def code_version() -> str:
    """Commit of the checkout the sweep runs from (``+dirty`` with uncommitted changes), or ``unknown``."""
    import subprocess

    here = Path(__file__).resolve().parent
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=10)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here,
                               capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    if commit.returncode != 0:
        return "unknown"
    return commit.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")


def _log_invocation(out: Path, entry: dict, clips) -> None:
    path = out / SWEEP_FILE
    log = json.loads(path.read_text()) if path.is_file() else {"invocations": []}
    log["clips"] = list(clips)
    log["invocations"].append(entry)
    write_text_atomic(path, json.dumps(log, indent=2))


def run_sweep(config: SweepConfig, out: str | Path, *, workers: int = 2, scheduler: str | None = None,
              motion_dir: str | Path | None = None, max_units: int | None = None, progress: bool = True,
              table2: bool = True) -> SweepSummary:
    """Run (or resume) a sweep and write its results.

    Parameters
    ----------
    config : SweepConfig
    out : str or Path
        Results folder (created). Finished units found there are not run again.
    workers : int
        Local worker processes; 0 runs everything in this process. Ignored with ``scheduler``.
    scheduler : str, optional
        Address of a Dask distributed scheduler (``tcp://host:8786``); its workers must see
        ``out`` (same machine or shared file system).
    motion_dir : str or Path, optional
        Folder of motion-capture clips driving the ``motion_actors`` too.
    max_units : int, optional
        Stop after this many units have been computed (the rest is left for a later resume).
    progress : bool
        Show progress bars.
    table2 : bool
        Also time Table 2 (image processing and costs per resolution).

    Returns
    -------
    SweepSummary

    Raises
    ------
    ValueError
        On a bad worker count, unit limit, or motion folder.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
        raise ValueError(f"workers must be a non-negative integer, got {workers!r}")
    if max_units is not None and (isinstance(max_units, bool) or not isinstance(max_units, int) or max_units < 1):
        raise ValueError(f"max_units must be a positive integer, got {max_units!r}")
    clips = find_clips(motion_dir) if motion_dir is not None else ()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    config.to_json(out / CONFIG_FILE)
    plan = make_plan(config, clips)
    root = str(out.resolve())
    summary = SweepSummary()
    started = time.perf_counter()
    when = datetime.now(timezone.utc).isoformat(timespec="seconds")
    version = code_version()
    backend = _Backend(workers, scheduler)
    futures: dict = {}
    try:
        _data_phase(plan, root, backend, progress, summary)
        budget = [max_units]                    # units still allowed (None: no limit)
        _run_phase(plan.runs, root, backend, progress, summary, budget, "runs", parallel=True)
        _run_phase(plan.timing, root, backend, progress, summary, budget, "timing (alone)", parallel=False)
        if table2 and not (out / TABLE2_FILE).is_file():
            if budget[0] is not None and budget[0] <= 0:
                summary.remaining += 1
            else:
                fut = backend.submit(measure_table2, config.table2_sizes, config.figure_sequence,
                                     config.table2_frames, config.seed, config.table2_min_runs,
                                     config.table2_min_seconds, root)
                futures = {fut: "table2"}
                write_text_atomic(out / TABLE2_FILE, json.dumps(fut.result(), indent=2))
                summary.computed += 1
        elif table2:
            summary.skipped += 1
    finally:
        backend.close(futures)
        summary.wall_s = time.perf_counter() - started
        _log_invocation(out, {"started_utc": when, "backend": backend.description, "code": version,
                              **asdict(summary)}, clips)
    return summary


def _data_phase(plan: Plan, root: str, backend: _Backend, progress: bool, summary: SweepSummary) -> None:
    from tqdm import tqdm

    todo = [d for d in plan.data if not (data_folder(d, root) / PREPARED_FILE).is_file()]
    if not todo:
        return
    futures = {backend.submit(prepare_data, d, root): d for d in todo}
    with tqdm(total=len(todo), desc="sequences", unit="seq", disable=not progress) as bar:
        for fut in backend.as_completed(futures):
            try:
                fut.result()
            except Exception as exc:           # a sequence that cannot be made stops the sweep
                raise RuntimeError(f"could not make sequence {futures[fut].key}: {type(exc).__name__}: {exc}") from exc
            bar.update(1)


def _run_phase(specs, root: str, backend: _Backend, progress: bool, summary: SweepSummary, budget: list,
               description: str, *, parallel: bool) -> None:
    from tqdm import tqdm

    pending = [s for s in specs if not s.path(root).is_file()]
    summary.skipped += len(specs) - len(pending)
    if budget[0] is not None:
        summary.remaining += max(0, len(pending) - budget[0])
        pending = pending[:budget[0]]
        budget[0] -= len(pending)
    if not specs:
        return
    bar = tqdm(total=len(specs), initial=len(specs) - len(pending), desc=description, unit="unit",
               disable=not progress)
    futures: dict = {}
    try:
        if parallel:
            futures = {backend.submit(run_unit, s, root): s for s in pending}
            finished = backend.as_completed(futures)
        else:
            finished = _one_at_a_time(backend, pending, root, futures)
        for fut in finished:
            spec = futures.pop(fut)
            try:
                save_unit(spec.path(root), fut.result())
                summary.computed += 1
            except Exception as exc:           # recorded; the sweep goes on without this unit
                summary.errors.append(f"{spec.data.key}/{spec.key}: {type(exc).__name__}: {exc}")
            bar.update(1)
    finally:
        for f in futures:
            f.cancel()
        bar.close()


def _one_at_a_time(backend: _Backend, specs, root: str, futures: dict):
    """Submit run units one after the other, each when the previous one is done (timing runs)."""
    for spec in specs:
        fut = backend.submit(run_unit, spec, root)
        futures[fut] = spec
        yield fut


def _parse_budgets(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"budgets must be comma-separated integers, got {text!r}") from None


def _parse_names(text: str) -> tuple[str, ...]:
    return tuple(v.strip() for v in text.split(",") if v.strip())


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m experiments.sweep", description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="small preset: a few minutes on 2 cores")
    p.add_argument("--config", type=Path, help="SweepConfig JSON (replaces the preset)")
    p.add_argument("--out", type=Path, help="results folder (default experiments/results/full or .../quick)")
    p.add_argument("--scheduler", help="Dask distributed scheduler address (default: local processes)")
    p.add_argument("--workers", type=int, default=2, help="local worker processes (0: in this process)")
    p.add_argument("--motion-dir", type=Path, help="folder of .bvh/.amc clips driving the actors too")
    p.add_argument("--sequences", type=_parse_names, help="comma-separated sequence names")
    p.add_argument("--frames", type=int, help="frames per sequence")
    p.add_argument("--region-budgets", type=_parse_budgets, help="comma-separated region-step budgets")
    p.add_argument("--edge-budgets", type=_parse_budgets, help="comma-separated edge-step budgets")
    p.add_argument("--gradient", action="store_true",
                   help="also run the grid and Fig. 4 with the gradient step on (a twin of each surface)")
    p.add_argument("--max-units", type=int, help="stop after computing this many units (resume later)")
    p.add_argument("--no-table2", action="store_true", help="skip the Table 2 timings")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    return p


def config_from_args(args: argparse.Namespace) -> SweepConfig:
    """The SweepConfig of the command line (preset or ``--config``, then overrides)."""
    config = SweepConfig.from_json(args.config) if args.config else SweepConfig.preset("quick" if args.quick else "full")
    changes = {}
    if args.sequences is not None:
        changes["sequences"] = args.sequences
        if config.figure_sequence not in args.sequences:
            changes["figure_sequence"] = args.sequences[0]
        changes["timing_sequences"] = tuple(s for s in config.timing_sequences if s in args.sequences) or args.sequences[:1]
    for name in ("frames", "region_budgets", "edge_budgets"):
        if getattr(args, name) is not None:
            changes[name] = getattr(args, name)
    if args.gradient:
        changes["gradient"] = True
    return config.with_changes(changes) if changes else config


def main(argv=None) -> int:
    """Command line entry point; returns the exit status (2 on bad input, 1 if units failed)."""
    args = build_parser().parse_args(argv)
    try:
        if args.config is not None and not args.config.is_file():
            raise ValueError(f"config file {args.config} does not exist")
        config = config_from_args(args)
        out = args.out or RESULTS_DIR / ("quick" if args.quick else "full")
        summary = run_sweep(config, out, workers=args.workers, scheduler=args.scheduler, motion_dir=args.motion_dir,
                            max_units=args.max_units, progress=not args.no_progress, table2=not args.no_table2)
    except ValueError as exc:
        print(f"experiments.sweep: error: {exc}", file=sys.stderr)
        return 2
    except RuntimeError as exc:
        print(f"experiments.sweep: {exc}", file=sys.stderr)
        return 1
    print(f"{summary.computed} units computed, {summary.skipped} already there, {summary.remaining} left, "
          f"{len(summary.errors)} failed, {summary.wall_s:.0f} s -> {out}")
    for e in summary.errors:
        print(f"failed: {e}", file=sys.stderr)
    return 1 if summary.errors else 0


if __name__ == "__main__":
    sys.exit(main())
