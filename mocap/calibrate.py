"""Calibration of one actor in one camera (paper section 3.1): automatic first-frame fit
(:func:`auto_calibrate`) and colour classes from a known pose (:func:`colour_model_from_pose`).

The record itself, :class:`~mocap.render.calibration.Calibration` (``calibration.json``), lives
low in the layers in :mod:`mocap.render.calibration`; it is re-exported here.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from mocap.body.dimensions import BodyDimensions, PartSize
from mocap.body.model import BodyModel
from mocap.body.skeleton import DEFAULT_PART_CLASS, MESH_PART_NAMES
from mocap.labels import CLASS_MERGES_INTO
from mocap.render.calibration import FORMAT, Calibration
from mocap.render.camera import Camera

__all__ = ["FORMAT", "MIN_COLOUR_SAMPLES", "PROPORTION_FACTORS", "PROPORTION_RANGE", "AutoCalibrationConfig",
           "Calibration", "auto_calibrate", "colour_model_from_pose"]

#: Fewest sample pixels a colour class needs to be learnt (what :class:`mocap.imaging.ColourModel` needs).
MIN_COLOUR_SAMPLES = 20


def colour_model_from_pose(frame: np.ndarray, background: np.ndarray | None, model: BodyModel, camera: Camera,
                           pose, imaging=None, *, foreground: np.ndarray | None = None):
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
    foreground : ndarray of bool, shape (H, W), optional
        The actor's pixels, when known otherwise (no background image); replaces the
        subtraction of ``background``.

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
    if foreground is not None:
        foreground = np.asarray(foreground, dtype=bool)
        if foreground.shape != camera.shape:
            raise ValueError(f"foreground of shape {foreground.shape} does not match the camera {camera.shape}")
    elif background is None:
        foreground = np.ones(camera.shape, bool)
    else:
        foreground = subtract_background(frame, background, imaging)
    labels = render(pose, model, camera).labels
    samples = {}
    for c, name in enumerate(model.class_names, start=1):
        inside = labels == c
        mask = ndimage.binary_erosion(inside) & foreground
        if np.count_nonzero(mask) < max(MIN_COLOUR_SAMPLES, MIN_SAMPLES):
            mask = inside & foreground                  # small regions (hair): keep the boundary
        if np.count_nonzero(mask) < MIN_COLOUR_SAMPLES:     # a small part far away: one pixel around it too
            mask = ndimage.binary_dilation(inside) & foreground
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
    """``base`` with each of :data:`PROPORTION_FACTORS`' sizes multiplied by its factor (in the
    table's order; a part the base lacks is skipped)."""
    sizes = {p: [s.length, s.width, s.depth] for p, s in base.parts.items()}
    for f, (parts_scaled, axes) in zip(factors, PROPORTION_FACTORS.values()):
        f = float(f)
        for p in parts_scaled:
            size = sizes.get(p)
            if size is not None:                        # None: an optional part the base lacks
                for i, axis in enumerate(("length", "width", "depth")):
                    if axis in axes:
                        size[i] *= f
    return BodyDimensions({p: PartSize(*size) for p, size in sizes.items()}, base.hairline)


def auto_calibrate(frame: np.ndarray, background: np.ndarray, camera: Camera, *, imaging=None,
                   base_dims: BodyDimensions | None = None, config: AutoCalibrationConfig | None = None,
                   progress: bool = False, keypoints=None) -> Calibration:
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
    keypoints : Keypoints, optional
        2D keypoints of the frame (:mod:`mocap.io.keypoints`, ``camera`` pixels): both fits
        also pull the model's joints onto them (:data:`CALIBRATION_KEYPOINT_WEIGHT`).

    Returns
    -------
    Calibration
        With the colour classes the frame supports.

    Raises
    ------
    ValueError
        If sizes differ or no actor is visible.
    """
    from mocap.imaging import ImagingConfig, subtract_background

    config = AutoCalibrationConfig() if config is None else config
    imaging = ImagingConfig() if imaging is None else imaging
    base = BodyDimensions() if base_dims is None else base_dims
    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[:2] != camera.shape:
        raise ValueError(f"frame of shape {frame.shape} does not match the camera ({camera.height}, {camera.width}, 3)")
    foreground = subtract_background(frame, background, imaging)
    if np.count_nonzero(foreground) < 50:
        raise ValueError("no actor in the first frame (the foreground is empty): cannot calibrate")
    calibration, _ = _fit_body(frame, foreground, camera, base, config, imaging, background=background,
                               keypoints=keypoints)
    return calibration


def _silhouette_starts(foreground: np.ndarray, camera: Camera, base: BodyDimensions, depths,
                       face=None) -> list[tuple[float, float, float]]:
    """Root positions (metres) to try first: the head on the silhouette's top (or on the face
    box's centre) at each depth."""
    rows, cols = np.nonzero(foreground)
    above_root = base["torso"].length + base["neck"].length * 0.7
    starts = []
    for z in depths:
        if face is not None:
            u = face.col + 0.5 * face.width
            v = face.row + 0.5 * face.height
            y = (v - camera.cy) * z / camera.fy + above_root + 0.5 * base["head"].length
        else:
            u, v = cols.mean() + 0.5, rows.min() + 0.5
            y = (v - camera.cy) * z / camera.fy + above_root + base["head"].length
        starts.append(((u - camera.cx) * z / camera.fx, y, float(z)))
    return starts


#: Weight of the keypoint distance in the calibration's fits, units of F per pixel (the tracker's
#: default ``keypoint_weight / REGION_WEIGHT``): shoulders, head and arms pulled onto 2D keypoints.
CALIBRATION_KEYPOINT_WEIGHT = 0.04


def calibration_keypoint_cost(keypoints, model: BodyModel, camera: Camera, foreground: np.ndarray):
    """The keypoint distance the calibration's fits add (:class:`~mocap.cost.KeypointCost`, pixels).

    Read under the labelling the tracker would take (issue 49 item 5): where the detector shows
    the person's front (:meth:`~mocap.io.keypoints.Keypoints.shows_front`: MediaPipe is right on
    96-100 % of such frames), its own labels; elsewhere the lower of its labelling and the
    left/right swapped one (``swap=True``), so that a detector that names the left arm the right
    one does not turn the upright, camera-facing body the calibration assumes (the refinement's
    colour classes, the face and the hair, see it).

    Parameters
    ----------
    keypoints : Keypoints
        The frame's 2D keypoints, ``camera`` pixels.
    model : BodyModel
    camera : Camera
    foreground : ndarray, shape (H, W), bool
        The frame's foreground: keypoints off it are gated out.
    """
    from mocap.cost import KeypointCost

    return KeypointCost(keypoints.uv, keypoints.confidence, model, camera, foreground=foreground,
                        swap=not keypoints.shows_front())


def _fit_body(frame: np.ndarray, foreground: np.ndarray, camera: Camera, base: BodyDimensions,
              config: AutoCalibrationConfig, imaging, *, background=None, face=None, depths=None, seed_colour=None,
              keypoints=None):
    """Fit pose and proportions to a foreground mask, learn the colours, refine on them.

    With ``keypoints`` (:class:`mocap.io.keypoints.Keypoints`, ``camera`` pixels) both fits add
    :data:`CALIBRATION_KEYPOINT_WEIGHT` times the keypoint distance (the shoulders' width and
    place, the head, the arms), gated by the foreground, under the labelling the tracker would
    take (:func:`calibration_keypoint_cost`).

    Returns the Calibration and the ColourModel learnt inside the fitted model (``seed_colour``,
    when given, where the fitted model covers too few foreground pixels of a class).
    """
    from mocap.body.pose import JOINT_LIMITS, PARAMETER_INDEX, neutral_pose
    from mocap.cost import RegionCost
    from mocap.imaging import prepare_frame
    from mocap.optimize import initial_simplex, minimize

    depths = config.depth_grid_m if depths is None else depths
    one_class = {p: "body" for p in MESH_PART_NAMES}
    pose_index = np.array([PARAMETER_INDEX[n] for n in CALIBRATED_POSE_PARAMETERS])
    n_pose, n_fac = len(pose_index), len(PROPORTION_FACTORS)
    lower = np.r_[JOINT_LIMITS[pose_index, 0], np.full(n_fac, PROPORTION_RANGE[0])]
    upper = np.r_[JOINT_LIMITS[pose_index, 1], np.full(n_fac, PROPORTION_RANGE[1])]
    # a neutral posture is assumed: keep the torso roughly upright and facing the camera
    for name, limit in (("chest_yaw", 0.6), ("chest_roll", 0.3)):
        k = CALIBRATED_POSE_PARAMETERS.index(name)
        lower[k], upper[k] = -limit, limit
    if face is not None:            # the face's size bounds the depth to the grid's range
        k = CALIBRATED_POSE_PARAMETERS.index("root_z")
        lower[k], upper[k] = max(lower[k], min(depths)), min(upper[k], max(depths))

    def unpack(x):
        pose = neutral_pose()
        pose[pose_index] = x[:n_pose]
        dims = _apply_factors(base, x[n_pose:n_pose + n_fac])
        return pose, (dims.with_hairline(float(x[-1])) if len(x) > n_pose + n_fac else dims)

    # the keypoints' gates and scales once: each trial body only re-reads its joints (for_model)
    keypoint_cost = None if keypoints is None else calibration_keypoint_cost(
        keypoints, BodyModel.build(base, resolution=config.resolution), camera, foreground)

    def objective(target, part_class, class_names):
        # the classes, and the target's class counts, once: each trial body only rebuilds its
        # mesh and skeleton (with_dimensions, for_model)
        model = BodyModel.build(base, resolution=config.resolution, part_class=part_class, class_names=class_names)
        region_cost = RegionCost(target, model, camera)

        def cost(x):
            pose, dims = unpack(x)
            trial = model.with_dimensions(dims)
            value = region_cost.for_model(trial)(pose)
            if keypoint_cost is not None:
                value += CALIBRATION_KEYPOINT_WEIGHT * keypoint_cost.for_model(trial)(pose)
            return value
        return cost

    # (1) silhouette: depth grid, then simplex
    target = foreground.astype(np.uint8)
    start = neutral_pose()
    best = (np.inf, None)
    cost1 = objective(target, one_class, ("body",))
    for root in _silhouette_starts(foreground, camera, base, depths, face):
        x = np.r_[start[pose_index], np.ones(n_fac)]
        x[:3] = root
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

    def colours(model, pose):
        try:
            return colour_model_from_pose(frame, None, model, camera, pose, imaging, foreground=foreground)
        except ValueError:
            if seed_colour is None:
                raise
            return seed_colour

    colour = colours(model, pose)
    labels = prepare_frame(frame, background, colour, imaging).labels
    labels[~foreground] = 0
    cost2 = objective(labels, dict(DEFAULT_PART_CLASS), colour.names)
    x, step2 = res.x, 0.5 * steps
    if "hair" in colour.names:
        x = np.r_[x, dims.hairline]
        step2 = np.r_[step2, 0.15]
        lower, upper = np.r_[lower, HAIRLINE_RANGE[0]], np.r_[upper, HAIRLINE_RANGE[1]]
    res2 = minimize(cost2, initial_simplex(np.clip(x, lower, upper), step2, lower, upper), lower, upper,
                    budget=config.evaluations, ftol=1e-6)
    pose, dims = unpack(res2.x)
    calibration = Calibration(dims, pose, camera, colour.names)
    return calibration, colours(calibration.body_model(config.resolution), pose)


#: Stature (metres) the default proportions (:data:`mocap.body.dimensions.DEFAULT_PART_SIZES`) stand for.
DEFAULT_STATURE_M = 1.75
#: How much more frequent outside the person's box than inside a colour must be to be the scene's.
SCENE_RATIO = 1.25
#: Width of a detected face box in head widths (the LBP cascade's box spans the face, temple to temple).
FACE_BOX_HEAD_WIDTHS = 0.95


def calibrate_person(frame: np.ndarray, camera: Camera, *, background: np.ndarray | None = None, face=None,
                     height_m: float | None = None, imaging=None,
                     config: AutoCalibrationConfig | None = None, keypoints=None):
    """Calibrate a real person on one frame: body proportions, initial pose and colours.

    The person need not hold a special pose (arms down is the common case) but should face
    the camera roughly. The face (:func:`mocap.imaging.detect_face`), when given, seeds the
    colours (skin inside it, clothes under it), the position (the head on the face) and the
    depth (the face box is :data:`FACE_BOX_HEAD_WIDTHS` head widths wide); then
    :func:`auto_calibrate`'s fit runs on the foreground: against ``background`` when there
    is one, else the pixels the face-seeded colour classes explain (colour-only), kept to
    the connected parts that touch the region under the face.

    One view cannot tell size from distance: without ``height_m`` the actor has the default
    adult proportions (:data:`DEFAULT_STATURE_M`) and the depth follows from them; with it
    the proportions are scaled to that stature first, which fixes the absolute scale.

    Parameters
    ----------
    frame : ndarray of uint8, shape (H, W, 3)
        RGB frame at the tracker's working resolution.
    camera : Camera
        Matching the frame size.
    background : ndarray of uint8, shape (H, W, 3), optional
        Empty scene (given or estimated).
    face : Box, optional
        The person's face in ``frame`` (pixels). Needed without a background.
    height_m : float, optional
        The person's stature in metres (1.0-2.5).
    imaging : ImagingConfig, optional
    config : AutoCalibrationConfig, optional
    keypoints : Keypoints, optional
        2D keypoints of the frame (:mod:`mocap.io.keypoints`, ``camera`` pixels): the fits also
        pull the model's joints onto them (shoulder width and place, head, arms).

    Returns
    -------
    PersonCalibration
        The calibration (at ``camera``), the colour classes learnt inside the fitted model's
        projected parts, and without a background the scene's colours
        (:class:`mocap.imaging.scene.SceneColours`, learnt outside a box around the person).

    Raises
    ------
    ValueError
        No face and no background, no person in the foreground, bad sizes.
    """
    from scipy import ndimage

    from mocap.imaging import ImagingConfig, learn_colour_model, prepare_frame, subtract_background
    from mocap.imaging import check_box
    from mocap.imaging.colour import clothes_box_of_face, skin_box_of_face
    from mocap.imaging.scene import SceneColours, person_box_of_face

    config = AutoCalibrationConfig() if config is None else config
    imaging = ImagingConfig() if imaging is None else imaging
    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[:2] != camera.shape:
        raise ValueError(f"frame of shape {frame.shape} does not match the camera ({camera.height}, {camera.width}, 3)")
    base = BodyDimensions()
    if height_m is not None:
        if not 1.0 <= height_m <= 2.5:
            raise ValueError(f"the person's height must be 1.0-2.5 metres, got {height_m}")
        base = base.scaled(height_m / DEFAULT_STATURE_M)
    scene = seed = None
    if face is None and background is None:
        raise ValueError("no face found and no background: cannot tell the person from the scene")
    if background is not None:
        foreground = subtract_background(frame, background, imaging)
    else:
        h, w = camera.shape
        clothes = check_box(clothes_box_of_face(face), (h, w), "clothes box under the face")
        seed = learn_colour_model(frame, None, skin_box_of_face(face), clothes, config=imaging)
        scene = SceneColours.learn(frame, person_box_of_face(face, (h, w)), ratio=SCENE_RATIO)
        foreground = prepare_frame(frame, None, seed, imaging, scene=scene).foreground
        # the person: connected parts touching the face or the box under it
        parts, _ = ndimage.label(foreground)
        near = np.zeros_like(foreground)
        near[face.row:clothes.row + clothes.height, clothes.col:clothes.col + clothes.width] = True
        near[face.slices] = True
        keep = np.unique(parts[near & foreground])
        foreground = np.isin(parts, keep[keep > 0])
    if np.count_nonzero(foreground) < 50:
        raise ValueError("no person in the calibration frame (the foreground is empty): cannot calibrate")
    depths = None
    if face is not None:
        z0 = camera.fx * base["head"].width * FACE_BOX_HEAD_WIDTHS / face.width
        depths = tuple(np.round(z0 * np.linspace(0.7, 1.4, 8), 3))
    calibration, colour = _fit_body(frame, foreground, camera, base, config, imaging, background=background,
                                    face=face, depths=depths, seed_colour=seed, keypoints=keypoints)
    return PersonCalibration(calibration, colour, scene, foreground)


@dataclass(frozen=True, eq=False)
class PersonCalibration:
    """What :func:`calibrate_person` found.

    Attributes
    ----------
    calibration : Calibration
    colour_model : mocap.imaging.ColourModel
    scene : mocap.imaging.scene.SceneColours or None
        The scene's colours (colour-only foreground), None with a background.
    foreground : ndarray of bool, shape (H, W)
        The person's pixels in the calibration frame.
    """

    calibration: Calibration
    colour_model: object
    scene: object
    foreground: np.ndarray
