"""A webcam's imperfections, from scene radiance to the 8-bit frame it delivers.

In order: auto-exposure and white-balance drift (slow random gains per frame and colour
channel), lens vignetting, optical blur (Gaussian), sensor noise (shot noise growing with the
signal plus read noise, drawn fresh for every frame), the sRGB tone curve and 8-bit
quantisation, and JPEG compression (encoded and decoded by Pillow through imageio, as an
MJPEG webcam does).
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass

import imageio.v3 as iio
import numpy as np
from scipy.ndimage import gaussian_filter

__all__ = ["SensorConfig", "SensorDrift", "apply_sensor", "linear_to_srgb"]


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """Linear light in [0, 1] to sRGB values in [0, 1]."""
    c = np.clip(c, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


@dataclass(frozen=True)
class SensorConfig:
    """Camera imperfections.

    Attributes
    ----------
    exposure_drift : float
        Peak relative change of the exposure (auto-exposure breathing).
    white_balance_drift : float
        Peak relative change of each colour channel's gain.
    vignetting : float
        Relative darkening at the image corners.
    blur_sigma_px : float
        Optical blur, Gaussian standard deviation in output pixels.
    shot_noise : float
        Shot-noise variance per unit of linear signal (noise std = sqrt(shot * signal)).
    read_noise : float
        Read-noise standard deviation, linear units.
    jpeg_quality : int or None
        JPEG quality 1-100 (None: no compression).
    """

    exposure_drift: float = 0.06
    white_balance_drift: float = 0.03
    vignetting: float = 0.12
    blur_sigma_px: float = 0.45
    shot_noise: float = 2.5e-4
    read_noise: float = 0.004
    jpeg_quality: int | None = 85

    def __post_init__(self) -> None:
        for key in ("exposure_drift", "white_balance_drift", "vignetting", "blur_sigma_px", "shot_noise",
                    "read_noise"):
            v = getattr(self, key)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ValueError(f"sensor {key} must be a finite non-negative number, got {v!r}")
        if self.jpeg_quality is not None and (isinstance(self.jpeg_quality, bool)
                                              or not isinstance(self.jpeg_quality, int)
                                              or not 1 <= self.jpeg_quality <= 100):
            raise ValueError(f"JPEG quality must be an integer in [1, 100] or None, got {self.jpeg_quality!r}")

    def to_dict(self) -> dict:
        """JSON-ready settings."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> "SensorConfig":
        """Inverse of :meth:`to_dict`; unknown keys are an error."""
        extra = set(data) - set(cls.__dataclass_fields__)
        if extra:
            raise ValueError(f"unknown sensor settings: {', '.join(sorted(extra))}")
        return cls(**data)

    def to_json(self) -> str:
        """:meth:`to_dict` as JSON text."""
        return json.dumps(self.to_dict(), indent=2)


@dataclass(frozen=True)
class SensorDrift:
    """Slow random exposure and white-balance variation of one sequence.

    Attributes
    ----------
    frequencies : ndarray, shape (4, 2)
        Two frequencies (Hz) for the exposure and each colour channel's gain.
    phases : ndarray, shape (4, 2)
    """

    frequencies: np.ndarray
    phases: np.ndarray

    @classmethod
    def random(cls, rng: np.random.Generator) -> "SensorDrift":
        """Periods of 4 to 33 seconds, random phases."""
        return cls(rng.uniform(0.03, 0.25, size=(4, 2)), rng.uniform(0.0, 2 * np.pi, size=(4, 2)))

    def gains(self, t: float, config: SensorConfig) -> np.ndarray:
        """RGB gains (3,) at time ``t`` seconds."""
        wave = np.sin(2 * np.pi * self.frequencies * t + self.phases).mean(axis=1)
        exposure = 1.0 + config.exposure_drift * wave[0]
        return exposure * (1.0 + config.white_balance_drift * wave[1:])


def apply_sensor(radiance: np.ndarray, config: SensorConfig, drift: SensorDrift, t: float,
                 rng: np.random.Generator) -> tuple[np.ndarray, bytes | None]:
    """The 8-bit frame a webcam makes of a radiance image.

    Parameters
    ----------
    radiance : ndarray, shape (H, W, 3), float
        Linear light at the output resolution.
    config : SensorConfig
    drift : SensorDrift
    t : float
        Time of the frame, seconds.
    rng : numpy.random.Generator
        Noise source of this frame.

    Returns
    -------
    frame : ndarray, shape (H, W, 3), uint8
        sRGB, as decoded from the JPEG stream.
    jpeg : bytes or None
        The JPEG stream itself (None without compression).
    """
    h, w = radiance.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    r2 = ((xx + 0.5 - w / 2) ** 2 + (yy + 0.5 - h / 2) ** 2) / ((w / 2) ** 2 + (h / 2) ** 2)
    img = radiance * drift.gains(t, config) * (1.0 - config.vignetting * r2)[:, :, None]
    if config.blur_sigma_px > 0:
        img = gaussian_filter(img, sigma=(config.blur_sigma_px, config.blur_sigma_px, 0), mode="nearest")
    signal = np.clip(img, 0.0, None)
    std = np.sqrt(config.shot_noise * signal + config.read_noise ** 2)
    img = img + std * rng.standard_normal(img.shape)
    out = np.round(255.0 * linear_to_srgb(img)).astype(np.uint8)
    if config.jpeg_quality is None:
        return out, None
    data = iio.imwrite("<bytes>", out, extension=".jpeg", quality=config.jpeg_quality)
    return iio.imread(data), data
