"""Pose tables as CSV: ``ground_truth.csv`` and the tracker's ``poses.csv`` (docs/design.md section 4).

Columns: ``frame``, the 23 pose parameters by name (positions in metres, angles in **degrees**,
since these files are read by people), the joint columns ``<joint>_x, <joint>_y, <joint>_z``
(metres, camera coordinates) for every joint in :data:`~mocap.body.skeleton.JOINT_NAMES`, then
any extra per-frame columns (residuals, flags, timings).
"""
from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mocap.body.pose import N_PARAMETERS, PARAMETER_NAMES
from mocap.body.skeleton import JOINT_NAMES
from mocap.io.files import write_text_atomic

#: Joint column names in order.
JOINT_COLUMNS: tuple[str, ...] = tuple(f"{j}_{a}" for j in JOINT_NAMES for a in "xyz")
#: Leading columns of every pose table.
BASE_COLUMNS: tuple[str, ...] = ("frame", *PARAMETER_NAMES, *JOINT_COLUMNS)
#: Extra columns that hold words, not numbers (read back as str arrays).
TEXT_COLUMNS: frozenset[str] = frozenset({"origin"})


@dataclass
class PoseTable:
    """Per-frame poses, joints and extra columns.

    Attributes
    ----------
    frames : ndarray, shape (N,), int64
    poses : ndarray, shape (N, 23), float64
        Metres and radians (converted from degrees on reading).
    joints : ndarray, shape (N, 10, 3), float64, metres
    extra : dict of str to ndarray, shape (N,)
    """

    frames: np.ndarray
    poses: np.ndarray
    joints: np.ndarray
    extra: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = len(self.frames)
        self.frames = np.asarray(self.frames, dtype=np.int64).reshape(n)
        self.poses = np.asarray(self.poses, dtype=np.float64).reshape(n, N_PARAMETERS)
        self.joints = np.asarray(self.joints, dtype=np.float64).reshape(n, len(JOINT_NAMES), 3)
        for key, value in list(self.extra.items()):
            if key in BASE_COLUMNS:
                raise ValueError(f"extra column {key!r} clashes with a pose-table column")
            value = np.asarray(value)
            if value.shape != (n,):
                raise ValueError(f"extra column {key!r} must have shape ({n},), got {value.shape}")
            self.extra[key] = value

    def __len__(self) -> int:
        return len(self.frames)

    def to_csv_text(self) -> str:
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow([*BASE_COLUMNS, *self.extra])
        deg = self.poses.copy()
        deg[:, 3:] = np.rad2deg(deg[:, 3:])
        flat = self.joints.reshape(len(self), -1)
        for i in range(len(self)):
            row = [str(int(self.frames[i]))]
            row += [repr(float(v)) for v in deg[i]]
            row += [repr(float(v)) for v in flat[i]]
            for value in self.extra.values():
                v = value[i]
                if value.dtype.kind in "UO":
                    row.append(str(v))
                else:
                    row.append(str(int(v)) if np.issubdtype(value.dtype, np.integer) or value.dtype == bool
                               else repr(float(v)))
            writer.writerow(row)
        return out.getvalue()

    def write(self, path: str | Path) -> None:
        """Write the table as CSV, atomically."""
        write_text_atomic(path, self.to_csv_text())

    def append_to(self, path: str | Path, *, sync: bool = True) -> None:
        """Append the rows to a CSV journal (header first if the file is new), flushed to the
        operating system and, with ``sync``, to disk (else the caller syncs it, as
        :func:`mocap.io.checkpoint.write_checkpoint` does).

        A run that is killed leaves at most a partial last line, which :meth:`read` with
        ``tolerate_partial`` drops.
        """
        import os

        text = self.to_csv_text()
        with Path(path).open("a", newline="") as fh:
            fh.write(text if fh.tell() == 0 else text.split("\n", 1)[1])      # the header once
            fh.flush()
            if sync:
                os.fsync(fh.fileno())

    @classmethod
    def read(cls, path: str | Path, *, tolerate_partial: bool = False) -> "PoseTable":
        """Read a table written by :meth:`write` or :meth:`append_to` (extra columns come back
        as float64, those of :data:`TEXT_COLUMNS` as str). With ``tolerate_partial`` a malformed last row (a run killed while writing
        it) is dropped instead of raising."""
        path = Path(path)
        with path.open(newline="") as fh:
            reader = csv.reader(fh)
            try:
                header = next(reader)
            except StopIteration:
                raise ValueError(f"{path}: empty pose table") from None
            if tuple(header[: len(BASE_COLUMNS)]) != BASE_COLUMNS:
                raise ValueError(f"{path}: not a pose table (columns must start with frame, the {N_PARAMETERS} "
                                 f"parameters and the joint columns)")
            rows = [r for r in reader if r]
        text = [k for k, name in enumerate(header) if name in TEXT_COLUMNS]
        numeric = [k for k in range(len(header)) if k not in text]
        if tolerate_partial and rows:
            try:
                if len(rows[-1]) != len(header):
                    raise ValueError
                [float(rows[-1][k]) for k in numeric]
            except ValueError:
                rows = rows[:-1]
        if any(len(r) != len(header) for r in rows):
            raise ValueError(f"{path}: malformed pose table (a row has other than {len(header)} fields)")
        try:
            data = np.full((len(rows), len(header)), np.nan)
            data[:, numeric] = np.array([[r[k] for k in numeric] for r in rows], dtype=np.float64).reshape(
                len(rows), len(numeric))
        except ValueError as exc:
            raise ValueError(f"{path}: malformed pose table ({exc})") from None
        poses = data[:, 1:1 + N_PARAMETERS].copy()
        poses[:, 3:] = np.deg2rad(poses[:, 3:])
        j0 = 1 + N_PARAMETERS
        joints = data[:, j0:j0 + len(JOINT_COLUMNS)]
        extra = {name: (np.array([r[k] for r in rows], dtype=str) if k in text else data[:, k])
                 for k, name in enumerate(header) if k >= len(BASE_COLUMNS)}
        return cls(data[:, 0].astype(np.int64), poses, joints, extra)
