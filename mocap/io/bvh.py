"""BVH (Biovision hierarchy) motion files: a reader for any clip and a writer for our model.

Reading
-------
:func:`read_bvh` returns a :class:`Bvh`: the joint hierarchy (names, parents, rest offsets,
channel lists; ``End Site`` entries become joints named ``<parent>_end`` without channels),
the frame time and the per-frame channel values exactly as in the file (rotations in degrees,
positions in file units). Both naming conventions of the CMU conversions are recognised by
:attr:`Bvh.convention` (``"motionbuilder"``: Hips, Spine1, LeftArm, LeftForeArm, LeftHand, ...;
``"3dsmax"``: Hips, Chest2, LeftShoulder, LeftElbow, lhand, ...) as are files written here
(``"mocap"``).

Semantics used by :meth:`Bvh.local_rotations` and :meth:`Bvh.global_transforms` (those of
Blender's importer and of the CMU conversions): the rotation channels of a joint compose in
the order listed, ``CHANNELS 3 Zrotation Xrotation Yrotation`` meaning ``R = Rz @ Rx @ Ry``
acting on column vectors of the joint's frame; a joint's position in its parent's frame is its
``OFFSET``, except that position channels, where present, replace it.

Writing
-------
:func:`write_bvh` exports poses of our model (``poses.bvh`` of the tracker): one joint per
segment of :data:`~mocap.body.skeleton.SEGMENT_NAMES` with offsets from the body dimensions,
in metres, in a Y-up world that is the camera frame turned upside down (``x`` right, ``y`` up,
``z`` towards the viewer: the camera sits at the origin looking along ``-z``, as an OpenGL or
Blender camera does). Channels per joint, with the sign that maps our angle (docs/design.md section
2; ``m`` is +1 for the right arm and -1 for the left):

===========  ============================================  =====================================
joint        channels                                      values
===========  ============================================  =====================================
chest        Xposition Yposition Zposition                 root_x, -root_y, -root_z (metres)
             Yrotation Xrotation Zrotation                 -chest_yaw, chest_pitch, -chest_roll
head         Xrotation Zrotation Yrotation                 head_flex, -head_tilt, -head_turn
*_upper_arm  Xrotation Zrotation Yrotation                 -shoulder_flex, -m abd, -m rot
*_forearm    Xrotation Yrotation Zrotation                 -elbow_flex, -m twist, 0
*_hand       Xrotation Zrotation Yrotation                 -wrist_flex, -m dev, 0
===========  ============================================  =====================================

(angles in degrees). These follow from conjugating our forward kinematics
(:mod:`mocap.body.kinematics`) by the 180-degree turn about x between the two frames, which
keeps rotations about x and negates those about y and z. :func:`read_pose_bvh` inverts the
table for files written here.
"""
from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from types import MappingProxyType

import numpy as np
from scipy.spatial.transform import Rotation

from mocap.body.dimensions import PART_NAMES, BodyDimensions
from mocap.body.pose import N_PARAMETERS, PARAMETER_INDEX, check_pose
from mocap.body.skeleton import SEGMENT_NAMES, SEGMENT_PARENTS, part_spans, segment_offsets
from mocap.io.files import write_text_atomic

__all__ = ["CAMERA_TO_BVH", "CHANNEL_NAMES", "CONVENTIONS", "JOINT_MAPS", "Bvh", "BvhJoint", "pose_channels",
           "read_bvh", "read_pose_bvh", "write_bvh"]

#: Channel names accepted, in their canonical spelling.
CHANNEL_NAMES: tuple[str, ...] = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
_CANONICAL = {c.lower(): c for c in CHANNEL_NAMES}

#: File joint of each of our segments (and of the root position), per BVH naming convention.
JOINT_MAPS = MappingProxyType({
    "mocap": MappingProxyType({
        "root": "chest", "chest": "chest", "head": "head",
        "r_upper_arm": "r_upper_arm", "r_forearm": "r_forearm", "r_hand": "r_hand",
        "l_upper_arm": "l_upper_arm", "l_forearm": "l_forearm", "l_hand": "l_hand"}),
    "motionbuilder": MappingProxyType({
        "root": "Hips", "chest": "Spine1", "head": "Head",
        "r_upper_arm": "RightArm", "r_forearm": "RightForeArm", "r_hand": "RightHand",
        "l_upper_arm": "LeftArm", "l_forearm": "LeftForeArm", "l_hand": "LeftHand"}),
    "3dsmax": MappingProxyType({
        "root": "Hips", "chest": "Chest2", "head": "Head",
        "r_upper_arm": "RightShoulder", "r_forearm": "RightElbow", "r_hand": "rhand",
        "l_upper_arm": "LeftShoulder", "l_forearm": "LeftElbow", "l_hand": "lhand"}),
})

#: Joints that identify each naming convention (all must be present): those of :data:`JOINT_MAPS`.
CONVENTIONS = MappingProxyType({key: tuple(dict.fromkeys(joints.values())) for key, joints in JOINT_MAPS.items()})

#: Rotation taking camera coordinates (x right, y down, z forward) to the BVH world written
#: here (x right, y up, z towards the viewer): a half turn about x.
CAMERA_TO_BVH: np.ndarray = np.diag([1.0, -1.0, -1.0])
CAMERA_TO_BVH.setflags(write=False)


@dataclass(frozen=True)
class BvhJoint:
    """One joint of a BVH hierarchy.

    Attributes
    ----------
    name : str
        Joint name (``<parent>_end`` for an ``End Site``).
    parent : int
        Index of the parent joint, -1 for the root.
    offset : tuple of 3 float
        Rest position in the parent's frame, file units.
    channels : tuple of str
        Channel names in file order (from :data:`CHANNEL_NAMES`); empty for an end site.
    end_site : bool
    """

    name: str
    parent: int
    offset: tuple[float, float, float]
    channels: tuple[str, ...] = ()
    end_site: bool = False


@dataclass(frozen=True)
class Bvh:
    """A parsed BVH file.

    Attributes
    ----------
    joints : tuple of BvhJoint
        Parents before children, in file order.
    frame_time : float
        Seconds per frame.
    motion : ndarray, shape (N, C), float64
        Channel values per frame in file order: degrees for rotations, file units for
        positions.
    """

    joints: tuple[BvhJoint, ...]
    frame_time: float
    motion: np.ndarray

    def __post_init__(self) -> None:
        if not self.joints:
            raise ValueError("a BVH hierarchy needs at least one joint")
        names = [j.name for j in self.joints]
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"duplicate BVH joint names: {', '.join(dup)}")
        for i, j in enumerate(self.joints):
            if not (-1 <= j.parent < i) or (j.parent == -1) != (i == 0):
                raise ValueError(f"joint {j.name!r} has a bad parent index {j.parent}")
            bad = [c for c in j.channels if c not in CHANNEL_NAMES]
            if bad:
                raise ValueError(f"joint {j.name!r} has unknown channel(s) {', '.join(bad)}")
        if not math.isfinite(self.frame_time) or self.frame_time <= 0:
            raise ValueError(f"frame time must be a positive number of seconds, got {self.frame_time}")
        motion = np.asarray(self.motion, dtype=np.float64)
        n_channels = sum(len(j.channels) for j in self.joints)
        if motion.ndim != 2 or motion.shape[1] != n_channels:
            raise ValueError(f"motion must have shape (frames, {n_channels}), got {motion.shape}")
        if not np.isfinite(motion).all():
            raise ValueError("motion holds non-finite channel values")
        motion.setflags(write=False)
        object.__setattr__(self, "motion", motion)

    # -- description -------------------------------------------------------------------
    @property
    def n_frames(self) -> int:
        return int(self.motion.shape[0])

    @property
    def fps(self) -> float:
        """Frames per second (1 / frame time)."""
        return 1.0 / self.frame_time

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    @property
    def parents(self) -> np.ndarray:
        """Parent index of every joint, int64 (J,), -1 for the root."""
        return np.array([j.parent for j in self.joints], dtype=np.int64)

    @property
    def offsets(self) -> np.ndarray:
        """Rest offsets, float64 (J, 3), file units."""
        return np.array([j.offset for j in self.joints], dtype=np.float64)

    @property
    def convention(self) -> str:
        """Naming convention: ``"mocap"``, ``"motionbuilder"``, ``"3dsmax"`` or ``"unknown"``."""
        names = set(self.names)
        for key, required in CONVENTIONS.items():
            if names.issuperset(required):
                return key
        return "unknown"

    def joint_index(self, name: str) -> int:
        """Index of joint ``name``; ValueError naming the joints when there is none."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(f"no BVH joint named {name!r}; joints: {', '.join(self.names)}") from None

    def channel_start(self, joint: int) -> int:
        """Column of ``motion`` holding the first channel of joint index ``joint``."""
        return sum(len(j.channels) for j in self.joints[:joint])

    def channel_values(self, name: str) -> np.ndarray:
        """Values of the channels of joint ``name``, float64 (N, k), in file order."""
        i = self.joint_index(name)
        start = self.channel_start(i)
        return self.motion[:, start:start + len(self.joints[i].channels)]

    def with_motion(self, motion) -> "Bvh":
        """The same hierarchy with other channel values (shape (N', C))."""
        return replace(self, motion=np.array(motion, dtype=np.float64))

    # -- kinematics ----------------------------------------------------------------------
    def local_rotations(self) -> np.ndarray:
        """Rotation of every joint relative to its parent, per frame.

        Returns
        -------
        ndarray, shape (N, J, 3, 3), float64
            Identity for joints without rotation channels.
        """
        n = self.n_frames
        out = np.broadcast_to(np.eye(3), (n, len(self.joints), 3, 3)).copy()
        for i, joint in enumerate(self.joints):
            rot = [k for k, c in enumerate(joint.channels) if c.endswith("rotation")]
            if not rot or n == 0:
                continue
            start = self.channel_start(i)
            seq = "".join(joint.channels[k][0] for k in rot)          # e.g. "ZXY", intrinsic
            angles = self.motion[:, [start + k for k in rot]]
            out[:, i] = Rotation.from_euler(seq, angles, degrees=True).as_matrix()
        return out

    def local_positions(self) -> np.ndarray:
        """Position of every joint in its parent's frame, per frame (file units).

        Returns
        -------
        ndarray, shape (N, J, 3), float64
            The rest offset, replaced by the position channels where a joint has them.
        """
        out = np.broadcast_to(self.offsets, (self.n_frames, len(self.joints), 3)).copy()
        for i, joint in enumerate(self.joints):
            start = self.channel_start(i)
            for k, c in enumerate(joint.channels):
                if c.endswith("position"):
                    out[:, i, "XYZ".index(c[0])] = self.motion[:, start + k]
        return out

    def global_transforms(self) -> tuple[np.ndarray, np.ndarray]:
        """World rotation and position of every joint, per frame (forward kinematics).

        Returns
        -------
        rotations : ndarray, shape (N, J, 3, 3), float64
        positions : ndarray, shape (N, J, 3), float64, file units
        """
        local_r, local_p = self.local_rotations(), self.local_positions()
        rot = np.empty_like(local_r)
        pos = np.empty_like(local_p)
        for i, joint in enumerate(self.joints):
            p = joint.parent
            if p < 0:
                rot[:, i], pos[:, i] = local_r[:, i], local_p[:, i]
            else:
                rot[:, i] = rot[:, p] @ local_r[:, i]
                pos[:, i] = np.einsum("nij,nj->ni", rot[:, p], local_p[:, i]) + pos[:, p]
        return rot, pos

    def rest_positions(self) -> np.ndarray:
        """Joint positions of the rest pose (every channel zero, offsets only), (J, 3), file units."""
        pos = np.zeros((len(self.joints), 3))
        for i, joint in enumerate(self.joints):
            if joint.parent >= 0:
                pos[i] = pos[joint.parent] + np.asarray(joint.offset)
        return pos


# ------------------------------------------------------------------------------- reading
class _Tokens:
    def __init__(self, text: str, source: str):
        self._tokens = text.split()
        self._i = 0
        self._source = source

    def next(self, what: str) -> str:
        if self._i >= len(self._tokens):
            raise ValueError(f"{self._source}: unexpected end of the hierarchy (expected {what})")
        tok = self._tokens[self._i]
        self._i += 1
        return tok

    def expect(self, word: str) -> None:
        tok = self.next(repr(word))
        if tok.upper() != word.upper():
            raise ValueError(f"{self._source}: expected {word!r} in the hierarchy, found {tok!r}")

    def number(self, what: str) -> float:
        tok = self.next(what)
        try:
            value = float(tok)
        except ValueError:
            raise ValueError(f"{self._source}: expected a number for {what}, found {tok!r}") from None
        if not math.isfinite(value):
            raise ValueError(f"{self._source}: {what} is not finite")
        return value

    def peek(self) -> str | None:
        return self._tokens[self._i] if self._i < len(self._tokens) else None


def _parse_joint(tok: _Tokens, name: str, parent: int, joints: list[BvhJoint]) -> None:
    tok.expect("{")
    tok.expect("OFFSET")
    offset = tuple(tok.number(f"the offset of {name}") for _ in range(3))
    channels: tuple[str, ...] = ()
    if (tok.peek() or "").upper() == "CHANNELS":
        tok.next("CHANNELS")
        count = tok.number(f"the channel count of {name}")
        if count != int(count) or not 0 <= count <= 6:
            raise ValueError(f"{tok._source}: joint {name!r} has a bad channel count {count}")
        chans = []
        for _ in range(int(count)):
            c = tok.next(f"a channel of {name}")
            if c.lower() not in _CANONICAL:
                raise ValueError(f"{tok._source}: joint {name!r} has unknown channel {c!r}")
            chans.append(_CANONICAL[c.lower()])
        channels = tuple(chans)
    index = len(joints)
    joints.append(BvhJoint(name, parent, offset, channels))
    while True:
        word = tok.next(f"JOINT, End Site or '}}' in {name}")
        upper = word.upper()
        if upper == "}":
            return
        if upper == "JOINT":
            _parse_joint(tok, tok.next("a joint name"), index, joints)
        elif upper == "END":
            tok.expect("Site")
            tok.expect("{")
            tok.expect("OFFSET")
            end = tuple(tok.number(f"the end-site offset of {name}") for _ in range(3))
            tok.expect("}")
            joints.append(BvhJoint(f"{name}_end", index, end, (), True))
        else:
            raise ValueError(f"{tok._source}: unexpected {word!r} in joint {name!r}")


def read_bvh(path: str | Path, *, max_frames: int | None = None) -> Bvh:
    """Read a BVH file.

    Parameters
    ----------
    path : str or Path
    max_frames : int, optional
        Read only the first ``max_frames`` frames (the rest of the file is not parsed).

    Returns
    -------
    Bvh

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        With the file name and a one-line reason on malformed content (bad hierarchy, missing
        ``Frames:``/``Frame Time:``, fewer frame lines than announced, wrong value count).
    """
    path = Path(path)
    if max_frames is not None and (isinstance(max_frames, bool) or not isinstance(max_frames, int)
                                   or max_frames < 0):
        raise ValueError(f"max_frames must be a non-negative integer, got {max_frames!r}")
    with path.open("r", encoding="utf-8", errors="replace") as fh:
        text = fh.read()
    marker = re.search(r"^\s*MOTION\s*$", text, flags=re.MULTILINE)
    if marker is None:
        raise ValueError(f"{path}: not a BVH file (no MOTION section)")
    head, body = text[:marker.start()], text[marker.end():]
    tok = _Tokens(head, str(path))
    tok.expect("HIERARCHY")
    tok.expect("ROOT")
    joints: list[BvhJoint] = []
    _parse_joint(tok, tok.next("the root name"), -1, joints)
    if tok.peek() is not None:
        raise ValueError(f"{path}: unexpected {tok.peek()!r} after the root joint (one root only)")
    lines = body.splitlines()
    k = 0
    values: dict[str, str] = {}
    for key in ("frames", "frame time"):
        while k < len(lines) and not lines[k].strip():
            k += 1
        if k >= len(lines) or ":" not in lines[k] or lines[k].split(":")[0].strip().lower() != key:
            raise ValueError(f"{path}: expected '{key.title()}:' after MOTION")
        values[key] = lines[k].split(":", 1)[1].strip()
        k += 1
    try:
        n_frames = int(values["frames"])
        frame_time = float(values["frame time"])
    except ValueError:
        raise ValueError(f"{path}: bad frame count or frame time") from None
    if n_frames < 0:
        raise ValueError(f"{path}: negative frame count")
    n_read = n_frames if max_frames is None else min(n_frames, max_frames)
    rows = list(itertools.islice((ln for ln in lines[k:] if ln.strip()), n_read))
    if len(rows) < n_read:
        raise ValueError(f"{path}: announces {n_frames} frames but holds {len(rows)}")
    n_channels = sum(len(j.channels) for j in joints)
    try:
        data = np.array(" ".join(rows).split(), dtype=np.float64)
    except ValueError:
        raise ValueError(f"{path}: a frame line holds something that is not a number") from None
    if data.size != n_read * n_channels:
        raise ValueError(f"{path}: frame lines hold {data.size} values, expected {n_read} x {n_channels} channels")
    try:
        return Bvh(tuple(joints), frame_time, data.reshape(n_read, n_channels))
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


# ------------------------------------------------------------------------------- writing
# (joint, channels, [(parameter or None, sign), ...]) for every segment; see the module table.
def _channel_table() -> tuple[tuple[str, tuple[str, ...], tuple[tuple[str | None, float], ...]], ...]:
    rows = [("chest", ("Xposition", "Yposition", "Zposition", "Yrotation", "Xrotation", "Zrotation"),
             (("root_x", 1.0), ("root_y", -1.0), ("root_z", -1.0), ("chest_yaw", -1.0),
              ("chest_pitch", 1.0), ("chest_roll", -1.0))),
            ("head", ("Xrotation", "Zrotation", "Yrotation"),
             (("head_flex", 1.0), ("head_tilt", -1.0), ("head_turn", -1.0)))]
    for side, m in (("r", 1.0), ("l", -1.0)):
        rows += [
            (f"{side}_upper_arm", ("Xrotation", "Zrotation", "Yrotation"),
             ((f"{side}_shoulder_flex", -1.0), (f"{side}_shoulder_abd", -m), (f"{side}_shoulder_rot", -m))),
            (f"{side}_forearm", ("Xrotation", "Yrotation", "Zrotation"),
             ((f"{side}_elbow_flex", -1.0), (f"{side}_forearm_twist", -m), (None, 0.0))),
            (f"{side}_hand", ("Xrotation", "Zrotation", "Yrotation"),
             ((f"{side}_wrist_flex", -1.0), (f"{side}_wrist_dev", -m), (None, 0.0))),
        ]
    order = {name: i for i, name in enumerate(SEGMENT_NAMES)}
    return tuple(sorted(rows, key=lambda r: order[r[0]]))


_TABLE = _channel_table()


def _check_poses(poses) -> np.ndarray:
    q = np.asarray(poses, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != N_PARAMETERS or q.shape[0] == 0:
        raise ValueError(f"poses must have shape (frames >= 1, {N_PARAMETERS}), got {q.shape}")
    for i in range(q.shape[0]):
        check_pose(q[i], name=f"pose of frame {i}")
    return q


def pose_channels(poses) -> np.ndarray:
    """BVH channel values of our poses (the writer's motion block).

    Parameters
    ----------
    poses : array_like, shape (N, 23)
        Metres and radians.

    Returns
    -------
    ndarray, shape (N, 24), float64
        Metres and degrees, in the channel order of :func:`write_bvh`.
    """
    q = _check_poses(poses)
    cols = []
    for _joint, _chans, params in _TABLE:
        for name, sign in params:
            if name is None:
                cols.append(np.zeros(len(q)))
                continue
            v = q[:, PARAMETER_INDEX[name]]
            cols.append(sign * (v if name.startswith("root_") else np.rad2deg(v)))
    return np.stack(cols, axis=1)


def _end_site(dims: BodyDimensions, joint: str) -> np.ndarray | None:
    """End-site offset (camera axes, parent frame) of the head and the hands, else None."""
    if joint == "head":
        return np.array([0.0, -part_spans(dims)[PART_NAMES.index("head"), 1], 0.0])
    if joint.endswith("_hand"):
        return np.array([0.0, dims[joint].length, 0.0])
    return None


def _fmt(v: float) -> str:
    s = f"{v:.6f}"
    return "0.000000" if s == "-0.000000" else s


def write_bvh(path: str | Path, poses, dims: BodyDimensions, fps: float) -> None:
    """Write poses of our model as a BVH file (atomically).

    Parameters
    ----------
    path : str or Path
    poses : array_like, shape (N, 23)
        One pose per frame, metres and radians (N >= 1).
    dims : BodyDimensions
        The actor's body dimensions (bone offsets), metres.
    fps : float
        Frames per second (> 0).

    Raises
    ------
    ValueError
        On a bad pose array, dimensions or frame rate.

    Notes
    -----
    The hierarchy, axes and channel mapping are in the module docstring. Units are metres
    (Blender: import with scale 1). :func:`read_pose_bvh` reads the poses back.
    """
    if not isinstance(dims, BodyDimensions):
        raise ValueError(f"dims must be BodyDimensions, got {type(dims).__name__}")
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)) \
            or not math.isfinite(fps) or fps <= 0:
        raise ValueError(f"fps must be a positive number, got {fps!r}")
    values = pose_channels(poses)
    offsets = segment_offsets(dims) @ CAMERA_TO_BVH.T
    children = {i: [k for k, p in enumerate(SEGMENT_PARENTS) if p == i] for i in range(len(SEGMENT_NAMES))}
    table = {row[0]: row for row in _TABLE}
    lines = ["HIERARCHY"]

    def emit(seg: int, depth: int) -> None:
        pad = "\t" * depth
        name = SEGMENT_NAMES[seg]
        lines.append(f"{pad}{'ROOT' if depth == 0 else 'JOINT'} {name}")
        lines.append(f"{pad}{{")
        off = np.zeros(3) if depth == 0 else offsets[seg]
        lines.append(f"{pad}\tOFFSET {' '.join(_fmt(v) for v in off)}")
        chans = table[name][1]
        lines.append(f"{pad}\tCHANNELS {len(chans)} {' '.join(chans)}")
        for child in children[seg]:
            emit(child, depth + 1)
        end = _end_site(dims, name)
        if end is not None:
            end = CAMERA_TO_BVH @ end
            lines.append(f"{pad}\tEnd Site")
            lines.append(f"{pad}\t{{")
            lines.append(f"{pad}\t\tOFFSET {' '.join(_fmt(v) for v in end)}")
            lines.append(f"{pad}\t}}")
        lines.append(f"{pad}}}")

    emit(0, 0)
    lines += ["MOTION", f"Frames: {len(values)}", f"Frame Time: {1.0 / float(fps):.8f}"]
    lines += [" ".join(_fmt(v) for v in row) for row in values]
    write_text_atomic(path, "\n".join(lines) + "\n")


def read_pose_bvh(path: str | Path) -> tuple[np.ndarray, float]:
    """Read back the poses of a file written by :func:`write_bvh`.

    Returns
    -------
    poses : ndarray, shape (N, 23), float64
        Metres and radians.
    fps : float

    Raises
    ------
    ValueError
        If the file is not one of ours (other joints or channels), or on malformed content.
    """
    bvh = read_bvh(path)
    expected = tuple((row[0], row[1]) for row in _TABLE)
    found = tuple((j.name, j.channels) for j in bvh.joints if not j.end_site)
    if found != expected:
        raise ValueError(f"{path}: not a mocap pose BVH (joints and channels differ from write_bvh's); "
                         "use mocap.synth.retarget for other clips")
    poses = np.zeros((bvh.n_frames, N_PARAMETERS))
    col = 0
    for _joint, _chans, params in _TABLE:
        for name, sign in params:
            if name is not None:
                v = sign * bvh.motion[:, col]
                poses[:, PARAMETER_INDEX[name]] = v if name.startswith("root_") else np.deg2rad(v)
            col += 1
    return poses, bvh.fps
