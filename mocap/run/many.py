"""Many videos at once: each tracked as ``python -m mocap track`` would, one task per video, on
a Dask cluster (docs/design.md sections 3-4, docs/cluster.md).

:func:`track_many` expands the inputs (video files, image folders, sequence folders, globs),
refuses two inputs that would write to the same output folder before anything runs, and sends
one task per video (:func:`track_input`) to a local Dask cluster of single-threaded worker
processes or to an existing cluster's scheduler. Each video goes to ``OUT/<name>/`` (its file
name without the extension, or its folder's name), tracked by
:func:`mocap.run.track` (what ``python -m mocap track`` calls): under the
folder's lock, with a crash-exact checkpoint after every frame.

What a crash leaves behind, and what happens next:

- A worker that dies mid-video: Dask gives the task to another worker, which resumes the video
  from its checkpoint (the dead process's lock went with it). Never restarted from zero, never
  two writers.
- A worker that stops responding mid-video (stopped by SIGSTOP, a stalled machine): once the
  scheduler has had no heartbeat from it for ``hung_after_s`` seconds (:data:`HUNG_AFTER_S`,
  ``--hung-after``) it is restarted through its nanny (``Client.restart_workers``: the hung
  process is killed, its folder lock with it) and its videos go to other workers, which resume
  them from their checkpoints; ``summary.csv`` counts it (``hung_restarts``). A worker without a
  nanny (``dask worker --no-nanny``) can only be removed from the cluster: its process keeps its
  video's folder, which is then reported failed ("in use by another run").
- The command itself stopped (Ctrl-C, killed): every finished video has its ``run.json`` with
  ``status: finished``; the same command again skips those and resumes the others.
- A video that cannot be tracked (damaged, nobody found, ...) is recorded with its one-line
  reason; the others go on.

At the end ``OUT/summary.csv`` (:data:`SUMMARY_COLUMNS`, one row per input, from each
video's :class:`mocap.run.RunSummary`: the run's own, or its ``run.json`` read back) and
``OUT/summary.png`` are written atomically. ``OUT/track-many.json`` keeps the options
(:class:`mocap.run.OwnVideoOptions`), so that a rerun with other options is refused instead of
mixing results.
"""
from __future__ import annotations

import csv
import glob
import io
import json
import logging
import time
import uuid
from dataclasses import dataclass, field, replace
from pathlib import Path

from mocap.io.files import write_bytes_atomic, write_text_atomic
from mocap.run import files
from mocap.run.options import OwnVideoOptions, available_cores, default_threads, resolve_keypoints
from mocap.run.outputs import RunSummary

__all__ = ["PER_VIDEO_OPTIONS", "ManySummary", "SUMMARY_COLUMNS", "expand_inputs", "track_input", "track_many",
           "read_summary", "summary_row"]

#: Files written at the top of the output folder (:mod:`mocap.run.files`).
SUMMARY_CSV, SUMMARY_PNG, OPTIONS_FILE = files.SUMMARY_CSV, files.SUMMARY_PNG, files.TRACK_MANY_JSON
#: Columns of ``summary.csv``: the input as given, its output folder (relative to ``OUT``),
#: ``finished`` or ``failed``, frames tracked, frames whose residual marked them failed, frames
#: per second (one core, run.json ``fps``), background mode and calibration source
#: (run.json ``settings.own_video``), seconds of the session that finished it (run.json
#: ``wall_seconds_this_session``), for a failed video its one-line reason, and how many times
#: a worker it was given to stopped responding and was restarted (:class:`HungWorkers`; 0 or
#: more on a cluster, empty in this process).
SUMMARY_COLUMNS = ("input", "output", "status", "frames", "failed_frames", "fps", "background", "calibration",
                   "time_s", "reason", "hung_restarts")
#: Options of :class:`mocap.run.OwnVideoOptions` that name one video's files or a window:
#: not for many videos (a sequence folder brings its own background, calibration, ground truth).
PER_VIDEO_OPTIONS = ("background", "background_frames", "calibration", "ground_truth", "show")
#: Seconds between two looks at the output folders for the progress bar (and at the workers).
POLL_S = 0.5
#: Seconds without a heartbeat after which a worker that holds a video is taken as hung
#: (``--hung-after``): Dask workers send one every 0.5 s to 2 s (more with many workers), also
#: while they compute.
HUNG_AFTER_S = 120.0
#: Seconds a hung worker's nanny is given to kill it and start it afresh.
RESTART_TIMEOUT_S = 30.0


@dataclass
class ManySummary:
    """What :func:`track_many` did.

    Attributes
    ----------
    out : Path
    rows : list of dict
        One per input, in input order, keys :data:`SUMMARY_COLUMNS`.
    skipped : int
        Inputs found finished in ``out`` and not tracked again.
    wall_s : float
        Seconds.
    backend : str
        Where the tasks ran.
    """

    out: Path
    rows: list[dict] = field(default_factory=list)
    skipped: int = 0
    wall_s: float = 0.0
    backend: str = ""

    @property
    def finished(self) -> int:
        return sum(r["status"] == "finished" for r in self.rows)

    @property
    def failed(self) -> int:
        return sum(r["status"] == "failed" for r in self.rows)


def output_name(path: Path) -> str:
    """Output folder name of an input: a file's name without its extension, a folder's name."""
    return path.stem if path.is_file() else path.resolve().name


def expand_inputs(patterns: list[str]) -> list[tuple[Path, str]]:
    """Inputs (paths and globs) as ``(path, output name)`` pairs, in the order given.

    A glob's matches are sorted; an input named twice (also through two globs) counts once.

    Raises
    ------
    ValueError
        No input, a path that does not exist, a glob that matches nothing, two inputs with the
        same output name (compared ignoring case, as some file systems do), or an output name
        that is one of the files written at the top of the output folder.
    """
    if not patterns:
        raise ValueError("no input given")
    paths: list[Path] = []
    for pattern in patterns:
        if glob.escape(pattern) != pattern:              # *, ? or [ in it
            matches = sorted(glob.glob(pattern))
            if not matches:
                raise ValueError(f"{pattern} matches no file or folder")
            paths.extend(Path(m) for m in matches)
        elif Path(pattern).exists():
            paths.append(Path(pattern))
        else:
            raise ValueError(f"no such video, image folder or sequence: {pattern}")
    unique: dict[Path, Path] = {}
    for p in paths:
        unique.setdefault(p.resolve(), p)
    by_name: dict[str, list[Path]] = {}
    for p in unique.values():
        by_name.setdefault(output_name(p).casefold(), []).append(p)
    clashes = [ps for ps in by_name.values() if len(ps) > 1]
    if clashes:
        text = "; ".join(" and ".join(str(p) for p in ps) + f" (both {output_name(ps[0])})" for ps in clashes)
        raise ValueError(f"inputs with the same output folder name: {text}; rename them or track them in "
                         "separate runs")
    reserved = [p for p in unique.values() if output_name(p).casefold() in (SUMMARY_CSV, SUMMARY_PNG, OPTIONS_FILE)]
    if reserved:
        raise ValueError(f"{reserved[0]} would be tracked into a folder named {output_name(reserved[0])}, the "
                         "name of a file track-many writes: rename it")
    return [(p, output_name(p)) for p in unique.values()]


def _finished(out_dir: Path) -> bool:
    return RunSummary.read(out_dir) is not None


def summary_row(source: str | Path, out_dir: str | Path, reason: str | None = None, *,
                summary: RunSummary | None = None) -> dict:
    """The ``summary.csv`` row of one input (keys :data:`SUMMARY_COLUMNS`), from its run's
    ``summary`` (default: its ``run.json`` read back, :meth:`mocap.run.RunSummary.read`).

    ``reason`` given: the input failed for it. Numbers of a failed input are left empty.
    """
    out_dir = Path(out_dir)
    row = dict.fromkeys(SUMMARY_COLUMNS, "")
    row.update(input=str(source), output=out_dir.name)
    run = None if reason is not None else summary if summary is not None else RunSummary.read(out_dir)
    if run is None:
        row.update(status="failed", reason=reason or "no finished run.json")
        return row
    setup = run.setup
    row.update(status="finished", frames=run.frames, failed_frames=run.failures, fps=round(run.fps, 2),
               background="" if setup is None else setup.background_mode,
               calibration="" if setup is None else setup.calibration_from, time_s=round(run.wall_s, 2))
    return row


def track_input(source: str, out_dir: str, options: OwnVideoOptions) -> dict:
    """Track one input into ``out_dir`` as ``python -m mocap track`` would
    (:func:`mocap.run.track`, no progress bar): the task a worker runs; its
    summary row.

    Resumes an unfinished run found in ``out_dir`` and does nothing to a finished one. Bad
    input (ValueError, OSError: a damaged video, nobody found, a folder another run holds)
    makes a ``failed`` row with the one-line reason instead of an error.
    """
    import mocap.run

    summary = RunSummary.read(out_dir)
    if summary is None:
        try:
            summary = mocap.run.track(source, out_dir, options, progress=False)
        except (ValueError, OSError) as exc:
            return summary_row(source, out_dir, reason=_one_line(exc))
    return summary_row(source, out_dir, summary=summary)


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text if isinstance(exc, (ValueError, OSError)) else f"{type(exc).__name__}: {text}"


def _clear_run(out_dir: Path) -> None:
    """Remove a video's run (journals, checkpoint, run.json) under its lock, to start it afresh."""
    from mocap.io.lock import FolderLock

    if not out_dir.is_dir():
        return
    with FolderLock(out_dir):
        for name in (files.POSES_CSV, files.KEYPOINTS_CSV, files.STATE_FILE, files.RUN_JSON):
            (out_dir / name).unlink(missing_ok=True)


def _check_options(out: Path, record: dict, overwrite: bool) -> None:
    """Refuse a folder written with other options (unless ``overwrite``); then record these."""
    from mocap.io.files import read_json, write_json

    path = out / OPTIONS_FILE
    if path.is_file() and not overwrite:
        try:
            previous = read_json(path)
        except ValueError:
            previous = None
        if previous != json.loads(json.dumps(record)):
            raise ValueError(f"{out} holds videos tracked with other options ({path}); use --overwrite or "
                             "another --out")
    out.mkdir(parents=True, exist_ok=True)
    write_json(path, record)


def _estimated_frames(path: Path, start: int, max_frames: int | None) -> int:
    """Frames an input will give from frame ``start``, for the progress bar: an image count, or
    what a video's container announces (duration times rate, no decoding); at most ``max_frames``."""
    from mocap.io.sequence import find_sequence
    from mocap.io.video import image_files

    frames = find_sequence(path).frames
    if frames.is_dir():
        n = len(image_files(frames))
    else:
        import imageio_ffmpeg
        reader = imageio_ffmpeg.read_frames(str(frames))
        try:
            meta = next(reader)
            n = int(round(meta.get("duration", 0) * meta.get("fps", 0)))
        except (OSError, RuntimeError, StopIteration):
            n = 0                       # unreadable: the task will say why
        finally:
            reader.close()
    n = max(n - start, 0)
    return n if max_frames is None else min(n, max_frames)


class _JournalRows:
    """Rows in each video's ``poses.csv`` so far, read incrementally (a resumed run cuts its
    journal back: then it is counted afresh)."""

    def __init__(self) -> None:
        self.seen: dict[Path, tuple[int, int]] = {}        # path -> (bytes read, newlines in them)

    def __call__(self, journal: Path) -> int:
        try:
            size = journal.stat().st_size
        except FileNotFoundError:
            return 0
        offset, lines = self.seen.get(journal, (0, 0))
        if size < offset:
            offset, lines = 0, 0
        if size > offset:
            with journal.open("rb") as fh:
                fh.seek(offset)
                chunk = fh.read(size - offset)
            offset, lines = offset + len(chunk), lines + chunk.count(b"\n")
        self.seen[journal] = (offset, lines)
        return max(lines - 1, 0)                            # the header line


def default_workers() -> int:
    """The machine's cores available to this process (:func:`mocap.run.options.available_cores`)."""
    return available_cores()


def _dask_client(workers: int, scheduler: str | None):
    """A distributed Client on ``scheduler``, or on a new local cluster of ``workers`` processes
    with one thread each; and a description."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ValueError("track-many needs Dask for its workers: pip install 'mocap[dask]' (or --workers 0: "
                         "one video after another in this process)") from None
    if scheduler is not None:
        return Client(scheduler), f"dask {scheduler}"
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, memory_limit=0,
                           dashboard_address=None, silence_logs=logging.ERROR)
    return Client(cluster), f"{workers} local worker processes"


def track_many(inputs: list[str | Path], out: str | Path, options: OwnVideoOptions | None = None, *,
               workers: int | None = None, scheduler: str | None = None, progress: bool = True,
               hung_after_s: float = HUNG_AFTER_S) -> ManySummary:
    """Track every input, one Dask task per video, and write ``summary.csv`` and ``summary.png``.

    Parameters
    ----------
    inputs : list of str or Path
        Video files, image folders, sequence folders, or globs of them.
    out : str or Path
        Output folder: ``out/<name>/`` per input, the summary files at the top.
    options : OwnVideoOptions, optional
        How every input is tracked (those of ``python -m mocap track``), none of
        :data:`PER_VIDEO_OPTIONS`. ``overwrite``: every input is tracked afresh (finished or
        not), and other options than the folder's previous run are accepted.
    workers : int, optional
        Local worker processes, one thread each (default: the machine's cores); 0 tracks the
        videos one after another in this process, without Dask. Ignored with ``scheduler``.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``); its workers must reach
        ``out`` at the same path and import this ``mocap``.
    progress : bool
        One progress bar over all frames of all videos.
    hung_after_s : float, seconds
        A worker holding a video that sends the scheduler no heartbeat for this long is taken as
        hung: restarted, its videos resumed elsewhere (:class:`HungWorkers`; not with
        ``workers=0``).

    Returns
    -------
    ManySummary

    Raises
    ------
    ValueError
        Bad inputs (missing, name clashes), a per-video option, a folder tracked with other
        options, a bad worker count or hang timeout, Dask missing for ``workers > 0``.
    """
    options, overwrite, workers = _checked(options, workers, hung_after_s)
    items = expand_inputs([str(i) for i in inputs])
    out = Path(out)
    started = time.perf_counter()
    # the threads change no pose: a rerun with other threads resumes
    _check_options(out, {k: v for k, v in options.to_dict().items() if k != "threads"}, overwrite)
    rows, todo = _plan(items, out, overwrite)
    summary = ManySummary(out, skipped=len(rows))
    bar = _ManyBar(out, items, rows, options, progress)
    try:
        summary.backend = _track_all(todo, out, options, rows, bar, workers=workers, scheduler=scheduler,
                                     hung_after_s=hung_after_s)
    finally:
        bar.close()
    return _summarise(summary, items, rows, time.perf_counter() - started)


def _checked(options: OwnVideoOptions | None, workers: int | None,
             hung_after_s: float) -> tuple[OwnVideoOptions, bool, int]:
    """The options every video is tracked with (``overwrite`` taken out: a task run again after
    a lost worker resumes), whether to overwrite, and the worker count; ValueError (one line)
    for a bad worker count or hang timeout and for a per-video option."""
    options = OwnVideoOptions() if options is None else options
    workers = default_workers() if workers is None else workers
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
        raise ValueError(f"workers must be a non-negative integer, got {workers!r}")
    if isinstance(hung_after_s, bool) or not isinstance(hung_after_s, (int, float)) or not hung_after_s > 0:
        raise ValueError(f"the hang timeout must be a positive number of seconds, got {hung_after_s!r}")
    default = OwnVideoOptions()
    per_video = [name for name in PER_VIDEO_OPTIONS if getattr(options, name) != getattr(default, name)]
    if per_video:
        raise ValueError(f"{', '.join(per_video)}: not for many videos (a sequence folder brings its own "
                         "background.png, calibration.json, ground_truth.csv)")
    if options.threads is None and workers > 0:       # the cores shared between the clips and their threads
        detector = resolve_keypoints(options.keypoints)[0] == "mediapipe"
        options = replace(options, threads=default_threads(detector, cores=max(1, default_workers() // workers)))
    return replace(options, overwrite=False), options.overwrite, workers


def _plan(items: list[tuple[Path, str]], out: Path, overwrite: bool) -> tuple[dict[str, dict], list[tuple[Path, str]]]:
    """Which inputs ``(path, name)`` are still to track: the summary rows of those finished
    before (by name), and the others in order. ``overwrite``: every folder is cleared first."""
    rows: dict[str, dict] = {}
    todo: list[tuple[Path, str]] = []
    for path, name in items:
        if overwrite:
            _clear_run(out / name)
        if _finished(out / name):
            rows[name] = summary_row(path, out / name)
        else:
            todo.append((path, name))
    return rows, todo


def _track_all(todo: list[tuple[Path, str]], out: Path, options: OwnVideoOptions, rows: dict[str, dict],
               bar: "_ManyBar", *, workers: int, scheduler: str | None, hung_after_s: float) -> str:
    """Track each of ``todo`` into ``out/<name>``, adding its summary row to ``rows`` as it
    finishes: one after another in this process (``workers == 0`` and no scheduler), else one
    Dask task each on a local cluster of ``workers`` processes or the ``scheduler``'s, set up
    here and closed at the end. Returns how (``ManySummary.backend``)."""
    if not todo:
        return "nothing to track"
    if workers == 0 and scheduler is None:
        for path, name in todo:
            rows[name] = {**track_input(str(path.resolve()), str((out / name).resolve()), options), "input": str(path)}
            bar.update(rows, running=0)
        return "this process"
    client, backend = _dask_client(workers, scheduler)
    try:
        _run_on_dask(client, todo, out, options, rows, bar, HungWorkers(hung_after_s))
    finally:
        _close_client(client, scheduler)
    return backend


def _summarise(summary: ManySummary, items: list[tuple[Path, str]], rows: dict[str, dict],
               wall_s: float) -> ManySummary:
    """``summary`` with every input's row in the inputs' order and the wall time (seconds);
    ``summary.csv`` and ``summary.png`` written into its folder."""
    summary.rows = [rows[name] for _, name in items]
    summary.wall_s = wall_s
    write_summary(summary.out, summary.rows)
    return summary


def _close_client(client, scheduler: str | None) -> None:
    cluster = client.cluster if scheduler is None else None
    client.close()
    if cluster is not None:
        cluster.close()


class HungWorkers:
    """Which workers have stopped responding: no new heartbeat at the scheduler (its
    ``last_seen`` unchanged) for ``after_s`` seconds of this process's ``clock``, while they
    hold one of the videos. Each look (:meth:`look`) compares the scheduler's view with the
    previous one, so the scheduler's clock is never compared with this machine's.
    """

    def __init__(self, after_s: float, clock=time.monotonic) -> None:
        self.after_s, self.clock = after_s, clock
        self.seen: dict[str, tuple[float, float]] = {}     # worker -> (its last_seen, our time it changed)

    def look(self, workers: dict[str, dict], busy: set[str]) -> list[str]:
        """The hung workers among ``busy`` (addresses), from ``workers`` (``scheduler_info()``'s:
        address -> ``{"last_seen": ...}``); each one once (it is forgotten)."""
        now = self.clock()
        self.seen = {w: seen for w, seen in self.seen.items() if w in workers}
        hung = []
        for address, info in workers.items():
            last = info.get("last_seen")
            previous = self.seen.get(address)
            if previous is None or previous[0] != last:
                self.seen[address] = (last, now)
            elif address in busy and now - previous[1] >= self.after_s:
                hung.append(address)
                del self.seen[address]
        return hung


def _run_on_dask(client, todo, out: Path, options: OwnVideoOptions, rows: dict, bar: "_ManyBar",
                 hung: HungWorkers) -> None:
    """Submit one task per video and collect the rows as they finish (a task whose workers
    kept dying, or that raised, becomes a failed row with the reason); restart the workers
    that stop responding (``hung``), counting it in the rows of the videos they held."""
    from distributed import wait

    token = uuid.uuid4().hex[:8]
    # the longest videos first: the last to finish is then a short one (less time with idle workers)
    # absolute paths: a remote worker's working folder is not this one
    futures = {client.submit(track_input, str(path.resolve()), str((out / name).resolve()), options, pure=False,
                             key=f"track-many-{name}-{token}", priority=bar.expected[name]): (path, name)
               for path, name in todo}
    keys = {f.key: name for f, (_, name) in futures.items()}
    restarts = {name: 0 for _, name in todo}
    pending = dict(futures)
    try:
        while pending:
            for fut in [f for f in pending if f.done()]:
                path, name = pending.pop(fut)
                try:
                    rows[name] = {**fut.result(), "input": str(path)}
                except Exception as exc:     # the task raised, or its workers died too often (KilledWorker)
                    rows[name] = summary_row(path, out / name, reason=_one_line(exc))
                rows[name]["hung_restarts"] = restarts[name]
            # a worker's processing list also holds what it has queued: at most nthreads of them run
            threads, processing = client.nthreads(), client.processing()
            running = sum(min(sum(k in keys for k in ks), threads.get(w, 1)) for w, ks in processing.items())
            bar.update(rows, running=running)
            busy = {w for w, ks in processing.items() if any(k in keys for k in ks)}
            for worker in hung.look(client.scheduler_info()["workers"], busy) if pending else ():
                held = [keys[k] for k in processing.get(worker, ()) if k in keys]
                # its nanny kills it (its folder locks go with it) and starts it afresh; its tasks go elsewhere
                client.restart_workers([worker], timeout=RESTART_TIMEOUT_S, raise_for_error=False)
                for name in held:
                    restarts[name] += 1
            if pending:
                try:                        # until a task ends, or the bar's next look
                    wait(list(pending), timeout=POLL_S, return_when="FIRST_COMPLETED")
                except TimeoutError:
                    pass
    finally:
        for fut in pending:
            fut.cancel()


class _ManyBar:
    """One tqdm bar over all frames of all videos: finished videos count their tracked frames,
    running ones the rows of their journal; the total is each video's expected frames
    (``expected``: name -> frames, estimated until the video has finished)."""

    def __init__(self, out: Path, items, rows: dict, options: OwnVideoOptions, progress: bool) -> None:
        from tqdm import tqdm

        self.out, self.items, self.count = out, items, _JournalRows()
        self.expected = {name: _estimated_frames(path, options.start, options.max_frames) for path, name in items}
        self.bar = tqdm(total=sum(self.expected.values()), desc="tracking", unit="frame", disable=not progress)
        self.update(rows, running=0)

    def update(self, rows: dict, running: int) -> None:
        if self.bar.disable:
            return
        done = {}
        for _, name in self.items:
            row = rows.get(name)
            if row is not None and row["status"] == "finished":
                done[name] = self.expected[name] = int(row["frames"])
            elif row is None:
                done[name] = self.count(self.out / name / files.POSES_CSV)
        self.bar.total = sum(self.expected.values())
        self.bar.n = sum(done.values())
        n_failed = sum(r["status"] == "failed" for r in rows.values())
        self.bar.set_postfix_str(f"videos: {len(rows) - n_failed} done, {running} running, {n_failed} failed, "
                                 f"{len(self.items)} in all")

    def close(self) -> None:
        self.bar.close()


def write_summary(out: Path, rows: list[dict]) -> None:
    """``out/summary.csv`` (:data:`SUMMARY_COLUMNS`) and ``out/summary.png``, atomically."""
    text = io.StringIO()
    writer = csv.DictWriter(text, SUMMARY_COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_text_atomic(out / SUMMARY_CSV, text.getvalue())
    _summary_plot(out / SUMMARY_PNG, rows)


def read_summary(out: str | Path) -> list[dict]:
    """Rows of ``out/summary.csv`` as written (values as strings)."""
    with open(Path(out) / SUMMARY_CSV, newline="") as fh:
        return list(csv.DictReader(fh))


#: Above this many videos summary.png shows one dot per video instead of one bar per video.
MAX_BARS = 50


def _summary_plot(path: Path, rows: list[dict]) -> None:
    """Frames per second and share of failed frames per video: a bar each, failed videos named
    in red; above :data:`MAX_BARS` videos one dot each (fps against failed share), unnamed."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    names = [r["output"] for r in rows]
    ok = np.array([r["status"] == "finished" for r in rows])
    fps = np.array([float(r["fps"]) if r["fps"] != "" else 0.0 for r in rows])
    share = np.array([100.0 * int(r["failed_frames"]) / max(int(r["frames"]), 1) if r["frames"] != "" else 0.0
                      for r in rows])
    note = f"{int(ok.sum())} of {len(rows)} videos tracked" + ("" if ok.all() else ", red: not tracked (reason in "
                                                                                  "summary.csv)")
    if len(rows) > MAX_BARS:
        fig, ax = plt.subplots(figsize=(6, 4.5), constrained_layout=True)
        ax.plot(fps[ok], share[ok], "o", ms=3, alpha=0.6, color="tab:blue")
        ax.set_xlabel("frames per second (one core)")
        ax.set_ylabel("failed frames (%)")
        ax.set_ylim(-2, 102)
        ax.set_title(note, fontsize=8, loc="left", color="black" if ok.all() else "tab:red")
    else:
        y = np.arange(len(rows))
        fig, axes = plt.subplots(1, 2, figsize=(9, 1.2 + 0.28 * len(rows)), sharey=True, constrained_layout=True)
        axes[0].barh(y, fps, color="tab:blue")
        axes[0].set_xlabel("frames per second (one core)")
        axes[1].barh(y, share, color="tab:orange")
        axes[1].set_xlabel("failed frames (%)")
        axes[1].set_xlim(0, 100)
        axes[0].set_yticks(y, names)
        axes[0].invert_yaxis()
        for tick, good in zip(axes[0].get_yticklabels(), ok):
            if not good:
                tick.set_color("tab:red")
        axes[0].set_title(note, fontsize=8, loc="left", color="black" if ok.all() else "tab:red")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    write_bytes_atomic(path, buf.getvalue())
