"""Accuracy against ground truth (docs/design.md section 5).

Every function takes whole sequences (frames first) and returns a plain float (or a per-frame
array when asked). Joints are the upper-body joints of
:data:`~mocap.body.skeleton.JOINT_NAMES` in camera coordinates (metres); poses are the
23-parameter vectors (metres and radians). Results are in the units people read: millimetres,
degrees, pixels.

=====================  ===================================================================
function               definition
=====================  ===================================================================
:func:`mpjpe`          mean over frames and joints of the 3D joint distance, mm
:func:`root_relative_mpjpe`  the same with both skeletons moved to put their necks at the
                       origin (the usual protocol for monocular methods, which cannot
                       see absolute depth well), mm
:func:`pa_mpjpe`       the same after aligning each predicted frame to the true one by the
                       best similarity transform (rotation, translation, uniform scale)
:func:`joint_angle_error`  mean absolute difference of the 20 joint angles, degrees,
                       wrap-around aware (179 vs -179 degrees is 2 degrees apart)
:func:`reprojection_error` mean 2D distance between the projected joints, pixels
:func:`failure_rate`   fraction of frames whose MPJPE exceeds a threshold (100 mm)
:func:`acceleration_error`  "Accel" of the video-pose papers: mean over frames and joints of
                       the distance between the predicted and the true acceleration
                       a_t = x_{t+1} - 2 x_t + x_{t-1}, mm per frame squared (about the neck,
                       after Procrustes alignment of each frame, or as is)
:func:`pck_2d`         share of 2D joints within a fraction of the reference's shoulder
                       width of the reference (another tool's keypoints), in [0, 1]
:func:`summary`        all of the above as the ``metrics`` object of ``run.json``
=====================  ===================================================================
"""
from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial.transform import Rotation

from mocap.body.pose import ANGLE_NAMES, N_PARAMETERS, PARAMETER_INDEX
from mocap.body.skeleton import JOINT_NAMES
from mocap.render.camera import Camera

__all__ = ["ACCELERATION_ALIGNMENTS", "DEFAULT_FAILURE_MM", "ROOT_JOINT", "SUMMARY_KEYS", "acceleration_error",
           "centred_mpjpe", "failure_rate", "joint_angle_error", "mpjpe",
           "pa_mpjpe", "pck_2d", "reprojection_error", "root_relative_mpjpe", "summary"]

#: Frames whose MPJPE exceeds this many millimetres count as failures (docs/design.md section 5).
DEFAULT_FAILURE_MM: float = 100.0
#: Keys of :func:`summary`, in order (the ``metrics`` object of ``run.json`` without ``fps``).
SUMMARY_KEYS: tuple[str, ...] = ("mpjpe_mm", "root_relative_mpjpe_mm", "pa_mpjpe_mm", "angle_error_deg", "reprojection_px",
                                 "failure_rate")
#: Joint that root-relative errors are taken about (its row in the joint arrays).
ROOT_JOINT: str = "neck"
#: How :func:`acceleration_error` aligns each frame before differencing.
ACCELERATION_ALIGNMENTS: tuple[str, ...] = ("neck", "procrustes", "none")
_ANGLE_COLUMNS = np.array([PARAMETER_INDEX[name] for name in ANGLE_NAMES])
_ANGLE_COLUMNS.setflags(write=False)


def _joint_pair(pred, true, min_joints: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Validate two joint arrays of the same shape (N, J, 3)."""
    p = np.asarray(pred, dtype=np.float64)
    t = np.asarray(true, dtype=np.float64)
    if p.ndim != 3 or p.shape[2] != 3:
        raise ValueError(f"predicted joints must have shape (frames, joints, 3), got {p.shape}")
    if t.shape != p.shape:
        raise ValueError(f"predicted joints {p.shape} and true joints {t.shape} differ in shape")
    if p.shape[0] == 0:
        raise ValueError("joint arrays hold no frames")
    if p.shape[1] < min_joints:
        raise ValueError(f"need at least {min_joints} joints per frame, got {p.shape[1]}")
    if not (np.isfinite(p).all() and np.isfinite(t).all()):
        raise ValueError("joint positions must be finite (no NaN or infinity)")
    return p, t


def mpjpe(pred, true, *, per_frame: bool = False):
    """Mean per-joint position error.

    Parameters
    ----------
    pred, true : array_like, shape (N, J, 3), metres
        Predicted and true joint positions, same joint order.
    per_frame : bool
        Return the error of every frame instead of the mean over frames.

    Returns
    -------
    float, or ndarray of shape (N,) with ``per_frame``
        Millimetres.

    Raises
    ------
    ValueError
        On shapes that differ or are not (N, J, 3), no frames, or non-finite values.
    """
    p, t = _joint_pair(pred, true)
    err = np.linalg.norm(p - t, axis=2).mean(axis=1) * 1000.0
    return err if per_frame else float(err.mean())


def root_relative_mpjpe(pred, true, *, per_frame: bool = False):
    """Mean per-joint position error with both skeletons translated to put :data:`ROOT_JOINT` at 0.

    Parameters
    ----------
    pred, true : array_like, shape (N, J, 3), metres
        Joints in :data:`~mocap.body.skeleton.JOINT_NAMES` order (the root joint's row is
        looked up there).
    per_frame : bool
        Return the error of each frame instead of the mean.

    Returns
    -------
    float or ndarray of shape (N,), millimetres
        The root joint itself contributes 0 to the mean over the J joints.
    """
    p, t = _joint_pair(pred, true)
    if p.shape[1] != len(JOINT_NAMES):
        raise ValueError(f"root-relative errors need the {len(JOINT_NAMES)} named joints, got {p.shape[1]}")
    r = JOINT_NAMES.index(ROOT_JOINT)
    return mpjpe(p - p[:, r:r + 1], t - t[:, r:r + 1], per_frame=per_frame)


def centred_mpjpe(pred, true, *, per_frame: bool = False):
    """Mean per-joint position error with each skeleton moved to put the centroid of its joints
    at 0, and no rotation: a body turned around (its left arm where the right should be, as after
    a detector's left/right swap) keeps its full error here, where :func:`pa_mpjpe`'s rotation
    hides it.

    Parameters
    ----------
    pred, true : array_like, shape (N, J, 3), metres
        Any joints in the same order (e.g. the arms' alone).
    per_frame : bool
        Return the error of each frame instead of the mean.

    Returns
    -------
    float or ndarray of shape (N,), millimetres
    """
    p, t = _joint_pair(pred, true)
    return mpjpe(p - p.mean(axis=1, keepdims=True), t - t.mean(axis=1, keepdims=True), per_frame=per_frame)


def _procrustes_align(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``p`` (J, 3) moved by the similarity transform that best fits it to ``t`` (least squares).

    (:func:`scipy.spatial.procrustes` normalises both sets to unit size, which loses the
    millimetres; the rotation comes from scipy's Kabsch solver instead.)
    """
    pc, tc = p - p.mean(axis=0), t - t.mean(axis=0)
    norm = float(np.sum(pc * pc))
    if norm == 0.0:  # all predicted joints at one point: only the translation can be fitted
        return np.broadcast_to(t.mean(axis=0), p.shape).copy()
    with warnings.catch_warnings():
        # a degenerate (collinear) frame has no unique rotation; any optimal one will do
        warnings.simplefilter("ignore", UserWarning)
        rot, _ = Rotation.align_vectors(tc, pc)
    rotated = rot.apply(pc)
    scale = float(np.sum(rotated * tc)) / norm
    return scale * rotated + t.mean(axis=0)


def pa_mpjpe(pred, true, *, per_frame: bool = False):
    """MPJPE after Procrustes alignment of every predicted frame to the true one.

    Each frame of ``pred`` is rotated (a proper rotation, no reflection; Kabsch via
    :meth:`scipy.spatial.transform.Rotation.align_vectors`), uniformly scaled and translated to
    fit the true frame in the least-squares sense before the error is taken. The fit minimises
    the sum of *squared* distances, so when one limb is far off it may raise the *mean*
    distance: PA-MPJPE can then exceed MPJPE.

    Parameters
    ----------
    pred, true : array_like, shape (N, J, 3), metres
        J >= 3.
    per_frame : bool
        Return the error of every frame.

    Returns
    -------
    float, or ndarray of shape (N,) with ``per_frame``
        Millimetres.

    Raises
    ------
    ValueError
        As :func:`mpjpe`, or fewer than 3 joints.
    """
    p, t = _joint_pair(pred, true, min_joints=3)
    aligned = np.stack([_procrustes_align(p[i], t[i]) for i in range(p.shape[0])])
    return mpjpe(aligned, t, per_frame=per_frame)


def acceleration_error(pred, true, *, align: str = "neck", per_frame: bool = False):
    """Acceleration error ("Accel"): how much more (or less) the prediction shakes than the truth.

    With ``a_t = x_{t+1} - 2 x_t + x_{t-1}`` of each joint over consecutive frames, the mean over
    the frames ``1 .. N-2`` and the joints of ``|a_pred - a_true|``.

    Parameters
    ----------
    pred, true : array_like, shape (N, J, 3), metres
        Consecutive frames, N >= 3.
    align : str
        ``"neck"``: both skeletons moved to put :data:`ROOT_JOINT` at 0 first (J must be the
        named joints); ``"procrustes"``: each predicted frame aligned to the true one as in
        :func:`pa_mpjpe` (J >= 3; e.g. the arm joints alone); ``"none"``: as given.
    per_frame : bool
        Return the error of each inner frame (shape (N-2,)) instead of the mean.

    Returns
    -------
    float, or ndarray of shape (N-2,), millimetres per frame squared
    """
    if align not in ACCELERATION_ALIGNMENTS:
        raise ValueError(f"align must be one of {ACCELERATION_ALIGNMENTS}, got {align!r}")
    p, t = _joint_pair(pred, true, min_joints=3 if align == "procrustes" else 1)
    if p.shape[0] < 3:
        raise ValueError(f"the acceleration needs at least 3 frames, got {p.shape[0]}")
    if align == "neck":
        if p.shape[1] != len(JOINT_NAMES):
            raise ValueError(f"errors about the neck need the {len(JOINT_NAMES)} named joints, got {p.shape[1]}")
        r = JOINT_NAMES.index(ROOT_JOINT)
        p, t = p - p[:, r:r + 1], t - t[:, r:r + 1]
    elif align == "procrustes":
        p = np.stack([_procrustes_align(p[i], t[i]) for i in range(p.shape[0])])
    accel = lambda x: x[2:] - 2.0 * x[1:-1] + x[:-2]
    errors = 1e3 * np.linalg.norm(accel(p) - accel(t), axis=2).mean(axis=1)
    return errors if per_frame else float(errors.mean())


def _pose_pair(pred, true) -> tuple[np.ndarray, np.ndarray]:
    p = np.asarray(pred, dtype=np.float64)
    t = np.asarray(true, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != N_PARAMETERS:
        raise ValueError(f"predicted poses must have shape (frames, {N_PARAMETERS}), got {p.shape}")
    if t.shape != p.shape:
        raise ValueError(f"predicted poses {p.shape} and true poses {t.shape} differ in shape")
    if p.shape[0] == 0:
        raise ValueError("pose arrays hold no frames")
    if not (np.isfinite(p).all() and np.isfinite(t).all()):
        raise ValueError("poses must be finite (no NaN or infinity)")
    return p, t


def joint_angle_error(pred, true, *, per_frame: bool = False):
    """Mean absolute error of the 20 joint angles, wrap-around aware.

    The difference of two angles is taken on the circle (in [-180, 180) degrees), so a chest
    yaw of 179 degrees against -179 degrees is an error of 2 degrees.

    Parameters
    ----------
    pred, true : array_like, shape (N, 23)
        Pose vectors (metres, radians); the three root positions are ignored.
    per_frame : bool
        Return the mean over the 20 angles of every frame.

    Returns
    -------
    float, or ndarray of shape (N,) with ``per_frame``
        Degrees.

    Raises
    ------
    ValueError
        On shapes that differ or are not (N, 23), no frames, or non-finite values.
    """
    p, t = _pose_pair(pred, true)
    diff = p[:, _ANGLE_COLUMNS] - t[:, _ANGLE_COLUMNS]
    wrapped = (diff + np.pi) % (2.0 * np.pi) - np.pi
    err = np.rad2deg(np.abs(wrapped)).mean(axis=1)
    return err if per_frame else float(err.mean())


def reprojection_error(pred_joints, true_joints, camera: Camera, *, per_frame: bool = False):
    """Mean 2D distance between predicted and true joints projected by ``camera``.

    Parameters
    ----------
    pred_joints, true_joints : array_like, shape (N, J, 3), metres
        Camera coordinates; every joint must lie in front of the camera (z > 0).
    camera : Camera
    per_frame : bool
        Return the error of every frame.

    Returns
    -------
    float, or ndarray of shape (N,) with ``per_frame``
        Pixels.

    Raises
    ------
    ValueError
        As :func:`mpjpe`, or a joint at or behind the camera.
    """
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a mocap.render.Camera, got {type(camera).__name__}")
    p, t = _joint_pair(pred_joints, true_joints)
    err = np.linalg.norm(camera.project(p) - camera.project(t), axis=2).mean(axis=1)
    return err if per_frame else float(err.mean())


def failure_rate(pred, true, threshold_mm: float = DEFAULT_FAILURE_MM) -> float:
    """Fraction of frames whose MPJPE exceeds ``threshold_mm``.

    Parameters
    ----------
    pred, true : array_like, shape (N, J, 3), metres
    threshold_mm : float
        Positive, millimetres; a frame fails when its MPJPE is strictly larger.

    Returns
    -------
    float
        In [0, 1].

    Raises
    ------
    ValueError
        As :func:`mpjpe`, or a threshold that is not a positive finite number.
    """
    if isinstance(threshold_mm, bool) or not isinstance(threshold_mm, (int, float, np.integer, np.floating)) \
            or not np.isfinite(threshold_mm) or threshold_mm <= 0:
        raise ValueError(f"failure threshold must be a positive number of millimetres, got {threshold_mm!r}")
    return float(np.mean(mpjpe(pred, true, per_frame=True) > threshold_mm))


def pck_2d(pred_uv, ref_uv, ref_shoulder_width, fraction: float = 0.5, *, per_frame: bool = False):
    """Percentage of correct 2D keypoints: share of joints within ``fraction`` of the
    reference's shoulder width (per frame) of the reference keypoints.

    Parameters
    ----------
    pred_uv, ref_uv : array_like, shape (N, J, 2), pixels
        Keypoints of the same joints in the same images. Joint-frames where either is NaN
        (not detected) are left out.
    ref_shoulder_width : array_like, shape (N,), pixels
        The reference's shoulder width in every frame (positive; NaN leaves the frame out).
    fraction : float
        Threshold in shoulder widths (0.5: half a shoulder width).
    per_frame : bool
        Return every frame's share (NaN for a frame with no joint left).

    Returns
    -------
    float in [0, 1], or ndarray of shape (N,) with ``per_frame``

    Raises
    ------
    ValueError
        On shapes that differ, a non-positive fraction, or no joint-frame to count.
    """
    p = np.asarray(pred_uv, dtype=np.float64)
    r = np.asarray(ref_uv, dtype=np.float64)
    w = np.asarray(ref_shoulder_width, dtype=np.float64)
    if p.ndim != 3 or p.shape[2] != 2 or p.shape != r.shape:
        raise ValueError(f"keypoints must both have shape (N, J, 2), got {p.shape} and {r.shape}")
    if w.shape != (p.shape[0],):
        raise ValueError(f"shoulder widths must have shape ({p.shape[0]},), got {w.shape}")
    if not fraction > 0:
        raise ValueError(f"fraction must be positive, got {fraction}")
    distance = np.linalg.norm(p - r, axis=2)
    valid = np.isfinite(distance) & np.isfinite(w)[:, None] & (w > 0)[:, None]
    with np.errstate(invalid="ignore"):
        hit = valid & (distance <= fraction * w[:, None])
    if per_frame:
        counts = valid.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(counts > 0, hit.sum(axis=1) / np.maximum(counts, 1), np.nan)
    if not valid.any():
        raise ValueError("no joint-frame has both keypoints and a shoulder width")
    return float(hit.sum() / valid.sum())


def summary(pred_poses, true_poses, pred_joints, true_joints, camera: Camera, *,
            threshold_mm: float = DEFAULT_FAILURE_MM) -> dict[str, float]:
    """All ground-truth metrics of a run, as ``run.json`` stores them.

    Parameters
    ----------
    pred_poses, true_poses : array_like, shape (N, 23)
        Metres and radians.
    pred_joints, true_joints : array_like, shape (N, J, 3), metres
        Camera coordinates.
    camera : Camera
    threshold_mm : float
        Failure threshold of :func:`failure_rate`.

    Returns
    -------
    dict
        Exactly the keys of :data:`SUMMARY_KEYS`: ``mpjpe_mm``, ``root_relative_mpjpe_mm``, ``pa_mpjpe_mm``,
        ``angle_error_deg``, ``reprojection_px``, ``failure_rate`` (plain floats).

    Raises
    ------
    ValueError
        On bad input to any metric, or pose and joint arrays with different frame counts.
    """
    n_pose = np.shape(pred_poses)[0] if np.ndim(pred_poses) else 0
    n_joint = np.shape(pred_joints)[0] if np.ndim(pred_joints) else 0
    if n_pose != n_joint:
        raise ValueError(f"poses cover {n_pose} frames but joints cover {n_joint}")
    return {
        "mpjpe_mm": mpjpe(pred_joints, true_joints),
        "root_relative_mpjpe_mm": root_relative_mpjpe(pred_joints, true_joints),
        "pa_mpjpe_mm": pa_mpjpe(pred_joints, true_joints),
        "angle_error_deg": joint_angle_error(pred_poses, true_poses),
        "reprojection_px": reprojection_error(pred_joints, true_joints, camera),
        "failure_rate": failure_rate(pred_joints, true_joints, threshold_mm),
    }
