"""Frame sources: where the tracker's frames come from, files and cameras alike.

A frame source has an input size, a frame rate, a frame count (``None`` for a live camera)
and :meth:`~VideoSource.frames`, an iterator of uint8 RGB frames at the input size. The
tracking run reduces them to its working resolution itself (:mod:`mocap.imaging.resample`),
so a camera and a file go through the same code.

* :class:`VideoSource` — a video file or a folder of images (:func:`mocap.io.video.iter_frames`).
* :class:`CameraSource` — frames streamed by ffmpeg from a capture device
  (``/dev/video0`` through ``v4l2`` on Linux); :meth:`CameraSource.replaying` makes a fake
  camera that streams a video file the same way (for tests and for rehearsing a live run).
"""
from __future__ import annotations

import platform
from collections.abc import Iterator
from pathlib import Path

import imageio_ffmpeg
import numpy as np

from mocap.io.video import count_frames, iter_frames, sample_frames
from mocap.io.video_check import RunningCheck, VideoCheck, announced

__all__ = ["VideoSource", "CameraSource", "camera_device"]


class VideoSource:
    """Frames of a video file or image folder.

    A video file is checked (:class:`mocap.io.video_check.RunningCheck`) by an ffmpeg process
    that decodes it once, alongside whatever reads the frames, started on first need (any of
    :attr:`checked`, :meth:`time_s`, :attr:`count`, :attr:`check`, :meth:`damaged_frames`):
    the frame timestamps come as it goes (:meth:`time_s`), the exact frame count and the damage
    (:attr:`count`, :attr:`check`, :meth:`damaged_frames`) when it has decoded the whole video
    (those wait for it). Opening reads only the container's header (:attr:`count_hint`).

    Parameters
    ----------
    path : str or Path
        Video file (anything ffmpeg decodes) or folder of images.
    fps : float, optional
        Frame rate of an image folder (its frame times are ``index / fps``); default 25.

    Attributes
    ----------
    path : Path
    width, height : int, pixels
        Input frame size (of the first frame).
    fps : float or None
        Announced frame rate of a video file (None for an image folder or an unknown rate).
    count : int
        Number of frames (of a video: waits for the check).
    count_hint : int
        The number of frames if known, else what the container announces (starts the check
        without waiting for it; a damaged file may hold fewer).
    check : VideoCheck or None
        What decoding the video found (None for an image folder; waits for the check).
    checked : bool
        Whether the check has ended (:attr:`check` does not wait); starts it.
    live : bool
        False: the frames can be read again (the run re-reads them for the overlay video).
    """

    live = False

    def __init__(self, path: str | Path, fps: float | None = None) -> None:
        self.path = Path(path)
        self._running: RunningCheck | None = None
        self._check: VideoCheck | None = None
        self._count: int | None = None
        self._video = not (self.path.is_dir() or not self.path.exists())
        if not self._video:
            self._count = count_frames(self.path)
            self.fps = None
            self._announced = self._count
        else:
            self._announced, self.fps = announced(self.path)
            if self._announced is None:          # nothing announced: the count is the check's
                self._announced = self.count
        first = next(iter_frames(self.path, 0, 1), None) if self._announced else None
        if first is None:
            if self._video:
                self.check                          # ffmpeg's own reason, when it has one
            raise ValueError(f"{self.path} has no frames" if not self._announced else
                             f"{self.path} has no decodable frame")
        self.height, self.width = first.shape[:2]
        self._folder_fps = fps or 25.0

    @property
    def name(self) -> str:
        return str(self.path)

    def _checking(self) -> RunningCheck:
        """The check, started on first need (for ``track``: the set-up's :attr:`count_hint`)."""
        if self._running is None:
            self._running = RunningCheck(self.path)
        return self._running

    @property
    def check(self) -> VideoCheck | None:
        if self._video and self._check is None:
            self._check = self._checking().result()
        return self._check

    @property
    def checked(self) -> bool:
        return not self._video or self._checking().done

    @property
    def count(self) -> int:
        if self._count is None:
            self._count = self.check.decoded
        return self._count

    @property
    def count_hint(self) -> int:
        return self.count if self.checked else self._announced

    def close(self) -> None:
        """Stop the check's ffmpeg if it still runs (safe to call twice)."""
        if self._running is not None:
            self._running.close()

    def frames(self, start: int = 0, stop: int | None = None, *, indices=None) -> Iterator[np.ndarray]:
        """Frames ``start`` to ``stop`` (exclusive), or only the sorted ``indices`` among them,
        uint8 RGB, shape (height, width, 3) (:func:`mocap.io.video.iter_frames`)."""
        return iter_frames(self.path, start, stop, indices=indices)

    def sample(self, count: int, stop: int, reduce) -> list:
        """Up to ``count`` frames spread over frames ``0`` to ``stop - 1``, each passed through
        ``reduce`` as it is read; a long video's are its key frames, read without decoding the
        frames between them (:func:`mocap.io.video.sample_frames`)."""
        return sample_frames(self.path, count, stop, reduce, fps=self.fps)

    def damaged_frames(self, allow: bool = False) -> list[int]:
        """The frame numbers of a damaged video (:class:`mocap.io.video_check.VideoCheck`),
        empty for an intact one or an image folder.

        Raises
        ------
        ValueError
            The video is damaged and ``allow`` is false (one sentence with the frame numbers).
        """
        if self.check is None or not self.check.damaged:
            return []
        if not allow:
            raise ValueError(f"{self.check.describe(self.path)}; to use the frames that decode anyway, "
                             "add --allow-damaged")
        return self.check.damaged_frames

    def time_s(self, index: int) -> float:
        """Time of frame ``index``, seconds from the first frame: a video frame's own timestamp,
        an image folder's ``index / fps``."""
        if not self._video:
            return index / self._folder_fps
        return self._checking().time_s(index)


def camera_device(index: int) -> tuple[str, list[str]]:
    """ffmpeg input (device name, input options) of capture device ``index`` on this system."""
    if isinstance(index, bool) or not isinstance(index, int) or index < 0:
        raise ValueError(f"camera index must be a non-negative integer, got {index!r}")
    system = platform.system()
    if system == "Linux":
        return f"/dev/video{index}", ["-f", "v4l2"]
    if system == "Darwin":
        return f"{index}:none", ["-f", "avfoundation", "-framerate", "30"]
    if system == "Windows":
        return f"video={index}", ["-f", "dshow"]
    raise ValueError(f"no known camera input for {system}")


class CameraSource:
    """Frames streamed live by ffmpeg from a capture device (or a file standing in for one).

    Frames are read once, as they come; there is no frame count and no going back.

    Parameters
    ----------
    device : str
        ffmpeg input name (``/dev/video0``, or a video file for :meth:`replaying`).
    input_params : list of str
        ffmpeg options placed before ``-i`` (``["-f", "v4l2"]``).
    name : str, optional
        What to call the source in messages and ``run.json``.

    Attributes
    ----------
    width, height : int, pixels
    fps : float or None
    count : None
    live : bool
        True.
    real_time : bool
        The frames come whether they are read or not (a capture device): a run takes the newest
        and drops the ones it is too slow for (:func:`mocap.io.prefetch.newest`). False for a
        file replayed as a camera (:meth:`replaying`): its frames wait to be read, none is
        dropped, so a rehearsal tracks every frame.

    Raises
    ------
    ValueError
        If ffmpeg cannot open the device (one line with ffmpeg's reason).
    """

    live = True
    count = None

    def __init__(self, device: str, input_params: list[str] | None = None, *, name: str | None = None,
                 real_time: bool = True) -> None:
        self.device, self.real_time = device, real_time
        self.input_params = list(input_params or [])
        self._name = name or device
        self._reader = imageio_ffmpeg.read_frames(device, input_params=self.input_params, pix_fmt="rgb24")
        try:
            meta = next(self._reader)
        except (RuntimeError, OSError, StopIteration) as exc:
            reason = str(exc).strip().splitlines()[-1] if str(exc).strip() else type(exc).__name__
            raise ValueError(f"cannot open {self._name}: {reason}") from None
        self.width, self.height = (int(v) for v in meta["size"])
        fps = meta.get("fps")
        self.fps = float(fps) if fps and np.isfinite(fps) and fps > 0 else None
        self._held: list[np.ndarray] = []

    def hold(self, frames: list[np.ndarray]) -> None:
        """Frames already read (by calibration) that :meth:`frames` gives again first."""
        self._held = list(frames)

    @classmethod
    def open(cls, index: int) -> "CameraSource":
        """Capture device ``index`` (0 = the first webcam)."""
        device, params = camera_device(index)
        return cls(device, params, name=f"webcam {index} ({device})")

    @classmethod
    def from_device(cls, device: str) -> "CameraSource":
        """A capture device by its ffmpeg name (``/dev/video2``; ``video=NAME`` on Windows), or a
        video file streamed as a fake camera."""
        if Path(device).is_file():
            return cls.replaying(device)
        system = platform.system()
        params = {"Linux": ["-f", "v4l2"], "Darwin": ["-f", "avfoundation"], "Windows": ["-f", "dshow"]}.get(system, [])
        return cls(device, params, name=f"camera device {device}")

    @classmethod
    def replaying(cls, path: str | Path) -> "CameraSource":
        """A fake camera that streams the frames of a video file, as a live camera would."""
        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"no such video file: {path}")
        return cls(str(path), [], name=f"fake camera replaying {path}", real_time=False)

    @property
    def name(self) -> str:
        return self._name

    def frames(self, start: int = 0, stop: int | None = None) -> Iterator[np.ndarray]:
        """The frames as they arrive (uint8 RGB, shape (height, width, 3)), read once: the
        first ``start`` are skipped and the stream ends after frame ``stop - 1`` or when the
        device closes."""
        shape = (self.height, self.width, 3)
        index = 0
        held, self._held = self._held, []
        for frame in held:
            if stop is not None and index >= stop:
                return
            if index >= start:
                yield frame
            index += 1
        for data in self._reader:
            if stop is not None and index >= stop:
                break
            if index >= start:
                yield np.frombuffer(data, np.uint8).reshape(shape).copy()
            index += 1

    def close(self) -> None:
        """Stop ffmpeg (safe to call twice)."""
        self._reader.close()
