"""Calibration of one actor in one camera (paper section 3.1): automatic first-frame fit
(:func:`auto_calibrate`) and colour classes from a known pose (:func:`colour_model_from_pose`).

The record itself, :class:`~mocap.render.calibration.Calibration` (``calibration.json``), lives
low in the layers in :mod:`mocap.render.calibration`; it is re-exported here.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from mocap.body.dimensions import BodyDimensions
from mocap.body.model import BodyModel
from mocap.body.skeleton import DEFAULT_PART_CLASS, MESH_PART_NAMES
from mocap.labels import CLASS_MERGES_INTO
from mocap.render.calibration import FORMAT, Calibration
from mocap.render.camera import Camera

__all__ = ["FORMAT", "MIN_COLOUR_SAMPLES", "PROPORTION_FACTORS", "PROPORTION_RANGE", "AutoCalibrationConfig",
           "Calibration", "auto_calibrate", "colour_model_from_pose"]

#: Fewest sample pixels a colour class needs to be learnt.
MIN_COLOUR_SAMPLES = 12


def colour_model_from_pose(frame: np.ndarray, background: np.ndarray | None, model: BodyModel, camera: Camera,
                           pose, imaging=None):
    """Learn the colour classes from a frame where the model's pose is known (calibration).

    Each class is sampled from the frame's foreground pixels inside the projection of the
    model parts of that class (eroded by one pixel so that boundary pixels, mixed with the
    background, are left out): hair inside the model's hair region, the lower body inside its
    lower-body part. Those two are optional: a class the frame does not support (too few
    pixels, or coloured like skin or clothes) is merged away, and the model should follow
    with ``model.with_class_names(colour_model.names)``.

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
        Classes ``model.class_names`` in label order, without the merged ones.

    Raises
    ------
    ValueError
        If the frame and camera sizes differ or a class that cannot be merged has too few
        sample pixels.
    """
    from scipy import ndimage

    from mocap.imaging import ColourModel, subtract_background
    from mocap.imaging.colour import MIN_SAMPLES
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
        if np.count_nonzero(mask) < max(MIN_COLOUR_SAMPLES, MIN_SAMPLES):
            mask = inside & foreground                  # small regions (hair): keep the boundary
        if np.count_nonzero(mask) < MIN_COLOUR_SAMPLES and name not in CLASS_MERGES_INTO:
            raise ValueError(f"the calibrated model covers only {np.count_nonzero(mask)} foreground pixels of "
                             f"class {name!r} in the first frame; is the initial pose right?")
        samples[name] = frame[mask]
    return ColourModel.from_samples(samples, CLASS_MERGES_INTO)


# ----------------------------------------------------------------------------- automatic calibration
#: Pose parameters fitted by automatic calibration (a roughly neutral posture is assumed).
CALIBRATED_POSE_PARAMETERS: tuple[str, ...] = (
    "root_x", "root_y", "root_z", "chest_yaw", "chest_roll",
    "r_shoulder_flex", "r_shoulder_abd", "r_elbow_flex", "l_shoulder_flex", "l_shoulder_abd", "l_elbow_flex",
)
#: Body proportions fitted by automatic calibration: factor name -> (parts, sizes it scales).
PROPORTION_FACTORS = MappingProxyType({
    "torso_width": (("torso", "lower_body"), ("width", "depth")),
    "torso_length": (("torso",), ("length",)),
    "arm_length": (("r_upper_arm", "r_forearm", "l_upper_arm", "l_forearm"), ("length",)),
    "arm_width": (("r_upper_arm", "r_forearm", "l_upper_arm", "l_forearm"), ("width", "depth")),
    "head_size": (("head", "neck"), ("length", "width", "depth")),
})
#: Range of every proportion factor relative to the default adult.
PROPORTION_RANGE = (0.75, 1.35)
#: Range of the hairline (fraction of half the head length above its centre) fitted by the
#: colour stage of automatic calibration.
HAIRLINE_RANGE = (0.0, 0.9)


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
            if p not in parts:
                continue                                # an optional part the base lacks
            s = parts[p]
            parts[p] = type(s)(**{k: getattr(s, k) * (f if k in sizes else 1.0) for k in ("length", "width", "depth")})
    return BodyDimensions(parts, base.hairline)


def auto_calibrate(frame: np.ndarray, background: np.ndarray, camera: Camera, *, imaging=None,
                   base_dims: BodyDimensions | None = None, config: AutoCalibrationConfig | None = None,
                   progress: bool = False) -> Calibration:
    """Fit body proportions and the initial pose to a first frame with a roughly neutral posture.

    Beyond the paper's manual adjustment (its section 3.1): (1) the foreground silhouette
    alone, as one class, fixes position, depth and arm pose over a grid of depths and then by
    downhill simplex over pose and proportions; (2) the colour classes are learnt inside the
    fitted model's projected parts (:func:`colour_model_from_pose`: hair inside the hair region
    under ``base_dims``' hairline, lower body inside the lower-body part; either merged away
    when the frame does not support it) and (3) a second simplex refines everything, and the
    hairline (within :data:`HAIRLINE_RANGE`) when hair was kept, on the label image with the
    non-overlapping ratio.

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
        Default adult proportions with a lower body and the default hairline; without a
        hairline (or lower body) there the calibration has no hair region (lower body).
    config : AutoCalibrationConfig, optional

    Returns
    -------
    Calibration
        With the colour classes the frame supports.

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
    one_class = {p: "body" for p in MESH_PART_NAMES}
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
        dims = _apply_factors(base, x[n_pose:n_pose + n_fac])
        return pose, (dims.with_hairline(float(x[-1])) if len(x) > n_pose + n_fac else dims)

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
    # (2) colours from the fitted pose, (3) refinement on the label image of those classes
    pose, dims = unpack(res.x)
    model = BodyModel.build(dims, resolution=config.resolution)
    colour = colour_model_from_pose(frame, background, model, camera, pose, imaging)
    labels = prepare_frame(frame, background, colour, imaging).labels
    cost2 = objective(labels, dict(DEFAULT_PART_CLASS), colour.names)
    x, step2 = res.x, 0.5 * steps
    if "hair" in colour.names:
        x = np.r_[x, dims.hairline]
        step2 = np.r_[step2, 0.15]
        lower, upper = np.r_[lower, HAIRLINE_RANGE[0]], np.r_[upper, HAIRLINE_RANGE[1]]
    res2 = minimize(cost2, initial_simplex(np.clip(x, lower, upper), step2, lower, upper), lower, upper,
                    budget=config.evaluations, ftol=1e-6)
    pose, dims = unpack(res2.x)
    return Calibration(dims, pose, camera, colour.names)
