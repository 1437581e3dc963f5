"""Pinhole camera: intrinsics in pixels, camera coordinates in metres (x right, y down, z forward)."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

#: Default image size (the paper's webcam resolution), pixels.
DEFAULT_SIZE = (160, 120)
#: Default horizontal field of view of a webcam, degrees.
DEFAULT_HFOV_DEG = 60.0
#: Nearest depth rendered, metres; triangles with a vertex closer are skipped.
NEAR_PLANE_M = 0.05


@dataclass(frozen=True)
class Camera:
    """Pinhole camera without distortion.

    A point (x, y, z) in metres projects to pixel coordinates ``u = fx * x / z + cx``,
    ``v = fy * y / z + cy``; pixel (row i, column j) covers ``[j, j+1) x [i, i+1)`` with its
    centre at ``(j + 0.5, i + 0.5)``.

    Attributes
    ----------
    width, height : int, pixels
    fx, fy : float, pixels
        Focal lengths.
    cx, cy : float, pixels
        Principal point.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    def __post_init__(self) -> None:
        for key in ("width", "height"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 1 <= v <= 16384:
                raise ValueError(f"camera {key} must be an integer number of pixels in [1, 16384], got {v!r}")
            object.__setattr__(self, key, int(v))
        for key in ("fx", "fy", "cx", "cy"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v):
                raise ValueError(f"camera {key} must be a finite number of pixels, got {v!r}")
            object.__setattr__(self, key, float(v))
        if self.fx <= 0 or self.fy <= 0:
            raise ValueError(f"focal lengths must be positive, got fx={self.fx}, fy={self.fy}")

    @classmethod
    def default(cls, width: int = DEFAULT_SIZE[0], height: int = DEFAULT_SIZE[1],
                hfov_deg: float = DEFAULT_HFOV_DEG) -> "Camera":
        """A webcam-like camera: square pixels, centred principal point, ``hfov_deg`` wide."""
        if not 1.0 <= hfov_deg <= 170.0:
            raise ValueError(f"horizontal field of view must be in [1, 170] degrees, got {hfov_deg}")
        f = 0.5 * width / math.tan(math.radians(hfov_deg) / 2.0)
        return cls(width, height, f, f, width / 2.0, height / 2.0)

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape ``(height, width)``."""
        return (self.height, self.width)

    def scaled(self, width: int, height: int) -> "Camera":
        """The same camera at another resolution (intrinsics scaled per axis)."""
        sx, sy = width / self.width, height / self.height
        return Camera(width, height, self.fx * sx, self.fy * sy, self.cx * sx, self.cy * sy)

    def working(self, input_width: int, input_height: int, factor: int) -> "Camera":
        """This camera at the working resolution of ``input_width`` x ``input_height`` frames
        reduced by the integer ``factor`` (:func:`mocap.imaging.resample.downscale`: the size is
        ``(input_width // factor, input_height // factor)``, the intrinsics divided by ``factor``,
        so that working pixel coordinates times ``factor`` are input pixels).

        The one size check of a camera against the frames: a camera of the input size is
        reduced, a camera already of the working size is returned as it is.

        Raises
        ------
        ValueError
            A camera of neither size (a calibration made for another video), or a bad factor.
        """
        if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
            raise ValueError(f"the working factor must be a positive integer, got {factor!r}")
        work = (input_height // factor, input_width // factor)
        if self.shape == work:
            return self
        if self.shape == (input_height, input_width):
            return Camera(work[1], work[0], self.fx / factor, self.fy / factor, self.cx / factor, self.cy / factor)
        raise ValueError(f"frames are {input_width}x{input_height} (working size {work[1]}x{work[0]}) but the "
                         f"camera is {self.width}x{self.height}: calibrate for this video (python -m mocap calibrate)")

    def enlarged(self, factor: int, input_width: int, input_height: int) -> "Camera":
        """The inverse of :meth:`working`: this working-resolution camera at the input size
        ``input_width`` x ``input_height`` (intrinsics times ``factor``)."""
        if self.working(input_width, input_height, factor) is not self:
            raise ValueError(f"a {self.width}x{self.height} camera is not the working camera of "
                             f"{input_width}x{input_height} frames reduced {factor}x")
        return Camera(input_width, input_height, self.fx * factor, self.fy * factor, self.cx * factor,
                      self.cy * factor)

    def intrinsics(self) -> np.ndarray:
        """The 3x3 intrinsic matrix K, float64, pixels."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def project(self, points) -> np.ndarray:
        """Project points in camera coordinates.

        Parameters
        ----------
        points : array_like, shape (..., 3), metres
            Must have z > 0.

        Returns
        -------
        ndarray, shape (..., 2), float64, pixels (u right, v down)
        """
        p = np.asarray(points, dtype=np.float64)
        if p.shape[-1] != 3:
            raise ValueError(f"points must have shape (..., 3), got {p.shape}")
        z = p[..., 2]
        if np.any(z <= 0):
            raise ValueError("cannot project points at or behind the camera (z <= 0)")
        return np.stack([self.fx * p[..., 0] / z + self.cx, self.fy * p[..., 1] / z + self.cy], axis=-1)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> "Camera":
        extra = set(data) - {"width", "height", "fx", "fy", "cx", "cy"}
        if extra:
            raise ValueError(f"unknown camera keys: {', '.join(sorted(extra))}")
        return cls(**data)

    def to_json(self, path: str | Path) -> None:
        """Save as JSON (atomically)."""
        from mocap.io.files import write_json
        write_json(path, self.to_dict())

    @classmethod
    def from_json(cls, path: str | Path) -> "Camera":
        """Load a file written by :meth:`to_json` (FileNotFoundError, ValueError)."""
        from mocap.io.files import read_json
        return cls.from_dict(read_json(path))

    def as_array(self) -> np.ndarray:
        """``[fx, fy, cx, cy, near]`` as float64, the form the compiled kernels take."""
        return np.array([self.fx, self.fy, self.cx, self.cy, NEAR_PLANE_M])
