"""Two commits' speed, alternated on this machine: ``python -m experiments.speed_ab OLD_REF [NEW_REF]`` (issue 45).

``python -m experiments.speed_ab OLD_REF [NEW_REF] [--pairs 5] [--groups render frame] [--out DIR]``

Each commit is checked out in a git worktree of its own (``.git/speed_ab-trees/<sha>``, kept
for the next call with its compiled-kernel caches; NEW_REF by default
is this checkout itself, its uncommitted changes included), and ``python -m mocap bench --json
--no-llvmpipe --groups ...`` runs in each tree in turn: ``--pairs`` pairs, the order swapped from
one pair to the next (old-new, new-old, ...) so that a drift in the machine's state falls on both
alike. Each tree's first run is preceded by an untimed ``--quick`` run of the same groups, so the
Numba caches of both trees are compiled before anything is timed. The bench times every row
but the ``video_640x480`` ones in CPU time of its timing thread on one pinned core
(:data:`mocap.bench.CLOCK`).

For every row (stage and size) measured in both trees it prints the ratio new / old of the
**fastest** run of each tree (the lowest of each run's median over the pairs), and the spread of
the per-pair ratios (the lowest and highest ``new_k / old_k``): a row whose spread holds 1.00
did not change measurably. Interference on a shared machine only ever slows a run, so the
fastest run is the one least disturbed: the median of the runs read 0.72-0.92 on the frame rows
of identical code (issue 50), a spread the minimum narrows (the research log, 2026-11-29, has
the identical-code check). Identical code reads 1.00 ± 0.05 on the render and cost rows on a
quiet machine (the research log, 2026-11-28).

A run warns when the 1-minute load average is above :data:`QUIET_LOAD` before it starts: on two
cores a second busy process swings the frame rows by up to 1.4x (issue 45). It warns too when
``mocap/bench.py`` differs between the trees: the two benches then measure with different
harnesses as well as different code.

Nothing is lost when a run is cut: each bench's JSON is written to ``DIR/runs/<k>-<old|new>.json``
as it ends, and the same command skips the runs already there (``--fresh`` starts over).
``DIR/speed_ab.json`` holds the summary: the refs, their commits, the load before each run, every
row's per-run medians, ratio and spread; ``DIR/speed_ab.md`` the table. DIR defaults to
``experiments/results/speed_ab/<old>-<new>`` (short shas; ``worktree`` for uncommitted changes).
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import shutil
import subprocess
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

from experiments import EXPERIMENTS_DIR

#: Load average (1 min) above which a run warns that its timings are not to be trusted.
QUIET_LOAD = 1.5
#: The bench groups compared by default: the render and cost rows, and the whole frames.
DEFAULT_GROUPS = ("render", "frame")
#: The repository this experiment belongs to.
REPO_ROOT = EXPERIMENTS_DIR.parent


@dataclass(frozen=True)
class RowComparison:
    """One bench row (stage at a size) in both trees.

    Attributes
    ----------
    stage : str
        The bench's stage name (``render``, ``cost_region``, ``frame_500``, ...).
    size : str
        ``WxH`` in pixels.
    old_us, new_us : list of float
        Each run's median (microseconds), in the order of the pairs.
    ratio : float
        ``min(new_us) / min(old_us)``: the fastest runs'.
    low, high : float
        The lowest and highest per-pair ratio ``new_us[k] / old_us[k]``.
    """

    stage: str
    size: str
    old_us: list[float]
    new_us: list[float]
    ratio: float
    low: float
    high: float


def _git(*args: str, cwd: Path = REPO_ROOT) -> str:
    done = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True)
    if done.returncode != 0:
        raise ValueError(f"git {' '.join(args)}: {done.stderr.strip().splitlines()[-1] if done.stderr.strip() else 'failed'}")
    return done.stdout.strip()


def resolve(ref: str | None) -> tuple[str, str]:
    """``(sha, label)`` of a ref; None is this checkout as it stands (``label`` ``worktree`` when
    it has uncommitted changes to tracked files, else its HEAD's short sha)."""
    if ref is None:
        sha = _git("rev-parse", "HEAD")
        dirty = bool(_git("status", "--porcelain", "--untracked-files=no"))
        return sha, "worktree" if dirty else sha[:7]
    sha = _git("rev-parse", "--verify", f"{ref}^{{commit}}")
    return sha, sha[:7]


def tree_of(sha: str | None, trees: Path) -> Path:
    """The folder to run a tree's bench in: this checkout for None, else a detached worktree of
    ``sha`` under ``trees`` (made once, kept for the next call)."""
    if sha is None:
        return REPO_ROOT
    folder = trees / sha[:12]
    if not (folder / "mocap" / "bench.py").is_file():
        if folder.exists():
            _git("worktree", "remove", "--force", str(folder))
        trees.mkdir(parents=True, exist_ok=True)
        _git("worktree", "add", "--detach", str(folder), sha)
    return folder


def bench_command(groups, quick: bool = False) -> list[str]:
    """The bench as a tree runs it (``python -m mocap`` imports the tree's own ``mocap``: the
    working directory comes first on ``sys.path``)."""
    return [sys.executable, "-m", "mocap", "bench", "--json", "--no-llvmpipe", *(["--quick"] if quick else []),
            "--groups", *groups]


def run_bench(tree: Path, groups, quick: bool = False) -> dict:
    """One bench run in ``tree``: its JSON result (ValueError with its last error line if it fails)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(bench_command(groups, quick), cwd=tree, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no output"])[-1]
        raise ValueError(f"the bench failed in {tree}: {last}")
    return json.loads(done.stdout)


def load_average() -> float | None:
    """The 1-minute load average, None where the OS does not tell."""
    try:
        return os.getloadavg()[0]
    except (AttributeError, OSError):
        return None


def schedule(pairs: int) -> list[tuple[int, str]]:
    """The runs in order: ``(pair, "old" or "new")``, the order swapped from one pair to the next."""
    order = []
    for k in range(pairs):
        first, second = ("old", "new") if k % 2 == 0 else ("new", "old")
        order += [(k, first), (k, second)]
    return order


def compare(old_runs: list[dict], new_runs: list[dict]) -> list[RowComparison]:
    """Every row measured in all runs of both trees, in the old bench's row order."""
    def medians(runs):
        table: dict[tuple[str, str], list[float]] = {}
        for run in runs:
            for row in run["rows"]:
                table.setdefault((row["stage"], f"{row['width']}x{row['height']}"), []).append(row["median_us"])
        return {key: values for key, values in table.items() if len(values) == len(runs)}

    old, new = medians(old_runs), medians(new_runs)
    rows = []
    for key, old_us in old.items():
        if key not in new:
            continue
        new_us = new[key]
        per_pair = [n / o for n, o in zip(new_us, old_us)]
        rows.append(RowComparison(stage=key[0], size=key[1], old_us=old_us, new_us=new_us,
                                  ratio=min(new_us) / min(old_us),
                                  low=min(per_pair), high=max(per_pair)))
    return rows


def format_table(rows: list[RowComparison], old_label: str, new_label: str) -> str:
    """The comparison as a Markdown table (the fastest run's median in µs, the ratio and its spread)."""
    lines = [f"| stage | size | {old_label} µs | {new_label} µs | new / old | spread |",
             "|---|---|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| {r.stage} | {r.size} | {min(r.old_us):.1f} | {min(r.new_us):.1f} "
                     f"| {r.ratio:.2f} | {r.low:.2f}-{r.high:.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.speed_ab", description=__doc__.splitlines()[0])
    p.add_argument("old", metavar="OLD_REF", help="the commit to compare against (any git ref)")
    p.add_argument("new", metavar="NEW_REF", nargs="?", default=None,
                   help="the commit measured against it (default: this checkout, uncommitted changes included)")
    p.add_argument("--pairs", type=int, default=5, help="alternated pairs of bench runs (at least 3; default 5)")
    p.add_argument("--groups", nargs="+", default=list(DEFAULT_GROUPS), metavar="GROUP",
                   help=f"bench groups (default: {' '.join(DEFAULT_GROUPS)})")
    p.add_argument("--out", type=Path, default=None, help="results folder (default experiments/results/speed_ab/OLD-NEW)")
    p.add_argument("--fresh", action="store_true", help="discard the runs a cut command left in --out")
    args = p.parse_args(argv)
    if args.pairs < 3:
        p.error("--pairs must be at least 3 (one pair cannot tell a change from the machine's swing)")
    try:
        old_sha, old_label = resolve(args.old)
        new_sha, new_label = resolve(args.new)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    out = args.out or EXPERIMENTS_DIR / "results" / "speed_ab" / f"{old_label}-{new_label}"
    runs_dir = out / "runs"
    if args.fresh and runs_dir.exists():
        shutil.rmtree(runs_dir)
    runs_dir.mkdir(parents=True, exist_ok=True)
    trees = Path(_git("rev-parse", "--path-format=absolute", "--git-common-dir")) / "speed_ab-trees"
    try:
        folders = {"old": tree_of(old_sha, trees), "new": tree_of(None if args.new is None else new_sha, trees)}
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if (folders["old"] / "mocap" / "bench.py").read_bytes() != (folders["new"] / "mocap" / "bench.py").read_bytes():
        print("warning: mocap/bench.py differs between the trees: their harnesses differ as well as their code",
              file=sys.stderr)
    loads: dict[str, float | None] = {}
    results: dict[str, list[dict]] = {"old": [], "new": []}
    warmed = set()
    for k, side in schedule(args.pairs):
        path = runs_dir / f"{k}-{side}.json"
        if path.is_file():
            results[side].append(json.loads(path.read_text()))
            continue
        try:
            if side not in warmed:              # both trees' kernels compiled before anything is timed
                run_bench(folders[side], args.groups, quick=True)
                warmed.add(side)
            load = loads[path.stem] = load_average()
            if load is not None and load > QUIET_LOAD:
                print(f"warning: load average {load:.2f} before run {path.stem} (above {QUIET_LOAD}): "
                      "its timings are not to be trusted", file=sys.stderr)
            result = run_bench(folders[side], args.groups)
        except ValueError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
        result["load_average"] = load
        path.write_text(json.dumps(result, indent=1))
        results[side].append(result)
        print(f"run {path.stem}: done (load {load if load is None else round(load, 2)})", file=sys.stderr)
    rows = compare(results["old"], results["new"])
    table = format_table(rows, old_label, new_label)
    summary = {"old": {"ref": args.old, "sha": old_sha}, "new": {"ref": args.new or "worktree", "sha": new_sha,
                                                              "label": new_label},
               "pairs": args.pairs, "groups": args.groups, "clock": results["new"][0].get("clock", "wall"),
               "load_averages": {side: [r.get("load_average") for r in results[side]] for side in ("old", "new")},
               "rows": [asdict(r) for r in rows], "command": " ".join(["python -m experiments.speed_ab", *sys.argv[1:]])
               if argv is None else " ".join(["python -m experiments.speed_ab", *argv]),
               "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
    (out / "speed_ab.json").write_text(json.dumps(summary, indent=1))
    (out / "speed_ab.md").write_text(table + "\n")
    print(table)
    print(f"written to {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
