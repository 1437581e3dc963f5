"""``python -m experiments.throughput``: frames per second of ``track`` on 1 and 2 cores, with and
without keypoints, next to MediaPipe's own time per frame.

Runs ``python -m mocap track CLIP --out DIR --overwrite --keypoints K`` (the command as a person
types it, default settings otherwise: overlay written; ``CLIP`` a video, or anything ``track``
takes, such as a sequence folder with its own calibration) as a subprocess pinned to the first 1 or 2
of this process's cores (``os.sched_setaffinity`` in the child before it starts, as ``taskset
-c`` does), for every pair of ``--cores`` and ``--keypoints``, alternating the pairs when
``--repeats`` is more than 1, so that all see the same load. For each run it keeps:

- ``fps``: ``run.json`` ``fps``, what ``track`` prints (1000 over the mean of the frames'
  ``ms_total``: the tracking thread's time per frame);
- ``loop_fps``: frames over ``run.json`` ``wall_seconds_this_session`` (decoding to the outputs,
  the set-up excluded);
- ``end_to_end_fps``: frames over the seconds from starting the command to its exit (imports,
  set-up, compiled-kernel cache and outputs included);
- ``keypoints_ms_per_frame``: ``run.json``'s median of MediaPipe's time per frame inside the run
  (beside the tracker, on the same cores).

MediaPipe's own time per frame is measured apart: :class:`mocap.io.mediapipe_keypoints.MediaPipeKeypoints`
on the same frames (input size), alone in a subprocess pinned to one core (median and mean of
its per-frame times; the decoding not counted), once in each repeat, after its runs. Runs with
``--keypoints mediapipe`` and that measurement need the optional extra ``keypoints``.

The table ends with the ratios issue 50 sets targets on, each taken within one repeat (whose
runs follow each other) and given as the median and range over the repeats (:func:`ratios`): a
run with MediaPipe on the most cores against MediaPipe alone (frames a second times MediaPipe
alone's seconds a frame), and each keypoint mode's time per frame on the most cores against one
core. The machine's speed drifts between calls by more than these ratios do within one.

Writes ``OUT/throughput.json`` (every run, the commands, the load average (1 min) before each
run, the cores, the CPU, the commit, the command) and ``OUT/throughput.md`` (one table: medians
over the repeats); ``--docs PAGE`` also puts the table into ``PAGE`` (``docs/results.md``) as its
``## Throughput`` section, replacing the one there; ``--from-json`` writes them from a stored
``throughput.json`` without measuring. Compare figures of one call only: the
machine may be shared (the load average says how much).
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from experiments import EXPERIMENTS_DIR

#: The real 640x480 clip measured by default.
DEFAULT_CLIP = EXPERIMENTS_DIR.parent.parent / "shared" / "data" / "video" / "intel_asl_book.mkv"
#: The heading of the section ``--docs`` writes.
SECTION = "## Throughput"


def pinned(cores: int):
    """A ``preexec_fn`` pinning the child to the first ``cores`` of this process's CPUs."""
    allowed = sorted(os.sched_getaffinity(0))
    if cores > len(allowed):
        raise ValueError(f"{cores} cores asked for, this process may use {len(allowed)}: {allowed}")
    chosen = set(allowed[:cores])
    return lambda: os.sched_setaffinity(0, chosen)


def track_run(clip: Path, out: Path, cores: int, keypoints: str, max_frames: int | None,
              threads: int | None = None) -> dict:
    """One ``track`` run pinned to ``cores`` cores (``threads``: its ``--threads``, None: track's
    default); its figures (see the module)."""
    from mocap.run import files

    command = [sys.executable, "-m", "mocap", "track", str(clip), "--out", str(out), "--overwrite",
               "--keypoints", keypoints]
    if max_frames is not None:
        command += ["--max-frames", str(max_frames)]
    if threads is not None:
        command += ["--threads", str(threads)]
    load = os.getloadavg()[0]
    started = time.perf_counter()
    done = subprocess.run(command, preexec_fn=pinned(cores), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, errors="replace", cwd=EXPERIMENTS_DIR.parent)     # this checkout's mocap
    wall = time.perf_counter() - started
    if done.returncode != 0:
        raise RuntimeError(f"`{' '.join(command)}` failed ({done.returncode}): {done.stderr[-2000:]}")
    run = json.loads((out / files.RUN_JSON).read_text())
    frames = int(run["frames"])
    size = run["settings"]["working_resolution"]
    return {"cores": cores, "keypoints": keypoints, "threads": run.get("threads"), "frames": frames,
            "fps": float(run["fps"]),
            "size": f"{size['input_width']}x{size['input_height']}",
            "loop_fps": frames / float(run["wall_seconds_this_session"]), "end_to_end_fps": frames / wall,
            "wall_s": wall, "keypoints_ms_per_frame": run.get("keypoints_ms_per_frame"), "load": load,
            "command": f"taskset -c {_cpu_list(cores)} " + " ".join(["python", *command[1:]])}


def _label(keypoints: str) -> str:
    """A folder name's part for a ``--keypoints`` value (a keypoint file: ``file-<its stem>``)."""
    return keypoints if keypoints in ("auto", "mediapipe", "none") else f"file-{Path(keypoints).stem}"


def _cpu_list(cores: int) -> str:
    allowed = sorted(os.sched_getaffinity(0))[:cores]
    return ",".join(map(str, allowed))


def detector_alone(clip: Path, max_frames: int | None) -> dict:
    """MediaPipe's time per frame on ``clip``'s frames, in a subprocess pinned to one core."""
    command = [sys.executable, "-m", "experiments.throughput", "--detector-only", str(clip)]
    if max_frames is not None:
        command += ["--max-frames", str(max_frames)]
    load = os.getloadavg()[0]
    done = subprocess.run(command, preexec_fn=pinned(1), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, errors="replace", cwd=EXPERIMENTS_DIR.parent)
    if done.returncode != 0:
        raise RuntimeError(f"MediaPipe alone failed ({done.returncode}): {done.stderr[-2000:]}")
    return {**json.loads(done.stdout.strip().splitlines()[-1]), "load": load,
            "command": f"taskset -c {_cpu_list(1)} python -m experiments.throughput --detector-only {_shown(clip)}"
                       + ("" if max_frames is None else f" --max-frames {max_frames}")}


def _detector_only(clip: Path, max_frames: int | None) -> int:
    """The child of :func:`detector_alone`: prints one JSON line."""
    from mocap.io.mediapipe_keypoints import MediaPipeKeypoints
    from mocap.io.video import iter_frames

    with MediaPipeKeypoints() as source:
        for index, frame in enumerate(iter_frames(clip, 0, max_frames)):
            source.keypoints(index, frame)
        ms = source.milliseconds
    print(json.dumps({"frames": len(ms), "ms_per_frame_median": statistics.median(ms),
                      "ms_per_frame_mean": statistics.fmean(ms)}))
    return 0


@dataclass(frozen=True)
class Ratio:
    """One ratio over the repeats: what it compares, its median and range, and how many repeats
    gave it."""

    name: str
    median: float
    low: float
    high: float
    repeats: int


def ratios(result: dict) -> list[Ratio]:
    """The ratios within each repeat of ``result`` (:func:`measure`), median and range over the
    repeats: ``"mediapipe / alone"``, frames a second (run.json) of the run with ``mediapipe`` on
    the most cores times MediaPipe alone's median seconds a frame of the same repeat (1: the run
    keeps pace with its detector); and for each keypoint mode ``K``, ``"K: N cores / 1"``, its time
    per frame on the most cores (N) over its time on one core (the one-core frames a second over
    the N-core ones). None of them where the runs carry no repeat (a JSON from before they
    did)."""
    runs = result["runs"]
    if not runs or any("repeat" not in r for r in runs):
        return []
    alone = {a["repeat"]: a["ms_per_frame_median"] for a in result.get("mediapipe_alone_runs", [])}
    most = max(result["cores"])
    fps = {(r["repeat"], r["cores"], r["keypoints"]): r["fps"] for r in runs}
    repeats = sorted({r["repeat"] for r in runs})
    found: dict[str, list[float]] = {}
    if "mediapipe" in result["keypoints"] and alone:
        found["mediapipe / alone"] = [fps[(i, most, "mediapipe")] * alone[i] / 1000.0
                                      for i in repeats if (i, most, "mediapipe") in fps and i in alone]
    if most > 1 and 1 in result["cores"]:
        for k in result["keypoints"]:
            found[f"{_label(k)}: {most} cores / 1"] = [fps[(i, 1, k)] / fps[(i, most, k)] for i in repeats
                                                     if (i, 1, k) in fps and (i, most, k) in fps]
    return [Ratio(name, statistics.median(v), min(v), max(v), len(v)) for name, v in found.items() if v]


def _median(rows: list[dict], key: str) -> float | None:
    values = [r[key] for r in rows if r.get(key) is not None]
    return statistics.median(values) if values else None


def table(result: dict) -> str:
    """The Markdown of ``result`` (:func:`measure`): one row per cores x keypoints, medians."""
    clip = result["clip"]
    loads = [r["load"] for r in result["runs"]]
    lines = [f"`{result.get('command', 'python -m experiments.throughput')}` on {result['date']} at commit "
             f"{result['commit']}: `python -m mocap track {_shown(clip)} --keypoints K` (default settings, overlay written"
             + ("" if result["max_frames"] is None else f", first {result['max_frames']} frames")
             + f"), pinned to the first 1 or 2 cores; {result['frames']} frames of {result['size']}, "
             f"median of {result['repeats']} alternating run(s); load average (1 min) "
             f"{min(loads):.1f}–{max(loads):.1f} during the runs, {result['cpu_count']} cores, CPU: {result['cpu']}.",
             "",
             "| cores | keypoints | threads | frames/s (run.json) | frames/s, decoding to outputs "
             "| frames/s, command end to end | MediaPipe in the run (ms/frame) |",
             "|---|---|---|---|---|---|---|"]
    for cores in result["cores"]:
        for keypoints in result["keypoints"]:
            rows = [r for r in result["runs"] if r["cores"] == cores and r["keypoints"] == keypoints]
            kp = _median(rows, "keypoints_ms_per_frame")
            threads = sorted({r.get("threads") or "?" for r in rows}, key=str)
            lines.append(f"| {cores} | {_shown(keypoints) if _label(keypoints) != keypoints else keypoints} | "
                         f"{', '.join(map(str, threads))} | {_median(rows, 'fps'):.1f} | {_median(rows, 'loop_fps'):.1f} | "
                         f"{_median(rows, 'end_to_end_fps'):.1f} | {'' if kp is None else f'{kp:.1f}'} |")
    if max(loads) > result["cpu_count"]:
        lines += ["", f"The load average reached {max(loads):.1f} on {result['cpu_count']} cores. It counts this "
                      "command's own earlier runs (a 2-core run with MediaPipe keeps more than two busy), so it "
                      "does not tell another job's share: read the ratios within a repeat below, not figures "
                      "of separate calls."]
    alone = result.get("mediapipe_alone")
    if alone is not None:
        lines += ["", f"MediaPipe Pose alone (`MediaPipeKeypoints`, image mode, model complexity 1) on the same "
                      f"{alone['frames']} frames, one core: {alone['ms_per_frame_median']:.1f} ms a frame (median; "
                      f"mean {alone['ms_per_frame_mean']:.1f}), load {alone['load']:.1f} "
                      f"(`{alone['command']}`)" + _spread_of_alone(result) + "."]
    found = ratios(result)
    if found:
        lines += ["", "Ratios within each repeat (median over the repeats, range in brackets): "
                      + "; ".join(f"{r.name} **{r.median:.2f}** ({r.low:.2f}-{r.high:.2f}, {r.repeats} repeat(s))"
                                  for r in found) + "."]
    return "\n".join(lines) + "\n"


def _spread_of_alone(result: dict) -> str:
    """", the median repeat of N (a-b ms)" where MediaPipe alone ran in more than one repeat."""
    ms = [a["ms_per_frame_median"] for a in result.get("mediapipe_alone_runs", [])]
    return f", the median repeat of {len(ms)} ({min(ms):.1f}-{max(ms):.1f} ms)" if len(ms) > 1 else ""


def _shown(path: str) -> str:
    """``path`` as the commands of this checkout name it: relative to the checkout's folder's
    parent (``../shared/data/...``) where it lies under it."""
    try:
        return "../" + Path(path).resolve().relative_to(EXPERIMENTS_DIR.parent.parent.resolve()).as_posix()
    except ValueError:
        return str(path)


def replace_section(page: Path, text: str) -> None:
    """Put ``text`` into ``page`` as its :data:`SECTION` (replacing the one there, else at the end)."""
    lines = page.read_text().splitlines() if page.is_file() else []
    body = [SECTION, "", *text.rstrip("\n").splitlines(), ""]
    if SECTION in lines:
        start = lines.index(SECTION)
        end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")), len(lines))
        lines[start:end] = body
    else:
        lines += ["", *body] if lines and lines[-1] != "" else body
    page.write_text("\n".join(lines).rstrip("\n") + "\n")


def section_of(page: Path) -> str | None:
    """The text of ``page``'s :data:`SECTION` (heading excluded), None where it has none
    (``python -m experiments.docs`` carries it over when it rewrites the page)."""
    lines = page.read_text().splitlines() if page.is_file() else []
    if SECTION not in lines:
        return None
    start = lines.index(SECTION)
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")), len(lines))
    return "\n".join(lines[start + 1:end]).strip("\n") + "\n"


def _commit() -> str:
    try:
        return subprocess.run(["git", "-C", str(EXPERIMENTS_DIR.parent), "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def _cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def measure(clip: Path, out: Path, *, cores=(1, 2), keypoints=("none", "mediapipe"), repeats: int = 1,
            max_frames: int | None = None, detector: bool = True, progress=print,
            command: str = "python -m experiments.throughput", threads: int | None = None) -> dict:
    """Every run (see the module); writes ``out/throughput.json`` and ``out/throughput.md`` and
    returns the result (``command``: the command line that asked, kept with it)."""
    out.mkdir(parents=True, exist_ok=True)
    result = {"command": command, "clip": str(clip), "cores": list(cores), "keypoints": list(keypoints),
              "repeats": repeats, "max_frames": max_frames, "commit": _commit(),
              "date": datetime.date.today().isoformat(), "cpu": _cpu_name(), "cpu_count": os.cpu_count(), "runs": []}
    pairs = [(c, k) for c in cores for k in keypoints]
    alone_runs = []
    for repeat in range(repeats):
        for c, k in (pairs if repeat % 2 == 0 else pairs[::-1]):
            run = track_run(clip, out / f"run-{c}core-{_label(k)}", c, k, max_frames, threads)
            result["runs"].append({**run, "repeat": repeat})
            progress(f"{c} core(s), keypoints {k}: {run['fps']:.1f} frames/s (run.json), {run['loop_fps']:.1f} "
                     f"decoding to outputs, {run['end_to_end_fps']:.1f} end to end; load {run['load']:.1f}")
        if detector:
            alone_runs.append({**detector_alone(clip, max_frames), "repeat": repeat})
            progress(f"MediaPipe alone, one core: {alone_runs[-1]['ms_per_frame_median']:.1f} ms a frame")
    result["frames"], result["size"] = result["runs"][0]["frames"], result["runs"][0]["size"]
    if detector:
        # the repeat whose MediaPipe alone was the median one stands for them in the text
        result["mediapipe_alone"] = sorted(alone_runs, key=lambda r: r["ms_per_frame_median"])[(len(alone_runs) - 1) // 2]
        result["mediapipe_alone_runs"] = alone_runs
    (out / "throughput.json").write_text(json.dumps(result, indent=1) + "\n")
    (out / "throughput.md").write_text(table(result))
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.throughput", description=__doc__.split("\n\n")[0])
    parser.add_argument("--clip", type=Path, default=DEFAULT_CLIP, help=f"video (default {DEFAULT_CLIP})")
    parser.add_argument("--out", type=Path, default=EXPERIMENTS_DIR / "results" / "throughput",
                        help="folder for the runs, throughput.json and throughput.md (default experiments/results/throughput)")
    parser.add_argument("--cores", default="1,2", help="core counts (default 1,2)")
    parser.add_argument("--keypoints", default="none,mediapipe", help="--keypoints values (default none,mediapipe)")
    parser.add_argument("--repeats", type=int, default=1, help="runs of each pair, alternating (default 1)")
    parser.add_argument("--max-frames", type=int, default=None, help="track only the first N frames (default all)")
    parser.add_argument("--no-detector", action="store_true", help="leave out MediaPipe alone")
    parser.add_argument("--threads", type=int, default=None, metavar="N",
                        help="track's --threads for every run (default: track's own, the cores less MediaPipe's)")
    parser.add_argument("--docs", type=Path, default=None, metavar="PAGE",
                        help=f"also write the table as the '{SECTION}' section of PAGE (docs/results.md)")
    parser.add_argument("--from-json", type=Path, default=None, metavar="JSON",
                        help="write the table (and --docs) from a stored throughput.json without measuring")
    parser.add_argument("--detector-only", type=Path, default=None, metavar="CLIP", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.detector_only is not None:
        return _detector_only(args.detector_only, args.max_frames)
    if args.from_json is not None:
        result = json.loads(args.from_json.read_text())
        print(table(result), end="")
        if args.docs is not None:
            replace_section(args.docs, table(result))
            print(f"wrote the '{SECTION}' section of {args.docs}")
        return 0
    if args.repeats < 1 or (args.max_frames is not None and args.max_frames < 1):
        parser.error("--repeats and --max-frames must be at least 1")
    if not args.clip.exists():
        parser.error(f"clip not found: {args.clip}")
    args.clip, args.out = args.clip.resolve(), args.out.resolve()
    try:
        cores = tuple(int(c) for c in args.cores.split(","))
    except ValueError:
        parser.error(f"--cores must be integers separated by commas, got {args.cores!r}")
    keypoints = tuple(k for k in args.keypoints.split(",") if k)
    try:
        asked = " ".join(["python -m experiments.throughput", *(sys.argv[1:] if argv is None else argv)])
        result = measure(args.clip, args.out, cores=cores, keypoints=keypoints, repeats=args.repeats,
                         max_frames=args.max_frames, detector=not args.no_detector and "mediapipe" in keypoints,
                         threads=args.threads,
                         command=asked)
    except (ValueError, RuntimeError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(table(result), end="")
    if args.docs is not None:
        replace_section(args.docs, table(result))
        print(f"wrote the '{SECTION}' section of {args.docs}")
    print(f"wrote {args.out / 'throughput.json'} and {args.out / 'throughput.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
