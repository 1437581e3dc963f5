"""What the image side sees (``python -m mocap segment``): per frame the label image, the edge
mask and the truncated distance map as PNG in ``labels/``, ``edges/`` and ``distance/``, plus
``segment.mp4`` (frame | labels / edges | distance), the colour model (``colour_model.json``)
and the parameters (``imaging.json``) it used.

Frames are reduced to the working resolution ``track`` uses, the background is found as the
run's set-up finds it (:func:`mocap.run.setup.find_background`) and the colours are learnt as
the run learns them (:func:`mocap.run.colours.learn_colours`, from a face or sample boxes), so
the pictures are the images the tracker compares its model against; what it is told is what
``track`` is told (:class:`~mocap.run.options.OwnVideoOptions`, resolved once by
:class:`~mocap.run.options.RunChoices`), with :class:`SegmentOptions` beside. An interrupted run
resumes: the same call keeps the frames already written (``segment.json`` holds the settings
they were made with).
"""
from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import imageio.v3 as iio
import numpy as np
from tqdm import tqdm

from mocap.io.files import read_json, write_bytes_atomic, write_json
from mocap.imaging import ColourModel, ImagingConfig, prepare_frame
from mocap.imaging.resample import downscale, working_factor
from mocap.imaging.visual import colour_distance, colour_labels, label_palette, overlay_edges, tile
from mocap.io.frames import VideoSource
from mocap.io.lock import FolderLock
from mocap.io.video import VideoWriter, read_image
from mocap.run import files
from mocap.run.colours import ColourRecipe, SampleBoxes, learn_colours
from mocap.run.options import OwnVideoOptions, RunChoices
from mocap.run.setup import FaceSearch, FrameAccess, SetupRequest, find_background

__all__ = ["SegmentOptions", "segment"]

Box = tuple[int, int, int, int]


@dataclass(frozen=True)
class SegmentOptions:
    """What ``segment`` is told besides what ``track`` is (:class:`~mocap.run.options.OwnVideoOptions`).

    Attributes
    ----------
    colour_model : Path or None
        Colour model to use (else learnt on the first frame that shows the person).
    boxes : dict of str to (int, int, int, int)
        Sample boxes in input pixels (``row, col, height, width``), by
        :class:`mocap.run.colours.SampleBoxes` field (``skin``, ``clothes``, ``hair``, ``lower_body``).
    imaging : ImagingConfig
    """

    colour_model: Path | None = None
    boxes: dict[str, Box] = field(default_factory=dict)
    imaging: ImagingConfig = field(default_factory=ImagingConfig)


def segment(video: Path, out: Path | None, options: OwnVideoOptions, own: SegmentOptions | None = None,
            choices: RunChoices | None = None) -> None:
    """Segment ``video`` into ``out`` (default ``<video name>_segment``); prints what it did.

    ``options`` as ``track`` takes them: the background (one of ``background``,
    ``background_frames``, ``no_background``: segment has no automatic one), ``work_width``,
    ``start``, ``max_frames``, ``allow_damaged`` and ``keypoints`` (drawn on the frame panel of
    ``segment.mp4``); the rest is not used. ``choices``: what they mean here (default
    :meth:`RunChoices.of` ``options``, made once the options are checked and closed at the end:
    its keypoint detector's process ends with the call; one given is the caller's to close).

    Raises
    ------
    ValueError
        No background option, bad frames, another segmentation's settings in ``out``.
    """
    own = SegmentOptions() if own is None else own
    if options.background_mode() == "auto":
        raise ValueError("give --background IMG, --background-frames A:B (median of empty "
                         "frames of VIDEO) or --no-background")
    if choices is None:
        with RunChoices.of(options) as made:    # a bad keypoint file stops here; its detector ended after
            segment(video, out, options, own, made)
        return
    print(f"keypoints: {choices.keypoints_line}")
    source = VideoSource(video)
    source.damaged_frames(options.allow_damaged)
    total = source.count
    if options.start >= total:
        raise ValueError(f"--start {options.start} is past the end of {video} ({total} frames)")
    stop = total if options.max_frames is None else min(total, options.start + options.max_frames)
    factor = working_factor(source.width, source.height, *(() if options.work_width is None else
                                                           (options.work_width,)))
    out = out if out is not None else Path(f"{video.stem}_segment")
    with FolderLock(out):
        _Segmenter(video, source, factor, out, options, own, choices, stop).run()


def _settings(video: Path, options: OwnVideoOptions, own: SegmentOptions, choices: RunChoices, stop: int,
              factor: int) -> dict:
    """What the output folder's images depend on (``segment.json``): a resume needs the same.
    ``keypoints``: what ``--keypoints`` gave (``auto`` resolved), ``mediapipe``, a file's
    absolute path or None."""
    path = lambda p: None if p is None else str(Path(p).resolve())
    box = lambda name: list(own.boxes[name]) if own.boxes.get(name) else None
    keypoints = choices.keypoint_cue
    return {"video": path(video), "background": path(options.background),
            "background_frames": list(options.background_frames) if options.background_frames else None,
            "no_background": bool(options.no_background), "colour_model": path(own.colour_model),
            "skin_box": box("skin"), "clothes_box": box("clothes"), "hair_box": box("hair"),
            "lower_body_box": box("lower_body"),
            "start": options.start, "stop": stop, "working_factor": factor, "imaging": own.imaging.to_dict(),
            "keypoints": keypoints if keypoints in (None, "mediapipe") else path(keypoints)}


def _other_settings(out: Path, held: dict, wanted: dict) -> str:
    """Why ``out``'s segmentation (``segment.json``: ``held``) is not resumed with ``wanted``, in one line."""
    what = "choose another --out (or delete the folder)"
    if held.get("keypoints") != wanted.get("keypoints"):
        return (f"{out} holds a segmentation made with keypoints {held.get('keypoints')!r}, this one's would be "
                f"{wanted.get('keypoints')!r} (--keypoints changed, or the optional extra 'keypoints' was installed "
                f"or removed since): give the keypoints it had, or {what}")
    differ = sorted(key for key in held.keys() | wanted.keys() if held.get(key) != wanted.get(key))
    return f"{out} holds a segmentation with other settings ({', '.join(differ)}); {what}"


def _working_box(box: Box | None, factor: int) -> Box | None:
    """An input-pixel box ``(row, col, height, width)`` at the working resolution (None stays None)."""
    if box is None:
        return None
    row, col, height, width = box
    return row // factor, col // factor, max(1, height // factor), max(1, width // factor)


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


class _Segmenter:
    """One segmentation into an output folder (held locked by :func:`segment`)."""

    def __init__(self, video: Path, source, factor: int, out: Path, options: OwnVideoOptions, own: SegmentOptions,
                 choices: RunChoices, stop: int) -> None:
        self.video, self.source, self.factor, self.out, self.options, self.stop = video, source, factor, out, options, stop
        self.own, self.choices, self.config = own, choices, own.imaging

    def background(self) -> np.ndarray | None:
        """The empty scene at the working resolution, as the run's set-up finds it."""
        options = self.options
        image = read_image(options.background) if options.background is not None else None
        request = SetupRequest(factor=self.factor, background_mode=options.background_mode(), background_image=image,
                               background_frames=options.background_frames, progress=False)
        return find_background(FrameAccess(self.source, 0), request, self.factor, FaceSearch(self.factor),
                               self.config).image

    def colours(self, background: np.ndarray | None) -> ColourModel:
        """The given colour model, a resumed run's, or one learnt on the first frame that shows the person."""
        options, out = self.options, self.out
        learned = out / files.COLOUR_MODEL_JSON
        if self.own.colour_model is not None:
            model = ColourModel.from_json(self.own.colour_model)
        elif learned.is_file():                   # a resumed run: the model its first images were made with
            model = ColourModel.from_json(learned)
        else:
            boxes = SampleBoxes(**{name: _working_box(box, self.factor) for name, box in self.own.boxes.items()})
            frames = ((i, downscale(f, self.factor)) for i, f in enumerate(self.source.frames(options.start, self.stop),
                                                                           start=options.start))
            learnt = learn_colours(frames, ColourRecipe("face", background, self.config, boxes=boxes), str(self.video))
            model = learnt.model
            if learnt.frame != options.start:
                print(f"colours learned on frame {learnt.frame}, the first that shows the person")
        model.to_json(learned)
        return model

    def run(self) -> None:
        options, out, source, factor = self.options, self.out, self.source, self.factor
        keypoints = self.choices.keypoint_source
        settings = _settings(self.video, options, self.own, self.choices, self.stop, factor)
        settings_file = out / files.SEGMENT_JSON
        if settings_file.is_file():
            held, wanted = read_json(settings_file), json.loads(json.dumps(settings))
            if held != wanted:
                raise ValueError(_other_settings(out, held, wanted))
        for sub in files.SEGMENT_PICTURES:
            (out / sub).mkdir(parents=True, exist_ok=True)
        write_json(settings_file, settings)
        background = self.background()
        if factor > 1:
            print(f"working resolution {source.width // factor}x{source.height // factor} (input "
                  f"{source.width}x{source.height} reduced {factor}x, as track sees it)")
        model = self.colours(background)
        self.config.to_json(out / files.IMAGING_JSON)
        started = time.perf_counter()
        counts = self.frames(background, model, keypoints)
        self.report(counts, time.perf_counter() - started, model)

    def frame(self, index: int, frame: np.ndarray, background, model: ColourModel, counts: dict):
        """One frame's three pictures, written (or read back from an interrupted run)."""
        name = f"{index:06d}.png"
        paths = [self.out / sub / name for sub in files.SEGMENT_PICTURES]
        if all(p.is_file() for p in paths):           # written by an interrupted run: kept
            labels_rgb, edges_img, distance_rgb = (read_image(p, allow_gray=True) for p in paths)
            counts["resumed"] += 1
            counts["empty"] += not labels_rgb.any()
            return labels_rgb, edges_img[..., 0] > 127, distance_rgb
        prepared = prepare_frame(frame, background, model, self.config)
        for key, value in prepared.timings.items():
            counts["timings"].setdefault(key, []).append(value)
        counts["empty"] += prepared.is_empty
        labels_rgb = colour_labels(prepared.labels, model.m, model.names)
        distance_rgb = colour_distance(prepared.distance, self.config.max_distance)
        # the distance map last: a frame counts as done when all three are there
        for path, image in zip(paths, (labels_rgb, prepared.edges.astype(np.uint8) * 255, distance_rgb)):
            _write_png(path, image)
        return labels_rgb, prepared.edges, distance_rgb

    def frames(self, background, model: ColourModel, keypoints) -> dict:
        """Every frame's pictures and ``segment.mp4``; the counts."""
        options, out = self.options, self.out
        counts = {"timings": {}, "empty": 0, "resumed": 0, "frames": 0}
        video_path = out / files.SEGMENT_MP4
        partial = out / f".{video_path.stem}.partial{video_path.suffix}"
        with VideoWriter(partial, self.source.fps or 10.0) as video:
            for index, full in tqdm(enumerate(self.source.frames(options.start, self.stop), start=options.start),
                                    total=self.stop - options.start, unit="frame", desc="segment"):
                frame = downscale(full, self.factor)
                labels_rgb, edges, distance_rgb = self.frame(index, frame, background, model, counts)
                to_working = (frame.shape[1] / full.shape[1], frame.shape[0] / full.shape[0])
                shown = frame if keypoints is None else \
                    _draw_keypoints(frame, keypoints.keypoints(index, full).scaled(*to_working))
                video.write(tile([shown, labels_rgb, overlay_edges(frame, edges), distance_rgb]))
            counts["frames"] = video.frames
        os.replace(partial, video_path)
        return counts

    def report(self, counts: dict, elapsed: float, model: ColourModel) -> None:
        stages = ", ".join(f"{k} {np.median(v) * 1e3:.1f}" for k, v in counts["timings"].items())
        again = f"; {counts['resumed']} kept from an interrupted run" if counts["resumed"] else ""
        print(f"segmented {counts['frames']} frames ({counts['empty']} with nobody in them{again}) in {elapsed:.1f} s; "
              f"median ms per frame: {stages}")
        print(f"colour model: {model!r}")
        palette = label_palette(model.m, model.names)
        print("labels: black background, " + ", ".join(
            f"RGB {tuple(int(v) for v in palette[c])} {name}" for c, name in enumerate(model.names, start=1))
            + ", grey unknown foreground")
        print(f"wrote {self.out}/labels, edges, distance (PNG), segment.mp4, colour_model.json, imaging.json")
