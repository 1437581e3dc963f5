"""``python -m experiments.first_frame``: seconds from the command to the first tracked row of ``poses.csv``.

Runs ``python -m mocap track CLIP --max-frames 1 --no-overlay`` as a newcomer would, several
times, and times each run from its start to the moment ``poses.csv`` holds a row (polled every
10 ms), with the moments its set-up lines appear (face search, working resolution, background,
calibration, the tracking bar) as the breakdown. The runs use a copy of the ``mocap`` package
in a temporary folder, so that the first run compiles every kernel it calls as on a fresh clone
(its time is reported apart) and the later ones load them from that copy's Numba cache;
``NUMBA_DEBUG_CACHE`` counts, for every run, the kernels loaded from the cache and the kernels
compiled and saved to it.

The clip, unless ``--clip`` names one, is the 60-s 1280x720 clip of ``docs/own-video.md``:
``../shared/data/video/intel_asl_no.mkv`` looped for 60 s at 25 frames/s, scaled to 1280x960 and
cropped to 1280x720 (x264 ``veryfast``, 1,500 frames; without ``../shared/data``, a synthetic
actor's frames looped the same way), made with the ffmpeg of imageio-ffmpeg into ``--work``.

Prints one line per run: the seconds to the first row and the CPU seconds the command's process
(its threads, not its ffmpeg children) had used by then, which a loaded machine moves less than
the wall-clock seconds; the load average (1 min) before each run: compare runs of one call.
``--baseline REF`` also times the ``mocap/`` of a git commit (``git archive``), compiled in its
own copy, its cached runs alternating with the working tree's, so that both see the same load.
``--keypoints A,B`` times both keypoint modes, their cached runs alternating, and prints the
first mode's time to the first row over the second's, run by run (:func:`mode_ratios`; issue 50's
target: ``--keypoints mediapipe,none`` at most 1.3x).
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import imageio_ffmpeg

ROOT = Path(__file__).resolve().parents[1]
SHARED_CLIP = ROOT.parent / "shared" / "data" / "video" / "intel_asl_no.mkv"
#: The clip: seconds, frames per second, size.
SECONDS, FPS, WIDTH, HEIGHT = 60, 25, 1280, 720
#: What the command prints as its set-up goes, in order: the breakdown's stages.
MARKERS = {"face search": "looking for a face", "set-up says compiling": "compiling the set-up's kernels",
           "set-up done": "working resolution", "tracking bar": "tracking", "bar says compiling": "(compiling, first run only)"}


def make_clip(path: Path, seconds: int = SECONDS) -> Path:
    """The 60-s 1280x720 clip (see the module), written to ``path``."""
    ffmpeg = imageio_ffmpeg.get_ffmpeg_exe()
    if SHARED_CLIP.is_file():
        source = ["-stream_loop", "-1", "-i", str(SHARED_CLIP)]
    else:
        from mocap.synth import generate_sequence
        seq = generate_sequence("gestures-1", path.parent / "synthetic", frames=25, seed=0, progress=False)
        source = ["-stream_loop", "-1", "-framerate", str(FPS), "-i", str(seq / "frames" / "%06d.png")]
    subprocess.run([ffmpeg, "-v", "error", "-y", *source, "-t", str(seconds), "-r", str(FPS), "-vf",
                    f"scale={WIDTH}:{WIDTH * 3 // 4},crop={WIDTH}:{HEIGHT}:0:{(WIDTH * 3 // 4 - HEIGHT) // 2}",
                    "-c:v", "libx264", "-preset", "veryfast", "-pix_fmt", "yuv420p", str(path)], check=True)
    return path


class _Stream(threading.Thread):
    """Reads a pipe to its end, keeping the text and when each marker first appeared."""

    def __init__(self, pipe, start: float) -> None:
        super().__init__(daemon=True)
        self.pipe, self.start_time = pipe, start
        self.text, self.seen = "", {}

    def run(self) -> None:
        for chunk in iter(lambda: self.pipe.read1(4096), b""):
            now = time.perf_counter() - self.start_time
            self.text += chunk.decode("utf-8", "replace")
            for name, marker in MARKERS.items():
                if name not in self.seen and marker in self.text:
                    self.seen[name] = now


def cpu_seconds(pid: int) -> float | None:
    """CPU seconds (user + system, all threads) process ``pid`` has used so far, from Linux's
    ``/proc/PID/stat`` (None elsewhere); its ffmpeg children are not counted."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def time_run(package_root: Path, clip: Path, out: Path, keypoints: str | None = None) -> dict:
    """One ``track`` run from ``package_root`` (with ``--keypoints KEYPOINTS`` when given, else
    the command's default): seconds to the first row and to the end, the breakdown, and the
    Numba cache's loads and saves."""
    from mocap.run import files

    shutil.rmtree(out, ignore_errors=True)
    env = {**os.environ, "PYTHONPATH": str(package_root), "NUMBA_DEBUG_CACHE": "1"}
    journal = out / files.POSES_CSV
    load = os.getloadavg()[0]
    start = time.perf_counter()
    command = [sys.executable, "-m", "mocap", "track", str(clip), "--max-frames", "1", "--no-overlay", "--out", str(out)]
    if keypoints is not None:
        command += ["--keypoints", keypoints]
    process = subprocess.Popen(command, cwd=package_root, env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    streams = [_Stream(process.stdout, start), _Stream(process.stderr, start)]
    for s in streams:
        s.start()
    first_row = cpu = None
    while first_row is None and process.poll() is None:
        if journal.is_file() and journal.read_bytes().count(b"\n") >= 2:
            first_row, cpu = time.perf_counter() - start, cpu_seconds(process.pid)
        else:
            time.sleep(0.01)
    process.wait()
    end = time.perf_counter() - start
    for s in streams:
        s.join()
    if process.returncode != 0:
        raise RuntimeError(f"track failed ({process.returncode}): {streams[1].text[-2000:]}")
    if first_row is None and journal.is_file() and journal.read_bytes().count(b"\n") >= 2:
        first_row = end                  # written in the last 10 ms
    text = streams[0].text + streams[1].text
    seen = {**streams[0].seen, **streams[1].seen}
    return {"first_row_s": first_row, "cpu_s": cpu, "end_s": end, "load": load, "seen": seen,
            "loaded": len(re.findall(r"\[cache\] data loaded from", text)),
            "saved": len(re.findall(r"\[cache\] data saved to", text))}


def mode_ratios(first: list[dict], second: list[dict]) -> tuple[float, float, float, float]:
    """The first mode's seconds to the first row over the second's: best over best, then the
    median, lowest and highest of the ratios of the runs made one after the other (the k-th of
    each)."""
    if not first or len(first) != len(second):
        raise ValueError(f"need as many runs of each mode, got {len(first)} and {len(second)}")
    pairs = sorted(a["first_row_s"] / b["first_row_s"] for a, b in zip(first, second))
    best = min(r["first_row_s"] for r in first) / min(r["first_row_s"] for r in second)
    return best, pairs[len(pairs) // 2], pairs[0], pairs[-1]


def describe(name: str, run: dict) -> str:
    stages = ", ".join(f"{k} {v:.1f} s" for k, v in sorted(run["seen"].items(), key=lambda kv: kv[1]))
    cpu = "" if run["cpu_s"] is None else f" ({run['cpu_s']:.2f} s of CPU)"
    return (f"{name:<14} first row {run['first_row_s']:5.2f} s{cpu}, exit {run['end_s']:5.2f} s | load {run['load']:.2f} | "
            f"kernels: {run['loaded']} loaded from the cache, {run['saved']} compiled | {stages}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.first_frame", description=__doc__.split("\n\n")[0])
    parser.add_argument("--clip", type=Path, help="a video to track (default: the 60-s 1280x720 clip, made in --work)")
    parser.add_argument("--work", type=Path, help="folder for the clip, the package copy and the runs "
                                                  "(default: a temporary folder, removed after)")
    parser.add_argument("--runs", type=int, default=3, help="runs after the compiling one (default 3)")
    parser.add_argument("--baseline", metavar="REF", help="also time the mocap/ of this git commit, its cached runs "
                                                          "alternating with the working tree's")
    parser.add_argument("--keypoints", metavar="auto|mediapipe|none[,...]",
                        help="pass --keypoints to track (default: track's own default, auto: MediaPipe where "
                             "the optional extra is installed); two, comma-separated: both, alternating, and "
                             "the first's time over the second's")
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error("--runs must be at least 1")
    temporary = None
    if args.work is None:
        temporary = tempfile.TemporaryDirectory(prefix="first-frame-")
        args.work = Path(temporary.name)
    args.work.mkdir(parents=True, exist_ok=True)
    try:
        clip = args.clip or args.work / "clip_60s_1280x720.mp4"
        if not clip.is_file():
            print(f"making {clip} ...", flush=True)
            make_clip(clip)
        copies = {"": args.work / "package"}
        shutil.rmtree(copies[""], ignore_errors=True)
        shutil.copytree(ROOT / "mocap", copies[""] / "mocap", ignore=shutil.ignore_patterns("__pycache__"))
        if args.baseline:
            copies[args.baseline] = args.work / "baseline"
            shutil.rmtree(copies[args.baseline], ignore_errors=True)
            copies[args.baseline].mkdir(parents=True)
            archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.baseline, "mocap"], check=True,
                                     capture_output=True).stdout
            subprocess.run(["tar", "-x", "-C", str(copies[args.baseline])], input=archive, check=True)
        modes = [None] if args.keypoints is None else args.keypoints.split(",")
        if len(modes) > 2 or not all(modes):
            parser.error(f"--keypoints takes one mode or two, comma-separated, got {args.keypoints!r}")
        given = "" if args.keypoints is None else f" --keypoints {' | '.join(modes)}"
        print(f"clip {clip}; `python -m mocap track CLIP --max-frames 1 --no-overlay{given}` from a fresh copy of mocap/ "
              f"({os.cpu_count()} cores)", flush=True)

        def label(name: str, mode: str | None) -> str:
            return (name or "this tree") + ("" if len(modes) == 1 else f" [{mode}]")

        runs_of = [(name, copy, mode) for name, copy in copies.items() for mode in modes]
        compiled, cached = {}, {(name, mode): [] for name, _, mode in runs_of}
        for name, copy, mode in runs_of:
            compiled[name, mode] = time_run(copy, clip, args.work / "run", mode)
            print(describe(f"{label(name, mode)}: compiling run", compiled[name, mode]), flush=True)
        for k in range(args.runs):
            for name, copy, mode in runs_of:
                cached[name, mode].append(time_run(copy, clip, args.work / "run", mode))
                print(describe(f"{label(name, mode)}: cached run {k + 1}", cached[name, mode][-1]), flush=True)
        for name, _, mode in runs_of:
            runs = cached[name, mode]
            print(f"{label(name, mode)}: first row {min(r['first_row_s'] for r in runs):.2f} s at best from the "
                  f"cache (median {sorted(r['first_row_s'] for r in runs)[len(runs) // 2]:.2f} s), "
                  f"{compiled[name, mode]['first_row_s']:.2f} s when compiling; cache used from the second run: "
                  f"{'yes' if all(r['saved'] == 0 and r['loaded'] > 0 for r in runs) else 'NO'}")
        if len(modes) == 2:
            for name in copies:
                best, median, low, high = mode_ratios(cached[name, modes[0]], cached[name, modes[1]])
                print(f"{name or 'this tree'}: first row with --keypoints {modes[0]} over {modes[1]}: {best:.2f}x best "
                      f"over best; run by run {median:.2f}x (median; {low:.2f}-{high:.2f})")
    finally:
        if temporary is not None:
            temporary.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())
