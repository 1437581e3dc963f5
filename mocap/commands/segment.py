"""``python -m mocap segment VIDEO --background IMG [--out DIR]``: what the image side sees.

Writes, per frame, the label image (coloured: black background, skin tone = skin, blue =
clothes, brown = hair, green = lower body, grey = unknown foreground; hair and lower body only
when the first frame supports them), the edge mask (white on black) and the truncated
distance map (viridis: dark on edges), as PNG in ``labels/``, ``edges/`` and ``distance/``,
plus ``segment.mp4`` (frame | labels / edges | distance), the colour model
(``colour_model.json``) and the parameters (``imaging.json``) it used.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import imageio.v3 as iio
import numpy as np
from tqdm import tqdm

from mocap.imaging import ColourModel, ImagingConfig, learn_colour_model, median_background, \
    prepare_frame
from mocap.imaging.visual import colour_distance, colour_labels, label_palette, overlay_edges, tile
from mocap.io.video import VideoWriter, count_frames, frame_rate, iter_frames, read_image


def _box(text: str) -> tuple[int, int, int, int]:
    try:
        values = tuple(int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected ROW,COL,HEIGHT,WIDTH integers, got {text!r}")
    if len(values) != 4 or values[2] <= 0 or values[3] <= 0:
        raise argparse.ArgumentTypeError(f"expected ROW,COL,HEIGHT,WIDTH (positive size), got {text!r}")
    return values  # type: ignore[return-value]


def _range(text: str) -> tuple[int, int]:
    try:
        a, b = (int(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected A:B frame numbers, got {text!r}")
    if a < 0 or b <= a:
        raise argparse.ArgumentTypeError(f"expected 0 <= A < B, got {text!r}")
    return a, b


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "segment", help="write label images, edges and distance maps of a video to inspect",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("video", type=Path, metavar="VIDEO", help="video file or folder of images")
    bg = p.add_mutually_exclusive_group()
    bg.add_argument("--background", type=Path, metavar="IMG", help="image of the empty scene")
    bg.add_argument("--background-frames", type=_range, metavar="A:B",
                    help="use the per-pixel median of frames A..B-1 of VIDEO (empty frames)")
    bg.add_argument("--no-background", action="store_true",
                    help="no empty view exists: the foreground is what the colour classes explain")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="output folder (default: <VIDEO name>_segment)")
    p.add_argument("--colour-model", type=Path, metavar="JSON",
                   help="colour model to use (default: learned on the first frame processed)")
    p.add_argument("--skin-box", type=_box, metavar="R,C,H,W",
                   help="skin sample box (row, col, height, width in pixels) instead of the face")
    p.add_argument("--clothes-box", type=_box, metavar="R,C,H,W",
                   help="clothes sample box instead of the box under the face")
    p.add_argument("--hair-box", type=_box, metavar="R,C,H,W",
                   help="hair sample box instead of the box above the face (with a background)")
    p.add_argument("--lower-body-box", type=_box, metavar="R,C,H,W",
                   help="lower-body (trousers, skirt) sample box; without it there is no lower-body class")
    p.add_argument("--config", type=Path, metavar="JSON", help="imaging parameters (ImagingConfig)")
    p.add_argument("--start", type=int, default=0, metavar="N", help="first frame (default 0)")
    p.add_argument("--max-frames", type=int, metavar="N", help="process at most N frames")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.background is None and args.background_frames is None and not args.no_background:
        raise ValueError("give --background IMG, --background-frames A:B (median of empty "
                         "frames of VIDEO) or --no-background")
    if args.start < 0:
        raise ValueError(f"--start must be >= 0, got {args.start}")
    if args.max_frames is not None and args.max_frames < 1:
        raise ValueError(f"--max-frames must be >= 1, got {args.max_frames}")
    config = ImagingConfig.from_json(args.config) if args.config else ImagingConfig()
    total = count_frames(args.video)
    if args.start >= total:
        raise ValueError(f"--start {args.start} is past the end of {args.video} ({total} frames)")
    stop = total if args.max_frames is None else min(total, args.start + args.max_frames)

    if args.background is not None:
        background = read_image(args.background)
    elif args.background_frames is not None:
        a, b = args.background_frames
        empty = list(iter_frames(args.video, a, b))
        if not empty:
            raise ValueError(f"--background-frames {a}:{b}: {args.video} has only {total} frames")
        background = median_background(empty)
    else:
        background = None

    frames = iter_frames(args.video, args.start, stop)
    first = next(frames)
    if background is not None and background.shape != first.shape:
        raise ValueError(f"background is {background.shape[1]}x{background.shape[0]} but the "
                         f"video is {first.shape[1]}x{first.shape[0]}")
    if args.colour_model is not None:
        model = ColourModel.from_json(args.colour_model)
    else:
        model = learn_colour_model(first, background, args.skin_box, args.clothes_box,
                                   hair_box=args.hair_box, lower_body_box=args.lower_body_box,
                                   config=config)

    out = args.out if args.out is not None else Path(f"{args.video.stem}_segment")
    for sub in ("labels", "edges", "distance"):
        (out / sub).mkdir(parents=True, exist_ok=True)
    model.to_json(out / "colour_model.json")
    config.to_json(out / "imaging.json")

    fps = frame_rate(args.video) or 10.0
    timings: dict[str, list[float]] = {}
    empty_frames = 0
    started = time.perf_counter()

    def all_frames():
        yield first
        yield from frames

    with VideoWriter(out / "segment.mp4", fps) as video:
        progress = tqdm(all_frames(), total=stop - args.start, unit="frame", desc="segment")
        for index, frame in enumerate(progress, start=args.start):
            prepared = prepare_frame(frame, background, model, config)
            for key, value in prepared.timings.items():
                timings.setdefault(key, []).append(value)
            empty_frames += prepared.is_empty
            labels_rgb = colour_labels(prepared.labels, model.m, model.names)
            distance_rgb = colour_distance(prepared.distance, config.max_distance)
            name = f"{index:06d}.png"
            iio.imwrite(out / "labels" / name, labels_rgb)
            iio.imwrite(out / "edges" / name, prepared.edges.astype(np.uint8) * 255)
            iio.imwrite(out / "distance" / name, distance_rgb)
            video.write(tile([frame, labels_rgb, overlay_edges(frame, prepared.edges),
                              distance_rgb]))
        n = video.frames
    elapsed = time.perf_counter() - started
    stages = ", ".join(f"{k} {np.median(v) * 1e3:.1f}" for k, v in timings.items())
    print(f"segmented {n} frames ({empty_frames} with nobody in them) in {elapsed:.1f} s; "
          f"median ms per frame: {stages}")
    print(f"colour model: {model!r}")
    palette = label_palette(model.m, model.names)
    print("labels: black background, " + ", ".join(
        f"RGB {tuple(int(v) for v in palette[c])} {name}" for c, name in enumerate(model.names, start=1))
        + ", grey unknown foreground")
    print(f"wrote {out}/labels, edges, distance (PNG), segment.mp4, colour_model.json, imaging.json")
    return 0
