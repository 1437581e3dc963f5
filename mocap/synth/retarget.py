"""Retargeting a motion-capture clip onto our 23-parameter pose.

A clip (BVH, or ASF/AMC) is first turned into a :class:`MotionClip`: joint hierarchy, rest
offsets (with every rotation zero the clip stands in its rest pose), per-frame local
rotations and root positions. :func:`retarget` then, per output frame:

1. resamples the clip to the output frame rate (spherical interpolation of every joint's
   local rotation, linear interpolation of the root position; CMU clips are 120 fps);
2. runs forward kinematics to get each joint's world rotation ``G_j`` (the identity in the
   rest pose);
3. gives each of our segments ``s`` the world rotation ``G_j B_s`` of its clip joint ``j``
   (table below), where ``B_s`` is the rest alignment: the identity for the chest and head
   (a clip's rest pose stands upright facing +z, as CMU's do), and for an arm segment the
   shortest rotation taking our zero pose's bone direction (hanging down) onto the clip's
   rest bone direction (so a T-pose rest maps to arms raised sideways, an arms-down rest to
   hanging arms);
4. turns the clip's world (y up, actor facing +z) into camera coordinates (y down, z
   forward) by a half turn about x, after removing the chest heading of the first frame
   (``face_camera``), so the actor starts facing the camera;
5. decomposes each segment's rotation relative to its parent into our angles, with the
   Euler orders of our forward kinematics (:mod:`mocap.body.kinematics`): chest
   ``Ry(yaw) Rx(pitch) Rz(roll)``, head ``Rx(flex) Rz(tilt) Ry(turn)``, shoulder
   ``Rx(-flex) Rz(m abd) Ry(m rot)``, elbow ``Rx(-flex) Ry(m twist)``, wrist
   ``Rx(-flex) Rz(m dev)`` (``m`` = +1 right, -1 left). Of the two Euler solutions the one
   nearer the joint limits is taken. Our elbow is a hinge: the upper arm is first turned about
   its own axis (shoulder rotation) until the clip's elbow bends in the hinge plane, which
   keeps both arm bones pointing exactly where the clip's do (nearly straight arms keep the
   clip's twist). The hand's rotation about its own long axis (which our wrist cannot do) is
   moved into the forearm twist, as anatomy has it (pronation is a forearm motion);
6. clamps every parameter into :data:`~mocap.body.pose.JOINT_LIMITS` (joint limits always
   hold) and wraps the chest yaw into [-180, 180) degrees;
7. places the root: the clip's root trajectory, in metres (``unit_m`` per clip unit; CMU
   units are 1/0.45 inch = 5.64 cm), is centred on its mean and, per axis, scaled down where
   needed to stay within ``max_offset_m`` of ``centre`` (camera coordinates), which keeps the
   actor in view while keeping the shape of the motion, depth included.

Mapping (our parameter ← clip joint; MotionBuilder-named CMU BVH / 3dsMax-named CMU BVH /
CMU ASF-AMC / BVH written by :func:`mocap.io.bvh.write_bvh`):

=====================================  ==================  ==============  ==========  ============
our parameters                         MotionBuilder       3dsMax          ASF/AMC     ours
=====================================  ==================  ==============  ==========  ============
root_x, root_y, root_z                 Hips (position)     Hips            root        chest
chest_yaw, chest_pitch, chest_roll     Spine1 (world)      Chest2          thorax      chest
head_flex, head_tilt, head_turn        Head vs Spine1      Head vs Chest2  head        head
*_shoulder_flex, _abd, _rot            (Right|Left)Arm     *Shoulder       *humerus    *_upper_arm
*_elbow_flex, *_forearm_twist          *ForeArm (+ twist   *Elbow (+ hand  *radius     *_forearm
                                       of the hand)        twist)          (+ hand)
*_wrist_flex, *_wrist_dev              *Hand               r/lhand         r/lhand     *_hand
=====================================  ==================  ==============  ==========  ============

Rotations are taken from world orientations, so joints between the mapped ones (spine links,
neck links, collar bones, the 3dsMax wrist link) contribute through their parents' and
children's world rotations: e.g. collar motion shows in the shoulder angles, neck motion in the
head angles.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from mocap.body.pose import DEFAULT_ROOT, JOINT_LIMITS, N_PARAMETERS, PARAMETER_INDEX, POSITION_NAMES
from mocap.io.bvh import CAMERA_TO_BVH, Bvh, read_bvh
from mocap.io.bvh import JOINT_MAPS as BVH_JOINT_MAPS

__all__ = ["CMU_UNIT_M", "JOINT_MAPS", "MotionClip", "RetargetConfig", "clip_from_asf_amc", "clip_from_bvh",
           "load_clip", "retarget"]

#: Metres per CMU length unit (the ASF ``length 0.45`` convention: 1/0.45 inch).
CMU_UNIT_M: float = 0.0254 / 0.45

#: Clip joint of each of our segments (and of the root position), per naming convention.
#: (The BVH conventions are :data:`mocap.io.bvh.JOINT_MAPS`; ``"asf"`` is the CMU ASF/AMC skeleton.)
JOINT_MAPS = MappingProxyType({**BVH_JOINT_MAPS, "asf": MappingProxyType({
    "root": "root", "chest": "thorax", "head": "head",
    "r_upper_arm": "rhumerus", "r_forearm": "rradius", "r_hand": "rhand",
    "l_upper_arm": "lhumerus", "l_forearm": "lradius", "l_hand": "lhand"})})
_ARM_CHAIN = ("upper_arm", "forearm", "hand")
_DOWN = np.array([0.0, -1.0, 0.0])   # our arms' zero-pose direction in clip coordinates
_DOWN.setflags(write=False)


@dataclass(frozen=True)
class MotionClip:
    """A motion clip in a common form: rest skeleton, local rotations, root positions.

    With every local rotation the identity the skeleton stands in its rest pose, joint ``j``
    at its parent's position plus ``offsets[j]`` (world axes).

    Attributes
    ----------
    names : tuple of str
        Joint names (parents before children).
    parents : ndarray, shape (J,), int64
        -1 for the root.
    offsets : ndarray, shape (J, 3), float64, clip units
        Rest offset of each joint from its parent.
    rotations : ndarray, shape (N, J, 3, 3), float64
        Rotation of each joint relative to its parent (world rest axes).
    root_positions : ndarray, shape (N, 3), float64, clip units
    frame_time : float
        Seconds per frame.
    unit_m : float
        Metres per clip unit.
    convention : str
        Key of :data:`JOINT_MAPS`.
    """

    names: tuple[str, ...]
    parents: np.ndarray
    offsets: np.ndarray
    rotations: np.ndarray
    root_positions: np.ndarray
    frame_time: float
    unit_m: float
    convention: str

    def __post_init__(self) -> None:
        j = len(self.names)
        if self.parents.shape != (j,) or self.offsets.shape != (j, 3):
            raise ValueError("clip parents/offsets do not match its joints")
        if self.rotations.ndim != 4 or self.rotations.shape[1:] != (j, 3, 3):
            raise ValueError(f"clip rotations must have shape (frames, {j}, 3, 3)")
        n = self.rotations.shape[0]
        if n < 1:
            raise ValueError("the clip holds no frames")
        if self.root_positions.shape != (n, 3):
            raise ValueError(f"clip root positions must have shape ({n}, 3)")
        if not (math.isfinite(self.frame_time) and self.frame_time > 0):
            raise ValueError(f"clip frame time must be positive, got {self.frame_time}")
        if not (math.isfinite(self.unit_m) and self.unit_m > 0):
            raise ValueError(f"clip unit must be a positive number of metres, got {self.unit_m}")
        if self.convention not in JOINT_MAPS:
            raise ValueError(f"unknown joint naming convention {self.convention!r}")
        missing = [v for v in JOINT_MAPS[self.convention].values() if v not in self.names]
        if missing:
            raise ValueError(f"clip lacks joint(s) {', '.join(sorted(set(missing)))} of the "
                             f"{self.convention} convention")

    @property
    def n_frames(self) -> int:
        return int(self.rotations.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return (self.n_frames - 1) * self.frame_time

    def index(self, name: str) -> int:
        """Index of joint ``name`` (ValueError when absent)."""
        return self.names.index(name)

    def rest_positions(self) -> np.ndarray:
        """Joint positions of the rest pose, (J, 3), clip units."""
        pos = np.zeros((len(self.names), 3))
        for i, p in enumerate(self.parents):
            if p >= 0:
                pos[i] = pos[p] + self.offsets[i]
        return pos


def clip_from_bvh(bvh: Bvh, *, unit_m: float | None = None) -> MotionClip:
    """A :class:`MotionClip` of a parsed BVH file.

    Parameters
    ----------
    bvh : Bvh
        With MotionBuilder, 3dsMax or mocap joint names (:attr:`Bvh.convention`).
    unit_m : float, optional
        Metres per file unit; default 1 for files written by :func:`~mocap.io.bvh.write_bvh`,
        :data:`CMU_UNIT_M` otherwise.

    Raises
    ------
    ValueError
        If the joint names follow no known convention.
    """
    conv = bvh.convention
    if conv == "unknown":
        raise ValueError("BVH joint names follow no known convention (need CMU MotionBuilder names "
                         "Hips/Spine1/LeftArm/..., 3dsMax names Hips/Chest2/LeftShoulder/..., or mocap's)")
    root_pos = bvh.local_positions()[:, 0]
    return MotionClip(bvh.names, bvh.parents, bvh.offsets, bvh.local_rotations(), root_pos,
                      bvh.frame_time, (1.0 if conv == "mocap" else CMU_UNIT_M) if unit_m is None else unit_m,
                      conv)


def clip_from_asf_amc(asf_path: str | Path, amc_path: str | Path, *, unit_m: float = CMU_UNIT_M,
                      fps: float = 120.0) -> MotionClip:
    """A :class:`MotionClip` of an Acclaim skeleton and motion (CMU ASF/AMC, 120 fps)."""
    from mocap.io.asf_amc import read_amc, read_asf
    asf = read_asf(asf_path)
    amc = read_amc(amc_path, asf)
    return MotionClip(asf.names, asf.parents, asf.offsets(), amc.local_rotations(),
                      amc.root_positions(), 1.0 / fps, unit_m, "asf")


def load_clip(path: str | Path, *, max_frames: int | None = None) -> MotionClip:
    """Read a motion file: ``.bvh``, or ``.amc`` with its skeleton ``.asf`` beside it.

    The skeleton of ``NAME.amc`` is ``NAME.asf`` or else the ``.asf`` in the same folder
    whose name is the longest prefix of ``NAME`` (CMU's ``cmu_charleston.asf`` for
    ``cmu_charleston1.amc``).

    Raises
    ------
    FileNotFoundError
        If the file (or the skeleton of an AMC file) does not exist.
    ValueError
        On another suffix or malformed content.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such motion file: {path}")
    suffix = path.suffix.lower()
    if suffix == ".bvh":
        return clip_from_bvh(read_bvh(path, max_frames=max_frames))
    if suffix == ".amc":
        candidates = sorted((p for p in path.parent.glob("*") if p.suffix.lower() == ".asf"
                             and path.stem.startswith(p.stem)), key=lambda p: -len(p.stem))
        if not candidates:
            raise FileNotFoundError(f"no skeleton for {path}: expected {path.stem}.asf (or an .asf whose "
                                    "name starts the .amc's name) in the same folder")
        clip = clip_from_asf_amc(candidates[0], path)
        if max_frames is not None and max_frames < clip.n_frames:
            clip = MotionClip(clip.names, clip.parents, clip.offsets, clip.rotations[:max_frames],
                              clip.root_positions[:max_frames], clip.frame_time, clip.unit_m, clip.convention)
        return clip
    raise ValueError(f"unsupported motion file {path.name}: expected .bvh or .amc (with its .asf)")


@dataclass(frozen=True)
class RetargetConfig:
    """How a clip becomes our poses.

    Attributes
    ----------
    fps : float
        Output frame rate.
    face_camera : bool
        Remove the chest heading of the first frame so the actor starts facing the camera.
    centre : tuple of 3 float, metres
        Camera-coordinate position of the mean root (chest base).
    max_offset_m : tuple of 3 float, metres
        Largest root excursion from ``centre`` per axis (x, y, z); a clip's centred root
        trajectory is scaled down on an axis where it goes farther. ``None`` keeps the clip's
        root exactly (in metres, through the axis change only; for our own files).
    """

    fps: float = 25.0
    face_camera: bool = True
    centre: tuple[float, float, float] = DEFAULT_ROOT
    max_offset_m: tuple[float, float, float] | None = (0.3, 0.15, 0.45)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.fps) and self.fps > 0):
            raise ValueError(f"fps must be positive, got {self.fps}")
        if len(self.centre) != 3 or not all(math.isfinite(v) for v in self.centre):
            raise ValueError(f"centre must be 3 finite numbers of metres, got {self.centre}")
        if self.max_offset_m is not None and (len(self.max_offset_m) != 3 or not all(
                math.isfinite(v) and v >= 0 for v in self.max_offset_m)):
            raise ValueError(f"max_offset_m must be 3 non-negative numbers, got {self.max_offset_m}")


def _resample(clip: MotionClip, fps: float, needed: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Local rotations of the ``needed`` joints and root positions at ``fps``."""
    n_out = int(math.floor(clip.duration * fps + 1e-3)) + 1   # file frame times are rounded
    if clip.n_frames == 1:
        return clip.rotations[:, needed], clip.root_positions
    t_in = np.arange(clip.n_frames) * clip.frame_time
    t_out = np.minimum(np.arange(n_out) / fps, t_in[-1])
    rots = np.empty((n_out, len(needed), 3, 3))
    for k, j in enumerate(needed):
        local = clip.rotations[:, j]
        if np.allclose(local, np.eye(3)):
            rots[:, k] = np.eye(3)
        else:
            rots[:, k] = Slerp(t_in, Rotation.from_matrix(local))(t_out).as_matrix()
    root = np.stack([np.interp(t_out, t_in, clip.root_positions[:, a]) for a in range(3)], axis=1)
    return rots, root


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def _euler_pair(mats: np.ndarray, seq: str) -> tuple[np.ndarray, np.ndarray]:
    """Both Tait-Bryan solutions (a, b, c) and (a + pi, pi - b, c + pi), wrapped, (N, 3) each."""
    with warnings.catch_warnings():
        # at gimbal lock any split of the coupled angles is as good; scipy picks one and warns
        warnings.simplefilter("ignore", UserWarning)
        e = Rotation.from_matrix(mats).as_euler(seq)
    alt = np.stack([e[:, 0] + np.pi, np.pi - e[:, 1], e[:, 2] + np.pi], axis=1)
    return _wrap(e), _wrap(alt)


def _choose(cands: tuple[np.ndarray, np.ndarray], to_params, names: tuple[str, ...],
            dropped: int | None = None) -> np.ndarray:
    """Per frame, the Euler solution whose parameters violate the joint limits least.

    For a joint with fewer degrees of freedom than the three Euler angles, ``dropped`` is the
    angle our model cannot do; the solution where it is smaller wins (dropping it then
    changes the rotation least), the joint limits deciding only ties.
    """
    lim = np.array([JOINT_LIMITS[PARAMETER_INDEX[n]] for n in names])
    vals = [to_params(c) for c in cands]
    viol = [np.sum(np.maximum(lim[:, 0] - v, 0) + np.maximum(v - lim[:, 1], 0), axis=1) for v in vals]
    second = viol[1] < viol[0] - 1e-9
    if dropped is not None:
        res = [np.abs(c[:, dropped]) for c in cands]
        second = np.where(np.abs(res[1] - res[0]) > 1e-6, res[1] < res[0], second)
    return np.where(second[:, None], vals[1], vals[0])


def _bone_direction(clip: MotionClip, joint: int, towards: int) -> np.ndarray:
    """Unit rest direction from clip joint ``joint`` to clip joint ``towards``."""
    rest = clip.rest_positions()
    d = rest[towards] - rest[joint]
    n = np.linalg.norm(d)
    if n < 1e-9:
        raise ValueError(f"clip joints {clip.names[joint]!r} and {clip.names[towards]!r} coincide in the rest pose")
    return d / n


def _alignment(clip: MotionClip, jmap) -> dict[str, np.ndarray]:
    """Rest alignment B_s of every segment (3x3, clip coordinates)."""
    out = {"chest": np.eye(3), "head": np.eye(3)}
    for side in ("r", "l"):
        chain = [clip.index(jmap[f"{side}_{p}"]) for p in _ARM_CHAIN]
        for k, part in enumerate(_ARM_CHAIN[:2]):
            d = _bone_direction(clip, chain[k], chain[k + 1])
            if np.dot(d, _DOWN) < -1.0 + 1e-9:       # straight up: any half turn; take the one about x
                out[f"{side}_{part}"] = Rotation.from_rotvec([np.pi, 0.0, 0.0]).as_matrix()
            else:
                rot, _ = Rotation.align_vectors(d[None], _DOWN[None])
                out[f"{side}_{part}"] = rot.as_matrix()
        # a rest hand continues its forearm (true of every CMU skeleton; finger and thumb
        # chains make a poor direction of their own)
        out[f"{side}_hand"] = out[f"{side}_forearm"]
    return out


def _rot_y(a: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(np.outer(a, [0.0, 1.0, 0.0])).as_matrix()


#: Elbow bend (radians) below which the bend plane is too uncertain to set the upper arm's
#: twist, and above which it sets it fully (smooth blend between).
_HINGE_BLEND = (math.radians(10.0), math.radians(25.0))


def _hinge_aligned(upper: np.ndarray, forearm: np.ndarray) -> np.ndarray:
    """Upper-arm frames turned about their long axis so the elbow bends in our hinge plane.

    Our elbow is a hinge: the forearm can only swing towards the upper arm's local -z. A
    clip's elbow bends in whatever plane its actor's did; turning the upper arm about its
    own axis (shoulder rotation) by the angle between the two planes keeps both bone
    directions exact. Nearly straight arms have no reliable plane and keep the clip's twist.

    Parameters
    ----------
    upper, forearm : ndarray, shape (N, 3, 3)
        World (camera axes) rotations of the upper arm and the forearm.

    Returns
    -------
    ndarray, shape (N, 3, 3)
    """
    f_local = np.einsum("nji,nj->ni", upper, forearm[:, :, 1])       # forearm axis in the upper-arm frame
    bend = np.arctan2(np.hypot(f_local[:, 0], f_local[:, 2]), f_local[:, 1])
    # angle about y taking the bend direction (x, z) onto -z
    delta = np.arctan2(-f_local[:, 0], -f_local[:, 2])
    lo, hi = _HINGE_BLEND
    t = np.clip((bend - lo) / (hi - lo), 0.0, 1.0)
    weight = t * t * (3.0 - 2.0 * t)
    return upper @ _rot_y(weight * delta)


def retarget(clip: MotionClip, config: RetargetConfig = RetargetConfig()) -> np.ndarray:
    """Our poses for every output frame of a clip (see the module docstring).

    Parameters
    ----------
    clip : MotionClip
    config : RetargetConfig

    Returns
    -------
    ndarray, shape (M, 23), float64
        Metres and radians, within :data:`~mocap.body.pose.JOINT_LIMITS`; ``M`` covers the
        clip's duration at ``config.fps``.
    """
    jmap = JOINT_MAPS[clip.convention]
    seg_joint = {s: clip.index(j) for s, j in jmap.items() if s != "root"}
    # joints on the paths from the root to the mapped ones
    needed: set[int] = set()
    for j in seg_joint.values():
        while j >= 0 and j not in needed:
            needed.add(j)
            j = int(clip.parents[j])
    order = sorted(needed)
    local, root = _resample(clip, config.fps, order)
    world = {}
    for k, j in enumerate(order):
        p = int(clip.parents[j])
        world[j] = local[:, k] if p < 0 else world[p] @ local[:, k]
    align = _alignment(clip, jmap)
    q = {s: world[j] @ align[s] for s, j in seg_joint.items()}
    n = root.shape[0]
    heading = np.eye(3)
    if config.face_camera:
        fwd = q["chest"][0] @ np.array([0.0, 0.0, 1.0])
        heading = Rotation.from_rotvec([0.0, -math.atan2(fwd[0], fwd[2]), 0.0]).as_matrix()
    # camera-coordinate world rotation of every segment
    r = {s: CAMERA_TO_BVH @ heading @ m @ CAMERA_TO_BVH for s, m in q.items()}
    pose = np.zeros((n, N_PARAMETERS))

    def put(names, values):
        for i, name in enumerate(names):
            pose[:, PARAMETER_INDEX[name]] = values[:, i]

    chest_names = ("chest_yaw", "chest_pitch", "chest_roll")
    put(chest_names, _choose(_euler_pair(r["chest"], "YXZ"), lambda e: e, chest_names))
    head_names = ("head_flex", "head_tilt", "head_turn")
    rel = np.swapaxes(r["chest"], 1, 2) @ r["head"]
    put(head_names, _choose(_euler_pair(rel, "XZY"), lambda e: e, head_names))
    for side, m in (("r", 1.0), ("l", -1.0)):
        upper = _hinge_aligned(r[f"{side}_upper_arm"], r[f"{side}_forearm"])
        names = tuple(f"{side}_{x}" for x in ("shoulder_flex", "shoulder_abd", "shoulder_rot"))
        rel = np.swapaxes(r["chest"], 1, 2) @ upper
        put(names, _choose(_euler_pair(rel, "XZY"), lambda e, m=m: np.stack([-e[:, 0], m * e[:, 1], m * e[:, 2]], 1),
                           names))
        # hand relative to the forearm as Ry(twist) Rx(a) Rz(b): the twist goes to the forearm
        rel_hand = np.swapaxes(r[f"{side}_forearm"], 1, 2) @ r[f"{side}_hand"]
        twist = _euler_pair(rel_hand, "YXZ")[0][:, 0]
        forearm = r[f"{side}_forearm"] @ _rot_y(twist)
        names = (f"{side}_wrist_flex", f"{side}_wrist_dev")
        rel = np.swapaxes(forearm, 1, 2) @ r[f"{side}_hand"]
        put(names, _choose(_euler_pair(rel, "XZY"), lambda e, m=m: np.stack([-e[:, 0], m * e[:, 1]], 1), names,
                           dropped=2))
        names = (f"{side}_elbow_flex", f"{side}_forearm_twist")
        rel = np.swapaxes(upper, 1, 2) @ forearm
        put(names, _choose(_euler_pair(rel, "XYZ"), lambda e, m=m: np.stack([-e[:, 0], m * e[:, 1]], 1), names,
                           dropped=2))
    # root: clip units -> metres, heading removed, camera axes, fitted into the view box
    root_cam = (root * clip.unit_m) @ (CAMERA_TO_BVH @ heading).T
    centre = np.asarray(config.centre, dtype=np.float64)
    if config.max_offset_m is None:
        placed = root_cam
    else:
        d = root_cam - root_cam.mean(axis=0)
        reach = np.abs(d).max(axis=0)
        limit = np.asarray(config.max_offset_m, dtype=np.float64)
        scale = np.where(reach > limit, limit / np.maximum(reach, 1e-12), 1.0)
        placed = centre + d * scale
    for axis, name in enumerate(POSITION_NAMES):
        pose[:, PARAMETER_INDEX[name]] = placed[:, axis]
    pose[:, PARAMETER_INDEX["chest_yaw"]] = _wrap(pose[:, PARAMETER_INDEX["chest_yaw"]])
    return np.clip(pose, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
