"""Is a video whole? Every frame it holds, with its own timestamp, and the damage found.

Cameras record with a variable frame rate, leave gaps in the timestamps and sometimes give
two frames one timestamp: none of that is damage, every decoded frame is a frame (the readers
of :mod:`mocap.io.video` deliver each decoded frame once, ``-fps_mode passthrough``).
Damage is what does not decode: packets the demuxer or the decoder reports as broken, and a
file that ends before the end its container announces (a cut or unfinished copy).

:func:`check_video` decodes the video once with ffmpeg (``showinfo``: the timestamp of every
decoded frame) and reports, by frame number in decoding order, the frames that decoded with
errors or after lost data, and the frames lost after an early end.
:func:`ffmpeg_failure` turns ffmpeg's failure output into one sentence.
"""
from __future__ import annotations

import os
import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import imageio_ffmpeg

__all__ = ["VideoCheck", "RunningCheck", "announced", "check_video", "ffmpeg_failure", "format_frames",
           "parse_check_log"]

#: Niceness of the running check's ffmpeg (POSIX): it decodes the whole clip beside the run and
#: takes the CPU the set-up and the tracker leave (on two cores it used to slow the first frame).
CHECK_NICENESS = 10
_DURATION = re.compile(r"Duration: (\d+):(\d\d):(\d\d(?:\.\d+)?)")
_FPS = re.compile(r"Stream #\d+:\d+.*?: Video: .*?(\d+(?:\.\d+)?)(k?) fps")
_PREFIX = re.compile(r"(?=\[[^\]\n]* @ 0x[0-9a-f]+\])")
_SHOWINFO_PREFIX = "[Parsed_showinfo"
_SHOWINFO = re.compile(r"\[Parsed_showinfo[^\]]*\] n:\s*(\d+) pts:\s*(-?\d+) pts_time:(-?[\d.e+-]+)")
#: Prefixes of the log lines of ffmpeg's output side (the null muxer's complaints about repeated
#: timestamps are about the input's timing, not damage).
_OUTPUT_SIDE = ("[null @", "[out#", "[vost#", "[enc:", "[vf#", "[Parsed_", "[fc#")
#: Log lines of demuxers and decoders that mean the data is damaged (matched lower-cased).
_DAMAGE_WORDS = ("error", "invalid", "corrupt", "concealing", "missing picture", "ended prematurely",
                 "truncat", "exceeds containing", "partial file")
#: Complaints of the output side (the null muxer's about repeated timestamps: the input's timing,
#: not damage) that may come glued to a showinfo line without their prefix (matched lower-cased).
_OUTPUT_SIDE_WORDS = ("non monoton",)


def _is_damage(line: str) -> bool:
    """Whether a log line (or a message glued into one) says the data is damaged."""
    low = line.lower()
    return any(w in low for w in _DAMAGE_WORDS) and not any(w in low for w in _OUTPUT_SIDE_WORDS)


@dataclass
class VideoCheck:
    """What decoding a video found.

    Attributes
    ----------
    announced_frames : int or None
        Frames the container's duration at its announced frame rate stands for (rounded), or
        None when it announces no duration or rate.
    fps : float or None
        Announced (average) frame rate, frames per second.
    times : list of float, seconds
        Timestamp of every decoded frame, in decoding order, from the first frame's (0.0): a
        variable frame rate, gaps and repeated timestamps kept as they are.
    corrupt : list of int
        Frame numbers (0-based, decoding order) that decoded with errors or right after data
        the demuxer or decoder could not read (a frame lost before them).
    missing : list of int
        Frames lost after an early end: from the first frame that never came to the end the
        container announces (numbered at the announced frame rate).
    messages : list of str
        The demuxer's and decoder's own error lines, for a log.
    """

    announced_frames: int | None
    fps: float | None
    times: list[float] = field(default_factory=list)
    corrupt: list[int] = field(default_factory=list)
    missing: list[int] = field(default_factory=list)
    messages: list[str] = field(default_factory=list)

    @property
    def decoded(self) -> int:
        """Frames that decoded (and that a reader delivers)."""
        return len(self.times)

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
            parts.append(f"it ends early: {len(self.missing)} frame(s) do not decode ({format_frames(self.missing)})")
        if self.corrupt:
            parts.append(f"{len(self.corrupt)} frame(s) decode with errors or after lost data "
                         f"({format_frames(self.corrupt)})")
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


#: How much earlier than its container announces a video may end without being taken as cut
#: (seconds, and frame intervals at the announced rate; the larger counts): durations are
#: rounded, and include the other streams (a phone's sound often outlasts its pictures).
END_TOLERANCE_S = 0.5
END_TOLERANCE_FRAMES = 3
#: Demuxer words that mean the file ends before its data does (matched lower-cased).
_EARLY_END_WORDS = ("ended prematurely", "truncat", "partial file", "end of file")


#: A gap between timestamps this many times the typical interval (the median) is where a frame
#: was lost, when the demuxer or decoder reported damage (and only then: cameras leave gaps).
LOST_FRAME_GAP = 1.5


def _after_gaps(times: list[float]) -> list[int]:
    """Frame numbers that follow a gap in ``times`` (seconds) longer than :data:`LOST_FRAME_GAP`
    typical intervals."""
    steps = [b - a for a, b in zip(times, times[1:])]
    positive = sorted(d for d in steps if d > 0)
    if not positive:
        return []
    typical = positive[len(positive) // 2]
    return [k + 1 for k, d in enumerate(steps) if d > LOST_FRAME_GAP * typical]


def check_video(path: str | Path) -> VideoCheck:
    """Decode a video file once: every frame's timestamp, and the damage.

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
    return RunningCheck(path).result()


class RunningCheck:
    """:func:`check_video` running on ffmpeg's own process while the caller goes on.

    The frames' timestamps come in as ffmpeg decodes (:meth:`time_s` waits for the one
    asked for); the damage is known when the whole video is decoded (:meth:`result`).
    The process runs ahead of any tracker (decoding only), holds no frames and stops with
    :meth:`close`.

    Parameters
    ----------
    path : str or Path
        A video file.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        If it is an empty file.
    """

    def __init__(self, path: str | Path) -> None:
        import threading

        self.path = Path(path)
        if not self.path.exists():
            raise FileNotFoundError(f"no such file: {self.path}")
        if self.path.is_file() and self.path.stat().st_size == 0:
            raise ValueError(ffmpeg_failure(self.path, ""))
        # showinfo without its per-plane checksums (a quarter of the decoding's CPU time at 720p)
        cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-nostats", "-nostdin", "-v", "info",
               "-i", str(self.path), "-map", "0:v:0", "-vf", "showinfo=checksum=0", "-fps_mode", "passthrough",
               "-f", "null", "-"]
        self._proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.PIPE, text=True, errors="replace")
        if hasattr(os, "setpriority"):      # behind what the run waits for (the set-up's reads, the tracker)
            try:
                os.setpriority(os.PRIO_PROCESS, self._proc.pid, CHECK_NICENESS)
            except OSError:
                pass
        self._lines: list[str] = []
        self._pts: list[float] = []             # pts_time of frames 0, 1, ... as they come
        self._result: VideoCheck | Exception | None = None
        self._changed = threading.Condition()
        self._thread = threading.Thread(target=self._read, name="mocap-video-check", daemon=True)
        self._thread.start()

    def _read(self) -> None:
        for line in self._proc.stderr:
            self._lines.append(line)
            shown = [float(m.group(3)) for m in _SHOWINFO.finditer(line)]
            if shown:
                with self._changed:
                    self._pts.extend(shown)
                    self._changed.notify_all()
        self._proc.wait()
        try:
            result: VideoCheck | Exception = parse_check_log(self.path, "".join(self._lines), self._proc.returncode)
        except ValueError as exc:
            result = exc
        with self._changed:
            self._result = result
            self._changed.notify_all()

    @property
    def done(self) -> bool:
        """Whether the whole video is decoded (:meth:`result` does not wait)."""
        return self._result is not None

    def result(self) -> VideoCheck:
        """The whole check (waits for the end of the decoding).

        Raises
        ------
        ValueError
            As :func:`check_video`.
        """
        with self._changed:
            self._changed.wait_for(lambda: self._result is not None)
        if isinstance(self._result, Exception):
            raise self._result
        return self._result

    def time_s(self, index: int) -> float:
        """Timestamp of decoded frame ``index``, seconds from frame 0 (waits until ffmpeg has
        decoded it).

        Raises
        ------
        ValueError
            The video has no frame ``index``, or the check failed (as :func:`check_video`).
        """
        with self._changed:
            self._changed.wait_for(lambda: len(self._pts) > index or self._result is not None)
            if len(self._pts) > index:
                return self._pts[index] - self._pts[0]
        check = self.result()
        if index >= check.decoded:
            raise ValueError(f"{self.path} has {check.decoded} decodable frames, no frame {index}")
        return check.times[index]

    def close(self) -> None:
        """Stop ffmpeg (safe to call twice, and after the end)."""
        if self._proc.poll() is None:
            self._proc.kill()
        self._thread.join()


def announced(path: str | Path) -> tuple[int | None, float | None]:
    """(frames, frame rate) a video file's container announces, from its header without
    decoding (the frames rounded from its duration); None for what it does not say or a file
    ffmpeg cannot open (:func:`check_video` says why)."""
    cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-nostdin", "-i", str(path)]
    log = subprocess.run(cmd, capture_output=True, text=True, errors="replace").stderr   # exits 1: no output
    duration, fps = _DURATION.search(log), _announced_fps(log)
    if not (duration and fps):
        return None, fps
    return int(round(_seconds(duration) * fps)), fps


def _announced_fps(log: str) -> float | None:
    """The video stream's announced frame rate in ffmpeg's log, or None."""
    match = _FPS.search(log)
    if not match:
        return None
    return float(match.group(1)) * (1000.0 if match.group(2) else 1.0)


def _seconds(duration: re.Match) -> float:
    """Seconds of an ffmpeg ``Duration: HH:MM:SS.ss`` match."""
    return int(duration.group(1)) * 3600 + int(duration.group(2)) * 60 + float(duration.group(3))


def parse_check_log(path: str | Path, log: str, returncode: int = 0) -> VideoCheck:
    """The :class:`VideoCheck` of ffmpeg's whole ``showinfo`` log of ``path`` (what
    :class:`RunningCheck` reads from ffmpeg's standard error; ``returncode`` is ffmpeg's exit status).

    Raises
    ------
    ValueError
        As :func:`check_video`, when no frame decoded.
    """
    path = Path(path)
    duration = _DURATION.search(log)
    fps = _announced_fps(log)
    times, corrupt, messages = [], [], []
    pending_damage = ended_early = False
    # ffmpeg's threads may interleave messages on one line: split at every "[name @ 0x...]" prefix.
    # ffmpeg prints a prefix only at the start of a line, and showinfo writes its line in pieces:
    # a demuxer's or decoder's message that comes between two pieces is glued, without its own
    # prefix, to a showinfo line (whose own text has no damage words), so those are read too.
    for message in _PREFIX.split(log):
        shown = _SHOWINFO.match(message)
        if shown:
            times.append(float(shown.group(3)))
            if pending_damage:
                corrupt.append(len(times) - 1)
                pending_damage = False
        if message.startswith(_OUTPUT_SIDE) and not message.startswith(_SHOWINFO_PREFIX):
            continue
        damage = [line.strip() for line in message.splitlines() if _is_damage(line)]
        if damage:
            messages.append(damage[0])
            if any(w in message.lower() for w in _EARLY_END_WORDS):
                ended_early = True
            else:
                pending_damage = True       # belongs to the next frame put out (data lost before it)
    if not times:
        if returncode != 0 or not fps:
            raise ValueError(ffmpeg_failure(path, log))
        raise ValueError(f"{path} has no video frames")
    start = times[0]            # frame 0 (containers may start their clock elsewhere, e.g. AVI with B-frames)
    times = [t - start for t in times]
    announced = None
    if duration and fps:
        seconds = _seconds(duration)
        announced = int(round(seconds * fps))
        interval = 1.0 / fps
        end = max(times) + interval
        if seconds - end > max(END_TOLERANCE_S, END_TOLERANCE_FRAMES * interval):
            ended_early = True
    if pending_damage and not ended_early:
        corrupt.append(len(times) - 1)          # damage after the last frame put out
    lost_before = _after_gaps(times) if (corrupt and len(times) > 2) else []
    if lost_before:
        # ffmpeg demuxes and decodes on threads of their own: its complaints come out of order
        # with the frames; the frames that follow a gap in the timestamps are where data was lost
        corrupt = lost_before
    missing = list(range(len(times), max(announced or 0, len(times) + 1))) if ended_early else []
    return VideoCheck(announced, fps, times, sorted(set(corrupt)), missing, messages)
