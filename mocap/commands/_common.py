"""Argument helpers shared by the tracking commands."""
from __future__ import annotations

import argparse
from pathlib import Path


def add_tracker_options(p: argparse.ArgumentParser) -> None:
    """Options that set :class:`mocap.track.TrackerConfig` fields."""
    p.add_argument("--iterations", type=int, default=None, metavar="N",
                   help="cost evaluations per frame for both steps together (default 500)")
    p.add_argument("--split", default=None, metavar="auto|R:E",
                   help="budget split between region and edge step: 'auto' (paper: all region below 200, "
                        "else 50/50) or a ratio like 1:1, 3:1, 1:0")
    p.add_argument("--config", type=Path, default=None, metavar="JSON",
                   help="TrackerConfig as JSON (options above override it)")
    p.add_argument("--max-frames", type=int, default=None, metavar="N", help="track only the first N frames")
    p.add_argument("--overwrite", action="store_true", help="start afresh instead of resuming a run in --out")
    p.add_argument("--no-overlay", action="store_true", help="skip writing overlay.mp4")


def tracker_config(args: argparse.Namespace):
    """The TrackerConfig the options describe."""
    import dataclasses

    from mocap.track import TrackerConfig

    config = TrackerConfig.from_json(args.config) if args.config else TrackerConfig()
    changes = {}
    if args.iterations is not None:
        changes["evaluations"] = args.iterations
    if args.split is not None:
        changes["split"] = args.split
    return dataclasses.replace(config, **changes) if changes else config


def print_summary(summary) -> None:
    """One paragraph about a finished run."""
    print(f"tracked {summary.frames} frames ({summary.failures} failed) at {summary.fps:.1f} frames/s "
          f"(one core, image processing included); outputs in {summary.out_dir}")
    if getattr(summary, "empty_frames", 0) or getattr(summary, "dark_frames", 0):
        print(f"{summary.empty_frames} frames with nobody in view (marked empty = 1 in poses.csv, pose kept), "
              f"{summary.dark_frames} very dark frames (marked dark = 1); tracking went on through them")
    if summary.metrics:
        m = summary.metrics
        print(f"accuracy vs ground truth: MPJPE {m['mpjpe_mm']:.1f} mm, PA-MPJPE {m['pa_mpjpe_mm']:.1f} mm, "
              f"joint angles {m['angle_error_deg']:.1f} deg, reprojection {m['reprojection_px']:.2f} px, "
              f"failure rate {100 * m['failure_rate']:.1f}% (MPJPE > 100 mm)")
