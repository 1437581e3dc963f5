"""``python -m mocap track-many INPUT... --out DIR [--workers N | --scheduler ADDRESS]``

Tracks every input (video files, image folders, sequence folders, globs) exactly as
``python -m mocap track INPUT`` would, into ``DIR/<input's name>/``, one Dask task per video:
on N local single-threaded worker processes (default: the machine's cores; 0: one after another
in this process) or on an existing Dask cluster (docs/cluster.md). A worker that dies is
replaced and its video resumes from its checkpoint; one that stops responding (no heartbeat for
--hung-after seconds) is restarted and its video resumed elsewhere; the same command again skips
finished videos and resumes the rest. Writes DIR/summary.csv and DIR/summary.png. Exit status 0 when
every input finished, 1 when some failed (their reasons in the summary), 2 on bad input.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mocap.commands._common import (add_camera_options, add_keypoints_option, add_run_options, add_tracker_options,
                                    keypoints_line, own_video_options)


def add_parser(subparsers) -> None:
    from mocap.run.many import HUNG_AFTER_S

    p = subparsers.add_parser("track-many", help="track many videos at once, locally or on a Dask cluster",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="video files, image folders or sequence folders, or globs of them ('clips/*.mp4')")
    p.add_argument("--out", type=Path, required=True, metavar="DIR",
                   help="output folder: DIR/<input's name>/ for each input, DIR/summary.csv, DIR/summary.png")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, metavar="N",
                       help="local worker processes, one thread each (default: the machine's cores; 0: in this "
                            "process, one video after another)")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="a running Dask scheduler (tcp://HOST:8786) whose workers reach DIR (docs/cluster.md)")
    p.add_argument("--hung-after", type=float, default=HUNG_AFTER_S, metavar="S",
                   help="seconds without a heartbeat after which a worker holding a video is restarted and its "
                        f"videos resumed elsewhere (default {HUNG_AFTER_S:g}; needs the worker's nanny, dask worker's "
                        "default)")
    p.add_argument("--no-background", action="store_true",
                   help="no empty view: the foreground is what the colour classes explain")
    add_camera_options(p, "the person's height in metres (the same person in every input)")
    add_run_options(p, "first frame to track in every input (default 0)",
                    "track the frames that decode of a damaged video instead of failing it")
    add_keypoints_option(p, "as a further cue (a file: the same for every input)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_tracker_options(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from mocap.run import files
    from mocap.run.many import track_many

    options = own_video_options(args)
    print(keypoints_line(options))
    summary = track_many(args.inputs, args.out, options, workers=args.workers, scheduler=args.scheduler,
                         progress=not args.no_progress,
                         hung_after_s=args.hung_after)
    for row in summary.rows:
        if row["status"] == "failed":
            print(f"failed: {row['input']}: {row['reason']}", file=sys.stderr)
        if row.get("hung_restarts"):
            print(f"{row['input']}: a worker it was on stopped responding and was restarted "
                  f"({row['hung_restarts']}x); tracked elsewhere from its checkpoint")
    print(f"{summary.finished} of {len(summary.rows)} inputs finished ({summary.skipped} already were), "
          f"{summary.failed} failed, {summary.wall_s:.0f} s on {summary.backend}; "
          f"summary in {args.out / files.SUMMARY_CSV}")
    return 1 if summary.failed else 0
