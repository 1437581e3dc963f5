"""Named benchmark sequences and the writer of a sequence folder (docs/design.md section 4).

A folder holds ``frames/000000.png ...`` (or ``.jpg``), ``background.png`` (the empty scene
through the same camera, with noise of its own), ``calibration.json`` (the true actor: body
dimensions, first pose, camera, colour classes), ``ground_truth.csv`` (per frame the 23
parameters and the joint columns, by :class:`~mocap.io.pose_table.PoseTable`) and
``meta.json`` (camera intrinsics, fps, generator settings; no time stamps, so that the same
seed gives the same bytes).

Randomness: one :class:`numpy.random.SeedSequence` per (seed, sequence) spawns independent
streams for the motion, the actor, the scene and light, the camera drift, and one per frame
for the sensor noise, so a longer sequence starts with the same frames as a shorter one.
"""
from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import Callable

import imageio.v3 as iio
import numpy as np
from tqdm import tqdm

import mocap
from mocap.body.model import BodyModel
from mocap.body.pose import JOINT_LIMITS
from mocap.io.files import write_bytes_atomic, write_text_atomic
from mocap.io.pose_table import PoseTable
from mocap.labels import DEFAULT_CLASS_NAMES
from mocap.render.calibration import Calibration
from mocap.render.camera import Camera
from mocap.synth.actor import LOWER_BODY, Actor
from mocap.synth.motion import MOTIONS, avoid_torso, root_height_for_depth
from mocap.synth.retarget import RetargetConfig, load_clip, retarget
from mocap.synth.scene import make_background
from mocap.synth.sensor import SensorConfig, SensorDrift, apply_sensor
from mocap.synth.shading import Light, downsample, render_actor

__all__ = ["FPS", "FRAME_FORMATS", "SEQUENCES", "SEQUENCE_NAMES", "SequenceSpec", "SequenceSetup", "parse_size",
           "generate_sequence", "setup_sequence"]


def parse_size(text: str) -> tuple[int, int]:
    """``"160x120"`` -> ``(160, 120)`` (width, height in pixels); ValueError with the expected form otherwise."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match:
        raise ValueError(f"--size must look like 160x120 (width x height in pixels), got {text!r}")
    return int(match.group(1)), int(match.group(2))


#: Frame rate of every synthetic sequence, frames per second.
FPS: float = 25.0
#: Image formats of the frame files.
FRAME_FORMATS: tuple[str, ...] = ("png", "jpg")
#: Largest frame count accepted.
MAX_FRAMES = 100_000
#: Format tag of meta.json.
META_FORMAT = "mocap-synth-1"


@dataclass(frozen=True)
class SequenceSpec:
    """One named sequence.

    Attributes
    ----------
    index : int
        Stable number of the sequence (mixed into its seed).
    frames : int
        Default frame count.
    description : str
    motion : callable
        ``f(rng, n_frames, fps) -> poses (n_frames, 23)``.
    bare_forearms : bool
        The actor wears short sleeves.
    pattern : str or None
        Clothes pattern (:data:`~mocap.synth.actor.PATTERNS`); drawn from the seed when None.
    """

    index: int
    frames: int
    description: str
    motion: Callable[[np.random.Generator, int, float], np.ndarray] = field(repr=False)
    bare_forearms: bool = False
    pattern: str | None = None


#: The six sequences of the paper's Fig. 5.
SEQUENCES = MappingProxyType({
    "gestures-1": SequenceSpec(1, 200, "various arm gestures facing the camera; plain clothes",
                               MOTIONS["gestures-1"], pattern="plain"),
    "gestures-2": SequenceSpec(2, 250, "gestures with fast motion in depth (stepping towards and away from "
                                       "the camera, reaching forwards); striped clothes",
                               MOTIONS["gestures-2"], pattern="stripes"),
    "gestures-3": SequenceSpec(3, 300, "fast, varied gestures with torso and head motion; short sleeves",
                               MOTIONS["gestures-3"], bare_forearms=True, pattern="plain"),
    "arms-crossing": SequenceSpec(4, 200, "arms crossing each other in front of the chest (occlusions)",
                                  MOTIONS["arms-crossing"], pattern="plain"),
    "not-facing": SequenceSpec(5, 200, "gestures with the actor turned 30-45 degrees from the camera; "
                                       "checked clothes", MOTIONS["not-facing"], pattern="checks"),
    "turning": SequenceSpec(6, 250, "the actor turns around himself; striped clothes", MOTIONS["turning"],
                            pattern="stripes"),
})
#: Names of the sequences, in the paper's order.
SEQUENCE_NAMES: tuple[str, ...] = tuple(SEQUENCES)


def _check_name(name: str) -> SequenceSpec:
    if name not in SEQUENCES:
        raise ValueError(f"unknown sequence {name!r}; choose one of: {', '.join(SEQUENCE_NAMES)}")
    return SEQUENCES[name]


def _check_size(size) -> tuple[int, int]:
    try:
        w, h = size
    except (TypeError, ValueError):
        raise ValueError(f"size must be (width, height), got {size!r}") from None
    for v in (w, h):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 16 <= v <= 4096:
            raise ValueError(f"image width and height must be integers in [16, 4096], got {size!r}")
    return int(w), int(h)


def _check_seed(seed) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2 ** 63:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return int(seed)


def _streams(seed: int, spec: SequenceSpec) -> dict[str, np.random.SeedSequence]:
    """Independent random streams of one (seed, sequence)."""
    keys = ("motion", "actor", "scene", "drift", "noise")
    return dict(zip(keys, np.random.SeedSequence([seed, spec.index]).spawn(len(keys))))


def supersampling(width: int) -> int:
    """Rendering samples per output pixel and axis: 3 up to 320 pixels wide, 2 up to 800, else 1."""
    return 3 if width <= 320 else 2 if width <= 800 else 1


@dataclass(frozen=True)
class SequenceSetup:
    """Everything about one sequence that does not change from frame to frame.

    Attributes
    ----------
    name : str
    seed : int
    camera : Camera
        The output camera.
    supersample : int
        Render samples per output pixel and axis.
    actor : Actor
    light : Light
    background : ndarray, shape (H * s, W * s, 3), float64
        Linear radiance of the empty scene at the render resolution.
    background_radiance : ndarray, shape (H, W, 3), float64
        The same at the output resolution (block averages).
    sensor : SensorConfig
    drift : SensorDrift
    """

    name: str
    seed: int
    camera: Camera
    supersample: int
    actor: Actor
    light: Light
    background: np.ndarray
    sensor: SensorConfig
    drift: SensorDrift
    noise_seed: np.random.SeedSequence = field(repr=False)
    background_radiance: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        small = downsample(self.background, self.supersample)
        for array in (self.background, small):
            array.setflags(write=False)
        object.__setattr__(self, "background_radiance", small)

    @property
    def render_camera(self) -> Camera:
        s = self.supersample
        return self.camera.scaled(self.camera.width * s, self.camera.height * s)

    def radiance(self, pose) -> tuple[np.ndarray, np.ndarray]:
        """Linear radiance of the scene with the actor in ``pose``, at the output size.

        Returns
        -------
        image : ndarray, shape (H, W, 3), float64
        coverage : ndarray, shape (H, W), float64
            Fraction of each output pixel covered by the actor's upper body (every part but
            the lower body), in [0, 1].
        """
        image, parts = render_actor(self.actor, pose, self.render_camera, self.light, self.background)
        s = self.supersample
        out = self.background_radiance.copy()
        coverage = np.zeros(out.shape[:2])
        rows, cols = np.nonzero(parts >= 0)
        if rows.size:
            # the box filter is linear and the image equals the background outside the actor:
            # only the blocks of the actor's bounding box change
            r0, r1 = rows.min() // s, rows.max() // s + 1
            c0, c1 = cols.min() // s, cols.max() // s + 1
            window = (slice(r0 * s, r1 * s), slice(c0 * s, c1 * s))
            out[r0:r1, c0:c1] = downsample(image[window], s)
            upper = ((parts[window] >= 0) & (parts[window] != LOWER_BODY)).astype(np.float64)
            coverage[r0:r1, c0:c1] = downsample(upper[:, :, None], s)[:, :, 0]
        return out, coverage

    def frame(self, pose, index: int) -> np.ndarray:
        """The 8-bit RGB frame number ``index`` (its time and noise) with the actor in ``pose``,
        (H, W, 3) uint8."""
        return self.frame_and_stream(pose, index)[0]

    def frame_and_stream(self, pose, index: int) -> tuple[np.ndarray, bytes | None]:
        """:meth:`frame` and the camera's JPEG stream of it (None without compression)."""
        image, _ = self.radiance(pose)
        return apply_sensor(image, self.sensor, self.drift, index / FPS, self._noise_rng(index))

    def background_frame(self) -> np.ndarray:
        """The empty scene through the camera (exposure of frame 0, noise of its own)."""
        return apply_sensor(self.background_radiance, self.sensor, self.drift, 0.0, self._noise_rng(-1))[0]

    def _noise_rng(self, index: int) -> np.random.Generator:
        return np.random.default_rng(np.random.SeedSequence(self.noise_seed.entropy,
                                                            spawn_key=(*self.noise_seed.spawn_key, index + 1)))


def setup_sequence(name: str, *, seed: int = 0, size=(160, 120), sensor: SensorConfig | None = None,
                   face: bool = True) -> SequenceSetup:
    """The fixed part of a sequence: camera, actor, scene, light, sensor.

    Parameters
    ----------
    name : str
        One of :data:`SEQUENCE_NAMES`.
    seed : int
        Non-negative.
    size : (int, int)
        Output width and height, pixels.
    sensor : SensorConfig, optional
    face : bool
        Draw the actor's face; False draws hair all round the head
        (:attr:`~mocap.synth.actor.Appearance.face`), everything else as with the face.

    Returns
    -------
    SequenceSetup
    """
    spec = _check_name(name)
    seed = _check_seed(seed)
    width, height = _check_size(size)
    streams = _streams(seed, spec)
    camera = Camera.default(width, height)
    s = supersampling(width)
    actor = Actor.random(np.random.default_rng(streams["actor"]), bare_forearms=spec.bare_forearms,
                         pattern=spec.pattern)
    if not face:
        actor = replace(actor, appearance=replace(actor.appearance, face=False))
    scene_rng = np.random.default_rng(streams["scene"])
    light = Light.random(scene_rng)
    background = make_background(scene_rng, width * s, height * s)
    return SequenceSetup(name, seed, camera, s, actor, light, background, sensor or SensorConfig(),
                         SensorDrift.random(np.random.default_rng(streams["drift"])), streams["noise"])


def sequence_poses(setup: SequenceSetup, *, frames: int | None = None,
                   motion: str | Path | None = None) -> tuple[np.ndarray, dict | None]:
    """Ground-truth poses of a sequence: procedural, or a retargeted motion clip.

    Parameters
    ----------
    setup : SequenceSetup
        The sequence (its name and seed fix the procedural motion; its actor the collision
        checks).
    frames : int, optional
        Frame count (default: the sequence's own, or the whole clip).
    motion : str or Path, optional
        A motion clip (:func:`~mocap.synth.retarget.load_clip`) instead of the procedural motion.

    Returns
    -------
    poses : ndarray, shape (N, 23), float64
        Metres and radians, within the joint limits.
    motion_info : dict or None
        Description of the clip used (file name, hash, frames, convention).
    """
    spec = _check_name(setup.name)
    if frames is not None and (isinstance(frames, bool) or not isinstance(frames, (int, np.integer))
                               or not 1 <= frames <= MAX_FRAMES):
        raise ValueError(f"frames must be an integer in [1, {MAX_FRAMES}], got {frames!r}")
    model = BodyModel.build(setup.actor.dims)
    info = None
    if motion is None:
        n = spec.frames if frames is None else int(frames)
        poses = spec.motion(np.random.default_rng(_streams(setup.seed, spec)["motion"]), n, FPS)
    else:
        path = Path(motion)
        clip = load_clip(path)
        z = 1.7
        poses = retarget(clip, RetargetConfig(fps=FPS, centre=(0.0, root_height_for_depth(z), z)))
        if frames is not None:
            if frames > len(poses):
                raise ValueError(f"{path.name} lasts {len(poses)} frames at {FPS:g} fps; asked for {frames}")
            poses = poses[:frames]
        info = {"file": path.name, "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
                "convention": clip.convention, "clip_frames": clip.n_frames,
                "clip_fps": round(1.0 / clip.frame_time, 3)}
    poses = avoid_torso(poses, model)
    return np.clip(poses, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]), info


def _encode(image: np.ndarray, fmt: str, stream: bytes | None = None) -> bytes:
    """PNG of ``image``, or for ``jpg`` the camera's own JPEG ``stream`` (else quality 92)."""
    if fmt == "png":
        return iio.imwrite("<bytes>", image, extension=".png")
    if stream is not None:
        return stream
    return iio.imwrite("<bytes>", image, extension=".jpeg", quality=92)


def _prepare_folder(out: Path) -> None:
    """Create ``out`` or reuse an earlier sequence folder (its old frames are removed)."""
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out} exists and is not a folder")
    if out.is_dir() and any(out.iterdir()) and not (out / "meta.json").is_file():
        raise ValueError(f"{out} is not empty and holds no synthetic sequence; choose another --out")
    frames = out / "frames"
    frames.mkdir(parents=True, exist_ok=True)
    for old in frames.iterdir():
        if re.fullmatch(r"\d{6}\.(png|jpg)", old.name):
            old.unlink()


def generate_sequence(name: str, out_dir: str | Path, *, frames: int | None = None, seed: int = 0,
                      size=(160, 120), motion: str | Path | None = None, frame_format: str = "png",
                      progress: bool = True, face: bool = True) -> Path:
    """Write a synthetic benchmark sequence with ground truth.

    Parameters
    ----------
    name : str
        One of :data:`SEQUENCE_NAMES` (it fixes the actor, scene and, without ``motion``,
        the procedural motion).
    out_dir : str or Path
        Folder to write (created; an earlier sequence folder there is replaced).
    frames : int, optional
        Frame count (default: the sequence's own, or the whole clip with ``motion``).
    seed : int
        Same seed, same bytes.
    size : (int, int)
        Width and height in pixels (default 160 x 120, the paper's).
    motion : str or Path, optional
        A BVH file (or an AMC file with its ASF beside it) to drive the actor instead of the
        procedural motion (:mod:`mocap.synth.retarget`).
    frame_format : {"png", "jpg"}
        Frame files: lossless PNG of the camera's frames, or the camera's own JPEG streams
        (same pixels once decoded, about four times smaller).
    progress : bool
        Show a progress bar.
    face : bool
        Draw the actor's face (default); False draws hair all round the head, everything else
        the same (:func:`setup_sequence`; ``meta.json``'s ``actor.appearance.face`` is then false).

    Returns
    -------
    Path
        The sequence folder.

    Raises
    ------
    ValueError
        On an unknown name, bad frame count, seed, size or format, or an unusable folder.
    FileNotFoundError
        If ``motion`` does not exist.
    """
    if frame_format not in FRAME_FORMATS:
        raise ValueError(f"frame format must be one of {', '.join(FRAME_FORMATS)}, got {frame_format!r}")
    setup = setup_sequence(name, seed=seed, size=size, face=face)
    poses, motion_info = sequence_poses(setup, frames=frames, motion=motion)
    out = Path(out_dir)
    _prepare_folder(out)
    (out / "meta.json").unlink(missing_ok=True)       # written last: its presence marks a finished folder
    model = BodyModel.build(setup.actor.dims)
    joints = np.stack([model.joint_positions(q) for q in poses])
    for i in tqdm(range(len(poses)), desc=f"synth {name}", unit="frame", disable=not progress, leave=False):
        pixels, stream = setup.frame_and_stream(poses[i], i)
        (out / "frames" / f"{i:06d}.{frame_format}").write_bytes(_encode(pixels, frame_format, stream))
    write_bytes_atomic(out / "background.png", _encode(setup.background_frame(), "png"))
    part_class = setup.actor.appearance.part_class()
    Calibration(setup.actor.dims, poses[0], setup.camera, DEFAULT_CLASS_NAMES, part_class).to_json(
        out / "calibration.json")
    PoseTable(np.arange(len(poses)), poses, joints).write(out / "ground_truth.csv")
    meta = {
        "format": META_FORMAT,
        "sequence": name,
        "description": SEQUENCES[name].description,
        "seed": setup.seed,
        "frames": int(len(poses)),
        "fps": FPS,
        "size": [setup.camera.width, setup.camera.height],
        "frame_format": frame_format,
        "camera": setup.camera.to_dict(),
        "motion": motion_info if motion_info is not None else {"procedural": name},
        "actor": {"dimensions": setup.actor.dims.to_dict(), "appearance": setup.actor.appearance.to_dict(),
                  "mesh_triangles": int(len(setup.actor.mesh.triangles))},
        "light": setup.light.to_dict(),
        "sensor": setup.sensor.to_dict(),
        "supersampling": setup.supersample,
        "generator": f"mocap.synth {mocap.__version__}",
        "units": {"positions": "metres", "angles_in_files": "degrees"},
    }
    write_text_atomic(out / "meta.json", json.dumps(meta, indent=2) + "\n")
    return out

