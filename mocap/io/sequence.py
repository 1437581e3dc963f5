"""Sequence folders (docs/design.md section 4): frames, background, calibration, ground truth."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class SequencePaths:
    """Where the parts of a sequence folder are (``None`` for parts it lacks)."""

    root: Path
    frames: Path
    background: Path | None
    calibration: Path | None
    ground_truth: Path | None
    meta: Path | None

    def fps(self, default: float = 25.0) -> float:
        """Frame rate from ``meta.json`` (``fps``), else ``default``."""
        if self.meta is not None:
            try:
                fps = float(json.loads(self.meta.read_text()).get("fps", default))
            except (json.JSONDecodeError, TypeError, ValueError):
                return default
            if fps > 0:
                return fps
        return default


def find_sequence(path: str | Path) -> SequencePaths:
    """Describe a sequence folder, or a bare video file / image folder.

    Parameters
    ----------
    path : str or Path
        A folder with ``frames/`` (or ``video.mp4``) and optionally ``background.png``,
        ``calibration.json``, ``ground_truth.csv``, ``meta.json``; or a video file; or a
        folder of images.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"no such video, image folder or sequence: {p}")
    if p.is_file():
        return SequencePaths(p.parent, p, None, None, None, None)
    frames = p / "frames" if (p / "frames").is_dir() else (p / "video.mp4" if (p / "video.mp4").is_file() else p)
    opt = lambda name: (p / name) if (p / name).is_file() else None
    return SequencePaths(p, frames, opt("background.png"), opt("calibration.json"), opt("ground_truth.csv"),
                         opt("meta.json"))
