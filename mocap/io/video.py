"""Frames in and out: images, video files and folders of images, as uint8 RGB.

Reading goes through imageio v3 (its Pillow plugin for images) and imageio-ffmpeg (videos:
every decoded frame once, ``-fps_mode passthrough``); writing a video streams frames to ffmpeg
through imageio-ffmpeg. Every failure on bad input is a
``FileNotFoundError`` (missing path) or a ``ValueError`` with a one-line reason (corrupt file,
unsupported channels or dtype, frames of different sizes), never a crash deep in a decoder.
"""
from __future__ import annotations

import queue
import threading
from collections.abc import Iterator
from pathlib import Path

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np

from mocap.io.video_check import ffmpeg_failure

__all__ = ["IMAGE_SUFFIXES", "read_image", "iter_frames", "sample_frames", "spread_numbers", "count_frames",
           "frame_rate", "image_files", "VideoWriter"]

#: x264's speed presets, fastest first (:class:`VideoWriter`).
X264_PRESETS: tuple[str, ...] = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower",
                                 "veryslow")
#: Suffixes (lower case) of the image files a frame folder may hold.
IMAGE_SUFFIXES: tuple[str, ...] = (".png", ".jpg", ".jpeg")
# What decoders raise on a corrupt or unsupported file (Pillow raises SyntaxError on a
# broken PNG; imageio raises OSError when no plugin can open the file).
_DECODE_ERRORS = (OSError, ValueError, SyntaxError, RuntimeError, EOFError, KeyError, IndexError)


def _check_exists(path: Path) -> None:
    if not path.exists():
        raise FileNotFoundError(f"no such file or folder: {path}")


def _to_rgb_uint8(image: np.ndarray, source: str, allow_gray: bool) -> np.ndarray:
    """Convert a decoded image to uint8 RGB (H, W, 3) or raise ValueError."""
    if image.ndim == 4:
        raise ValueError(f"{source} holds {image.shape[0]} images; expected a single image")
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] not in (1, 2, 3, 4)):
        raise ValueError(f"{source} has unsupported shape {image.shape}; expected an RGB image")
    if image.dtype == np.uint8:
        data = image
    elif image.dtype == np.uint16:
        data = np.round(image / 257.0).astype(np.uint8)
    elif image.dtype == np.bool_:
        data = image.astype(np.uint8) * 255
    elif image.dtype.kind == "f" and image.size and np.isfinite(image).all() \
            and image.min() >= 0.0 and image.max() <= 1.0:
        data = np.round(image * 255.0).astype(np.uint8)
    else:
        raise ValueError(f"{source} has unsupported sample type {image.dtype}")
    if data.ndim == 3 and data.shape[2] in (2, 4):
        alpha = data[..., -1]
        if alpha.min() < 255:
            raise ValueError(f"{source} has transparent pixels; flatten it onto an opaque "
                             "background first")
        data = data[..., :-1]
    if data.ndim == 2 or data.shape[2] == 1:
        if not allow_gray:
            raise ValueError(f"{source} is a grayscale image; an RGB image is needed (colour "
                             "classes need colour)")
        data = np.repeat(data.reshape(data.shape[0], data.shape[1], 1), 3, axis=2)
    return np.ascontiguousarray(data)


def read_image(path: str | Path, *, allow_gray: bool = False) -> np.ndarray:
    """Read one image file as RGB.

    Parameters
    ----------
    path : str or Path
        PNG, JPEG or any other format Pillow reads.
    allow_gray : bool
        Accept a grayscale image by replicating its channel (off by default: a grayscale
        background for a colour video would silently mark everything as foreground).

    Returns
    -------
    ndarray of uint8, shape (H, W, 3)
        RGB, 0-255. 16-bit images are rounded to 8 bits; an RGBA image whose alpha is fully
        opaque loses its alpha channel.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        If the file is a folder, corrupt or not an image, holds several images, has
        transparent pixels, is grayscale (unless ``allow_gray``) or an unsupported sample type.
    """
    path = Path(path)
    _check_exists(path)
    if path.is_dir():
        raise ValueError(f"{path} is a folder, not an image file")
    try:
        image = iio.imread(path, plugin="pillow")
    except _DECODE_ERRORS as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"cannot read image {path}: corrupt or unsupported file ({reason})") \
            from None
    return _to_rgb_uint8(np.asarray(image), str(path), allow_gray)


def image_files(folder: str | Path) -> list[Path]:
    """Sorted image files (:data:`IMAGE_SUFFIXES`) of a frame folder; ValueError if none."""
    folder = Path(folder)
    _check_exists(folder)
    files = sorted(p for p in folder.iterdir()
                   if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise ValueError(f"folder {folder} holds no {'/'.join(IMAGE_SUFFIXES)} images")
    return files


def _check_range(start: int, stop: int | None) -> None:
    if isinstance(start, bool) or not isinstance(start, (int, np.integer)) or start < 0:
        raise ValueError(f"start must be a non-negative integer, got {start!r}")
    if stop is not None and (isinstance(stop, bool) or not isinstance(stop, (int, np.integer))
                             or stop < start):
        raise ValueError(f"stop must be an integer >= start ({start}) or None, got {stop!r}")


def iter_frames(source: str | Path, start: int = 0, stop: int | None = None, *,
                indices=None) -> Iterator[np.ndarray]:
    """Frames ``start`` (inclusive) to ``stop`` (exclusive) of a video or a folder of images.

    A video's frames are every frame it decodes to, once each, in decoding order (a variable
    frame rate, gaps and repeated timestamps as recorded: :mod:`mocap.io.video_check`).

    Parameters
    ----------
    source : str or Path
        A video file (any format ffmpeg decodes) or a folder of images (sorted by name,
        :data:`IMAGE_SUFFIXES`).
    start, stop : int
        Frame range, 0-based; ``stop=None`` reads to the end. Past the end yields nothing.
    indices : sequence of int, optional
        Only these frames (sorted, unique, within the range): a video's other frames are
        dropped inside ffmpeg (``select``), never converted or copied.

    Yields
    ------
    ndarray of uint8, shape (H, W, 3)
        RGB frames, all of the same size.

    Raises
    ------
    FileNotFoundError
        If ``source`` does not exist.
    ValueError
        If the video cannot be decoded (also in the middle), a folder image is unreadable,
        or folder images differ in size.
    """
    source = Path(source)
    _check_range(start, stop)
    _check_exists(source)
    wanted = None
    if indices is not None:
        wanted = sorted({int(i) for i in indices if i >= start and (stop is None or i < stop)})
        if not wanted:
            return
        start, stop = wanted[0], wanted[-1] + 1
    if source.is_dir():
        files = image_files(source)
        numbers = range(start, min(len(files), stop if stop is not None else len(files))) if wanted is None \
            else [i for i in wanted if i < len(files)]
        first_shape = None
        for i in numbers:
            frame = read_image(files[i])
            if first_shape is None:
                first_shape = frame.shape
            elif frame.shape != first_shape:
                raise ValueError(f"{files[i]} is {frame.shape[1]}x{frame.shape[0]} but the first frame "
                                 f"is {first_shape[1]}x{first_shape[0]}")
            yield frame
        return
    output = ["-map", "0:v:0", "-fps_mode", "passthrough"]
    chosen = None           # frames ffmpeg delivers (it selects them: the others are never converted)
    if wanted is not None:
        expression = _select_expression(wanted)
        if expression is None:           # too irregular for one expression: a range, the rest skipped here
            expression = f"between(n,{wanted[0]},{wanted[-1]})"
            chosen = range(wanted[0], wanted[-1] + 1)
        output += ["-vf", f"select='{expression}'", "-frames:v", str(len(chosen or wanted))]
    elif start > 0 or stop is not None:
        output += ["-vf", f"select='between(n,{start},{(stop if stop is not None else 2 ** 62) - 1})'"]
        if stop is not None:
            output += ["-frames:v", str(stop - start)]      # ffmpeg stops there instead of decoding on
    numbers = iter(chosen or wanted or range(start, stop if stop is not None else 2 ** 62))
    keep = None if chosen is None else set(wanted)
    reader = None
    try:
        reader = imageio_ffmpeg.read_frames(str(source), output_params=output)
        meta = next(reader)
        width, height = (int(v) for v in meta["size"])
        for data, index in zip(reader, numbers):
            frame = np.frombuffer(data, np.uint8)
            if frame.size != width * height * 3:
                raise ValueError(f"frame {index} has {frame.size} bytes, not {width}x{height}x3")
            if keep is None or index in keep:
                yield frame.reshape(height, width, 3)
            if stop is not None and index >= stop - 1:
                break
    except _DECODE_ERRORS as exc:
        raise ValueError(ffmpeg_failure(source, str(exc))) from None
    finally:
        if reader is not None:
            reader.close()


def spread_numbers(start: int, stop: int, count: int) -> list[int]:
    """Up to ``count`` frame numbers spread evenly over ``start`` to ``stop - 1`` (sorted, unique)."""
    if stop <= start:
        return []
    return sorted({int(i) for i in np.linspace(start, stop - 1, min(count, stop - start)).round()})


#: A video with at most this many frames (before the sample's ``stop``) times the sample's size
#: is sampled by number, decoding every frame up to the last chosen one (as cheap as seeking there).
SAMPLE_BY_NUMBER_RATIO = 4


def sample_frames(source: str | Path, count: int, stop: int, reduce, *, fps: float | None = None) -> list[np.ndarray]:
    """Up to ``count`` frames spread over frames ``0`` to ``stop - 1``, each passed through
    ``reduce`` as it is read, without decoding every frame of a long video.

    A folder of images, and a video of at most :data:`SAMPLE_BY_NUMBER_RATIO` times ``count``
    frames (or of unknown frame rate), give the frames chosen by number
    (:func:`spread_numbers`, :func:`iter_frames`). A longer video gives its key frames among the
    first ``stop / fps`` seconds, decoded alone (ffmpeg's ``-skip_frame nokey``: the other
    frames' packets are read and dropped, never decoded), ``count`` of them spread by order when
    there are more; when there are fewer (an encoder that puts one every 10 s), the rest are
    the first frames of the video after the first, every second one (its first seconds). The frames come in no
    particular order.

    Parameters
    ----------
    source : str or Path
        Video file or folder of images.
    count : int
        Frames wanted (> 0).
    stop : int
        Frames from ``stop`` on are not sampled (for a video's key frames: ``stop / fps``
        seconds).
    reduce : callable
        Applied to each frame (uint8 RGB, shape (H, W, 3), input size) as it is read: at most
        one input-size frame is held, and the reduced key frames until they are chosen.
    fps : float, optional
        The video's frame rate (frames per second); None: sampled by number.

    Returns
    -------
    list
        ``reduce``'s results, at most ``count``.

    Raises
    ------
    FileNotFoundError, ValueError
        As :func:`iter_frames`.
    """
    if count <= 0:
        raise ValueError(f"count must be positive, got {count}")
    source = Path(source)
    _check_exists(source)
    if source.is_dir() or not fps or stop <= SAMPLE_BY_NUMBER_RATIO * count:
        return [reduce(frame) for frame in iter_frames(source, indices=spread_numbers(0, stop, count))]
    keys = []
    reader = None
    try:
        reader = imageio_ffmpeg.read_frames(str(source), input_params=["-skip_frame", "nokey", "-t", f"{stop / fps:.6f}"],
                                            output_params=["-map", "0:v:0", "-fps_mode", "passthrough"])
        meta = next(reader)
        width, height = (int(v) for v in meta["size"])
        for data in reader:
            frame = np.frombuffer(data, np.uint8)
            if frame.size != width * height * 3:
                raise ValueError(f"a key frame has {frame.size} bytes, not {width}x{height}x3")
            keys.append(reduce(frame.reshape(height, width, 3)))
    except _DECODE_ERRORS as exc:
        raise ValueError(ffmpeg_failure(source, str(exc))) from None
    finally:
        if reader is not None:
            reader.close()
    if len(keys) >= count:
        return [keys[i] for i in spread_numbers(0, len(keys), count)]
    rest = count - len(keys)           # frame 0 is a key frame: the others from frame 1 on
    first = [reduce(frame) for frame in iter_frames(source, indices=range(1, 2 * rest + 1, 2))]
    return keys + first


#: Most terms of an ffmpeg ``select`` expression (ffmpeg refuses expressions much longer).
MAX_SELECT_TERMS = 100


def _select_expression(numbers: list[int]) -> str | None:
    """An ffmpeg ``select`` expression true for the sorted frame ``numbers`` (runs of equal steps
    as one term each), or None when it would take more than :data:`MAX_SELECT_TERMS` terms."""
    terms, i = [], 0
    while i < len(numbers):
        j = i + 1
        if j < len(numbers):
            step = numbers[j] - numbers[i]
            while j + 1 < len(numbers) and numbers[j + 1] - numbers[j] == step:
                j += 1
            if j - i >= 2:       # three or more at one step
                terms.append(f"between(n,{numbers[i]},{numbers[j]})*not(mod(n-{numbers[i]},{step}))")
                i = j + 1
                continue
        terms.append(f"eq(n,{numbers[i]})")
        i += 1
        if len(terms) > MAX_SELECT_TERMS:
            return None
    return "+".join(terms) if len(terms) <= MAX_SELECT_TERMS else None


def count_frames(source: str | Path) -> int:
    """Number of frames of a video file (decoded exactly by ffmpeg) or image folder."""
    source = Path(source)
    _check_exists(source)
    if source.is_dir():
        return len(image_files(source))
    try:
        n, _ = imageio_ffmpeg.count_frames_and_secs(str(source))
    except _DECODE_ERRORS as exc:
        raise ValueError(ffmpeg_failure(source, str(exc))) from None
    return int(n)


def frame_rate(source: str | Path) -> float | None:
    """Frames per second of a video file, or None (image folders, unknown rate)."""
    source = Path(source)
    _check_exists(source)
    if source.is_dir():
        return None
    try:
        fps = iio.immeta(source, plugin="FFMPEG").get("fps")
    except _DECODE_ERRORS as exc:
        raise ValueError(ffmpeg_failure(source, str(exc))) from None
    return float(fps) if fps and np.isfinite(fps) and fps > 0 else None


class VideoWriter:
    """Write uint8 RGB frames to an H.264 MP4 (or any ffmpeg format) one at a time.

    Frames are padded with black to even sizes (yuv420p needs them); all frames must have
    the size of the first. Use as a context manager::

        with VideoWriter("out.mp4", fps=10) as video:
            for frame in frames:
                video.write(frame)

    A frame is copied and handed to a thread that feeds ffmpeg (at most :data:`FRAMES_AHEAD`
    waiting), so that the caller goes on while the encoder works; an encoder's failure is
    raised by the next ``write`` or by ``close``.

    Parameters
    ----------
    path : str or Path
        Output file; its folder must exist.
    fps : float
        Frames per second (> 0).
    preset : str
        x264's speed preset (``ultrafast`` ... ``veryslow``; default ``medium``, x264's own):
        a faster one encodes the same pictures with less CPU into a larger file.
    """

    #: Frames that may wait for the encoder before ``write`` blocks.
    FRAMES_AHEAD = 4

    def __init__(self, path: str | Path, fps: float, *, preset: str = "medium") -> None:
        if not fps > 0:
            raise ValueError(f"fps must be > 0, got {fps}")
        if preset not in X264_PRESETS:
            raise ValueError(f"unknown x264 preset {preset!r}; known: {', '.join(X264_PRESETS)}")
        self.path = Path(path)
        if not self.path.parent.is_dir():
            raise FileNotFoundError(f"folder {self.path.parent} does not exist")
        self.fps = float(fps)
        self.preset = preset
        self._writer = None
        self._queue: queue.Queue | None = None
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None
        self._shape: tuple[int, ...] | None = None
        self.frames = 0

    def write(self, frame: np.ndarray) -> None:
        """Append one frame: uint8 RGB, shape (H, W, 3) (copied: the caller may reuse it)."""
        frame = np.asarray(frame)
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
            raise ValueError(f"video frames must be uint8 (H, W, 3), got {frame.dtype} "
                             f"{frame.shape}")
        self._raise_failure()
        if self._shape is None:
            self._shape = frame.shape
            h, w = frame.shape[0] + frame.shape[0] % 2, frame.shape[1] + frame.shape[1] % 2
            self._writer = imageio_ffmpeg.write_frames(
                str(self.path), (w, h), fps=self.fps, codec="libx264", pix_fmt_out="yuv420p",
                macro_block_size=1, quality=7,
                output_params=[] if self.preset == "medium" else ["-preset", self.preset])
            self._writer.send(None)
            self._queue = queue.Queue(maxsize=self.FRAMES_AHEAD)
            self._thread = threading.Thread(target=self._feed, name="video-writer", daemon=True)
            self._thread.start()
        elif frame.shape != self._shape:
            raise ValueError(f"frame {self.frames} has shape {frame.shape}, the first "
                             f"{self._shape}")
        pad = ((0, frame.shape[0] % 2), (0, frame.shape[1] % 2), (0, 0))
        self._queue.put(np.ascontiguousarray(np.pad(frame, pad)))
        self.frames += 1

    def _feed(self) -> None:
        """The thread: frames to ffmpeg until None; after a failure, frames are dropped."""
        while True:
            frame = self._queue.get()
            if frame is None:
                return
            if self._error is None:
                try:
                    self._writer.send(frame)
                except BaseException as exc:        # raised in the caller's thread (write, close)
                    self._error = exc

    def _raise_failure(self) -> None:
        if self._error is not None:
            error, self._error = self._error, None
            self.close()
            raise error

    def close(self) -> None:
        """Finish the file (safe to call twice)."""
        if self._thread is not None:
            self._queue.put(None)
            self._thread.join()
            self._thread = None
        if self._writer is not None:
            writer, self._writer = self._writer, None
            if self._error is not None:
                error, self._error = self._error, None
                writer.close()
                raise error
            writer.close()

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
