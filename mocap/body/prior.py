"""A learned prior over body postures: a Gaussian mixture over the torso, head and arm angles.

The density is fitted by ``python -m experiments.fit_pose_prior`` (scikit-learn's
:class:`~sklearn.mixture.GaussianMixture`) on the CMU motion capture trials of
``../shared/data/mocap/train/`` retargeted onto the 23-parameter model, and shipped with the
package as ``mocap/body/pose_prior.json`` (weights, means and the Cholesky factors of the
precisions, with the data's attribution and a checksum of the parameters), so the toolkit
works without the training data. The synthetic benchmark's own motion is never used for it.

Only the posture enters the density: the root position and the chest's heading (``chest_yaw``,
where the actor faces) are free, every other angle is in :data:`PRIOR_PARAMETERS`. The
negative log-density of one pose is a compiled kernel (a few microseconds); the tracker adds it
to the score of its hypotheses, never to the registration costs themselves.

Conventions are scikit-learn's ``covariance_type="full"``: ``precisions_cholesky[k]`` is the
upper-triangular ``U`` with ``precision = U @ U.T``, so that
``log N(x | mean, cov) = -d/2 log(2 pi) + sum(log diag U) - |(x - mean) @ U|^2 / 2``.
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from mocap._numba import jit
from mocap.body.pose import N_PARAMETERS, PARAMETER_INDEX, PARAMETER_NAMES

#: Parameters the prior is a density over (radians), in the order of its dimensions: every
#: angle but the chest's heading.
PRIOR_PARAMETERS: tuple[str, ...] = tuple(n for n in PARAMETER_NAMES[3:] if n != "chest_yaw")
#: Rows of :data:`PRIOR_PARAMETERS` in the pose vector.
PRIOR_INDEX: np.ndarray = np.array([PARAMETER_INDEX[n] for n in PRIOR_PARAMETERS], dtype=np.int64)
PRIOR_INDEX.setflags(write=False)
#: File name of the shipped prior inside the package.
PRIOR_FILE = "pose_prior.json"
#: Format tag of the file.
PRIOR_FORMAT = "mocap-pose-prior-1"


def parameter_checksum(weights, means, precisions_cholesky, parameter_names) -> str:
    """SHA-256 of the mixture's parameters, rounded to 12 significant digits (hex string).

    The same numbers give the same checksum whatever JSON formatting carried them.
    """
    payload = json.dumps({"weights": [float(f"{v:.12g}") for v in np.ravel(weights)],
                          "means": [float(f"{v:.12g}") for v in np.ravel(means)],
                          "precisions_cholesky": [float(f"{v:.12g}") for v in np.ravel(precisions_cholesky)],
                          "parameters": list(parameter_names)}, sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()


@dataclass(frozen=True)
class PosePrior:
    """Gaussian mixture density over :data:`PRIOR_PARAMETERS` (radians).

    Attributes
    ----------
    weights : ndarray, shape (k,), float64
        Mixture weights, summing to 1.
    means : ndarray, shape (k, d), float64, radians
    precisions_cholesky : ndarray, shape (k, d, d), float64, 1/radians
        Upper-triangular ``U`` per component, ``precision = U @ U.T`` (scikit-learn's layout).
    attribution : str
        Where the training data came from (the data's licence asks for it).
    """

    weights: np.ndarray
    means: np.ndarray
    precisions_cholesky: np.ndarray
    attribution: str = ""

    def __post_init__(self) -> None:
        w, m, u = (np.ascontiguousarray(a, dtype=np.float64) for a in
                   (self.weights, self.means, self.precisions_cholesky))
        d = len(PRIOR_PARAMETERS)
        k = w.shape[0] if w.ndim == 1 else -1
        if w.ndim != 1 or m.shape != (k, d) or u.shape != (k, d, d):
            raise ValueError(f"a pose prior needs weights (k,), means (k, {d}) and precisions_cholesky "
                             f"(k, {d}, {d}); got {w.shape}, {m.shape}, {u.shape}")
        if not (np.isfinite(w).all() and np.isfinite(m).all() and np.isfinite(u).all()):
            raise ValueError("pose prior parameters must be finite")
        if (w <= 0).any() or abs(w.sum() - 1.0) > 1e-6:
            raise ValueError(f"mixture weights must be positive and sum to 1, got sum {w.sum()}")
        diag = np.diagonal(u, axis1=1, axis2=2)
        if (diag <= 0).any() or np.abs(np.tril(u, -1)).max() > 0:
            raise ValueError("precisions_cholesky must be upper-triangular with a positive diagonal")
        for name, value in (("weights", w), ("means", m), ("precisions_cholesky", u)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        log_norm = np.log(w) + np.log(diag).sum(axis=1) - 0.5 * d * math.log(2.0 * math.pi)
        log_norm.setflags(write=False)
        object.__setattr__(self, "_log_norm", log_norm)

    @property
    def n_components(self) -> int:
        return int(self.weights.shape[0])

    @property
    def checksum(self) -> str:
        """:func:`parameter_checksum` of this mixture."""
        return parameter_checksum(self.weights, self.means, self.precisions_cholesky, PRIOR_PARAMETERS)

    def log_density(self, poses) -> np.ndarray:
        """Log-density of poses (NumPy, vectorised; the reference for the compiled kernel).

        Parameters
        ----------
        poses : array_like, shape (n, 23) or (23,)
            Full pose vectors (metres, radians); only :data:`PRIOR_PARAMETERS` are read.

        Returns
        -------
        ndarray, shape (n,) (or float for one pose), log of 1/radians**d
        """
        q = np.asarray(poses, dtype=np.float64)
        single = q.ndim == 1
        q = np.atleast_2d(q)
        if q.shape[1] != N_PARAMETERS:
            raise ValueError(f"poses must have {N_PARAMETERS} columns, got shape {np.shape(poses)}")
        x = q[:, PRIOR_INDEX]
        y = np.einsum("nkd,kde->nke", x[:, None, :] - self.means[None], self.precisions_cholesky)
        log = self._log_norm[None] - 0.5 * (y ** 2).sum(axis=2)
        top = log.max(axis=1)
        out = top + np.log(np.exp(log - top[:, None]).sum(axis=1))
        return float(out[0]) if single else out

    def energy(self, pose) -> float:
        """Negative log-density of one pose (compiled; what the tracker adds to its score).

        Parameters
        ----------
        pose : ndarray, shape (23,), float64
            Metres and radians.
        """
        q = np.ascontiguousarray(pose, dtype=np.float64)
        if q.shape != (N_PARAMETERS,):
            raise ValueError(f"pose must have shape ({N_PARAMETERS},), got {q.shape}")
        return -_log_density(q, PRIOR_INDEX, self._log_norm, self.means, self.precisions_cholesky)

    def to_dict(self, **provenance) -> dict:
        """JSON-ready form (``provenance`` entries are stored beside the parameters)."""
        return {"format": PRIOR_FORMAT, "parameters": list(PRIOR_PARAMETERS), "units": "radians",
                "attribution": self.attribution, **provenance,
                "weights": self.weights.tolist(), "means": self.means.tolist(),
                "precisions_cholesky": self.precisions_cholesky.tolist(), "sha256": self.checksum}

    @classmethod
    def from_dict(cls, data: dict) -> "PosePrior":
        """Read :meth:`to_dict`'s form; the parameter names and the checksum must match."""
        if not isinstance(data, dict) or data.get("format") != PRIOR_FORMAT:
            raise ValueError(f"not a pose prior file (format {PRIOR_FORMAT!r} expected)")
        if tuple(data.get("parameters", ())) != PRIOR_PARAMETERS:
            raise ValueError("the pose prior's parameters are not this model's: refit it "
                             "(python -m experiments.fit_pose_prior)")
        prior = cls(np.array(data["weights"]), np.array(data["means"]), np.array(data["precisions_cholesky"]),
                    str(data.get("attribution", "")))
        if prior.checksum != data.get("sha256"):
            raise ValueError("pose prior file is damaged: its checksum does not match its parameters")
        return prior

    @classmethod
    def from_json(cls, path: str | Path) -> "PosePrior":
        """Read a prior file (FileNotFoundError, ValueError)."""
        return cls.from_dict(json.loads(Path(path).read_text()))


def default_prior() -> PosePrior:
    """The prior shipped with the package (fitted on CMU motion capture; see the module)."""
    text = resources.files("mocap.body").joinpath(PRIOR_FILE).read_text()
    return PosePrior.from_dict(json.loads(text))


@jit
def _log_density(pose, index, log_norm, means, prec_chol):
    k, d = means.shape
    best = -np.inf
    logs = np.empty(k)
    for c in range(k):
        s = 0.0
        for j in range(d):              # y_j = sum_i (x_i - mean_i) U_ij, U upper-triangular
            y = 0.0
            for i in range(j + 1):
                y += (pose[index[i]] - means[c, i]) * prec_chol[c, i, j]
            s += y * y
        logs[c] = log_norm[c] - 0.5 * s
        if logs[c] > best:
            best = logs[c]
    total = 0.0
    for c in range(k):
        total += math.exp(logs[c] - best)
    return best + math.log(total)
