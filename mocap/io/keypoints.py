"""2D keypoints of the body's joints, per frame, and the keypoint file (docs/design.md section 4).

A detector (MediaPipe Pose, OpenPose, a hand annotation, ...) gives, for some frames and some
joints, a pixel position and a confidence. :class:`Keypoints` holds one frame of them, by the
joint names of :data:`mocap.body.skeleton.JOINT_NAMES`; a joint the detector did not give (or
gave as NaN) is absent evidence: confidence 0, position NaN.

The keypoint file is a CSV with the header ``frame,joint,u,v,confidence`` and one row per
(frame, joint): ``frame`` the 0-based frame index of the input video, ``joint`` a name of
:data:`~mocap.body.skeleton.JOINT_NAMES`, ``u, v`` pixels of the input frame (u right, v down,
pixel centres at half-integers as in :class:`~mocap.render.camera.Camera`), ``confidence`` in
[0, 1]. Frames or joints without a row, empty or NaN fields are absent evidence; anything else
that does not parse (a wrong header, an unknown joint, a confidence outside [0, 1], a repeated
(frame, joint)) is a ValueError naming the line.

A detector that also gives 3D (MediaPipe Pose's world landmarks) writes the header
``frame,joint,u,v,confidence,x,y,z`` instead: ``x, y, z`` the joint in metres about the
detector's own origin (MediaPipe's: the hips' midpoint) on the camera's axes (x right, y down,
z away from the camera), empty where the detector gave none (:attr:`Keypoints.world`).

**Labellings.** A detector may name the person's left arm the right one (MediaPipe does on a
figure whose face it does not see: docs/research-log.md, issue 44). The sided joints are the
shoulders, elbows, wrists and hands (``r_*`` and ``l_*``); the head and the neck have no side.
:data:`SWAPPED_JOINTS` maps each joint to its twin on the other side and
:meth:`Keypoints.swapped` gives a frame's keypoints under the other labelling; the tracker scores
both (:class:`mocap.cost.KeypointCost`, ``swap``) and files keep the detector's own labels.
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Protocol

import numpy as np

from mocap.body.skeleton import JOINT_NAMES
from mocap.io.files import write_text_atomic

#: Header of the keypoint file.
KEYPOINT_COLUMNS: tuple[str, ...] = ("frame", "joint", "u", "v", "confidence")
#: Header of a keypoint file that also carries the detector's 3D (:attr:`Keypoints.world`).
KEYPOINT_WORLD_COLUMNS: tuple[str, ...] = KEYPOINT_COLUMNS + ("x", "y", "z")
_JOINT = {name: i for i, name in enumerate(JOINT_NAMES)}


def _twin(name: str) -> str:
    """The joint's name on the other side (``r_elbow`` <-> ``l_elbow``; unsided joints are their own)."""
    for a, b in (("r_", "l_"), ("l_", "r_")):
        if name.startswith(a):
            return b + name[len(a):]
    return name


#: Row of each joint's twin on the other side (:data:`~mocap.body.skeleton.JOINT_NAMES` order):
#: the permutation that swaps the detector's left and right labels (an involution).
SWAPPED_JOINTS: tuple[int, ...] = tuple(_JOINT[_twin(name)] for name in JOINT_NAMES)


@dataclass(frozen=True)
class Keypoints:
    """One frame's 2D keypoints, one row per joint of :data:`~mocap.body.skeleton.JOINT_NAMES`.

    Attributes
    ----------
    uv : ndarray, shape (10, 2), float64, pixels
        ``(u, v)`` of each joint; NaN where absent.
    confidence : ndarray, shape (10,), float64
        In [0, 1]; 0 where absent (and wherever ``uv`` is NaN).
    world : ndarray, shape (10, 3), float64, metres, or None
        The detector's own 3D of each joint (MediaPipe Pose's world landmarks,
        :func:`mocap.io.mediapipe_keypoints.world_joints`): about its origin, camera axes (x right,
        y down, z away); NaN where absent, and wherever the joint's 2D is absent. None: the
        detector gave no 3D.
    """

    uv: np.ndarray
    confidence: np.ndarray
    world: np.ndarray | None = None

    def __post_init__(self) -> None:
        uv = np.array(self.uv, dtype=np.float64)
        conf = np.array(self.confidence, dtype=np.float64)
        if uv.shape != (len(JOINT_NAMES), 2) or conf.shape != (len(JOINT_NAMES),):
            raise ValueError(f"keypoints need uv of shape ({len(JOINT_NAMES)}, 2) and confidence of shape "
                             f"({len(JOINT_NAMES)},), got {uv.shape} and {conf.shape}")
        conf = np.where(np.isnan(conf), 0.0, conf)
        if np.any(conf < 0.0) or np.any(conf > 1.0):
            raise ValueError("keypoint confidences must be in [0, 1]")
        if np.any(np.isinf(uv)):
            raise ValueError("keypoint positions must be finite or NaN (absent)")
        absent = np.isnan(uv).any(axis=1) | (conf == 0.0)
        uv[absent] = np.nan
        conf[absent] = 0.0
        arrays = [uv, conf]
        if self.world is not None:
            world = np.array(self.world, dtype=np.float64)
            if world.shape != (len(JOINT_NAMES), 3):
                raise ValueError(f"keypoints' world must have shape ({len(JOINT_NAMES)}, 3), got {world.shape}")
            if np.any(np.isinf(world)):
                raise ValueError("keypoints' world positions must be finite or NaN (absent)")
            world[absent | np.isnan(world).any(axis=1)] = np.nan
            arrays.append(world)
            object.__setattr__(self, "world", world)
        for a in arrays:
            a.setflags(write=False)
        object.__setattr__(self, "uv", uv)
        object.__setattr__(self, "confidence", conf)

    @classmethod
    def empty(cls) -> "Keypoints":
        """No joint present."""
        return cls(np.full((len(JOINT_NAMES), 2), np.nan), np.zeros(len(JOINT_NAMES)))

    @classmethod
    def from_mapping(cls, joints: Mapping[str, tuple[float, float, float]]) -> "Keypoints":
        """From ``{joint name: (u, v, confidence)}`` (pixels); joints left out are absent.

        Raises
        ------
        ValueError
            On a name not in :data:`~mocap.body.skeleton.JOINT_NAMES`.
        """
        uv = np.full((len(JOINT_NAMES), 2), np.nan)
        conf = np.zeros(len(JOINT_NAMES))
        for name, (u, v, c) in joints.items():
            if name not in _JOINT:
                raise ValueError(f"unknown joint {name!r}; joints are {', '.join(JOINT_NAMES)}")
            uv[_JOINT[name]] = u, v
            conf[_JOINT[name]] = c
        return cls(uv, conf)

    def as_mapping(self) -> dict[str, tuple[float, float, float]]:
        """``{joint name: (u, v, confidence)}`` of the joints present."""
        return {name: (float(self.uv[i, 0]), float(self.uv[i, 1]), float(self.confidence[i]))
                for i, name in enumerate(JOINT_NAMES) if self.confidence[i] > 0.0}

    @property
    def present(self) -> np.ndarray:
        """Whether each joint is present, bool (10,)."""
        return self.confidence > 0.0

    def shows_front(self) -> bool:
        """Whether the detector's labels put the person facing the camera: its left shoulder on
        the image's right of its right shoulder, both present (False otherwise, also when it
        cannot tell). MediaPipe Pose is right 96-100 % of the times it says so, on drawn and real
        faces; its contrary is no evidence of a back (docs/research-log.md, 2026-11-29)."""
        left, right = _JOINT["l_shoulder"], _JOINT["r_shoulder"]
        if not (self.confidence[left] > 0.0 and self.confidence[right] > 0.0):
            return False
        return bool(self.uv[left, 0] > self.uv[right, 0])

    def swapped(self) -> "Keypoints":
        """The same frame's keypoints with left and right swapped (:data:`SWAPPED_JOINTS`): the
        detector's ``r_elbow`` becomes ``l_elbow`` and so on; positions, confidences and 3D move
        with their labels (the 3D is not mirrored)."""
        rows = list(SWAPPED_JOINTS)
        return Keypoints(self.uv[rows], self.confidence[rows], None if self.world is None else self.world[rows])

    def scaled(self, sx: float, sy: float) -> "Keypoints":
        """The keypoints of the same frame resampled by ``sx`` horizontally and ``sy`` vertically.

        Positions scale with the image: ``(u, v)`` becomes ``(sx u, sy v)`` (pixel edges, not
        centres, scale), as :meth:`mocap.render.camera.Camera.scaled` scales the principal point.
        """
        if not (math.isfinite(sx) and math.isfinite(sy) and sx > 0 and sy > 0):
            raise ValueError(f"scale factors must be finite and positive, got {sx}, {sy}")
        return Keypoints(self.uv * np.array([sx, sy]), self.confidence, self.world)


class KeypointSource(Protocol):
    """Where a video's keypoints come from: a file, a detector run on each frame, an oracle."""

    def keypoints(self, frame_index: int, image: np.ndarray | None) -> Keypoints:
        """Keypoints of one frame in its input pixels.

        Parameters
        ----------
        frame_index : int
            0-based index of the frame in the input video.
        image : ndarray, shape (H, W, 3), uint8, or None
            The input-resolution frame (RGB), for detectors; files and oracles ignore it.
        """


class KeypointFile:
    """Keypoints read from a keypoint file (see the module): a :class:`KeypointSource`.

    Parameters
    ----------
    path : str or Path

    Raises
    ------
    FileNotFoundError, ValueError
        When the file is missing or malformed (the message names the line).
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.frames = read_keypoints(self.path)
        self.description = f"file {self.path.resolve()}"

    def keypoints(self, frame_index: int, image: np.ndarray | None = None) -> Keypoints:
        return self.frames.get(int(frame_index)) or Keypoints.empty()


def _number(text: str, what: str, where: str) -> float:
    if text.strip() == "":
        return math.nan
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{where}: {what} {text!r} is not a number") from None


def parse_keypoints(text: str, source: str = "keypoint file") -> dict[int, Keypoints]:
    """Parse the text of a keypoint file (see the module).

    Parameters
    ----------
    text : str
    source : str
        Name of the file, for messages.

    Returns
    -------
    dict of int to Keypoints
        By frame index; frames without a present joint are left out.
    """
    rows = csv.reader(io.StringIO(text))
    header = next(rows, None)
    columns = None if header is None else tuple(h.strip() for h in header)
    if columns not in (KEYPOINT_COLUMNS, KEYPOINT_WORLD_COLUMNS):
        raise ValueError(f"{source}: the first line must be {','.join(KEYPOINT_COLUMNS)} (or "
                         f"{','.join(KEYPOINT_WORLD_COLUMNS)}), got {','.join(header) if header else 'nothing'}")
    has_world = columns == KEYPOINT_WORLD_COLUMNS
    uv: dict[int, np.ndarray] = {}
    conf: dict[int, np.ndarray] = {}
    world: dict[int, np.ndarray] = {}
    for line, row in enumerate(rows, start=2):
        if not row or all(not cell.strip() for cell in row):
            continue
        where = f"{source} line {line}"
        if len(row) != len(columns):
            raise ValueError(f"{where}: expected {len(columns)} fields ({','.join(columns)}), got {len(row)}")
        frame_text, joint, u_text, v_text, c_text = (cell.strip() for cell in row[:5])
        try:
            frame = int(frame_text)
        except ValueError:
            raise ValueError(f"{where}: frame {frame_text!r} is not an integer") from None
        if frame < 0:
            raise ValueError(f"{where}: frame {frame} is negative")
        if joint not in _JOINT:
            raise ValueError(f"{where}: unknown joint {joint!r}; joints are {', '.join(JOINT_NAMES)}")
        u, v, c = (_number(t, name, where) for t, name in ((u_text, "u"), (v_text, "v"), (c_text, "confidence")))
        if math.isinf(u) or math.isinf(v) or math.isinf(c):
            raise ValueError(f"{where}: u, v and confidence must be finite (or NaN / empty for absent)")
        if not math.isnan(c) and not 0.0 <= c <= 1.0:
            raise ValueError(f"{where}: confidence {c} is outside [0, 1]")
        frame_uv = uv.setdefault(frame, np.full((len(JOINT_NAMES), 2), np.nan))
        frame_conf = conf.setdefault(frame, np.full(len(JOINT_NAMES), -1.0))
        j = _JOINT[joint]
        if frame_conf[j] != -1.0:
            raise ValueError(f"{where}: frame {frame} gives joint {joint!r} twice")
        frame_uv[j] = u, v
        frame_conf[j] = 0.0 if math.isnan(c) else c
        if has_world:
            xyz = [_number(t.strip(), name, where) for t, name in zip(row[5:], "xyz")]
            if any(math.isinf(x) for x in xyz):
                raise ValueError(f"{where}: x, y and z must be finite (or NaN / empty for absent)")
            world.setdefault(frame, np.full((len(JOINT_NAMES), 3), np.nan))[j] = xyz
    out = {}
    for frame in sorted(uv):
        k = Keypoints(uv[frame], np.maximum(conf[frame], 0.0),
                      world.get(frame, np.full((len(JOINT_NAMES), 3), np.nan)) if has_world else None)
        if k.present.any():
            out[frame] = k
    return out


def read_keypoints(path: str | Path) -> dict[int, Keypoints]:
    """Read a keypoint file (see the module): keypoints by frame index, input pixels.

    Raises
    ------
    FileNotFoundError
    ValueError
        When malformed; the message names the file and line.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"keypoint file not found: {path}")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a UTF-8 text file") from None
    return parse_keypoints(text, str(path))


def write_keypoints(path: str | Path, frames: Mapping[int, Keypoints]) -> None:
    """Write keypoints by frame index as a keypoint file (atomically; present joints only).

    Parameters
    ----------
    path : str or Path
    frames : mapping of int to Keypoints
        Input pixels; values are written with 17 significant digits (they read back exactly).
    """
    write_text_atomic(path, _text(frames, header=True))


def append_keypoints(path: str | Path, frame: int, keypoints: Keypoints) -> None:
    """Append one frame's keypoints to a keypoint file used as a journal (the header first if the
    file is new or empty; no row for a frame without a present joint), flushed to the operating
    system, not synced (the caller syncs it with its checkpoint, as :mod:`mocap.run.journal` does).

    A process killed while appending leaves at most a partial last line, which the journal's
    checkpoint cuts off on resume (:func:`mocap.io.checkpoint.cut_journal`).

    Parameters
    ----------
    path : str or Path
    frame : int
        0-based frame index.
    keypoints : Keypoints
        Input pixels (written as :func:`write_keypoints` writes them: they read back exactly).
    """
    with Path(path).open("a", newline="") as fh:
        fh.write(_text({frame: keypoints}, header=fh.tell() == 0))
        fh.flush()


def _text(frames: Mapping[int, Keypoints], header: bool) -> str:
    """The keypoint file's lines of ``frames`` (present joints only, 17 significant digits)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    with_world = any(k.world is not None for k in frames.values())
    if header:
        writer.writerow(KEYPOINT_WORLD_COLUMNS if with_world else KEYPOINT_COLUMNS)
    for frame in sorted(frames):
        keypoints = frames[frame]
        for name, (u, v, c) in keypoints.as_mapping().items():
            row = [int(frame), name, repr(u), repr(v), repr(c)]
            if with_world:
                xyz = np.full(3, np.nan) if keypoints.world is None else keypoints.world[_JOINT[name]]
                row += ["" if math.isnan(x) else repr(float(x)) for x in xyz]
            writer.writerow(row)
    return buf.getvalue()


__all__ = ["KEYPOINT_COLUMNS", "KEYPOINT_WORLD_COLUMNS", "SWAPPED_JOINTS", "KeypointFile", "KeypointSource", "Keypoints",
           "append_keypoints", "parse_keypoints",
           "read_keypoints", "write_keypoints"]
