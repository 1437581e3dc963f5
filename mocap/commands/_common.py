"""Argument helpers shared by the tracking commands, and the one builder of their
:class:`mocap.run.OwnVideoOptions` (:func:`own_video_options`): each option is declared once
here, with the default of the field it sets."""
from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

#: The :class:`mocap.run.OwnVideoOptions` field each command-line option sets (its argparse
#: ``dest``); ``overlay`` is ``not no_overlay``, ``tracker`` :func:`tracker_config`.
FIELD_OPTIONS = {"background": "background", "background_frames": "background_frames",
                 "no_background": "no_background", "calibration": "calibration", "hfov_deg": "hfov",
                 "height_m": "height", "work_width": "work_width", "colour": "colour",
                 "ground_truth": "ground_truth", "start": "start", "max_frames": "max_frames",
                 "allow_damaged": "allow_damaged", "show": "show", "overwrite": "overwrite",
                 "keypoints": "keypoints", "threads": "threads"}


def default(field: str):
    """The default of a :class:`mocap.run.OwnVideoOptions` field: the command line's too."""
    from mocap.run import OwnVideoOptions

    return next(f.default for f in dataclasses.fields(OwnVideoOptions) if f.name == field)


def own_video_options(args: argparse.Namespace):
    """The :class:`mocap.run.OwnVideoOptions` a command line describes: the fields whose
    options the command declares (:data:`FIELD_OPTIONS`, ``--no-overlay``, the tracker's), the
    others at their defaults (the same as the options'). Paths become strings."""
    from mocap.run import OwnVideoOptions

    fields = {}
    for name, dest in FIELD_OPTIONS.items():
        if hasattr(args, dest):
            value = getattr(args, dest)
            fields[name] = str(value) if isinstance(value, Path) else value
    if hasattr(args, "no_overlay"):
        fields["overlay"] = not args.no_overlay
    if hasattr(args, "iterations"):
        fields["tracker"] = tracker_config(args)
    return OwnVideoOptions(**fields)


def add_tracker_options(p: argparse.ArgumentParser) -> None:
    """Options that set :class:`mocap.track.TrackerConfig` fields."""
    p.add_argument("--iterations", type=int, default=None, metavar="N",
                   help="cost evaluations per frame for both steps together (default 500)")
    p.add_argument("--split", default=None, metavar="auto|R:E",
                   help="budget split between region and edge step: 'auto' (paper: all region below 200, "
                        "else 50/50) or a ratio like 1:1, 3:1, 1:0")
    p.add_argument("--beam", type=int, default=None, metavar="K",
                   help="pose hypotheses kept per frame (default 3; 1: a single hypothesis)")
    p.add_argument("--lag", type=int, default=None, metavar="L",
                   help="decide each frame's pose L frames later by the best path through the hypotheses "
                        "(default 8; 0: at once)")
    p.add_argument("--offline", action="store_true",
                   help="decide every frame at the end of the video by the best path through all of them")
    p.add_argument("--paper", action="store_true",
                   help="the paper's method: one hypothesis, no recovery, re-acquisition, jumps or prior")
    p.add_argument("--config", type=Path, default=None, metavar="JSON",
                   help="TrackerConfig as JSON (options above override it)")
    p.add_argument("--threads", type=int, default=None, metavar="N",
                   help="threads the tracker's registrations run on (the same poses for every N; default: the "
                        "cores, less one for MediaPipe's process)")
    add_max_frames_option(p, "track only the first N frames")
    p.add_argument("--overwrite", action="store_true", help="start afresh instead of resuming a run in --out")
    p.add_argument("--no-overlay", action="store_true", help="skip writing overlay.mp4")


def tracker_config(args: argparse.Namespace):
    """The TrackerConfig the options describe."""
    import dataclasses

    from mocap.track import TrackerConfig

    if args.config and args.paper:
        raise ValueError("give either --config or --paper, not both")
    config = (TrackerConfig.from_json(args.config) if args.config
              else TrackerConfig.paper() if args.paper else TrackerConfig())
    changes = {}
    if args.iterations is not None and args.iterations < 1:
        raise ValueError(f"--iterations must be at least 1, got {args.iterations}: with no cost "
                         "evaluations every frame would keep the initial pose")
    for option, name in (("iterations", "evaluations"), ("split", "split"), ("beam", "beam"), ("lag", "lag")):
        if getattr(args, option) is not None:
            changes[name] = getattr(args, option)
    if args.iterations is None and config.evaluations < 1:
        raise ValueError(f"{args.config}: evaluations must be at least 1, got {config.evaluations}: with no "
                         "cost evaluations every frame would keep the initial pose")
    if args.offline:
        changes["offline"] = True
    return dataclasses.replace(config, **changes) if changes else config


def print_summary(summary) -> None:
    """One paragraph about a finished run."""
    print(f"tracked {summary.frames} frames ({summary.failures} failed) at {summary.fps:.1f} frames/s "
          f"(wall clock, image processing and writing included); outputs in {summary.out_dir}")
    if summary.damaged_frames:
        from mocap.io.video_check import format_frames
        print(f"warning: the video is damaged: {format_frames(list(summary.damaged_frames))} did not decode "
              "cleanly (listed in run.json as damaged_frames)", file=sys.stderr)
    if summary.empty_frames or summary.dark_frames:
        print(f"{summary.empty_frames} frames with nobody in view (marked empty = 1 in poses.csv, pose kept), "
              f"{summary.dark_frames} very dark frames (marked dark = 1); tracking went on through them")
    if summary.advice:
        print(summary.advice)
    if summary.metrics:
        m = summary.metrics
        print(f"accuracy vs ground truth: MPJPE {m['mpjpe_mm']:.1f} mm, root-relative "
              f"{m['root_relative_mpjpe_mm']:.1f} mm, PA-MPJPE {m['pa_mpjpe_mm']:.1f} mm, "
              f"joint angles {m['angle_error_deg']:.1f} deg, reprojection {m['reprojection_px']:.2f} px, "
              f"failure rate {100 * m['failure_rate']:.1f}% (MPJPE > 100 mm)")


def frame_range(text: str) -> tuple[int, int]:
    """``A:B`` on the command line: frames ``A`` to ``B - 1`` (argparse type)."""
    try:
        a, b = (int(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected A:B frame numbers, got {text!r}")
    if a < 0 or b <= a:
        raise argparse.ArgumentTypeError(f"expected 0 <= A < B, got {text!r}")
    return a, b


def add_background_options(p: argparse.ArgumentParser) -> None:
    """``--background IMG`` | ``--background-frames A:B`` | ``--no-background`` (one of them at most)."""
    bg = p.add_mutually_exclusive_group()
    bg.add_argument("--background", type=Path, default=None, metavar="IMG", help="image of the empty scene")
    bg.add_argument("--background-frames", type=frame_range, metavar="A:B",
                    help="use the per-pixel median of frames A..B-1 of VIDEO (empty frames)")
    bg.add_argument("--no-background", action="store_true",
                    help="no empty view: the foreground is what the colour classes explain")


def add_keypoints_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--keypoints auto|mediapipe|none|FILE`` (default ``auto``, the options': MediaPipe Pose
    where the optional extra ``keypoints`` imports, none otherwise); ``what`` says what they are for."""
    p.add_argument("--keypoints", default=default("keypoints"), metavar="auto|mediapipe|none|FILE",
                   help=f"2D keypoints {what}: 'auto' (default: MediaPipe Pose where the optional extra "
                        "'keypoints' is installed, none otherwise), 'mediapipe', 'none', or a CSV "
                        "frame,joint,u,v,confidence in input pixels (docs/design.md section 4)")


def add_camera_options(p: argparse.ArgumentParser, height_help: str) -> None:
    """``--hfov DEG`` and ``--height M`` (what an automatic calibration assumes)."""
    p.add_argument("--hfov", type=float, default=default("hfov_deg"), metavar="DEG",
                   help=f"camera horizontal field of view without a calibration (default {default('hfov_deg'):g}, "
                        "a webcam)")
    p.add_argument("--height", type=float, default=default("height_m"), metavar="M", help=height_help)


def add_max_frames_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--max-frames N``."""
    p.add_argument("--max-frames", type=int, default=default("max_frames"), metavar="N", help=what)


def add_frame_options(p: argparse.ArgumentParser, width_default: str, start_help: str, damaged_help: str) -> None:
    """``--work-width PX``, ``--start N``, ``--allow-damaged`` (``width_default``: what the
    default working width is, in words)."""
    p.add_argument("--work-width", type=int, default=default("work_width"), metavar="PX",
                   help=f"working width: frames are reduced by the integer factor that brings them nearest to it "
                        f"(default: {width_default})")
    p.add_argument("--start", type=int, default=default("start"), metavar="N", help=start_help)
    add_allow_damaged_option(p, damaged_help)


def add_allow_damaged_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--allow-damaged``."""
    p.add_argument("--allow-damaged", action="store_true", help=what)


def add_run_options(p: argparse.ArgumentParser, start_help: str, damaged_help: str) -> None:
    """``--work-width PX``, ``--colour calibration|face``, ``--start N``, ``--allow-damaged``."""
    from mocap.imaging.resample import DEFAULT_WORK_WIDTH
    from mocap.run.options import COLOUR_SOURCES

    add_frame_options(p, f"the tracker chooses, near {DEFAULT_WORK_WIDTH} or less for a person close to the camera; "
                         "see docs/own-video.md", start_help, damaged_help)
    p.add_argument("--colour", choices=COLOUR_SOURCES, default=default("colour"),
                   help="learn colours inside the calibrated model (default) or from the detected face (needs "
                        "--calibration and a background)")


def keypoints_line(options) -> str:
    """``keypoints: ...``: which keypoints :class:`mocap.run.OwnVideoOptions` ``options`` give
    here (and why, for ``auto``: :func:`mocap.run.options.resolve_keypoints`), without making the
    source (``track-many``'s workers make their own)."""
    from mocap.run.options import resolve_keypoints

    return f"keypoints: {resolve_keypoints(options.keypoints)[1]}"
