"""Every parameter of the image side, with defaults, saved as JSON."""
from __future__ import annotations

import dataclasses
import math

from mocap.config import JsonConfig

#: Default squared-Mahalanobis limit of a colour class: the 99.9 % quantile of a chi-square
#: with 3 degrees of freedom (scipy.stats.chi2.ppf(0.999, 3)).
DEFAULT_COLOUR_THRESHOLD: float = 16.266236196238129

EDGE_METHODS: tuple[str, ...] = ("canny", "deriche")
DISTANCE_METHODS: tuple[str, ...] = ("edt", "chamfer")


@dataclasses.dataclass(frozen=True)
class ImagingConfig(JsonConfig):
    """Parameters of :func:`mocap.imaging.prepare_frame` (background, colour, edges, distance).

    Intensities are on the 0-255 scale whatever the image dtype; lengths are in pixels.
    The defaults work on :func:`mocap.imaging.testing.synthetic_scene` and on real webcam
    frames from 160x120 to 768x432.

    Attributes
    ----------
    change_threshold : float
        A pixel is *changed* when the Euclidean RGB distance between frame and background
        exceeds this (0-255 units). Set above the sensor noise (about 4 to 5 noise sigmas).
    shadow_min_brightness, shadow_max_brightness : float
        A changed pixel whose brightness ratio ``alpha = <I, E> / <E, E>`` (frame ``I``,
        background ``E``) lies in this range and whose chromaticity did not change is a
        shadow (``alpha < 1``) or a highlight (``alpha > 1``), not foreground.
    shadow_max_chroma : float
        Largest relative chromaticity distortion ``|I - alpha E| / |alpha E|`` (about the
        sine of the angle between the two colours) of a shadow.
    chroma_noise : float
        Absolute slack (0-255 units) added to the allowed chromaticity distortion, for
        sensor noise on dark pixels.
    opening_size : int
        Side of the square opening that removes speckle from the foreground (1 disables).
    closing_size : int
        Side of the square closing that bridges small gaps in the foreground (1 disables).
    min_object_fraction : float
        Connected foreground parts smaller than this fraction of the image area are dropped.
    max_hole_fraction : float
        Holes in the foreground smaller than this fraction of the image area are filled.
    colour_threshold : float
        Largest squared Mahalanobis distance (HSV) at which a pixel still belongs to a colour
        class; farther from every class it is labelled unknown (255).
    edge_method : {'canny', 'deriche'}
        Edge detector: scikit-image's Canny, or a recursive Deriche gradient with the same
        non-maximum suppression and hysteresis.
    edge_sigma : float
        Gaussian smoothing of Canny, in pixels (Deriche uses ``alpha = sqrt(pi) / sigma``).
    edge_low_threshold, edge_high_threshold : float
        Hysteresis thresholds on the gradient magnitude of the grey image in [0, 1], in the
        units of :func:`skimage.feature.canny` (Sobel response: 8 times the grey-level slope
        per pixel; a sharp step of contrast ``d`` peaks near ``8 d / (sqrt(2 pi) sigma)``,
        about ``2.1 d`` at ``sigma = 1.5``).
    edge_dilation : int
        Edges are kept within this many pixels of the foreground.
    silhouette_edges : bool
        Add the outline of the foreground mask to the edges (it survives where actor and
        background have the same grey level and the image edge vanishes).
    distance_method : {'edt', 'chamfer'}
        Exact Euclidean distance (scipy) or Borgefors' chamfer 3-4 (compiled two-pass).
    max_distance : float
        The distance map is truncated at this many pixels, so outliers cannot dominate.
    """

    change_threshold: float = 30.0
    shadow_min_brightness: float = 0.7
    shadow_max_brightness: float = 1.25
    shadow_max_chroma: float = 0.05
    chroma_noise: float = 6.0
    opening_size: int = 3
    closing_size: int = 3
    min_object_fraction: float = 0.002
    max_hole_fraction: float = 0.002
    colour_threshold: float = DEFAULT_COLOUR_THRESHOLD
    edge_method: str = "canny"
    edge_sigma: float = 1.5
    edge_low_threshold: float = 0.08
    edge_high_threshold: float = 0.20
    edge_dilation: int = 4
    silhouette_edges: bool = True
    distance_method: str = "edt"
    max_distance: float = 20.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.type in ("float", float):
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    raise ValueError(f"{f.name} must be a number, got {value!r}")
                if not math.isfinite(value):
                    raise ValueError(f"{f.name} must be finite, got {value!r}")
                object.__setattr__(self, f.name, float(value))
            elif f.type in ("bool", bool):
                if not isinstance(value, bool):
                    raise ValueError(f"{f.name} must be true or false, got {value!r}")
            elif f.type in ("int", int):
                if isinstance(value, bool) or not isinstance(value, int):
                    raise ValueError(f"{f.name} must be an integer, got {value!r}")
        positive = ("change_threshold", "shadow_max_brightness", "colour_threshold",
                    "edge_sigma", "max_distance", "edge_high_threshold")
        for name in positive:
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        non_negative = ("shadow_min_brightness", "shadow_max_chroma", "chroma_noise",
                        "min_object_fraction", "max_hole_fraction", "edge_low_threshold",
                        "edge_dilation")
        for name in non_negative:
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        if self.shadow_min_brightness > self.shadow_max_brightness:
            raise ValueError("shadow_min_brightness must not exceed shadow_max_brightness")
        if self.edge_low_threshold > self.edge_high_threshold:
            raise ValueError("edge_low_threshold must not exceed edge_high_threshold")
        for name in ("opening_size", "closing_size"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1 (1 disables it), got {getattr(self, name)}")
        if self.min_object_fraction >= 1 or self.max_hole_fraction >= 1:
            raise ValueError("min_object_fraction and max_hole_fraction must be < 1")
        if self.edge_method not in EDGE_METHODS:
            raise ValueError(f"edge_method must be one of {EDGE_METHODS}, got {self.edge_method!r}")
        if self.distance_method not in DISTANCE_METHODS:
            raise ValueError(
                f"distance_method must be one of {DISTANCE_METHODS}, got {self.distance_method!r}")

