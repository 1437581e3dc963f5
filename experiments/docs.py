"""``python -m experiments.docs``: measure, and write ``docs/results.md`` from the measurements.

``docs/results.md`` is never edited by hand. This command measures what it shows and writes it:

1. speed: ``mocap bench`` (:func:`mocap.bench.run_benchmark`), or a stored ``--bench-json``;
2. accuracy against ground truth: the six synthetic sequences (seed 0, 160x120) tracked with the
   default :class:`~mocap.track.TrackerConfig` at each ``--evaluations`` budget with the true
   calibration, and at the last budget after automatic first-frame calibration; medians over the
   sequences (``mocap track`` writes the same ``run.json`` metrics);
3. the bundled default sequence tracked as ``python -m mocap demo`` does.

Measurements are kept in ``WORK/measurements.json`` (and every run folder under ``WORK``, so
an interrupted command resumes); ``--from-json`` rewrites the page from stored measurements
without measuring. Tracking is pinned to one core as the benchmark is. The page's ``## Throughput``
section, written by ``python -m experiments.throughput --docs``, is kept as it is.
"""
from __future__ import annotations

import argparse
import datetime
import subprocess
import sys
from pathlib import Path

import numpy as np

from experiments import EXPERIMENTS_DIR, throughput
from experiments.tables import PAPER_TABLE2
from mocap.io.files import read_json, write_json, write_text_atomic

#: Where the page goes by default.
DOCS_RESULTS = EXPERIMENTS_DIR.parent / "docs" / "results.md"
#: Budgets (cost evaluations per frame) of the accuracy table by default.
DEFAULT_EVALUATIONS = (100, 200, 500)
#: The bench's cost and render stages, as the page names them.
BENCH_STAGES = (("cost_region", "one evaluation, render + F (µs)"),
                ("cost_edge", "one evaluation, render + edge distance (µs)"),
                ("render", "label render, public call (µs)"),
                ("llvmpipe_render", "Mesa llvmpipe render + read-back (µs)"))
BENCH_SIZES = ((160, 120), (320, 240), (640, 480))
#: Metrics of ``run.json`` shown, with their column titles and digits.
METRIC_COLUMNS = (("mpjpe_mm", "MPJPE (mm)", 0), ("pa_mpjpe_mm", "PA-MPJPE (mm)", 0),
                  ("angle_error_deg", "joint angles (°)", 1), ("reprojection_px", "reprojection (px)", 1),
                  ("failure_rate", "frames > 100 mm", None), ("fps", "fps", 0))


def _git_commit(root: Path) -> str:
    try:
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, check=True)
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
        return out.stdout.strip() + (" (with uncommitted changes)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def _track(seq, calibration, out: Path, evaluations: int | None, frames: int | None) -> dict:
    """Track one sequence folder; the ``run.json`` metrics (resumes a finished or partial run)."""
    import mocap.run
    from mocap.track import TrackerConfig

    config = TrackerConfig() if evaluations is None else TrackerConfig(evaluations=evaluations)
    out.parent.mkdir(parents=True, exist_ok=True)
    calibration_file = out.parent / f"{out.name}.calibration.json"     # beside the run: its folder holds one run
    calibration.to_json(calibration_file)
    options = mocap.run.OwnVideoOptions(calibration=str(calibration_file), max_frames=frames, overlay=False,
                                        tracker=config, keypoints="none")
    summary = mocap.run.track(seq.root, out, options, progress=False)
    return dict(summary.metrics)


def measure(work: str | Path, *, evaluations=DEFAULT_EVALUATIONS, names=None, frames: int | None = None,
            auto_calibration: bool = True, bench: bool = True, bench_json: str | Path | None = None,
            progress: bool = True) -> dict:
    """Run every measurement of the page; returns (and stores in ``work/measurements.json``) them.

    Parameters
    ----------
    work : path
        Folder for the generated sequences and tracking runs (kept: reruns resume).
    evaluations : sequence of int
        Budgets of the accuracy table.
    names : sequence of str, optional
        Sequences (default all six of :data:`mocap.synth.SEQUENCE_NAMES`).
    frames : int, optional
        Track only the first ``frames`` frames of each (default: all; for quick checks).
    auto_calibration : bool
        Also the row with automatic first-frame calibration (at the last budget).
    bench, bench_json :
        Run ``mocap bench``, or read its ``--json`` output from ``bench_json``.
    """
    from tqdm import tqdm

    from mocap.bench import pin_to_one_core, run_benchmark
    from mocap.calibrate import Calibration, auto_calibrate
    from mocap.io.sequence import find_sequence
    from mocap.io.video import iter_frames, read_image
    from mocap.synth import SEQUENCE_NAMES
    from mocap.synth.datasets import default_sequence, make_benchmark

    work = Path(work)
    names = tuple(SEQUENCE_NAMES if names is None else names)
    evaluations = tuple(int(e) for e in evaluations)
    if not evaluations or min(evaluations) < 1:
        raise ValueError(f"evaluations must be positive budgets, got {evaluations}")
    result = {"date": datetime.date.today().isoformat(), "commit": _git_commit(EXPERIMENTS_DIR.parent),
              "sequences": list(names), "frames": frames, "seed": 0, "size": [160, 120],
              "evaluations": list(evaluations), "tracking": [], "per_sequence": {}}
    if bench_json is not None:
        result["bench"] = read_json(bench_json)
    elif bench:
        result["bench"] = run_benchmark(progress=progress)
    pin_to_one_core()
    folders = make_benchmark(work / "data", seed=0, size=(160, 120), frames=frames, names=names, progress=progress)
    rows = [(f"{e}", e, False) for e in evaluations]
    if auto_calibration:
        rows.append((f"{evaluations[-1]}, automatic calibration", evaluations[-1], True))
    jobs = [(label, e, auto, folder) for label, e, auto in rows for folder in folders]
    per_row: dict[str, list[dict]] = {label: [] for label, _, _ in rows}
    for label, e, auto, folder in tqdm(jobs, desc="tracking", unit="run", disable=not progress, file=sys.stderr):
        seq = find_sequence(folder)
        calibration = Calibration.from_json(seq.calibration)
        if auto:
            cal_file = work / "calibration" / f"{folder.name}.json"
            if cal_file.is_file():
                calibration = Calibration.from_json(cal_file)
            else:
                first = next(iter_frames(seq.frames, 0, 1))
                calibration = auto_calibrate(first, read_image(seq.background), calibration.camera)
                calibration.to_json(cal_file)
        tag = f"{folder.name}-{e}{'-auto' if auto else ''}"
        metrics = _track(seq, calibration, work / "runs" / tag, e, frames)
        per_row[label].append(metrics)
        result["per_sequence"][tag] = metrics
    for label, _, _ in rows:
        runs = per_row[label]
        row = {"label": label}
        for key, _, _ in METRIC_COLUMNS:
            values = np.array([r[key] for r in runs], dtype=float)
            row[key] = float(np.median(values))
            row[key + "_range"] = [float(values.min()), float(values.max())]
        result["tracking"].append(row)
    demo = find_sequence(default_sequence(work / "default", progress=progress))
    result["demo"] = _track(demo, Calibration.from_json(demo.calibration), work / "runs" / "demo", None, frames)
    write_json(work / "measurements.json", result)
    return result


def _num(v: float, digits: int) -> str:
    return f"{v:,.{digits}f}" if digits else f"{v:,.0f}"


def _bench_section(bench: dict) -> list[str]:
    rows = {(r["stage"], r["width"], r["height"]): r["median_us"] for r in bench["rows"]}
    sizes = [s for s in BENCH_SIZES if ("cost_region", *s) in rows]
    if not sizes:
        return []
    head = "| stage | " + " | ".join(f"{w}x{h}" for w, h in sizes) + " | the paper (GPU) |"
    out = ["## Speed", "", "`python -m mocap bench` (medians on one core; renders over 256 varied poses):", "",
           head, "|---" * (len(sizes) + 2) + "|"]

    def cell(v):
        return "" if v is None else _num(v, 1 if v < 100 else 0)

    paper = {"cost_region": 1, "cost_edge": 2}
    for stage, title in BENCH_STAGES:
        values = [rows.get((stage, *s)) for s in sizes]
        if all(v is None for v in values):
            continue
        ref = " / ".join(_num(PAPER_TABLE2[s][paper[stage]] * 1000, 0) for s in sizes) if stage in paper else ""
        out.append(f"| {title} | " + " | ".join(cell(v) for v in values) + f" | {ref} |")
    ratios = [rows.get(("llvmpipe_render", *s)) / rows[("render", *s)]
              if rows.get(("llvmpipe_render", *s)) and rows.get(("render", *s)) else None for s in sizes]
    if any(r is not None for r in ratios):
        out.append("| llvmpipe / ours | " + " | ".join("" if r is None else f"{r:.1f}x" for r in ratios) + " | |")
    prep = [rows.get(("prepare_frame", *s)) for s in sizes]
    if any(v is not None for v in prep):
        out.append("| image side, `prepare_frame` (ms) | " + " | ".join("" if v is None else f"{v / 1000:.1f}" for v in prep)
                   + " | " + " / ".join(_num(PAPER_TABLE2[s][0], 0) for s in sizes) + " |")
    for budget in (100, 500):
        v = rows.get((f"frame_{budget}", 160, 120))
        if v is not None:
            out.append(f"\nA whole frame at 160x120 (image side + registration) at {budget} evaluations: "
                       f"{v / 1000:.1f} ms ({1e6 / v:.0f} frames per second).")
    out += ["", f"CPU: {bench.get('cpu', 'unknown')}; " + "; ".join(bench.get("notes", [])) if bench.get("notes")
            else f"CPU: {bench.get('cpu', 'unknown')}.", ""]
    return out


def render_page(m: dict) -> str:
    """The Markdown of ``docs/results.md`` from :func:`measure`'s result."""
    frames = "all frames" if m["frames"] is None else f"the first {m['frames']} frames"
    out = ["# Measured results", "",
           f"Written by `python -m experiments.docs` on {m['date']} at commit {m['commit']}; do not edit by hand "
           "(rerun the command). History and what was tried: [research-log.md](research-log.md).", ""]
    if "bench" in m:
        out += _bench_section(m["bench"])
    names = ", ".join(f"`{n}`" for n in m["sequences"])
    out += ["## Accuracy against ground truth", "",
            f"Sequences {names} (seed {m['seed']}, {m['size'][0]}x{m['size'][1]}, {frames}), default tracker, true "
            "calibration unless the row says otherwise; median over the sequences (MPJPE: min–max in brackets); "
            "fps on one core, image side included. Each row is "
            "`python -m mocap synth NAME --out DIR` then `python -m mocap track DIR --iterations N` "
            "(automatic calibration: `python -m mocap calibrate DIR --background DIR/background.png` and "
            "`--calibration calibration.json`).", "",
            "| evaluations / frame | " + " | ".join(t for _, t, _ in METRIC_COLUMNS) + " |",
            "|---" * (len(METRIC_COLUMNS) + 1) + "|"]
    for row in m["tracking"]:
        cells = []
        for key, _, digits in METRIC_COLUMNS:
            if key == "failure_rate":
                cells.append(f"{100 * row[key]:.0f} %")
            elif key == "mpjpe_mm":
                lo, hi = row[key + "_range"]
                cells.append(f"{row[key]:.0f} ({lo:.0f}–{hi:.0f})")
            else:
                cells.append(_num(row[key], digits))
        out.append(f"| {row['label']} | " + " | ".join(cells) + " |")
    d = m["demo"]
    out += ["", f"The bundled default sequence (`python -m mocap demo`, {frames}): MPJPE {d['mpjpe_mm']:.0f} mm, "
            f"PA-MPJPE {d['pa_mpjpe_mm']:.0f} mm, {d['reprojection_px']:.2f} px reprojection, "
            f"{100 * d['failure_rate']:.0f} % of frames over 100 mm, {d['fps']:.0f} fps.", "",
            "Per sequence (MPJPE, mm):", "", "| run | MPJPE | frames > 100 mm |", "|---|---|---|"]
    out += [f"| {tag} | {r['mpjpe_mm']:.0f} | {100 * r['failure_rate']:.0f} % |" for tag, r in m["per_sequence"].items()]
    out += ["", "The paper's own experiments, reproduced: [experiments/REPORT.md](../experiments/REPORT.md)."]
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.docs", description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=DOCS_RESULTS, help="page to write (default docs/results.md)")
    parser.add_argument("--work", type=Path, default=EXPERIMENTS_DIR / "results" / "docs",
                        help="folder for sequences, runs and measurements.json (default experiments/results/docs)")
    parser.add_argument("--evaluations", default=",".join(map(str, DEFAULT_EVALUATIONS)), metavar="N,N,...",
                        help="budgets of the accuracy table (default 100,200,500)")
    parser.add_argument("--only", nargs="+", metavar="NAME", default=None, help="sequences (default all six)")
    parser.add_argument("--frames", type=int, default=None, metavar="N", help="only the first N frames (quick checks)")
    parser.add_argument("--no-auto-calibration", action="store_true", help="leave out the automatic-calibration row")
    parser.add_argument("--no-bench", action="store_true", help="leave out the speed table")
    parser.add_argument("--bench-json", type=Path, default=None, help="read `mocap bench --json` output instead of running it")
    parser.add_argument("--from-json", type=Path, default=None, help="write the page from stored measurements.json")
    args = parser.parse_args(argv)
    try:
        if args.from_json is not None:
            m = read_json(args.from_json)
        else:
            budgets = tuple(int(e) for e in args.evaluations.split(","))
            m = measure(args.work, evaluations=budgets, names=args.only, frames=args.frames,
                        auto_calibration=not args.no_auto_calibration, bench=not args.no_bench,
                        bench_json=args.bench_json)
        kept = throughput.section_of(args.out)     # measured apart (python -m experiments.throughput --docs)
        write_text_atomic(args.out, render_page(m))
        if kept is not None:
            throughput.replace_section(args.out, kept)
    except (ValueError, OSError, KeyError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
