"""Is a video whole? What its container announces against what actually decodes.

A cut or damaged file often decodes without any error from the reading library: ffmpeg stops
early, or conceals broken frames, or skips them. :func:`check_video` decodes the video once
with ffmpeg (``showinfo``: the timestamp of every decoded frame) and compares with the
duration and frame rate the container announces; frames that never decode (a gap in the
timestamps, or a file that ends early) and frames the decoder reported errors on (concealed)
come out by number. :func:`ffmpeg_failure` turns ffmpeg's failure output into one sentence.
"""
from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import imageio_ffmpeg

__all__ = ["VideoCheck", "check_video", "ffmpeg_failure", "format_frames"]

_DURATION = re.compile(r"Duration: (\d+):(\d\d):(\d\d(?:\.\d+)?)")
_FPS = re.compile(r"Stream #\d+:\d+.*?: Video: .*?(\d+(?:\.\d+)?)(k?) fps")
_PREFIX = re.compile(r"(?=\[[^\]\n]* @ 0x[0-9a-f]+\])")
_SHOWINFO = re.compile(r"\[Parsed_showinfo[^\]]*\] n:\s*(\d+) pts:\s*(-?\d+) pts_time:(-?[\d.e+-]+)")
#: Log lines of demuxers and decoders that mean the data is damaged (matched lower-cased).
_DAMAGE_WORDS = ("error", "invalid", "corrupt", "concealing", "missing picture", "ended prematurely",
                 "truncat", "exceeds containing")


@dataclass
class VideoCheck:
    """What decoding a video found.

    Attributes
    ----------
    announced_frames : int or None
        Frames the container announces (duration times frame rate, rounded), or None when it
        announces no duration.
    fps : float or None
        Announced frame rate (frames per second).
    decoded : int
        Frames that decoded.
    readable : int
        Frames a reader at the announced rate delivers: up to the last decoded one (gaps are
        filled with the frame before, as :func:`mocap.io.video.iter_frames` does).
    missing : list of int
        Frame numbers (0-based, on the announced frame grid) that did not decode: gaps and the
        frames after an early end.
    corrupt : list of int
        Frame numbers that decoded with errors (the decoder concealed damage in them).
    messages : list of str
        The decoder's own error lines, for a log.
    """

    announced_frames: int | None
    fps: float | None
    decoded: int
    readable: int
    missing: list[int] = field(default_factory=list)
    corrupt: list[int] = field(default_factory=list)
    messages: list[str] = field(default_factory=list)

    @property
    def damaged(self) -> bool:
        """Whether frames are missing or corrupt."""
        return bool(self.missing or self.corrupt)

    @property
    def damaged_frames(self) -> list[int]:
        """Missing and corrupt frame numbers, sorted."""
        return sorted(set(self.missing) | set(self.corrupt))

    def describe(self, path: str | Path) -> str:
        """One sentence on the damage, with the frame numbers."""
        parts = []
        if self.missing:
            parts.append(f"{len(self.missing)} frame(s) do not decode ({format_frames(self.missing)})")
        if self.corrupt:
            parts.append(f"{len(self.corrupt)} frame(s) decode with errors ({format_frames(self.corrupt)})")
        announced = f"{self.announced_frames} announced, " if self.announced_frames is not None else ""
        return f"{path} is damaged: {announced}{self.decoded} decodable; " + "; ".join(parts)


def format_frames(frames: list[int], limit: int = 8) -> str:
    """``"frames 3, 7-9 and 12"``-style text of sorted frame numbers (ranges joined, long lists cut)."""
    runs: list[list[int]] = []
    for f in sorted(frames):
        if runs and f == runs[-1][1] + 1:
            runs[-1][1] = f
        else:
            runs.append([f, f])
    text = [str(a) if a == b else f"{a}-{b}" for a, b in runs]
    if len(text) > limit:
        text = text[:limit] + [f"{len(runs) - limit} more ranges"]
    joined = text[0] if len(text) == 1 else ", ".join(text[:-1]) + " and " + text[-1]
    return f"frame{'s' if len(frames) > 1 else ''} {joined}"


def ffmpeg_failure(path: str | Path, log: str) -> str:
    """One sentence a person understands for ffmpeg's failure output ``log`` on ``path``."""
    path = Path(path)
    low = log.lower()
    if path.is_file() and path.stat().st_size == 0:
        return f"{path} is empty (0 bytes): not a video"
    if "moov atom not found" in low and path.is_file() and b"ftyp" in path.read_bytes()[:12]:
        return (f"{path} is a truncated video: the index at the end of the file is missing (a recording that "
                "was cut off or a copy that did not finish)")
    if "decoder" in low and "not found" in low or "unsupported codec" in low or "no decoder" in low:
        return f"{path} uses a video codec this ffmpeg cannot decode; convert it (for example to H.264)"
    if "could not find codec parameters" in low:
        return f"{path} is a damaged or truncated video: not even its first frame decodes"
    if "does not contain any stream" in low or "matches no streams" in low or "no video stream" in low:
        return f"{path} has no video stream (no frames)"
    if "ended prematurely" in low or "error opening input: end of file" in low \
            or "error opening input: input/output error" in low:
        return f"{path} is a truncated or damaged video: it ends before its first frame"
    if "invalid data found when processing input" in low or "could not load meta information" in low \
            or "moov atom not found" in low:
        return f"{path} is not a video ffmpeg can read (unknown format or a damaged header)"
    if "permission denied" in low:
        return f"{path} cannot be read: permission denied"
    if "could not convert string to float: 'n/a'" in low:     # imageio-ffmpeg's count of a frameless file
        return f"{path} has no video frames"
    first = log.strip().splitlines()[0] if log.strip() else ""
    if first and not low.startswith(("ffmpeg call failed", "could not load meta", "ffmpeg version")):
        return f"{path} could not be decoded as a video ({first})"     # a reader's own one-line reason
    return f"{path} could not be decoded as a video"


#: Frames the decoded video may end short of the container's announced duration times rate
#: without being reported: the duration is rounded (to 10 ms in ffmpeg's report) and may include
#: the last frame's display time (seen: an 87-frame clip at 30 fps announcing 2.93 s, 88 frames).
END_TOLERANCE_FRAMES = 1


def check_video(path: str | Path) -> VideoCheck:
    """Decode a video file once and compare it with what its container announces.

    Parameters
    ----------
    path : str or Path
        A video file.

    Returns
    -------
    VideoCheck

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        With one sentence (:func:`ffmpeg_failure`) if ffmpeg cannot open it, or if no frame
        decodes.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such file: {path}")
    if path.is_file() and path.stat().st_size == 0:
        raise ValueError(ffmpeg_failure(path, ""))
    cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-nostats", "-nostdin", "-v", "info", "-threads", "1", "-i", str(path),
           "-map", "0:v:0", "-vf", "showinfo", "-f", "null", "-"]
    proc = subprocess.run(cmd, capture_output=True, text=True, errors="replace")
    log = proc.stderr
    duration = _DURATION.search(log)
    fps_match = _FPS.search(log)
    fps = None
    if fps_match:
        fps = float(fps_match.group(1)) * (1000.0 if fps_match.group(2) else 1.0)
    times, corrupt, messages = [], [], []
    pending_damage = False
    # ffmpeg's threads may interleave messages on one line: split at every "[name @ 0x...]" prefix
    for message in _PREFIX.split(log):
        shown = _SHOWINFO.match(message)
        if shown:
            times.append(float(shown.group(3)))
            if pending_damage:
                corrupt.append(len(times) - 1)          # provisional: renumbered on the grid below
                pending_damage = False
        elif any(w in message.lower() for w in _DAMAGE_WORDS):
            messages.append(message.strip().splitlines()[0])
            # a decoder's complaint belongs to the next frame it puts out (the demuxer's to none)
            pending_damage = pending_damage or not message.startswith("[in#")
    if not times:
        if proc.returncode != 0 or not fps:
            raise ValueError(ffmpeg_failure(path, log))
        raise ValueError(f"{path} has no video frames")
    start = min(times)          # frame 0 (containers may start their clock elsewhere, e.g. AVI with B-frames)
    announced = None
    if duration and fps:
        seconds = int(duration.group(1)) * 3600 + int(duration.group(2)) * 60 + float(duration.group(3))
        announced = int(round(seconds * fps))
    if fps:
        numbers = [int(round((t - start) * fps)) for t in times]
    else:
        numbers = list(range(len(times)))
    corrupt = sorted({numbers[i] for i in corrupt})
    decoded_end = max(numbers) + 1
    if announced is not None and announced - decoded_end <= END_TOLERANCE_FRAMES:
        announced_end = decoded_end         # a container's duration rounds up by up to a frame (its clock
    else:                                   # in 10 ms steps, the last frame's display time): not a lost frame
        announced_end = announced
    grid = decoded_end if announced_end is None else max(announced_end, decoded_end)
    missing = sorted(set(range(grid)) - set(numbers))
    return VideoCheck(announced, fps, len(set(numbers)), max(numbers) + 1, missing, corrupt, messages)
