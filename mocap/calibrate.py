"""Calibration of one actor in one camera (paper section 3.1).

:class:`Calibration` holds body dimensions, initial pose, camera and colour classes, saved as
``calibration.json`` (DESIGN.md section 4) with angles in degrees for people to read.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

import numpy as np

from mocap.body.dimensions import PART_NAMES, BodyDimensions
from mocap.body.model import BodyModel
from mocap.body.pose import JOINT_LIMITS, PARAMETER_NAMES, check_pose, neutral_pose, pose_from_dict, pose_to_dict
from mocap.body.skeleton import DEFAULT_PART_CLASS
from mocap.labels import DEFAULT_CLASS_NAMES
from mocap.render.camera import Camera

_KEYS = {"format", "dimensions", "initial_pose_deg", "camera", "class_names", "part_class"}
FORMAT = "mocap-calibration-1"


@dataclass(frozen=True)
class Calibration:
    """Everything the tracker needs to know about the actor and the camera before frame 0.

    Attributes
    ----------
    dims : BodyDimensions
    initial_pose : ndarray, shape (23,), float64
        Pose in the first frame (metres, radians).
    camera : Camera
    class_names : tuple of str
    part_class : mapping of part name to class name
    """

    dims: BodyDimensions = field(default_factory=BodyDimensions)
    initial_pose: np.ndarray = field(default_factory=neutral_pose)
    camera: Camera = field(default_factory=Camera.default)
    class_names: tuple[str, ...] = DEFAULT_CLASS_NAMES
    part_class: Mapping[str, str] = field(default_factory=lambda: dict(DEFAULT_PART_CLASS))

    def __post_init__(self) -> None:
        q = check_pose(self.initial_pose, name="initial pose")
        q.setflags(write=False)
        object.__setattr__(self, "initial_pose", q)
        object.__setattr__(self, "class_names", tuple(self.class_names))
        object.__setattr__(self, "part_class", MappingProxyType(dict(self.part_class)))
        self.body_model()  # validates classes and parts

    def body_model(self, resolution: int | None = None) -> BodyModel:
        """The body model of this actor (mesh level of detail ``resolution``, default 12)."""
        return BodyModel.build(self.dims, resolution=12 if resolution is None else resolution,
                               part_class=self.part_class, class_names=self.class_names)

    def to_dict(self) -> dict:
        return {"format": FORMAT, "dimensions": self.dims.to_dict(),
                "initial_pose_deg": pose_to_dict(self.initial_pose, degrees=True),
                "camera": self.camera.to_dict(), "class_names": list(self.class_names),
                "part_class": {p: self.part_class[p] for p in PART_NAMES}}

    @classmethod
    def from_dict(cls, data: Mapping) -> "Calibration":
        if not isinstance(data, Mapping):
            raise ValueError("calibration must be a JSON object")
        extra = set(data) - _KEYS
        if extra:
            raise ValueError(f"unknown keys in calibration: {', '.join(sorted(extra))}")
        missing = _KEYS - set(data)
        if missing:
            raise ValueError(f"calibration lacks: {', '.join(sorted(missing))}")
        if data["format"] != FORMAT:
            raise ValueError(f"calibration format {data['format']!r} is not {FORMAT!r}")
        return cls(BodyDimensions.from_dict(data["dimensions"]),
                   _pose_within_limits(data["initial_pose_deg"]),
                   Camera.from_dict(data["camera"]), tuple(data["class_names"]), dict(data["part_class"]))

    def to_json(self, path: str | Path) -> None:
        """Save (atomically) as JSON."""
        from mocap.io.jsonfile import write_json
        write_json(path, self.to_dict())

    @classmethod
    def from_json(cls, path: str | Path) -> "Calibration":
        """Load a file written by :meth:`to_json`; raises ValueError with the file name on bad content."""
        from mocap.io.jsonfile import read_json
        data = read_json(path)
        try:
            return cls.from_dict(data)
        except (ValueError, TypeError, KeyError) as exc:
            raise ValueError(f"{path}: {exc}") from None


def _pose_within_limits(values_deg) -> np.ndarray:
    """The calibration file's ``initial_pose_deg`` as a pose (metres, radians); ValueError naming
    the first parameter that is not a number or lies outside :data:`JOINT_LIMITS`."""
    if not isinstance(values_deg, Mapping):
        raise ValueError("initial_pose_deg must be an object of parameter: value")
    for name, value in values_deg.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"initial_pose_deg {name} must be a number, got {value!r}")
    pose = pose_from_dict(dict(values_deg), degrees=True)
    for i, name in enumerate(PARAMETER_NAMES):
        lo, hi = JOINT_LIMITS[i]
        if not lo - 1e-9 <= pose[i] <= hi + 1e-9:           # (slack for the degree round trip)
            unit = " m" if i < 3 else " deg"
            lo, hi = (lo, hi) if i < 3 else (math.degrees(lo), math.degrees(hi))
            raise ValueError(f"initial_pose_deg {name} = {values_deg[name]:g}{unit} is outside its joint limits "
                             f"[{lo:g}, {hi:g}]{unit}")
    return pose


#: Fewest sample pixels a colour class needs to be learnt.
MIN_COLOUR_SAMPLES = 12


def colour_model_from_pose(frame: np.ndarray, background: np.ndarray | None, model: BodyModel, camera: Camera,
                           pose, imaging=None):
    """Learn the colour classes from a frame where the model's pose is known (calibration).

    Each class is sampled from the frame's foreground pixels inside the projection of the
    model parts of that class (eroded by one pixel so that boundary pixels, mixed with the
    background, are left out).

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3)
        RGB, uint8 or float in [0, 1].
    background : ndarray, shape (H, W, 3), or None
        Empty scene; without it every projected pixel is used.
    model : BodyModel
    camera : Camera
        Must match the frame size.
    pose : array_like, shape (23,)
        The actor's pose in ``frame`` (metres, radians).
    imaging : ImagingConfig, optional
        Background-subtraction settings.

    Returns
    -------
    mocap.imaging.ColourModel
        Classes ``model.class_names`` in label order.

    Raises
    ------
    ValueError
        If the frame and camera sizes differ or a class has too few sample pixels.
    """
    from scipy import ndimage

    from mocap.imaging import ColourModel, subtract_background
    from mocap.render import render

    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[:2] != camera.shape:
        raise ValueError(f"frame of shape {frame.shape} does not match the camera ({camera.height}, {camera.width}, 3)")
    foreground = np.ones(camera.shape, bool)
    if background is not None:
        foreground = subtract_background(frame, background, imaging)
    labels = render(pose, model, camera).labels
    samples = {}
    for c, name in enumerate(model.class_names, start=1):
        inside = labels == c
        mask = ndimage.binary_erosion(inside) & foreground
        if np.count_nonzero(mask) < MIN_COLOUR_SAMPLES:
            mask = inside & foreground
        if np.count_nonzero(mask) < MIN_COLOUR_SAMPLES:
            raise ValueError(f"the calibrated model covers only {np.count_nonzero(mask)} foreground pixels of "
                             f"class {name!r} in the first frame; is the initial pose right?")
        samples[name] = frame[mask]
    return ColourModel.from_samples(samples)


# ----------------------------------------------------------------------------- automatic calibration
#: Pose parameters fitted by automatic calibration (a roughly neutral posture is assumed).
CALIBRATED_POSE_PARAMETERS: tuple[str, ...] = (
    "root_x", "root_y", "root_z", "chest_yaw", "chest_roll",
    "r_shoulder_flex", "r_shoulder_abd", "r_elbow_flex", "l_shoulder_flex", "l_shoulder_abd", "l_elbow_flex",
)
#: Body proportions fitted by automatic calibration: factor name -> (parts, sizes it scales).
PROPORTION_FACTORS = MappingProxyType({
    "torso_width": (("torso",), ("width", "depth")),
    "torso_length": (("torso",), ("length",)),
    "arm_length": (("r_upper_arm", "r_forearm", "l_upper_arm", "l_forearm"), ("length",)),
    "arm_width": (("r_upper_arm", "r_forearm", "l_upper_arm", "l_forearm"), ("width", "depth")),
    "head_size": (("head", "neck"), ("length", "width", "depth")),
})
#: Range of every proportion factor relative to the default adult.
PROPORTION_RANGE = (0.75, 1.35)


@dataclass(frozen=True)
class AutoCalibrationConfig:
    """Settings of :func:`auto_calibrate`.

    Attributes
    ----------
    depth_grid_m : tuple of float, metres
        Candidate actor depths tried before the simplex search.
    evaluations : int
        Cost evaluations of each of the two simplex stages (silhouette, then colours).
    resolution : int
        Mesh level of detail used while fitting.
    """

    depth_grid_m: tuple[float, ...] = tuple(np.round(np.linspace(1.0, 4.0, 16), 3))
    evaluations: int = 1500
    resolution: int = 8


def _apply_factors(base: BodyDimensions, factors: np.ndarray) -> BodyDimensions:
    parts = dict(base.parts)
    for f, (parts_scaled, sizes) in zip(factors, PROPORTION_FACTORS.values()):
        for p in parts_scaled:
            s = parts[p]
            parts[p] = type(s)(**{k: getattr(s, k) * (f if k in sizes else 1.0) for k in ("length", "width", "depth")})
    return BodyDimensions(parts)


def auto_calibrate(frame: np.ndarray, background: np.ndarray, camera: Camera, *, imaging=None,
                   base_dims: BodyDimensions | None = None, config: AutoCalibrationConfig | None = None,
                   progress: bool = False) -> Calibration:
    """Fit body proportions and the initial pose to a first frame with a roughly neutral posture.

    Beyond the paper's manual adjustment (its section 3.1): (1) the foreground silhouette
    alone, as one class, fixes position, depth and arm pose over a grid of depths and then by
    downhill simplex over pose and proportions; (2) the colour classes are learnt inside the
    fitted model's projected parts (:func:`colour_model_from_pose`) and (3) a second simplex
    refines everything on the two-class label image with the non-overlapping ratio.

    From one view, a larger actor farther away looks the same as a smaller one nearer: the
    overall scale stays that of ``base_dims`` (default adult proportions) and the fit adjusts
    the depth and the *relative* proportions (:data:`PROPORTION_FACTORS`, within
    :data:`PROPORTION_RANGE`).

    Parameters
    ----------
    frame, background : ndarray, shape (H, W, 3)
        First frame and empty scene, RGB uint8 or float in [0, 1].
    camera : Camera
        Must match the frame size.
    imaging : ImagingConfig, optional
    base_dims : BodyDimensions, optional
    config : AutoCalibrationConfig, optional

    Returns
    -------
    Calibration

    Raises
    ------
    ValueError
        If sizes differ or no actor is visible.
    """
    from mocap.body.pose import JOINT_LIMITS, PARAMETER_INDEX, neutral_pose
    from mocap.cost import RegionCost
    from mocap.imaging import ImagingConfig, prepare_frame, subtract_background
    from mocap.optimize import initial_simplex, minimize

    config = AutoCalibrationConfig() if config is None else config
    imaging = ImagingConfig() if imaging is None else imaging
    base = BodyDimensions() if base_dims is None else base_dims
    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[:2] != camera.shape:
        raise ValueError(f"frame of shape {frame.shape} does not match the camera ({camera.height}, {camera.width}, 3)")
    foreground = subtract_background(frame, background, imaging)
    if np.count_nonzero(foreground) < 50:
        raise ValueError("no actor in the first frame (the foreground is empty): cannot calibrate")
    one_class = {p: "body" for p in PART_NAMES}
    pose_index = np.array([PARAMETER_INDEX[n] for n in CALIBRATED_POSE_PARAMETERS])
    n_pose, n_fac = len(pose_index), len(PROPORTION_FACTORS)
    lower = np.r_[JOINT_LIMITS[pose_index, 0], np.full(n_fac, PROPORTION_RANGE[0])]
    upper = np.r_[JOINT_LIMITS[pose_index, 1], np.full(n_fac, PROPORTION_RANGE[1])]
    # a neutral posture is assumed: keep the torso roughly upright and facing the camera
    for name, limit in (("chest_yaw", 0.6), ("chest_roll", 0.3)):
        k = CALIBRATED_POSE_PARAMETERS.index(name)
        lower[k], upper[k] = -limit, limit

    def unpack(x):
        pose = neutral_pose()
        pose[pose_index] = x[:n_pose]
        return pose, _apply_factors(base, x[n_pose:])

    def objective(target, part_class, class_names):
        def cost(x):
            pose, dims = unpack(x)
            model = BodyModel.build(dims, resolution=config.resolution, part_class=part_class, class_names=class_names)
            return RegionCost(target, model, camera)(pose)
        return cost

    # (1) silhouette: depth grid, then simplex
    target = foreground.astype(np.uint8)
    rows, cols = np.nonzero(foreground)
    top, centre_col = rows.min(), cols.mean()
    start = neutral_pose()
    head_top = -(base["torso"].length + base["neck"].length * 0.7 + base["head"].length)
    best = (np.inf, None)
    cost1 = objective(target, one_class, ("body",))
    for z in config.depth_grid_m:
        x = np.r_[start[pose_index], np.ones(n_fac)]
        x[0] = (centre_col + 0.5 - camera.cx) * z / camera.fx
        x[1] = (top + 0.5 - camera.cy) * z / camera.fy - head_top
        x[2] = z
        x = np.clip(x, lower, upper)
        f = cost1(x)
        if f < best[0]:
            best = (f, x)
    steps = np.r_[0.03, 0.03, 0.1, 0.1, 0.05, np.full(n_pose - 5, 0.25), np.full(n_fac, 0.08)]
    res = minimize(cost1, initial_simplex(best[1], steps, lower, upper), lower, upper,
                   budget=config.evaluations, ftol=1e-6)
    # (2) colours from the fitted pose, (3) two-class refinement
    pose, dims = unpack(res.x)
    model = BodyModel.build(dims, resolution=config.resolution)
    colour = colour_model_from_pose(frame, background, model, camera, pose, imaging)
    labels = prepare_frame(frame, background, colour, imaging).labels
    cost2 = objective(labels, dict(DEFAULT_PART_CLASS), DEFAULT_CLASS_NAMES)
    res2 = minimize(cost2, initial_simplex(res.x, 0.5 * steps, lower, upper), lower, upper,
                    budget=config.evaluations, ftol=1e-6)
    pose, dims = unpack(res2.x)
    return Calibration(dims, pose, camera)
