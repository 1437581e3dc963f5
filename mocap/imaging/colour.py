"""Colour model: one Gaussian per colour class in HSV, hue treated as a circular quantity.

A pixel's HSV colour is ``(h, s, v)`` with hue ``h`` in degrees [0, 360) and saturation
``s``, value ``v`` in [0, 1] (the convention of :func:`skimage.color.rgb2hsv`, hue times
360). The hue deviation from a class mean is wrapped to [-180, 180) degrees, so reds near 0
and near 360 degrees are neighbours. Classes are learned from the first frame: skin from the
face found by scikit-image's LBP frontal-face cascade (the paper's Adaboost detector), clothes
from a box under the face, hair from a box above it (foreground pixels only); or from boxes
the user gives.

Optional classes (:data:`mocap.labels.CLASS_MERGES_INTO`: hair, lower body) are kept only when
the image supports them: a sample that is too small, or whose colour lies in the core of the
class it merges into (a bald head is skin, trousers the colour of the shirt are clothes), drops
the class (:meth:`ColourModel.from_samples` with ``merges``).
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from scipy import special
from skimage import color, data, feature, transform

from mocap._numba import jit
from mocap.imaging._validate import Box, check_box, check_mask, check_rgb, check_same_size
from mocap.imaging.config import DEFAULT_COLOUR_THRESHOLD, ImagingConfig
from mocap.io.files import read_json, write_json
from mocap.labels import CLASS_MERGES_INTO, MAX_CLASSES, UNKNOWN

__all__ = ["ColourModel", "learn_colour_model", "detect_face", "rgb_to_hsv", "skin_box_of_face",
           "clothes_box_of_face", "hair_box_of_face"]

#: Standard deviations added (in quadrature) to every learned class (hue degrees,
#: saturation, value): a uniform sample must still give an invertible covariance, and the
#: sample (a face, a patch of chest) is lit more evenly than the whole body, so value (the
#: brightness) gets the widest allowance.
MIN_STD: tuple[float, float, float] = (2.0, 0.02, 0.05)
#: A pixel is achromatic when its saturation is below ACHROMATIC_SATURATION or its chroma
#: ``s * v = max - min`` (RGB in [0, 1]) is below ACHROMATIC_CHROMA (dark pixels: there hue
#: and saturation are sensor noise). A class whose sample is mostly achromatic gets the hue
#: variance of a uniform hue (``360**2 / 12``) and no hue correlations: hue is ignored.
ACHROMATIC_SATURATION: float = 0.12
ACHROMATIC_CHROMA: float = 0.06
_UNIFORM_HUE_VAR = 360.0 ** 2 / 12.0
#: Fewest sample pixels a class is learned from.
MIN_SAMPLES: int = 20
#: An optional class is merged into its stand-in when its mean lies inside the central half of
#: the stand-in's Gaussian: squared Mahalanobis distance below the chi-square median (3 degrees
#: of freedom, 2.37). A bald head's "hair" is the face's colour (distance ~0); dark-brown hair
#: against a face is ~10 even though the face's wide brightness spread holds most hair pixels.
MERGE_DISTANCE2: float = float(2 * special.gammaincinv(1.5, 0.5))
#: A class's Gaussian is fitted to the pixels within the chi-square 95 % quantile (3 degrees of
#: freedom, squared Mahalanobis distance 7.81), its covariance enlarged by the consistency
#: factor of that cut (chi-square CDFs with 3 and 5 degrees of freedom there).
MODE_CUT2 = 2 * special.gammaincinv(1.5, 0.95)
MODE_CONSISTENCY = special.chdtr(3, MODE_CUT2) / special.chdtr(5, MODE_CUT2)
# (scipy.stats.chi2's own formulas from scipy.special: scipy.stats takes about 0.3 s to import)


# --------------------------------------------------------------------------- kernels

@jit
def _hsv_pixel(r, g, b):  # pragma: no cover - compiled
    """HSV of one RGB pixel in [0, 1]: hue in degrees [0, 360), s, v in [0, 1]."""
    v = max(r, g, b)
    delta = v - min(r, g, b)
    if delta <= 0.0:
        return 0.0, 0.0, v
    s = delta / v
    if b == v:
        h = 4.0 + (r - g) / delta
    elif g == v:
        h = 2.0 + (b - r) / delta
    else:
        h = (g - b) / delta
    h *= 60.0
    if h < 0.0:
        h += 360.0
    elif h >= 360.0:
        h -= 360.0
    return h, s, v


@jit
def _rgb_to_hsv_kernel(image, scale, out):  # pragma: no cover - compiled
    height, width = out.shape[:2]
    for y in range(height):
        for x in range(width):
            h, s, v = _hsv_pixel(image[y, x, 0] * scale, image[y, x, 1] * scale,
                                 image[y, x, 2] * scale)
            out[y, x, 0] = h
            out[y, x, 1] = s
            out[y, x, 2] = v


@jit
def _classify_kernel(image, scale, mask, means, inv_covs, half_log_dets, threshold,
                     out):  # pragma: no cover - compiled
    height, width = out.shape
    m = means.shape[0]
    for y in range(height):
        for x in range(width):
            if not mask[y, x]:
                out[y, x] = 0
                continue
            h, s, v = _hsv_pixel(image[y, x, 0] * scale, image[y, x, 1] * scale,
                                 image[y, x, 2] * scale)
            best = -np.inf
            label = UNKNOWN
            for c in range(m):
                dh = h - means[c, 0]
                if dh >= 180.0:
                    dh -= 360.0
                elif dh < -180.0:
                    dh += 360.0
                ds = s - means[c, 1]
                dv = v - means[c, 2]
                ic = inv_covs[c]
                d2 = (ic[0, 0] * dh * dh + ic[1, 1] * ds * ds + ic[2, 2] * dv * dv
                      + 2.0 * (ic[0, 1] * dh * ds + ic[0, 2] * dh * dv + ic[1, 2] * ds * dv))
                if d2 <= threshold:
                    score = -0.5 * d2 - half_log_dets[c]
                    if score > best:
                        best = score
                        label = c + 1
            out[y, x] = label


# --------------------------------------------------------------------------- HSV helpers

def rgb_to_hsv(image: np.ndarray) -> np.ndarray:
    """HSV of an RGB image, hue in degrees.

    Parameters
    ----------
    image : ndarray, shape (H, W, 3)
        RGB, ``uint8`` or float in [0, 1].

    Returns
    -------
    ndarray of float64, shape (H, W, 3)
        Hue in degrees [0, 360), saturation and value in [0, 1] (as
        :func:`skimage.color.rgb2hsv`, hue times 360).
    """
    image, scale = check_rgb(image, "image")
    out = np.empty(image.shape, dtype=np.float64)
    _rgb_to_hsv_kernel(image, scale / 255.0, out)
    return out


def _wrap_degrees(d: np.ndarray) -> np.ndarray:
    """Angles wrapped to [-180, 180)."""
    return (np.asarray(d, dtype=np.float64) + 180.0) % 360.0 - 180.0


def _circular_mean_degrees(h: np.ndarray) -> float:
    rad = np.deg2rad(h)
    return float(np.rad2deg(np.arctan2(np.sin(rad).mean(), np.cos(rad).mean())) % 360.0)


def _deviations(hsv: np.ndarray, mean: np.ndarray) -> np.ndarray:
    dev = hsv - mean
    dev[:, 0] = _wrap_degrees(dev[:, 0])
    return dev


def _mahalanobis2(hsv: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    dev = _deviations(hsv, mean)
    return np.einsum("ni,ij,nj->n", dev, np.linalg.inv(cov), dev)


def _chromatic(hsv: np.ndarray) -> np.ndarray:
    return (hsv[:, 1] >= ACHROMATIC_SATURATION) & (hsv[:, 1] * hsv[:, 2] >= ACHROMATIC_CHROMA)


def _gaussian(hsv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean (circular hue) and regularised covariance of HSV samples ``(N, 3)``."""
    mean = np.array([_circular_mean_degrees(hsv[:, 0]), hsv[:, 1].mean(), hsv[:, 2].mean()])
    dev = _deviations(hsv, mean)
    cov = dev.T @ dev / max(len(hsv) - 1, 1)
    if _chromatic(hsv).mean() < 0.5:
        cov[0, :] = 0.0
        cov[:, 0] = 0.0
        cov[0, 0] = _UNIFORM_HUE_VAR
    cov += np.diag(np.square(MIN_STD))
    return mean, cov


def _fit_mode(hsv: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Gaussian of the dominant colour of a sample, robust to other colours in the box.

    Starts at the densest cell of a coarse HSV histogram, then alternately fits a Gaussian
    and keeps the pixels inside its 95 % ellipsoid (covariance corrected for the trimming,
    as in the minimum-covariance-determinant estimator), until the selection is stable.
    """
    if len(hsv) < MIN_SAMPLES:
        raise ValueError(f"colour class {name!r}: only {len(hsv)} sample pixels "
                         f"(need {MIN_SAMPLES}); enlarge its sample box")
    chromatic = _chromatic(hsv)
    hue_bin = np.where(chromatic, np.floor(hsv[:, 0] / 30.0).astype(int) % 12 + 1, 0)
    sat_bin = np.minimum((hsv[:, 1] * 6).astype(int), 5)
    val_bin = np.minimum((hsv[:, 2] * 6).astype(int), 5)
    cell = (hue_bin * 6 + sat_bin) * 6 + val_bin
    selected = cell == np.argmax(np.bincount(cell))
    cut, consistency = MODE_CUT2, MODE_CONSISTENCY
    mean, cov = _gaussian(hsv[selected])
    for _ in range(20):
        keep = _mahalanobis2(hsv, mean, cov) <= cut
        if keep.sum() < MIN_SAMPLES:
            break
        mean, cov = _gaussian(hsv[keep])
        cov *= consistency
        if np.array_equal(keep, selected):
            break
        selected = keep
    return mean, cov


# --------------------------------------------------------------------------- model

class ColourModel:
    """One Gaussian per colour class in HSV (hue circular).

    Parameters
    ----------
    names : sequence of str, length m
        Class names in label order (label ``c + 1`` is ``names[c]``), e.g.
        ``("skin", "clothes")``.
    means : array_like, shape (m, 3)
        Class means ``(hue degrees in [0, 360), saturation, value)``.
    covariances : array_like, shape (m, 3, 3)
        Symmetric positive-definite covariances in the same units (hue deviations in
        degrees, wrapped to [-180, 180)).

    Raises
    ------
    ValueError
        On inconsistent shapes, duplicate names, non-finite values or a covariance that is
        not symmetric positive-definite.
    """

    def __init__(self, names: Sequence[str], means: object, covariances: object) -> None:
        names = tuple(str(n) for n in names)
        means = np.array(means, dtype=np.float64)
        covariances = np.array(covariances, dtype=np.float64)
        m = len(names)
        if not 1 <= m <= MAX_CLASSES:
            raise ValueError(f"a colour model needs 1 to {MAX_CLASSES} classes, got {m}")
        if len(set(names)) != m:
            raise ValueError(f"colour class names must be unique, got {names}")
        if means.shape != (m, 3) or covariances.shape != (m, 3, 3):
            raise ValueError(f"means must be ({m}, 3) and covariances ({m}, 3, 3), got "
                             f"{means.shape} and {covariances.shape}")
        if not (np.isfinite(means).all() and np.isfinite(covariances).all()):
            raise ValueError("colour model means and covariances must be finite")
        means[:, 0] %= 360.0
        if not np.allclose(covariances, covariances.transpose(0, 2, 1)):
            raise ValueError("colour class covariances must be symmetric")
        try:
            chol = np.linalg.cholesky(covariances)
        except np.linalg.LinAlgError:
            raise ValueError("colour class covariances must be positive-definite") from None
        self._names = names
        self._means = means
        self._covariances = covariances
        self._inv_covs = np.linalg.inv(covariances)
        self._half_log_dets = np.log(np.diagonal(chol, axis1=1, axis2=2)).sum(axis=1)
        for a in (self._means, self._covariances, self._inv_covs, self._half_log_dets):
            a.flags.writeable = False

    @property
    def names(self) -> tuple[str, ...]:
        """Class names in label order."""
        return self._names

    @property
    def m(self) -> int:
        """Number of colour classes."""
        return len(self._names)

    @property
    def means(self) -> np.ndarray:
        """Class means, shape (m, 3): hue (degrees), saturation, value (read-only)."""
        return self._means

    @property
    def covariances(self) -> np.ndarray:
        """Class covariances, shape (m, 3, 3) (read-only)."""
        return self._covariances

    def __repr__(self) -> str:
        parts = ", ".join(f"{n}: h={mu[0]:.0f} s={mu[1]:.2f} v={mu[2]:.2f}"
                          for n, mu in zip(self._names, self._means))
        return f"ColourModel({parts})"

    @classmethod
    def from_samples(cls, samples: Mapping[str, np.ndarray],
                     merges: Mapping[str, str] | None = None) -> ColourModel:
        """Learn one class per entry of ``samples`` (name -> RGB pixels).

        Parameters
        ----------
        samples : mapping of str to ndarray, shape (N, 3)
            RGB sample pixels of each class, ``uint8`` or float in [0, 1], in label order.
            Each class is the dominant colour of its sample (robust to a minority of other
            colours, see the module notes).
        merges : mapping of str to str, optional
            Optional classes and the class each stands in for (e.g.
            :data:`mocap.labels.CLASS_MERGES_INTO`). An optional class is left out when its
            sample has fewer than :data:`MIN_SAMPLES` pixels or when its mean lies within :data:`MERGE_DISTANCE2` of the class it merges into (the
            image does not tell them apart). Without ``merges`` every class must be learnable.

        Returns
        -------
        ColourModel
            The learnt classes in the order of ``samples`` (without the merged ones).
        """
        if not samples:
            raise ValueError("no colour samples given")
        merges = {} if merges is None else dict(merges)
        fitted = {}
        for name, pixels in samples.items():
            pixels = np.asarray(pixels)
            if pixels.ndim != 2 or pixels.shape[1] != 3:
                raise ValueError(f"samples of {name!r} must have shape (N, 3), got {pixels.shape}")
            if name in merges and len(pixels) < MIN_SAMPLES:
                continue
            fitted[name] = _fit_mode(rgb_to_hsv(pixels[np.newaxis]).reshape(-1, 3), name)
        if not any(n not in merges for n in fitted):
            raise ValueError("at least one colour class that merges into no other is needed")
        keep = []
        for name, (mean, _) in fitted.items():
            target = merges.get(name)
            if target in fitted and target not in merges:
                if _mahalanobis2(mean[np.newaxis], *fitted[target])[0] < MERGE_DISTANCE2:
                    continue
            keep.append(name)
        return cls(keep, [fitted[n][0] for n in keep], [fitted[n][1] for n in keep])

    @classmethod
    def from_boxes(cls, frame: np.ndarray, boxes: Mapping[str, object],
                   foreground: np.ndarray | None = None) -> ColourModel:
        """Learn one class per named sample box of ``frame``.

        Parameters
        ----------
        frame : ndarray, shape (H, W, 3)
            RGB, ``uint8`` or float in [0, 1].
        boxes : mapping of str to (row, col, height, width)
            Sample box of each class in pixels, in label order; clipped to the image.
        foreground : ndarray of bool, shape (H, W), optional
            Only foreground pixels of each box are used.
        """
        return cls.from_samples(cls.sample_boxes(frame, boxes, foreground))

    @staticmethod
    def sample_boxes(frame: np.ndarray, boxes: Mapping[str, object], foreground: np.ndarray | None = None, *,
                     min_pixels: int = MIN_SAMPLES) -> dict[str, np.ndarray]:
        """The (foreground) pixels of each named box, RGB ``(N, 3)`` as ``frame``'s dtype; see
        :meth:`from_boxes`. A box with fewer than ``min_pixels`` foreground pixels is an error."""
        frame, _ = check_rgb(frame, "frame")
        if foreground is not None:
            check_mask(foreground, frame.shape[:2], "foreground")
        samples = {}
        for name, box in boxes.items():
            box = check_box(box, frame.shape[:2], f"{name} box")
            pixels = frame[box.slices]
            if foreground is not None:
                pixels = pixels[foreground[box.slices]]
                if len(pixels) < min_pixels:
                    raise ValueError(f"{name} box {tuple(box)} holds only {len(pixels)} "
                                     "foreground pixels; is the person in it?")
            samples[name] = pixels.reshape(-1, 3)
        return samples

    def classify(self, frame: np.ndarray, foreground: np.ndarray | None = None,
                 threshold: float = DEFAULT_COLOUR_THRESHOLD) -> np.ndarray:
        """Label image: each foreground pixel's most likely class, or unknown.

        Parameters
        ----------
        frame : ndarray, shape (H, W, 3)
            RGB, ``uint8`` or float in [0, 1].
        foreground : ndarray of bool, shape (H, W), optional
            Pixels to classify; the others get label 0 (background). Default: all.
        threshold : float
            Largest squared Mahalanobis distance to a class mean (HSV, hue wrapped) for the
            pixel to belong to that class; beyond it for every class the label is
            ``mocap.labels.UNKNOWN`` (255). Default: chi-square 99.9 % with 3 degrees of
            freedom.

        Returns
        -------
        ndarray of uint8, shape (H, W)
            0 background, ``c + 1`` for class ``names[c]``, 255 unknown foreground.
        """
        frame, scale = check_rgb(frame, "frame")
        if foreground is None:
            foreground = np.ones(frame.shape[:2], dtype=np.bool_)
        else:
            check_mask(foreground, frame.shape[:2], "foreground")
        if not (isinstance(threshold, (int, float)) and threshold > 0 and math.isfinite(threshold)):
            raise ValueError(f"threshold must be a positive finite number, got {threshold!r}")
        return self._classify(frame, scale, foreground, float(threshold))

    def _classify(self, frame, scale, foreground, threshold):
        out = np.empty(frame.shape[:2], dtype=np.uint8)
        _classify_kernel(frame, scale / 255.0, foreground, self._means, self._inv_covs,
                         self._half_log_dets, threshold, out)
        return out

    # -- persistence
    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary (hue in degrees)."""
        return {"names": list(self._names), "means": self._means.tolist(),
                "covariances": self._covariances.tolist(),
                "hsv_units": "hue degrees [0, 360), saturation [0, 1], value [0, 1]"}

    @classmethod
    def from_dict(cls, data: Mapping[str, object]) -> ColourModel:
        """Inverse of :meth:`to_dict`; unknown or missing keys raise ValueError."""
        if not isinstance(data, Mapping):
            raise ValueError("colour model must be a JSON object")
        required = {"names", "means", "covariances"}
        missing = required - set(data)
        unknown = set(data) - required - {"hsv_units"}
        if missing or unknown:
            raise ValueError(f"colour model keys: missing {sorted(missing)}, unknown {sorted(unknown)}")
        return cls(data["names"], data["means"], data["covariances"])  # type: ignore[arg-type]

    def to_json(self, path: str | Path) -> None:
        """Write the model to a JSON file (atomically)."""
        write_json(path, self.to_dict())

    @classmethod
    def from_json(cls, path: str | Path) -> ColourModel:
        """Read a model written by :meth:`to_json` (FileNotFoundError, ValueError)."""
        return cls.from_dict(read_json(path))


# --------------------------------------------------------------------------- face & learning

def skin_prior(hsv: np.ndarray) -> np.ndarray:
    """Broad prior of skin tones (any complexion, most lighting), only to rank detections."""
    hue = hsv[..., 0]
    return (((hue <= 50.0) | (hue >= 340.0)) & (hsv[..., 1] >= 0.08) & (hsv[..., 1] <= 0.8)
            & (hsv[..., 2] >= 0.15))


def skin_box_of_face(face: Box) -> Box:
    """The skin sample box inside a face box: central 60 % of the width, rows 25-85 %."""
    return Box(face.row + round(0.25 * face.height), face.col + round(0.2 * face.width),
               max(round(0.6 * face.height), 1), max(round(0.6 * face.width), 1))


def clothes_box_of_face(face: Box) -> Box:
    """The clothes sample box under a face box: 1.5 to 2.5 face heights below the chin,
    twice the face width, centred (chest height, clear of the neck and collar)."""
    return Box(face.row + round(2.5 * face.height), face.col - round(0.5 * face.width),
               face.height, 2 * face.width)


def hair_box_of_face(face: Box) -> Box:
    """The hair sample box above and around a face box: from 0.45 face heights above its top
    down to 0.1 below it, 1.2 face widths wide, centred (forehead hair and crown)."""
    return Box(face.row - round(0.45 * face.height), face.col - round(0.1 * face.width),
               max(round(0.55 * face.height), 1), max(round(1.2 * face.width), 1))


def detect_face(frame: np.ndarray, *, min_size: int = 24, max_side: int = 640) -> Box | None:
    """The most face-like frontal face in ``frame``, or None.

    Runs scikit-image's LBP frontal-face cascade (``skimage.data.lbp_frontal_face_cascade_
    filename()``, a Viola-Jones style boosted detector as in the paper) over all scales.
    Among several detections the one whose centre holds the most skin-toned pixels wins
    (a printed face on a T-shirt loses), then the largest.

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3)
        RGB, ``uint8`` or float in [0, 1].
    min_size : int
        Smallest face side searched, in pixels of the (possibly reduced) image; >= 24, the
        cascade's window.
    max_side : int
        Frames larger than this are reduced (anti-aliased) so their longer side is
        ``max_side`` before the search (a speed/size trade-off); the box is scaled back.

    Returns
    -------
    Box or None
        ``(row, col, height, width)`` in pixels of ``frame``.
    """
    frame, scale = check_rgb(frame, "frame")
    if min_size < 24:
        raise ValueError(f"min_size must be >= 24 (the cascade window), got {min_size}")
    image = frame.astype(np.float64) * (scale / 255.0)
    factor = 1.0
    if max(image.shape[:2]) > max_side:
        factor = max_side / max(image.shape[:2])
        image = transform.rescale(image, factor, channel_axis=-1, anti_aliasing=True)
    side = min(image.shape[:2])
    if side < min_size:
        return None
    cascade = feature.Cascade(data.lbp_frontal_face_cascade_filename())
    found = cascade.detect_multi_scale(image, scale_factor=1.2, step_ratio=1,
                                       min_size=(min_size, min_size), max_size=(side, side))
    if not found:
        return None
    hsv = color.rgb2hsv(image)
    hsv[..., 0] *= 360.0
    best, best_key = None, None
    for det in found:
        box = Box(int(det["r"]), int(det["c"]), int(det["height"]), int(det["width"]))
        skin = skin_prior(hsv[skin_box_of_face(box).slices]).mean()
        key = (round(float(skin), 1), box.height * box.width)
        if best_key is None or key > best_key:
            best, best_key = box, key
    h, w = frame.shape[:2]
    return check_box((round(best.row / factor), round(best.col / factor),
                      round(best.height / factor), round(best.width / factor)), (h, w), "face")


def learn_colour_model(frame: np.ndarray, background: np.ndarray | None = None,
                       skin_box: object | None = None, clothes_box: object | None = None, *,
                       hair_box: object | None = None, lower_body_box: object | None = None,
                       config: ImagingConfig | None = None) -> ColourModel:
    """Learn the skin and clothes classes from the first frame, as the paper does, and hair
    and lower body when the image supports them.

    The skin sample is the centre of the face found by :func:`detect_face`, the clothes
    sample a box under it (:func:`clothes_box_of_face`), the hair sample (with a background
    only: its foreground pixels) a box above and around it (:func:`hair_box_of_face`). Boxes
    given by the user replace the automatic ones (needed when no face is found); the lower
    body is learnt only from a box the user gives. With a background, only foreground pixels
    of the boxes are used. Hair and lower body are merged away when their sample is small or
    looks like skin or clothes (:meth:`ColourModel.from_samples` with ``merges``).

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3)
        RGB first frame, ``uint8`` or float in [0, 1].
    background : ndarray, shape (H, W, 3), optional
        Empty-scene image (see :func:`mocap.imaging.subtract_background`).
    skin_box, clothes_box, hair_box, lower_body_box : (row, col, height, width), optional
        Sample boxes in pixels.
    config : ImagingConfig, optional
        Background-subtraction parameters used with ``background``.

    Returns
    -------
    ColourModel
        Classes ``("skin", "clothes")`` (labels 1 and 2), then those of ``("hair",
        "lower_body")`` that were sampled and kept.

    Raises
    ------
    ValueError
        If no face is found and a sample box is missing, if a box is outside the image or
        holds too few (foreground) pixels, or on a bad image.
    """
    frame, _ = check_rgb(frame, "frame")
    foreground = None
    if background is not None:
        from mocap.imaging.background import subtract_background
        check_rgb(background, "background")
        check_same_size(frame, background, "background")
        foreground = subtract_background(frame, background, config)
    face = None
    if skin_box is None or clothes_box is None or (hair_box is None and foreground is not None):
        face = detect_face(frame)
    if skin_box is None or clothes_box is None:
        if face is None:
            missing = [n for n, b in (("skin_box", skin_box), ("clothes_box", clothes_box))
                       if b is None]
            raise ValueError(
                "no face found in the frame to learn the colour model from; pass "
                + " and ".join(missing) + " as (row, col, height, width) sample boxes "
                "(command line: --skin-box/--clothes-box ROW,COL,HEIGHT,WIDTH)")
        skin_box = skin_box if skin_box is not None else skin_box_of_face(face)
        if clothes_box is None:
            try:
                clothes_box = check_box(clothes_box_of_face(face), frame.shape[:2], "clothes box")
            except ValueError:
                raise ValueError(f"the clothes box under the face {tuple(face)} falls outside "
                                 "the image; pass clothes_box") from None
    boxes = {"skin": skin_box, "clothes": clothes_box}
    samples = ColourModel.sample_boxes(frame, boxes, foreground)
    if hair_box is None and face is not None and foreground is not None:
        hair_box = _clipped(hair_box_of_face(face), frame.shape[:2])
    for name, box in (("hair", hair_box), ("lower_body", lower_body_box)):
        if box is not None:
            samples.update(ColourModel.sample_boxes(frame, {name: box}, foreground, min_pixels=0))
    return ColourModel.from_samples(samples, CLASS_MERGES_INTO)


def _clipped(box: Box, shape: tuple[int, int]) -> Box | None:
    """``box`` cut to the image, or None when nothing of it is inside."""
    r0, c0 = max(box.row, 0), max(box.col, 0)
    r1, c1 = min(box.row + box.height, shape[0]), min(box.col + box.width, shape[1])
    return Box(r0, c0, r1 - r0, c1 - c0) if r1 > r0 and c1 > c0 else None
