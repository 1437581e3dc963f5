"""``python -m experiments.front_back``: does the input's pixels tell a person facing the camera from one facing away?

Issue 49, item 1: a front/back observation per frame, from the input's pixels, audited before
it is used. Each **observer** gives per frame "facing" (the camera), "away" or no answer
(:data:`NO_ANSWER`); the table counts them against the truth.

**The truth.** On the synthetic sequences (:mod:`mocap.synth`), the chest's heading relative to
the camera (:func:`relative_heading_deg`): the chest heading (:data:`mocap.body.pose.HEADING`)
less the direction of the camera seen from the root, on the circle, in (-180, 180] degrees; 0 is
the chest facing the camera, facing = ``|heading| < 90``. The head's own turn (``head_turn``,
a sway of 6-12 degrees on these sequences) is not counted. On the real clips
(:data:`REAL_CLIPS`, people signing to the camera) the truth is "facing" on every frame.

**Material** (:data:`MATERIALS`): the synthetic figure with its face (``face``), the same
sequences with hair all round the head (``faceless``: :func:`mocap.synth.setup_sequence` with
``face=False``; same poses, body and scene; its truth is still its heading, and a good observer
abstains or answers "away" there since nothing shows the face), and the real clips (``real``) at
their own size and reduced by 2 and 4 (:func:`mocap.imaging.resample.downscale`). Synthetic
frames are rendered in memory at each input size (``--sizes``; the renderer's own
supersampling), every ``--stride``-th frame of ``--sequences`` (``turning`` turns round, the
others face the camera within 45 degrees).

**The head's box** (:class:`HeadBox`): on synthetic frames, the true head (the model's ``head``
joint, its centre, and the actor's head length and width) projected by the output camera
(``truth box``); on every frame, from MediaPipe Pose's landmarks (:func:`head_box_of_landmarks`:
the ears' midpoint, the head's width from the ears, nose and shoulders: ``MediaPipe's box``).

**Observers** (:data:`OBSERVERS`, cheapest first):

* ``head-colour`` (:func:`head_colour_score`): the head's face band (40-70 % of the box's height
  from its top, the middle half of its width: eyes, nose, cheeks) against its crown (the top
  30 %), the distance of their median colours' CIE Lab chroma (a*, b*; lightness, which the
  light changes from crown to face, left out). Facing, the band is skin under a crown of
  hair; facing away both are hair. Answers "facing" at or above a threshold fitted on the seeds
  :data:`FIT_SEEDS` with the face (:func:`fit_threshold`: the best balanced accuracy), no answer
  where either region has fewer than :data:`MIN_REGION_PIXELS` pixels in the frame. With the
  truth box and with MediaPipe's.
* ``mediapipe-order``: MediaPipe's left shoulder and ear image-right of its right ones (the
  person's left on the image's right is a front view); no answer without a person.
* ``mediapipe-depth``: MediaPipe's world landmarks: the nose nearer the camera than the ears'
  midpoint by more than :data:`NOSE_DEPTH_MARGIN_M` is "facing", farther by as much "away",
  between no answer.
* ``mediapipe-agree``: ``mediapipe-order``'s answer where ``mediapipe-depth`` gives the same,
  else no answer (:func:`agreeing`).
* ``mediapipe-visibility``: the least visibility of the nose, eyes and mouth corners at least
  :data:`FACE_VISIBILITY` is "facing", else "away" (the issue measured the nose's at 1.00 facing
  or not: a check of that).
* ``face-cascade`` (:func:`cascade_in_box`): the project's LBP frontal face cascade
  (:func:`mocap.imaging.detect_face`) on a square crop about the head's box
  (:data:`CASCADE_CROP` head heights a side), resized to :data:`CASCADE_SIDE_PX` pixels (the
  cascade's window is 24 pixels: a head of 15 pixels must be enlarged): a face found is
  "facing", none "away". With the truth box and MediaPipe's.

**Cost**: each observer's wall-clock milliseconds per frame (MediaPipe once for its three
observers and its box), measured in this process; run under ``taskset -c 0`` for one core.

Results go to ``--out`` (default ``experiments/results/front_back``): one JSON of per-frame
records per (material, size, seed or clip) under ``frames/`` (reused when present), and
``front_back.md`` and ``summary.json`` from ``report``.

Measured on 2026-11-29 (docs/research-log.md): MediaPipe's "facing" is right on 96-100 % of the
frames it says it and on every real frame; its "away" is not evidence; a hidden face reads as a
back to every observer; head colour fails on the real clips; the cascade sees real faces only.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from skimage import color, transform

from experiments import RESULTS_DIR
from mocap.body.model import BodyModel
from mocap.body.pose import HEADING, PARAMETER_INDEX
from mocap.body.skeleton import JOINT_INDEX
from mocap.imaging import detect_face
from mocap.imaging.resample import downscale
from mocap.io.video import count_frames, iter_frames
from mocap.synth import sequence_poses, setup_sequence
from mocap.synth.sequence import parse_size

#: Decisions of an observer.
FACING, AWAY, NO_ANSWER = "facing", "away", "none"
#: Observers, cheapest first; ``[truth]`` uses the true head's box, ``[mediapipe]`` MediaPipe's.
OBSERVERS: tuple[str, ...] = ("head-colour[truth]", "head-colour[mediapipe]", "mediapipe-order",
                              "mediapipe-depth", "mediapipe-agree", "mediapipe-visibility", "face-cascade[truth]",
                              "face-cascade[mediapipe]")
#: Materials: the synthetic figure with its face, with hair all round, and the real clips.
MATERIALS: tuple[str, ...] = ("face", "faceless", "real")
#: Seeds any threshold is fitted on; others are reported apart.
FIT_SEEDS: tuple[int, ...] = (0, 1, 2, 3, 4)
#: Seeds never used for fitting, by default.
UNSEEN_SEEDS: tuple[int, ...] = (7,)
#: Synthetic sequences measured by default: one that turns round, two that face the camera.
DEFAULT_SEQUENCES: tuple[str, ...] = ("turning", "gestures-1", "not-facing")
#: Real clips (people signing to the camera), under ``--data``/video.
REAL_CLIPS: tuple[str, ...] = ("intel_asl_book.mkv", "intel_asl_no.mkv", "intel_asl_sister.mkv")
#: Input sizes by default (width, height).
DEFAULT_SIZES: tuple[tuple[int, int], ...] = ((160, 120), (320, 240), (640, 480))
#: Bins of |relative heading|, degrees (45-degree steps).
ABS_BINS_DEG: tuple[tuple[float, float], ...] = ((0, 45), (45, 90), (90, 135), (135, 180))
#: Fewest in-frame pixels of each region the head-colour observer compares.
MIN_REGION_PIXELS = 2
#: The head-colour observer's regions, as fractions of the box's height from its top and of its width.
CROWN_ROWS, FACE_ROWS, REGION_COLS = (0.0, 0.3), (0.4, 0.7), (0.25, 0.75)
#: MediaPipe landmarks (indices of its 33).
NOSE, LEFT_EYE, RIGHT_EYE, LEFT_EAR, RIGHT_EAR = 0, 2, 5, 7, 8
MOUTH_LEFT, MOUTH_RIGHT, LEFT_SHOULDER, RIGHT_SHOULDER = 9, 10, 11, 12
#: mediapipe-depth: the nose nearer than the ears by more than this is "facing", metres.
NOSE_DEPTH_MARGIN_M = 0.02
#: mediapipe-visibility: the face landmarks' least visibility taken as a face seen.
FACE_VISIBILITY = 0.9
#: face-cascade: the crop's side in head heights, and the side it is resized to (pixels).
CASCADE_CROP, CASCADE_SIDE_PX = 1.4, 80
#: The head's height over its width, for a box made from MediaPipe's landmarks.
HEAD_ASPECT = 1.45


@dataclass(frozen=True)
class HeadBox:
    """The head's box in the input frame, pixels.

    Attributes
    ----------
    u, v : float
        Its centre (column, row coordinates; pixel (i, j) covers [j, j+1) x [i, i+1)).
    half_width, half_height : float
        Half its width and height.
    """

    u: float
    v: float
    half_width: float
    half_height: float


@dataclass
class FrameRecord:
    """One frame's truth and every observer's answer.

    Attributes
    ----------
    material : str
        One of :data:`MATERIALS`.
    source : str
        The sequence's name or the clip's file name.
    seed : int
        The generator's seed (-1 on real clips).
    size : str
        ``WIDTHxHEIGHT`` of the input, pixels.
    frame : int
    heading_deg : float
        The chest's heading relative to the camera (:func:`relative_heading_deg`), degrees; 0 on
        real clips (facing throughout).
    decisions : dict of str to str
        Per observer (:data:`OBSERVERS`), :data:`FACING`, :data:`AWAY` or :data:`NO_ANSWER`;
        the head-colour observers' are made at report time from ``scores``.
    scores : dict of str to float
        Per observer, its continuous score where it has one (NaN for no answer): head-colour's Lab
        chroma distance, mediapipe-depth's ears-less-nose depth (metres), mediapipe-visibility's least
        face visibility.
    milliseconds : dict of str to float
        Wall-clock time per observer (``mediapipe``: the detector, shared by its observers).
    """

    material: str
    source: str
    seed: int
    size: str
    frame: int
    heading_deg: float
    decisions: dict = field(default_factory=dict)
    scores: dict = field(default_factory=dict)
    milliseconds: dict = field(default_factory=dict)

    @property
    def facing(self) -> bool:
        """The truth: the chest within 90 degrees of facing the camera."""
        return abs(self.heading_deg) < 90.0


def relative_heading_deg(pose) -> float:
    """The chest's heading relative to the camera, degrees in (-180, 180].

    The chest faces ``(-sin yaw, -cos yaw)`` in the camera's (x, z) plane
    (:mod:`mocap.body.pose`: yaw 0 faces the camera, positive turns the face to -x); the camera
    is seen from the root in the direction ``(-x, -z)``. Their angle is
    ``yaw - atan2(x, z)``, wrapped.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Metres and radians.
    """
    q = np.asarray(pose, dtype=np.float64)
    yaw = q[PARAMETER_INDEX[HEADING]]
    towards = math.atan2(q[PARAMETER_INDEX["root_x"]], q[PARAMETER_INDEX["root_z"]])
    deg = math.degrees(yaw - towards)
    deg = (deg + 180.0) % 360.0 - 180.0
    return 180.0 if deg == -180.0 else deg


def head_box_of_pose(pose, model: BodyModel, camera) -> HeadBox:
    """The true head's box: its centre (the ``head`` joint) projected, its length and width at
    its depth (upright; the head's tilt is not counted)."""
    centre = model.joint_positions(pose)[JOINT_INDEX["head"]]
    u, v = camera.project(centre)
    head = model.dims["head"]
    return HeadBox(float(u), float(v), 0.5 * head.width * camera.fx / centre[2],
                   0.5 * head.length * camera.fy / centre[2])


def head_box_of_landmarks(landmarks: np.ndarray | None, width: int, height: int) -> HeadBox | None:
    """The head's box from MediaPipe Pose's landmarks (33, 4; x, y normalised), or None.

    The centre is the ears' midpoint raised by a tenth of the head's height; the width the
    largest of the ears' distance, twice the nose's distance from the ears' midpoint and 0.4 of
    the shoulders' (a profile brings the ears together); the height :data:`HEAD_ASPECT` times it.
    """
    if landmarks is None:
        return None
    xy = landmarks[:, :2] * np.array([width, height])
    ears = 0.5 * (xy[LEFT_EAR] + xy[RIGHT_EAR])
    head_width = max(float(np.linalg.norm(xy[LEFT_EAR] - xy[RIGHT_EAR])),
                     2.0 * float(np.linalg.norm(xy[NOSE] - ears)),
                     0.4 * float(np.linalg.norm(xy[LEFT_SHOULDER] - xy[RIGHT_SHOULDER])), 1.0)
    half_h = 0.5 * HEAD_ASPECT * head_width
    return HeadBox(float(ears[0]), float(ears[1] - 0.2 * half_h), 0.5 * head_width, half_h)


def _region(frame: np.ndarray, box: HeadBox, rows: tuple[float, float], cols: tuple[float, float]) -> np.ndarray:
    """The frame's pixels (K, 3) in a part of the box (fractions of its height and width), clipped to the frame."""
    top, left = box.v - box.half_height, box.u - box.half_width
    r0 = int(math.floor(top + rows[0] * 2 * box.half_height))
    r1 = int(math.ceil(top + rows[1] * 2 * box.half_height))
    c0 = int(math.floor(left + cols[0] * 2 * box.half_width))
    c1 = int(math.ceil(left + cols[1] * 2 * box.half_width))
    h, w = frame.shape[:2]
    return frame[max(r0, 0):min(r1, h), max(c0, 0):min(c1, w)].reshape(-1, 3)


def head_colour_score(frame: np.ndarray, box: HeadBox | None) -> float:
    """The head's face band against its crown: the CIE Lab chroma distance (a* and b*; the
    lightness, which shading changes from crown to face, left out) of their median colours, or
    NaN where either has fewer than :data:`MIN_REGION_PIXELS` pixels.

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3), uint8
        RGB at the input's size.
    box : HeadBox or None
    """
    if box is None:
        return math.nan
    crown = _region(frame, box, CROWN_ROWS, REGION_COLS)
    band = _region(frame, box, FACE_ROWS, REGION_COLS)
    if len(crown) < MIN_REGION_PIXELS or len(band) < MIN_REGION_PIXELS:
        return math.nan
    medians = np.stack([np.median(crown, axis=0), np.median(band, axis=0)]) / 255.0
    lab = color.rgb2lab(medians[None])[0]
    return float(np.linalg.norm(lab[1, 1:] - lab[0, 1:]))


def cascade_in_box(frame: np.ndarray, box: HeadBox | None) -> str:
    """The LBP frontal face cascade on a square crop about the head's box (edges repeated where
    it leaves the frame), resized to :data:`CASCADE_SIDE_PX`: :data:`FACING` when it finds a
    face, :data:`AWAY` when not, :data:`NO_ANSWER` without a box."""
    if box is None:
        return NO_ANSWER
    half = 0.5 * CASCADE_CROP * 2.0 * box.half_height
    r0, r1 = int(round(box.v - half)), int(round(box.v + half))
    c0, c1 = int(round(box.u - half)), int(round(box.u + half))
    if r1 - r0 < 2 or c1 - c0 < 2:
        return NO_ANSWER
    h, w = frame.shape[:2]
    pad = max(0, -r0, -c0, r1 - h, c1 - w)
    padded = np.pad(frame, ((pad, pad), (pad, pad), (0, 0)), mode="edge") if pad else frame
    crop = padded[r0 + pad:r1 + pad, c0 + pad:c1 + pad]
    crop = transform.resize(crop, (CASCADE_SIDE_PX, CASCADE_SIDE_PX), anti_aliasing=crop.shape[0] > CASCADE_SIDE_PX)
    found = detect_face(np.clip(crop, 0.0, 1.0), min_size=24)
    return FACING if found is not None else AWAY


def mediapipe_observations(landmarks: np.ndarray | None, world: np.ndarray | None
                           ) -> tuple[dict[str, str], dict[str, float]]:
    """The three MediaPipe observers' decisions and scores from one frame's landmarks
    (:meth:`mocap.io.mediapipe_pose.PoseLandmarks.detect`)."""
    names = ("mediapipe-order", "mediapipe-depth", "mediapipe-visibility")
    if landmarks is None:
        return {n: NO_ANSWER for n in names}, {n: math.nan for n in names}
    x = landmarks[:, 0]
    order = (x[LEFT_SHOULDER] - x[RIGHT_SHOULDER]) + (x[LEFT_EAR] - x[RIGHT_EAR])
    decisions = {"mediapipe-order": FACING if order > 0 else AWAY}
    scores = {"mediapipe-order": float(order)}
    if world is None:
        decisions["mediapipe-depth"], scores["mediapipe-depth"] = NO_ANSWER, math.nan
    else:
        depth = 0.5 * (world[LEFT_EAR, 2] + world[RIGHT_EAR, 2]) - world[NOSE, 2]   # > 0: the nose nearer
        decisions["mediapipe-depth"] = (FACING if depth > NOSE_DEPTH_MARGIN_M else
                                        AWAY if depth < -NOSE_DEPTH_MARGIN_M else NO_ANSWER)
        scores["mediapipe-depth"] = float(depth)
    seen = float(landmarks[[NOSE, LEFT_EYE, RIGHT_EYE, MOUTH_LEFT, MOUTH_RIGHT], 3].min())
    decisions["mediapipe-visibility"] = FACING if seen >= FACE_VISIBILITY else AWAY
    scores["mediapipe-visibility"] = seen
    return decisions, scores


def observe(frame: np.ndarray, detector, truth_box: HeadBox | None) -> tuple[dict, dict, dict]:
    """Every observer on one frame: decisions, scores and milliseconds (see :class:`FrameRecord`).

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3), uint8
    detector : mocap.io.mediapipe_pose.PoseLandmarks
    truth_box : HeadBox or None
        The true head's box (None on real clips: those observers are left out).
    """
    decisions, scores, ms = {}, {}, {}
    h, w = frame.shape[:2]
    t = time.perf_counter()
    landmarks, world = detector.detect(frame)
    ms["mediapipe"] = 1e3 * (time.perf_counter() - t)
    d, s = mediapipe_observations(landmarks, world)
    decisions.update(d)
    scores.update(s)
    boxes = {"mediapipe": head_box_of_landmarks(landmarks, w, h)}
    if truth_box is not None:
        boxes["truth"] = truth_box
    for which, box in boxes.items():
        t = time.perf_counter()
        scores[f"head-colour[{which}]"] = head_colour_score(frame, box)
        ms[f"head-colour[{which}]"] = 1e3 * (time.perf_counter() - t)
        t = time.perf_counter()
        decisions[f"face-cascade[{which}]"] = cascade_in_box(frame, box)
        ms[f"face-cascade[{which}]"] = 1e3 * (time.perf_counter() - t)
    return decisions, scores, ms


def size_text(size: tuple[int, int]) -> str:
    return f"{size[0]}x{size[1]}"


def measure_synthetic(sequence: str, seed: int, size: tuple[int, int], face: bool, stride: int,
                      detector) -> list[FrameRecord]:
    """Every ``stride``-th frame of one synthetic sequence at one size, with or without the face."""
    setup = setup_sequence(sequence, seed=seed, size=size, face=face)
    poses, _ = sequence_poses(setup)
    model = BodyModel.build(setup.actor.dims)
    out = []
    for i in range(0, len(poses), stride):
        frame = setup.frame(poses[i], i)
        decisions, scores, ms = observe(frame, detector, head_box_of_pose(poses[i], model, setup.camera))
        out.append(FrameRecord("face" if face else "faceless", sequence, seed, size_text(size), i,
                               relative_heading_deg(poses[i]), decisions, scores, ms))
    return out


def measure_real(path: Path, factor: int, stride: int, detector) -> list[FrameRecord]:
    """Every ``stride``-th frame of a real clip reduced by ``factor``; the truth "facing"."""
    out = []
    indices = list(range(0, count_frames(path), stride))
    for i, frame in zip(indices, iter_frames(path, indices=indices)):
        small = downscale(frame, factor)
        decisions, scores, ms = observe(small, detector, None)
        out.append(FrameRecord("real", path.name, -1, size_text((small.shape[1], small.shape[0])), i, 0.0,
                               decisions, scores, ms))
    return out


# ------------------------------------------------------------------------------------------------ tables

def heading_bin(heading_deg: float) -> str:
    """The |heading| bin's label (:data:`ABS_BINS_DEG`), e.g. ``"0-45"``; 180 goes in the last."""
    a = abs(heading_deg)
    for lo, hi in ABS_BINS_DEG:
        if lo <= a < hi or (hi == 180 and a == 180):
            return f"{lo:g}-{hi:g}"
    raise ValueError(f"heading {heading_deg} is outside [-180, 180]")


def fit_threshold(scores: np.ndarray, facing: np.ndarray) -> float:
    """The head-colour threshold (score at or above: "facing") of the best balanced accuracy
    over the answered frames; NaN scores are left out. Candidates are the midpoints of the
    sorted scores; a tie goes to the lowest."""
    s, y = np.asarray(scores, dtype=np.float64), np.asarray(facing, dtype=bool)
    keep = np.isfinite(s)
    s, y = s[keep], y[keep]
    if not y.any() or y.all():
        raise ValueError("a threshold needs frames facing and facing away")
    values = np.unique(s)
    candidates = np.concatenate([[values[0] - 1.0], 0.5 * (values[1:] + values[:-1]), [values[-1] + 1.0]])
    best, best_t = -1.0, math.nan
    for t in candidates:
        said = s >= t
        balanced = 0.5 * (said[y].mean() + (~said[~y]).mean())
        if balanced > best + 1e-12:
            best, best_t = balanced, float(t)
    return best_t


def agreeing(records: list[FrameRecord], first: str = "mediapipe-order", second: str = "mediapipe-depth",
             name: str = "mediapipe-agree") -> None:
    """Fill ``name``'s decisions (in place): ``first``'s answer where ``second`` gives the same,
    else :data:`NO_ANSWER`."""
    for r in records:
        if first in r.decisions and second in r.decisions:
            a, b = r.decisions[first], r.decisions[second]
            r.decisions[name] = a if a == b and a != NO_ANSWER else NO_ANSWER


def precision(records: list[FrameRecord], observer: str, said: str) -> tuple[float, int]:
    """Of the frames where ``observer`` said ``said`` (:data:`FACING` or :data:`AWAY`), the
    share (%) whose truth agrees, and their number."""
    rs = [r for r in records if r.decisions.get(observer) == said]
    right = sum(r.facing == (said == FACING) for r in rs)
    return (100.0 * right / len(rs) if rs else math.nan), len(rs)


def apply_thresholds(records: list[FrameRecord], thresholds: dict[str, float]) -> None:
    """Fill the head-colour observers' decisions from their scores (in place)."""
    for r in records:
        for name, t in thresholds.items():
            if name in r.scores:
                s = r.scores[name]
                r.decisions[name] = NO_ANSWER if not np.isfinite(s) else FACING if s >= t else AWAY


@dataclass(frozen=True)
class Cell:
    """Counts of one observer's decisions on a group of frames.

    Attributes
    ----------
    frames : int
    said_facing, said_away, no_answer : int
    truth_facing : int
        Frames whose truth is facing.
    right : int
        Answered frames whose answer is the truth.
    """

    frames: int
    said_facing: int
    said_away: int
    no_answer: int
    truth_facing: int
    right: int

    @property
    def answered(self) -> int:
        return self.said_facing + self.said_away

    def share(self, count: int) -> float:
        """``count`` as a percentage of the frames (NaN for none)."""
        return 100.0 * count / self.frames if self.frames else math.nan


def count(records: list[FrameRecord], observer: str) -> Cell:
    """One observer's decisions on ``records`` (frames where it was not run are left out)."""
    rs = [r for r in records if observer in r.decisions]
    said = [r.decisions[observer] for r in rs]
    right = sum((d == FACING) == r.facing for r, d in zip(rs, said) if d != NO_ANSWER)
    return Cell(len(rs), said.count(FACING), said.count(AWAY), said.count(NO_ANSWER),
                sum(r.facing for r in rs), right)


def balanced_accuracy(records: list[FrameRecord], observer: str) -> tuple[float, float, float]:
    """Right share (%) on frames facing, on frames facing away (no answer counts as wrong), and
    their mean; NaN where there are none."""
    facing = count([r for r in records if r.facing], observer)
    away = count([r for r in records if not r.facing], observer)
    a = 100.0 * facing.said_facing / facing.frames if facing.frames else math.nan
    b = 100.0 * away.said_away / away.frames if away.frames else math.nan
    return a, b, 0.5 * (a + b) if facing.frames and away.frames else math.nan


def _pct(x: float) -> str:
    return "–" if not np.isfinite(x) else f"{x:.0f}"


def binned_table(records: list[FrameRecord], observers, sizes: list[str], material: str) -> list[str]:
    """Markdown rows: per observer and size, "said facing / no answer" % per |heading| bin."""
    bins = [f"{lo:g}-{hi:g}" for lo, hi in ABS_BINS_DEG]
    lines = [f"| observer | size | " + " | ".join(f"\\|h\\| {b}°: facing / none % (n)" for b in bins)
             + " | balanced accuracy % |", "|---|---|" + "---|" * len(bins) + "---|"]
    for name in observers:
        for size in sizes:
            rs = [r for r in records if r.material == material and r.size == size and name in r.decisions]
            if not rs:
                continue
            cells = []
            for b in bins:
                c = count([r for r in rs if heading_bin(r.heading_deg) == b], name)
                cells.append(f"{_pct(c.share(c.said_facing))} / {_pct(c.share(c.no_answer))} ({c.frames})")
            lines.append(f"| {name} | {size} | " + " | ".join(cells) + f" | {_pct(balanced_accuracy(rs, name)[2])} |")
    return lines


def real_table(records: list[FrameRecord], observers, sizes: list[str]) -> list[str]:
    lines = ["| observer | " + " | ".join(f"{s}: facing / none % (n)" for s in sizes) + " |",
             "|---|" + "---|" * len(sizes)]
    for name in observers:
        cells = []
        for size in sizes:
            c = count([r for r in records if r.material == "real" and r.size == size], name)
            cells.append(f"{_pct(c.share(c.said_facing))} / {_pct(c.share(c.no_answer))} ({c.frames})"
                         if c.frames else "–")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines


def cost_table(records: list[FrameRecord], sizes: list[str]) -> list[str]:
    keys = ("head-colour[truth]", "head-colour[mediapipe]", "mediapipe", "face-cascade[truth]",
            "face-cascade[mediapipe]")
    lines = ["| cost, ms per frame (median / 90th percentile) | " + " | ".join(sizes) + " |",
             "|---|" + "---|" * len(sizes)]
    for k in keys:
        cells = []
        for size in sizes:
            v = np.array([r.milliseconds[k] for r in records if r.size == size and k in r.milliseconds])
            cells.append(f"{np.median(v):.2f} / {np.percentile(v, 90):.2f}" if len(v) else "–")
        label = "MediaPipe Pose (its three observers and its box)" if k == "mediapipe" else k
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return lines


def report(records: list[FrameRecord], fit_seeds, out: Path) -> dict:
    """Fit the head-colour thresholds on ``fit_seeds`` (with the face, every size together),
    apply them, write ``front_back.md`` and ``summary.json``; returns the summary."""
    fit = [r for r in records if r.material == "face" and r.seed in fit_seeds]
    thresholds = {}
    for name in ("head-colour[truth]", "head-colour[mediapipe]"):
        rs = [r for r in fit if name in r.scores]
        thresholds[name] = fit_threshold(np.array([r.scores[name] for r in rs]), np.array([r.facing for r in rs]))
    apply_thresholds(records, thresholds)
    agreeing(records)
    sizes = sorted({r.size for r in records}, key=lambda s: int(s.split("x")[0]))
    synthetic_sizes = sorted({r.size for r in records if r.material != "real"}, key=lambda s: int(s.split("x")[0]))
    real_sizes = sorted({r.size for r in records if r.material == "real"}, key=lambda s: int(s.split("x")[0]))
    seeds = sorted({r.seed for r in records if r.material != "real"})
    unseen = [s for s in seeds if s not in fit_seeds]
    lines = ["# Front or back from the input's pixels (issue 49, item 1)", "",
             f"Head-colour thresholds (Lab chroma distance, fitted on seeds {', '.join(map(str, fit_seeds))} with the face): "
             + ", ".join(f"{k} {v:.1f}" for k, v in thresholds.items()), ""]
    groups = [("face", [s for s in seeds if s in fit_seeds], "with the face, seeds " + ",".join(map(str, fit_seeds))),
              ("faceless", [s for s in seeds if s in fit_seeds], "hair all round, seeds " + ",".join(map(str, fit_seeds)))]
    if unseen:
        groups += [("face", unseen, "with the face, unseen seeds " + ",".join(map(str, unseen))),
                   ("faceless", unseen, "hair all round, unseen seeds " + ",".join(map(str, unseen)))]
    summary = {"thresholds": thresholds, "fit_seeds": list(fit_seeds), "unseen_seeds": unseen, "groups": []}
    lines += ["## Summary", "",
              "Right on facing / on facing away: the share of the synthetic frames with the face whose answer is "
              "the truth (no answer counts as not right). Faceless, facing: the figure with hair all round, "
              "|heading| < 90°, said facing / said away. \"facing\" right: of all synthetic frames (face and "
              "faceless, seeds 0–4) said facing, the share truly facing; \"away\" right: the same for away, "
              "with the face only (every faceless frame said away is wrong when it faces the camera). Real: the real clips said facing.", "",
              "| observer | size | face, seeds 0–4: right on facing / away % | face, unseen: right on facing / away % "
              "| faceless, facing: said facing / away % | \"facing\" right % (n), seeds 0–4 / unseen "
              "| \"away\" right % (n), seeds 0–4 / unseen | real: said facing % |",
              "|---|---|---|---|---|---|---|---|"]
    for name in OBSERVERS:
        for size in synthetic_sizes:
            at = [r for r in records if r.size == size and r.material != "real" and name in r.decisions]
            if not at:
                continue
            fit_face = [r for r in at if r.material == "face" and r.seed in fit_seeds]
            new_face = [r for r in at if r.material == "face" and r.seed not in fit_seeds]
            faceless = count([r for r in at if r.material == "faceless" and r.facing], name)
            a, b, _ = balanced_accuracy(fit_face, name)
            ua, ub, _ = balanced_accuracy(new_face, name) if new_face else (math.nan, math.nan, math.nan)
            pf, nf = precision([r for r in at if r.seed in fit_seeds], name, FACING)
            pa, na = precision(fit_face, name, AWAY)
            upf, unf = precision([r for r in at if r.seed not in fit_seeds], name, FACING)
            upa, una = precision(new_face, name, AWAY)
            real_size = f"{size}"
            real = count([r for r in records if r.material == "real" and r.size == real_size], name)
            lines.append(f"| {name} | {size} | {_pct(a)} / {_pct(b)} | {_pct(ua)} / {_pct(ub)} | "
                         f"{_pct(faceless.share(faceless.said_facing))} / {_pct(faceless.share(faceless.said_away))} | "
                         f"{_pct(pf)} ({nf}) / {_pct(upf)} ({unf}) | {_pct(pa)} ({na}) / {_pct(upa)} ({una}) | "
                         f"{_pct(real.share(real.said_facing)) if real.frames else '–'} |")
    lines.append("")
    for material, group_seeds, title in groups:
        rs = [r for r in records if r.material == material and r.seed in group_seeds]
        if not rs:
            continue
        lines += [f"## Synthetic, {title}", "", "Per |heading| bin: the share of frames said facing "
                  "(right below 90°) and with no answer.", ""]
        lines += binned_table(rs, OBSERVERS, synthetic_sizes, material) + [""]
        for name in OBSERVERS:
            for size in synthetic_sizes:
                sub = [r for r in rs if r.size == size and name in r.decisions]
                if sub:
                    a, b, m = balanced_accuracy(sub, name)
                    summary["groups"].append({"material": material, "seeds": group_seeds, "observer": name,
                                              "size": size, "right_facing_pct": a, "right_away_pct": b,
                                              "balanced_pct": m, "frames": len(sub),
                                              "bins": {bn: asdict(count([r for r in sub if heading_bin(r.heading_deg) == bn], name))
                                                       for bn in (f"{lo:g}-{hi:g}" for lo, hi in ABS_BINS_DEG)}})
    if real_sizes:
        lines += ["## Real clips (facing the camera on every frame)", ""]
        lines += real_table(records, [o for o in OBSERVERS if "[truth]" not in o], real_sizes) + [""]
        for name in OBSERVERS:
            for size in real_sizes:
                c = count([r for r in records if r.material == "real" and r.size == size], name)
                if c.frames:
                    summary["groups"].append({"material": "real", "observer": name, "size": size, **asdict(c)})
    lines += ["## Cost", "", "Wall-clock ms per frame in this process (a shared 2-core machine; under "
              "`taskset -c 0` for one core).", ""] + cost_table(records, sizes) + [""]
    out.mkdir(parents=True, exist_ok=True)
    (out / "front_back.md").write_text("\n".join(lines) + "\n")
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=float) + "\n")
    return summary


# ------------------------------------------------------------------------------------------------ files

def _unit_path(out: Path, material: str, size: str, source: str) -> Path:
    return out / "frames" / f"{material}_{size}_{source}.json"


def _write(path: Path, records: list[FrameRecord]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps([asdict(r) for r in records], default=float))
    tmp.replace(path)


def load_records(out: Path) -> list[FrameRecord]:
    """Every record under ``out/frames``."""
    records = []
    for path in sorted((out / "frames").glob("*.json")):
        records += [FrameRecord(**row) for row in json.loads(path.read_text())]
    return records


def measure(args) -> None:
    from mocap.io.mediapipe_pose import PoseLandmarks

    detector = PoseLandmarks()
    try:
        for size in args.sizes:
            for seed in args.seeds:
                for face in (True, False):
                    material = "face" if face else "faceless"
                    path = _unit_path(args.out, material, size_text(size), f"seed{seed}")
                    if path.exists():
                        continue
                    records = []
                    for sequence in args.sequences:
                        records += measure_synthetic(sequence, seed, size, face, args.stride, detector)
                    _write(path, records)
                    print(f"{material} {size_text(size)} seed {seed}: {len(records)} frames", flush=True)
        for clip in args.real:
            path = Path(args.data) / "video" / clip
            for factor in args.factors:
                unit = _unit_path(args.out, "real", f"by{factor}", path.stem)
                if unit.exists():
                    continue
                records = measure_real(path, factor, args.real_stride, detector)
                _write(unit, records)
                print(f"real {clip} /{factor}: {len(records)} frames", flush=True)
    finally:
        detector.close()


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m experiments.front_back", description=__doc__.split("\n\n")[0])
    p.add_argument("command", choices=("measure", "report", "all"), nargs="?", default="all",
                   help="measure the frames, report the tables from what is measured, or both (default)")
    p.add_argument("--seeds", default=",".join(map(str, FIT_SEEDS + UNSEEN_SEEDS)),
                   help=f"generator seeds (thresholds fitted on {FIT_SEEDS}; others reported apart)")
    p.add_argument("--sequences", default=",".join(DEFAULT_SEQUENCES), help="synthetic sequences")
    p.add_argument("--sizes", default=",".join(size_text(s) for s in DEFAULT_SIZES), help="input sizes, e.g. 160x120,320x240")
    p.add_argument("--stride", type=int, default=4, help="every N-th synthetic frame (default 4)")
    p.add_argument("--real", default=",".join(REAL_CLIPS), help="real clips under DATA/video ('' for none)")
    p.add_argument("--factors", default="1,2,4", help="reduction factors of the real clips (default 1,2,4)")
    p.add_argument("--real-stride", type=int, default=2, help="every N-th real frame (default 2)")
    p.add_argument("--data", default="../shared/data", help="the shared data folder")
    p.add_argument("--out", type=Path, default=RESULTS_DIR / "front_back", help="results folder")
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    args.seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    args.sequences = [s for s in args.sequences.split(",") if s.strip()]
    args.sizes = [parse_size(s) for s in args.sizes.split(",") if s.strip()]
    args.real = [s for s in args.real.split(",") if s.strip()]
    args.factors = [int(s) for s in args.factors.split(",") if s.strip()]
    if args.command in ("measure", "all"):
        measure(args)
    if args.command in ("report", "all"):
        records = load_records(args.out)
        if not records:
            print(f"nothing measured under {args.out}", file=sys.stderr)
            return 1
        report(records, FIT_SEEDS, args.out)
        print((args.out / "front_back.md").read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
