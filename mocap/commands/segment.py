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
import json
import os
import time
from pathlib import Path

import imageio.v3 as iio
import numpy as np
from tqdm import tqdm

from mocap.commands._common import add_background_options, add_keypoints_option, keypoints_line
from mocap.imaging import ColourModel, ImagingConfig, learn_colour_model, median_background, \
    prepare_frame
from mocap.imaging.visual import colour_distance, colour_labels, label_palette, overlay_edges, tile
from mocap.io.atomic import write_bytes_atomic
from mocap.io.jsonfile import read_json, write_json
from mocap.imaging.resample import working_factor
from mocap.io.frames import VideoSource
from mocap.io.video import VideoWriter, read_image


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
    p.add_argument("--work-width", type=int, default=None, metavar="PX",
                   help="working width: frames are reduced by the integer factor that brings them nearest to it "
                        "(default: as track, near 160 pixels)")
    p.add_argument("--allow-damaged", action="store_true",
                   help="segment a video whose frames do not all decode instead of stopping")
    add_keypoints_option(p, "the tracker would get, drawn")
    p.add_argument("--start", type=int, default=0, metavar="N", help="first frame (default 0)")
    p.add_argument("--max-frames", type=int, metavar="N", help="process at most N frames")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from mocap.io.lock import FolderLock

    if args.background is None and args.background_frames is None and not args.no_background:
        raise ValueError("give --background IMG, --background-frames A:B (median of empty "
                         "frames of VIDEO) or --no-background")
    if args.start < 0:
        raise ValueError(f"--start must be >= 0, got {args.start}")
    if args.max_frames is not None and args.max_frames < 1:
        raise ValueError(f"--max-frames must be >= 1, got {args.max_frames}")
    config = ImagingConfig.from_json(args.config) if args.config else ImagingConfig()
    source = VideoSource(args.video)
    source.damaged_frames(args.allow_damaged)
    total = source.count
    if args.start >= total:
        raise ValueError(f"--start {args.start} is past the end of {args.video} ({total} frames)")
    stop = total if args.max_frames is None else min(total, args.start + args.max_frames)
    factor = working_factor(source.width, source.height, *(() if args.work_width is None else (args.work_width,)))
    out = args.out if args.out is not None else Path(f"{args.video.stem}_segment")
    with FolderLock(out):
        return _segment(args, source, factor, out, config, stop)


def _settings(args: argparse.Namespace, config: ImagingConfig, stop: int, factor: int) -> dict:
    """What the output folder's images depend on (``segment.json``): a resume needs the same."""
    path = lambda p: None if p is None else str(Path(p).resolve())
    return {"video": path(args.video), "background": path(args.background),
            "background_frames": list(args.background_frames) if args.background_frames else None,
            "no_background": bool(args.no_background), "colour_model": path(args.colour_model),
            "skin_box": list(args.skin_box) if args.skin_box else None,
            "clothes_box": list(args.clothes_box) if args.clothes_box else None,
            "hair_box": list(args.hair_box) if args.hair_box else None,
            "lower_body_box": list(args.lower_body_box) if args.lower_body_box else None,
            "start": args.start, "stop": stop, "working_factor": factor, "imaging": config.to_dict(),
            "keypoints": _keypoints_setting(args.keypoints, path)}


def _keypoints_setting(name, path) -> str | None:
    """What ``--keypoints NAME`` gave (``auto`` resolved): ``mediapipe``, a file's absolute path or None."""
    from mocap.own_video import resolve_keypoints

    resolved = resolve_keypoints(None if name is None else str(name))[0]
    return resolved if resolved in (None, "mediapipe") else path(resolved)


def _working_box(box, factor: int):
    """An input-pixel box ``(row, col, height, width)`` at the working resolution (None stays None)."""
    if box is None:
        return None
    row, col, height, width = box
    return row // factor, col // factor, max(1, height // factor), max(1, width // factor)


def _learn(frames, background, args, config, factor: int) -> tuple[ColourModel, int]:
    """Colour model learned on the first frame that shows the person (a face, or the sample
    boxes on foreground), and that frame's number."""
    reason = "no frame"
    boxes = {name: _working_box(getattr(args, name), factor)
             for name in ("skin_box", "clothes_box", "hair_box", "lower_body_box")}
    for index, frame in frames:
        try:
            return learn_colour_model(frame, background, boxes["skin_box"], boxes["clothes_box"],
                                      hair_box=boxes["hair_box"], lower_body_box=boxes["lower_body_box"],
                                      config=config), index
        except ValueError as exc:
            reason = f"frame {index}: {exc}"
    raise ValueError(f"no frame of {args.video} shows the person to learn the colours from; last: {reason}")


def _write_png(path: Path, image: np.ndarray) -> None:
    write_bytes_atomic(path, iio.imwrite("<bytes>", image, extension=".png"))


def _draw_keypoints(frame: np.ndarray, keypoints) -> np.ndarray:
    """A copy of ``frame`` (H, W, 3) with the present keypoints (working pixels) as yellow dots."""
    from skimage.draw import disk

    out = frame.copy()
    for u, v, _ in keypoints.as_mapping().values():
        rows, cols = disk((v - 0.5, u - 0.5), 1.5, shape=out.shape[:2])
        out[rows, cols] = (255, 220, 0)
    return out


def _segment(args: argparse.Namespace, source, factor: int, out: Path, config: ImagingConfig, stop: int) -> int:
    from mocap.imaging.resample import downscale
    from mocap.own_video import keypoint_source

    keypoints = keypoint_source(args.keypoints)            # a bad keypoint file stops before anything is written
    print(keypoints_line(args.keypoints))

    settings = _settings(args, config, stop, factor)
    settings_file = out / "segment.json"
    if settings_file.is_file():
        if read_json(settings_file) != json.loads(json.dumps(settings)):
            raise ValueError(f"{out} holds a segmentation with other settings; choose another --out "
                             "(or delete the folder)")
    for sub in ("labels", "edges", "distance"):
        (out / sub).mkdir(parents=True, exist_ok=True)
    write_json(settings_file, settings)

    frames = lambda: ((i, downscale(f, factor)) for i, f in enumerate(source.frames(args.start, stop),
                                                                       start=args.start))
    full_frames = lambda: enumerate(source.frames(args.start, stop), start=args.start)
    if args.background is not None:
        background = read_image(args.background)
        if background.shape[:2] != (source.height, source.width):
            raise ValueError(f"background is {background.shape[1]}x{background.shape[0]} but the "
                             f"video is {source.width}x{source.height}")
        background = downscale(background, factor)
    elif args.background_frames is not None:
        a, b = args.background_frames
        empty = [downscale(f, factor) for f in source.frames(a, b)]
        if not empty:
            raise ValueError(f"--background-frames {a}:{b}: {args.video} has only {source.count} frames")
        background = median_background(empty)
    else:
        background = None
    if factor > 1:
        print(f"working resolution {source.width // factor}x{source.height // factor} (input "
              f"{source.width}x{source.height} reduced {factor}x, as track sees it)")
    learned = out / "colour_model.json"
    if args.colour_model is not None:
        model = ColourModel.from_json(args.colour_model)
    elif learned.is_file():                   # a resumed run: the model its first images were made with
        model = ColourModel.from_json(learned)
    else:
        model, index = _learn(frames(), background, args, config, factor)
        if index != args.start:
            print(f"colours learned on frame {index}, the first that shows the person")
    model.to_json(learned)
    config.to_json(out / "imaging.json")

    fps = source.fps or 10.0
    timings: dict[str, list[float]] = {}
    empty_frames = resumed = 0
    started = time.perf_counter()
    video_path = out / "segment.mp4"
    partial = out / f".{video_path.stem}.partial{video_path.suffix}"
    with VideoWriter(partial, fps) as video:
        for index, full in tqdm(full_frames(), total=stop - args.start, unit="frame", desc="segment"):
            frame = downscale(full, factor)
            name = f"{index:06d}.png"
            paths = [out / sub / name for sub in ("labels", "edges", "distance")]
            if all(p.is_file() for p in paths):           # written by an interrupted run: kept
                labels_rgb, edges_img, distance_rgb = (read_image(p, allow_gray=True) for p in paths)
                edges = edges_img[..., 0] > 127
                resumed += 1
                empty_frames += not labels_rgb.any()
            else:
                prepared = prepare_frame(frame, background, model, config)
                for key, value in prepared.timings.items():
                    timings.setdefault(key, []).append(value)
                empty_frames += prepared.is_empty
                labels_rgb = colour_labels(prepared.labels, model.m, model.names)
                distance_rgb = colour_distance(prepared.distance, config.max_distance)
                edges = prepared.edges
                # the distance map last: a frame counts as done when all three are there
                for path, image in zip(paths, (labels_rgb, edges.astype(np.uint8) * 255, distance_rgb)):
                    _write_png(path, image)
            to_working = (frame.shape[1] / full.shape[1], frame.shape[0] / full.shape[0])
            shown = frame if keypoints is None else \
                _draw_keypoints(frame, keypoints.keypoints(index, full).scaled(*to_working))
            video.write(tile([shown, labels_rgb, overlay_edges(frame, edges), distance_rgb]))
        n = video.frames
    os.replace(partial, video_path)
    elapsed = time.perf_counter() - started
    stages = ", ".join(f"{k} {np.median(v) * 1e3:.1f}" for k, v in timings.items())
    again = f"; {resumed} kept from an interrupted run" if resumed else ""
    print(f"segmented {n} frames ({empty_frames} with nobody in them{again}) in {elapsed:.1f} s; "
          f"median ms per frame: {stages}")
    print(f"colour model: {model!r}")
    palette = label_palette(model.m, model.names)
    print("labels: black background, " + ", ".join(
        f"RGB {tuple(int(v) for v in palette[c])} {name}" for c, name in enumerate(model.names, start=1))
        + ", grey unknown foreground")
    print(f"wrote {out}/labels, edges, distance (PNG), segment.mp4, colour_model.json, imaging.json")
    return 0
