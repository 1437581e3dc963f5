"""The learned 2D->3D lifter: a frame's 2D keypoints to K whole-body pose hypotheses.

A multilayer perceptron (ReLU hidden layers) maps the frame's visible 2D joints
(:data:`~mocap.body.skeleton.JOINT_NAMES`, working-camera pixels) to K = 10 hypotheses of the
20 joint angles and chest heading, each with a probability. The angles come out inside the
joint limits by construction (a sigmoid between each angle's bounds,
:data:`~mocap.body.pose.JOINT_LIMITS`; the chest heading as a direction, atan2 of two outputs),
the calibrated body model's forward kinematics gives each hypothesis's joints, and its root
(chest base) is placed in camera coordinates by the translation whose projection best fits the
visible keypoints (:func:`fit_roots`: linear least squares in the three root coordinates, then
Gauss-Newton on the pixel error; the depth follows from the calibrated body's size and the
keypoints' scale).

Input normalisation (:func:`lifter_features`): pixels become image-plane coordinates
``((u - cx) / fx, (v - cy) / fy)``; the visible joints are centred on their mean and divided by
their RMS distance from it; missing joints are zero and flagged by a mask. The features are the
20 normalised coordinates, the 10 mask values and the 2 image-plane coordinates of the centre
(the viewing direction): 32 numbers.

The forward pass is NumPy (float32 weights, no PyTorch at run time). The weights were trained by
``python -m experiments.fit_lifter`` with PyTorch on the CPU, on trials of the CMU Graphics Lab
Motion Capture Database (attribution in the file's metadata, :attr:`Lifter.attribution`), with
keypoint noise measured from MediaPipe Pose on the toolkit's synthetic frames.

File: ``mocap/track/lifter.npz`` (float16 weight arrays; a ``meta`` JSON with the format tag, the
architecture, the parameter layout, the attribution, the training's provenance and the SHA-256
of the arrays, checked at load).
"""
from __future__ import annotations

import functools
import hashlib
import io
import json
import zipfile
import zlib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from mocap.body.kinematics import apply_transforms_into, segment_transforms_into
from mocap.body.model import BodyModel
from mocap.body.pose import JOINT_LIMITS, N_PARAMETERS, PARAMETER_INDEX, PARAMETER_NAMES, within_limits
from mocap.body.skeleton import JOINT_INDEX, JOINT_NAMES
from mocap.render.camera import Camera

__all__ = ["BOUNDED_ANGLES", "DENSITY_SIGMA_M", "LIFTER_FILE", "LIFTER_FORMAT", "MIN_VISIBLE", "N_FEATURES",
           "LiftedHypotheses", "Lifter", "fit_roots", "lifter_checksum", "lifter_features", "relative_joints"]

#: File name of the shipped weights inside the package.
LIFTER_FILE = "lifter.npz"
#: Format tag of the file.
LIFTER_FORMAT = "mocap-lifter-1"
#: Joint angles predicted through a sigmoid between their limits, in output order (every angle
#: but the chest's heading, which comes out as a direction).
BOUNDED_ANGLES: tuple[str, ...] = tuple(n for n in PARAMETER_NAMES[3:] if n != "chest_yaw")
#: Outputs per hypothesis: a confidence logit, cos and sin of the heading, the bounded angles.
OUTPUTS_PER_HYPOTHESIS = 3 + len(BOUNDED_ANGLES)
#: Input features: 20 normalised coordinates, 10 mask values, the centre's 2 image-plane coordinates.
N_FEATURES = 3 * len(JOINT_NAMES) + 2
#: Fewest visible joints the lifter accepts (fewer give no scale to normalise by).
MIN_VISIBLE = 3
#: Standard deviation (metres, per coordinate) of the isotropic Gaussians of :meth:`Lifter.log_density`:
#: about the lifter's best-of-ten error, so that the truth is rarely far out in the tails. Chosen in
#: the tracker's score (issue 29; oracle keypoints, seed 0, gestures-2 / gestures-1, a 512x3
#: candidate model, lifter_weight 0.5): 0.06 m gave 169 / 100 mm, 0.12 m 103 / 107 mm.
DENSITY_SIGMA_M = 0.12
#: Gauss-Newton steps refining each hypothesis's root on the pixel reprojection error.
ROOT_REFINE_STEPS = 3
#: Joint about which hypotheses' joints are given (the metrics' root joint, :data:`mocap.metrics.ROOT_JOINT`).
RELATIVE_TO = "neck"

_NECK = JOINT_INDEX[RELATIVE_TO]
_BOUNDED_INDEX = np.array([PARAMETER_INDEX[n] for n in BOUNDED_ANGLES])
_YAW = PARAMETER_INDEX["chest_yaw"]
_ROOT = np.array([PARAMETER_INDEX[n] for n in ("root_x", "root_y", "root_z")])


def lifter_checksum(arrays: list[np.ndarray]) -> str:
    """SHA-256 (hex) of the weight arrays as stored: index, dtype, shape and bytes of each in turn.

    Parameters
    ----------
    arrays : list of ndarray
        ``W0, b0, W1, b1, ...`` in layer order (as stored: float16).
    """
    h = hashlib.sha256()
    for i, a in enumerate(arrays):
        a = np.ascontiguousarray(a)
        h.update(f"{i}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def relative_joints(joints) -> np.ndarray:
    """Joints about the neck (:data:`RELATIVE_TO`), as the lifter's hypotheses and density use them.

    Parameters
    ----------
    joints : array_like, shape (..., 10, 3), metres
        Camera coordinates, :data:`~mocap.body.skeleton.JOINT_NAMES` order.

    Returns
    -------
    ndarray, shape (..., 10, 3), float64, metres
        The neck's row is zero.
    """
    j = np.asarray(joints, dtype=np.float64)
    return j - j[..., _NECK:_NECK + 1, :]


def lifter_features(keypoints_uv, visible, camera: Camera) -> np.ndarray:
    """The network's input for one frame (see the module docstring).

    Parameters
    ----------
    keypoints_uv : array_like, shape (10, 2), float, pixels
        Working-camera pixels, :data:`~mocap.body.skeleton.JOINT_NAMES` order (missing joints:
        any value, NaN included).
    visible : array_like of bool, shape (10,)
        Which joints are present; at least :data:`MIN_VISIBLE`.
    camera : Camera
        The working camera (its intrinsics).

    Returns
    -------
    ndarray of float32, shape (32,)

    Raises
    ------
    ValueError
        On a wrong shape, fewer than :data:`MIN_VISIBLE` visible joints, a non-finite visible
        keypoint or visible joints all at one point.
    """
    uv = np.asarray(keypoints_uv, dtype=np.float64)
    mask = np.asarray(visible)
    if uv.shape != (len(JOINT_NAMES), 2):
        raise ValueError(f"keypoints_uv must have shape ({len(JOINT_NAMES)}, 2), got {uv.shape}")
    if mask.shape != (len(JOINT_NAMES),) or mask.dtype != bool:
        raise ValueError(f"visible must be a bool array of shape ({len(JOINT_NAMES)},), got {mask.dtype} {mask.shape}")
    if mask.sum() < MIN_VISIBLE:
        raise ValueError(f"the lifter needs at least {MIN_VISIBLE} visible keypoints, got {int(mask.sum())}")
    if not np.isfinite(uv[mask]).all():
        raise ValueError("visible keypoints must be finite")
    xy = np.column_stack([(uv[:, 0] - camera.cx) / camera.fx, (uv[:, 1] - camera.cy) / camera.fy])
    centre = xy[mask].mean(axis=0)
    scale = np.sqrt(np.mean(np.sum((xy[mask] - centre) ** 2, axis=1)))
    if not scale > 0:
        raise ValueError("the visible keypoints all lie at one point")
    rel = np.where(mask[:, None], (xy - centre) / scale, 0.0)
    return np.concatenate([rel.ravel(), mask.astype(np.float64), centre]).astype(np.float32)


@dataclass(frozen=True)
class LiftedHypotheses:
    """The lifter's hypotheses for one frame, most probable first.

    Attributes
    ----------
    poses : ndarray, shape (K, 23), float64
        Full poses (metres and radians), inside :data:`~mocap.body.pose.JOINT_LIMITS`, the root
        placed in camera coordinates (fitted to the visible keypoints).
    probabilities : ndarray, shape (K,), float64
        The lifter's confidence in each, summing to 1, non-increasing.
    joints : ndarray, shape (K, 10, 3), float64, metres
        Each pose's joints about the neck (:func:`relative_joints`) with the calibrated body.
    """

    poses: np.ndarray
    probabilities: np.ndarray
    joints: np.ndarray

    def __len__(self) -> int:
        return len(self.poses)

    @functools.cached_property
    def top_log_density(self) -> float:
        """:meth:`Lifter.log_density` at the most probable hypothesis's own joints, computed
        once (every candidate's lifter energy is measured from it)."""
        return _log_density(self, self.joints[0])


def _log_density(lifted: LiftedHypotheses, x: np.ndarray) -> float:
    """:meth:`Lifter.log_density` without its check of ``x`` (a float64 (10, 3) array)."""
    d2 = np.sum((lifted.joints - x) ** 2, axis=(1, 2))
    dims = 3 * (len(JOINT_NAMES) - 1)
    s2 = DENSITY_SIGMA_M ** 2
    terms = np.log(np.maximum(lifted.probabilities, 1e-300)) - 0.5 * d2 / s2
    top = terms.max()
    return float(top + np.log(np.exp(terms - top).sum()) - 0.5 * dims * np.log(2.0 * np.pi * s2))


@dataclass(frozen=True, eq=False)
class Lifter:
    """The multilayer perceptron's weights and what was recorded with them.

    Attributes
    ----------
    weights : tuple of ndarray of float32
        ``W_i`` of shape (n_in, n_out) and ``b_i`` of shape (n_out,), alternating, layer order;
        the first takes :data:`N_FEATURES` inputs, the last gives K * :data:`OUTPUTS_PER_HYPOTHESIS`.
    checksum : str
        :func:`lifter_checksum` of the weights as stored.
    attribution : str
        The training data's attribution (CMU).
    provenance : dict
        What the training recorded (command, seed, wall time, noise model, ...).
    """

    weights: tuple
    checksum: str = ""
    attribution: str = ""
    provenance: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        ws = self.weights
        if len(ws) < 2 or len(ws) % 2:
            raise ValueError("lifter weights come in (W, b) pairs")
        n_in = N_FEATURES
        for i in range(0, len(ws), 2):
            w, b = ws[i], ws[i + 1]
            if w.ndim != 2 or w.shape[0] != n_in or b.shape != (w.shape[1],):
                raise ValueError(f"lifter layer {i // 2} has shapes {w.shape}, {b.shape}; expected ({n_in}, n), (n,)")
            if not (np.isfinite(w).all() and np.isfinite(b).all()):
                raise ValueError(f"lifter layer {i // 2} has non-finite weights")
            n_in = w.shape[1]
        if n_in % OUTPUTS_PER_HYPOTHESIS:
            raise ValueError(f"lifter output size {n_in} is not a multiple of {OUTPUTS_PER_HYPOTHESIS}")

    @property
    def n_hypotheses(self) -> int:
        """K, the hypotheses per frame."""
        return self.weights[-1].shape[0] // OUTPUTS_PER_HYPOTHESIS

    # -- the network ---------------------------------------------------------------------------
    def forward(self, features) -> np.ndarray:
        """Raw network outputs (float32), the twin of the training's PyTorch module.

        Parameters
        ----------
        features : array_like, shape (n, 32) or (32,)
            :func:`lifter_features`.

        Returns
        -------
        ndarray of float32, shape (n, K * 22) or (K * 22,)
        """
        h = np.asarray(features, dtype=np.float32)
        ws = self.weights
        for i in range(0, len(ws) - 2, 2):
            h = h @ ws[i] + ws[i + 1]
            np.maximum(h, 0.0, out=h)
        return h @ ws[-2] + ws[-1]

    def decode(self, outputs) -> tuple[np.ndarray, np.ndarray]:
        """Network outputs to hypotheses' angles and probabilities (unsorted).

        Parameters
        ----------
        outputs : array_like, shape (K * 22,)

        Returns
        -------
        poses : ndarray, shape (K, 23), float64
            Root at zero, angles in radians inside the limits.
        probabilities : ndarray, shape (K,), float64
        """
        out = np.asarray(outputs, dtype=np.float64).reshape(self.n_hypotheses, OUTPUTS_PER_HYPOTHESIS)
        logits = out[:, 0]
        p = np.exp(logits - logits.max())
        p /= p.sum()
        poses = np.zeros((len(out), N_PARAMETERS))
        poses[:, _YAW] = np.arctan2(out[:, 2], out[:, 1])
        lo, hi = JOINT_LIMITS[_BOUNDED_INDEX, 0], JOINT_LIMITS[_BOUNDED_INDEX, 1]
        poses[:, _BOUNDED_INDEX] = lo + (hi - lo) / (1.0 + np.exp(-out[:, 3:]))
        return poses, p

    # -- the public calls ----------------------------------------------------------------------
    def lift(self, keypoints_uv, visible, camera: Camera, model: BodyModel) -> LiftedHypotheses:
        """K whole-body hypotheses for a frame's keypoints.

        Parameters
        ----------
        keypoints_uv : array_like, shape (10, 2), float, pixels
            Working-camera pixels in :data:`~mocap.body.skeleton.JOINT_NAMES` order.
        visible : array_like of bool, shape (10,)
            Present joints (at least :data:`MIN_VISIBLE`); the others are ignored.
        camera : Camera
            The working camera.
        model : BodyModel
            The calibrated body: its forward kinematics gives the joints, its size the depth.

        Returns
        -------
        LiftedHypotheses
            Most probable first.

        Raises
        ------
        ValueError
            See :func:`lifter_features`.
        """
        features = lifter_features(keypoints_uv, visible, camera)
        poses, p = self.decode(self.forward(features))
        order = np.argsort(-p, kind="stable")
        poses, p = poses[order], p[order]
        uv = np.asarray(keypoints_uv, dtype=np.float64)
        mask = np.asarray(visible)
        sk = model.skeleton
        transforms = np.empty((8, 3, 4))
        joints = np.empty((len(poses), len(JOINT_NAMES), 3))
        for k, q in enumerate(poses):
            segment_transforms_into(q, sk.offsets, transforms)
            apply_transforms_into(transforms, sk.joint_segment, sk.joint_local, joints[k])
        poses[:, _ROOT] = fit_roots(joints[:, mask], uv[mask], camera)
        poses = np.clip(poses, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
        if not all(within_limits(q) for q in poses):       # cannot happen: decode bounds every angle
            raise RuntimeError("lifter produced a pose outside the joint limits")
        return LiftedHypotheses(poses, p, relative_joints(joints))

    def log_density(self, lifted: LiftedHypotheses, joints_rel) -> float:
        """The lifter's log density at a candidate pose's joints.

        A mixture over the hypotheses, weighted by their probabilities, of isotropic Gaussians
        (:data:`DENSITY_SIGMA_M` per coordinate) around their joints about the neck, over the nine
        joints other than the neck (27 dimensions; the neck is zero in both).

        Parameters
        ----------
        lifted : LiftedHypotheses
            :meth:`lift` of the frame.
        joints_rel : array_like, shape (10, 3), metres
            The candidate's joints about the neck (:func:`relative_joints` of its joints with
            the same body model).

        Returns
        -------
        float
            Natural log of the density (per cubic metre to the 9th); larger is more likely.
        """
        x = np.asarray(joints_rel, dtype=np.float64)
        if x.shape != (len(JOINT_NAMES), 3):
            raise ValueError(f"joints_rel must have shape ({len(JOINT_NAMES)}, 3), got {x.shape}")
        return _log_density(lifted, x)

    # -- the file ------------------------------------------------------------------------------
    def save(self, path: str | Path) -> str:
        """Write the weights (float16, compressed ``.npz``, atomically) and the metadata; returns
        the checksum of the stored arrays."""
        from mocap.io.files import write_bytes_atomic

        stored = [np.asarray(a, dtype=np.float16) for a in self.weights]
        checksum = lifter_checksum(stored)
        meta = {"format": LIFTER_FORMAT, "attribution": self.attribution, "provenance": self.provenance,
                "n_layers": len(stored) // 2, "bounded_angles": list(BOUNDED_ANGLES),
                "joint_names": list(JOINT_NAMES), "sha256": checksum}
        buffer = io.BytesIO()
        np.savez_compressed(buffer, meta=np.array(json.dumps(meta, sort_keys=True)),
                            **{f"a{i}": a for i, a in enumerate(stored)})
        write_bytes_atomic(Path(path), buffer.getvalue())
        return checksum

    @classmethod
    def load(cls, path: str | Path | None = None) -> "Lifter":
        """Read a lifter file; None: the one shipped with the package.

        Raises
        ------
        ValueError
            If it is not a lifter file, or it is damaged (its checksum does not match its arrays).
        FileNotFoundError
            If ``path`` does not exist.
        """
        if path is None:
            with resources.files("mocap.track").joinpath(LIFTER_FILE).open("rb") as f:
                source = io.BytesIO(f.read())
            name = f"the shipped {LIFTER_FILE}"
        else:
            source, name = Path(path), str(path)
            if not source.is_file():
                raise FileNotFoundError(f"no lifter file {path}")
        redo = "rebuild it with python -m experiments.fit_lifter"
        try:
            with np.load(source, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                stored = [z[f"a{i}"] for i in range(2 * int(meta["n_layers"]))]
        except (OSError, KeyError, ValueError, TypeError, EOFError, zipfile.BadZipFile, zlib.error) as error:
            raise ValueError(f"{name} is not a readable lifter file ({type(error).__name__}): {redo}") from None
        if not isinstance(meta, dict) or meta.get("format") != LIFTER_FORMAT:
            raise ValueError(f"{name} is not a lifter file (format {LIFTER_FORMAT!r} expected): {redo}")
        checksum = lifter_checksum(stored)
        if checksum != meta.get("sha256"):
            raise ValueError(f"{name} is damaged: its checksum does not match its weights; {redo}")
        if tuple(meta.get("bounded_angles", ())) != BOUNDED_ANGLES or tuple(meta.get("joint_names", ())) != JOINT_NAMES:
            raise ValueError(f"{name} was trained for another parameter or joint layout: {redo}")
        return cls(tuple(np.asarray(a, dtype=np.float32) for a in stored), checksum,
                   str(meta.get("attribution", "")), dict(meta.get("provenance", {})))


def fit_roots(joints, keypoints_uv, camera: Camera) -> np.ndarray:
    """Root translations that put posed joints on their keypoints.

    Linear least squares of ``fx (X + tx) = (u - cx)(Z + tz)`` and the same for y (the
    projection's algebraic error), then :data:`ROOT_REFINE_STEPS` Gauss-Newton steps on the
    reprojection error in pixels, all K at once; kept inside the root's limits.

    Parameters
    ----------
    joints : array_like, shape (K, n, 3), metres
        Each pose's n joints with its root at zero (camera axes).
    keypoints_uv : array_like, shape (n, 2), pixels
        Where those joints are seen (finite; n >= 2, not all at one point).
    camera : Camera

    Returns
    -------
    ndarray, shape (K, 3), float64, metres
        The root (``root_x, root_y, root_z``) of each pose.
    """
    joints = np.asarray(joints, dtype=np.float64)
    uv = np.asarray(keypoints_uv, dtype=np.float64)
    k, n = joints.shape[:2]
    du, dv = uv[:, 0] - camera.cx, uv[:, 1] - camera.cy
    a = np.zeros((2 * n, 3))
    a[0::2, 0], a[0::2, 2] = camera.fx, -du
    a[1::2, 1], a[1::2, 2] = camera.fy, -dv
    b = np.empty((k, 2 * n))
    b[:, 0::2] = du * joints[..., 2] - camera.fx * joints[..., 0]
    b[:, 1::2] = dv * joints[..., 2] - camera.fy * joints[..., 1]
    t = np.linalg.lstsq(a, b.T, rcond=None)[0].T                 # one matrix for all K
    for _ in range(ROOT_REFINE_STEPS):                            # Gauss-Newton on the pixel error
        p = joints + t[:, None, :]
        if (p[..., 2] < 0.05).any():
            break
        inv = 1.0 / p[..., 2]
        jac = np.zeros((k, 2 * n, 3))
        jac[:, 0::2, 0], jac[:, 0::2, 2] = camera.fx * inv, -camera.fx * p[..., 0] * inv ** 2
        jac[:, 1::2, 1], jac[:, 1::2, 2] = camera.fy * inv, -camera.fy * p[..., 1] * inv ** 2
        res = np.empty((k, 2 * n))
        res[:, 0::2] = camera.fx * p[..., 0] * inv + camera.cx - uv[:, 0]
        res[:, 1::2] = camera.fy * p[..., 1] * inv + camera.cy - uv[:, 1]
        jt = jac.transpose(0, 2, 1)
        try:
            t = t - np.linalg.solve(jt @ jac, (jt @ res[..., None]))[..., 0]
        except np.linalg.LinAlgError:
            break
    return np.clip(t, JOINT_LIMITS[_ROOT, 0], JOINT_LIMITS[_ROOT, 1])
