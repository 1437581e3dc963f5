"""``python -m mocap segment VIDEO --background IMG [--out DIR]``: what the image side sees.

Frames are reduced to the working resolution ``track`` uses (``--work-width``, default near
160 pixels wide: :func:`mocap.imaging.resample.working_factor`), so the pictures are the images
the tracker compares its model against; sample boxes are given in input pixels. Writes, per frame, the label image (coloured: black background, skin tone = skin, blue =
clothes, brown = hair, green = lower body, grey = unknown foreground; hair and lower body only
when the first frame supports them), the edge mask (white on black) and the truncated
distance map (viridis: dark on edges), as PNG in ``labels/``, ``edges/`` and ``distance/``,
plus ``segment.mp4`` (frame | labels / edges | distance), the colour model
(``colour_model.json``, learned on the first frame that shows the person) and the parameters
(``imaging.json``) it used. With keypoints (``--keypoints auto``, the default: MediaPipe Pose
where the optional extra ``keypoints`` is installed; or ``mediapipe`` or a FILE; ``none``) the
2D keypoints the tracker would get are drawn on the frame panel of ``segment.mp4`` (yellow dots, working pixels). An interrupted run resumes: the same command keeps the frames
already written (``segment.json`` holds the settings they were made with).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from mocap.commands._common import (add_background_options, add_frame_options, add_keypoints_option,
                                    add_max_frames_option, own_video_options)


def _box(text: str) -> tuple[int, int, int, int]:
    try:
        values = tuple(int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected ROW,COL,HEIGHT,WIDTH integers, got {text!r}")
    if len(values) != 4 or values[2] <= 0 or values[3] <= 0:
        raise argparse.ArgumentTypeError(f"expected ROW,COL,HEIGHT,WIDTH (positive size), got {text!r}")
    return values  # type: ignore[return-value]


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "segment", help="write label images, edges and distance maps of a video to inspect",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("video", type=Path, metavar="VIDEO", help="video file or folder of images")
    add_background_options(p)
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="output folder (default: <VIDEO name>_segment)")
    p.add_argument("--colour-model", type=Path, metavar="JSON",
                   help="colour model to use (default: learned on the first frame that shows the person)")
    p.add_argument("--skin-box", type=_box, metavar="R,C,H,W",
                   help="skin sample box (row, col, height, width in pixels) instead of the face")
    p.add_argument("--clothes-box", type=_box, metavar="R,C,H,W",
                   help="clothes sample box instead of the box under the face")
    p.add_argument("--hair-box", type=_box, metavar="R,C,H,W",
                   help="hair sample box instead of the box above the face (with a background)")
    p.add_argument("--lower-body-box", type=_box, metavar="R,C,H,W",
                   help="lower-body (trousers, skirt) sample box; without it there is no lower-body class")
    p.add_argument("--config", type=Path, metavar="JSON", help="imaging parameters (ImagingConfig)")
    add_frame_options(p, "as track, near 160 pixels", "first frame (default 0)",
                      "segment a video whose frames do not all decode instead of stopping")
    add_max_frames_option(p, "process at most N frames")
    add_keypoints_option(p, "the tracker would get, drawn")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from mocap.imaging import ImagingConfig
    from mocap.run.segment import SegmentOptions, segment

    boxes = {name: getattr(args, f"{name}_box") for name in ("skin", "clothes", "hair", "lower_body")
             if getattr(args, f"{name}_box") is not None}
    options = own_video_options(args)          # background, frames, working width, keypoints: as track's
    own = SegmentOptions(colour_model=args.colour_model, boxes=boxes,
                         imaging=ImagingConfig.from_json(args.config) if args.config else ImagingConfig())
    segment(args.video, args.out, options, own)
    return 0
