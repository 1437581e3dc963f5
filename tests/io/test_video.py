"""Frame input/output: images, folders, videos, and clear errors on bad files."""
from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

from mocap.io.video import (VideoWriter, count_frames, frame_rate, image_files, iter_frames,
                            read_image, sample_frames)


@pytest.fixture()
def rgb():
    rng = np.random.default_rng(0)
    return rng.integers(0, 256, (12, 16, 3), dtype=np.uint8)


def test_read_image_round_trip(tmp_path, rgb):
    iio.imwrite(tmp_path / "a.png", rgb)
    got = read_image(tmp_path / "a.png")
    assert got.dtype == np.uint8 and got.shape == (12, 16, 3)
    np.testing.assert_array_equal(got, rgb)


def test_read_image_converts_opaque_rgba_and_16_bit(tmp_path, rgb):
    iio.imwrite(tmp_path / "rgba.png", np.dstack([rgb, np.full((12, 16), 255, np.uint8)]))
    np.testing.assert_array_equal(read_image(tmp_path / "rgba.png"), rgb)
    iio.imwrite(tmp_path / "deep.png", rgb[..., 0].astype(np.uint16) * 257)
    np.testing.assert_array_equal(read_image(tmp_path / "deep.png", allow_gray=True)[..., 1],
                                  rgb[..., 0])


def test_read_image_grayscale_needs_consent(tmp_path, rgb):
    iio.imwrite(tmp_path / "g.png", rgb[..., 0])
    with pytest.raises(ValueError, match="grayscale"):
        read_image(tmp_path / "g.png")
    got = read_image(tmp_path / "g.png", allow_gray=True)
    np.testing.assert_array_equal(got, np.repeat(rgb[..., :1], 3, axis=2))


def test_read_image_errors(tmp_path, rgb):
    with pytest.raises(FileNotFoundError):
        read_image(tmp_path / "missing.png")
    (tmp_path / "corrupt.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"garbage" * 10)
    with pytest.raises(ValueError, match="corrupt"):
        read_image(tmp_path / "corrupt.png")
    (tmp_path / "empty.jpg").write_bytes(b"")
    with pytest.raises(ValueError, match="corrupt"):
        read_image(tmp_path / "empty.jpg")
    # a truncated JPEG: the header is fine, the data stops
    iio.imwrite(tmp_path / "full.jpg", np.repeat(np.repeat(rgb, 8, 0), 8, 1))
    data = (tmp_path / "full.jpg").read_bytes()
    (tmp_path / "cut.jpg").write_bytes(data[: len(data) // 3])
    with pytest.raises(ValueError, match="corrupt"):
        read_image(tmp_path / "cut.jpg")
    with pytest.raises(ValueError, match="folder"):
        read_image(tmp_path)
    iio.imwrite(tmp_path / "clear.png", np.dstack([rgb, np.zeros((12, 16), np.uint8)]))
    with pytest.raises(ValueError, match="transparent"):
        read_image(tmp_path / "clear.png")


def _write_folder(folder, n, shape=(12, 16)):
    folder.mkdir()
    frames = [np.full(shape + (3,), 10 * i, np.uint8) for i in range(n)]
    for i, f in enumerate(frames):
        iio.imwrite(folder / f"{i:06d}.png", f)
    (folder / "notes.txt").write_text("not a frame")
    return frames


def test_folder_of_images(tmp_path):
    frames = _write_folder(tmp_path / "frames", 5)
    assert count_frames(tmp_path / "frames") == 5
    assert frame_rate(tmp_path / "frames") is None
    assert [p.name for p in image_files(tmp_path / "frames")][0] == "000000.png"
    got = list(iter_frames(tmp_path / "frames", start=1, stop=4))
    assert len(got) == 3
    for g, f in zip(got, frames[1:4]):
        np.testing.assert_array_equal(g, f)
    assert list(iter_frames(tmp_path / "frames", start=9)) == []


def test_folder_errors(tmp_path):
    (tmp_path / "none").mkdir()
    with pytest.raises(ValueError, match="no .png"):
        count_frames(tmp_path / "none")
    frames = _write_folder(tmp_path / "mixed", 2)
    iio.imwrite(tmp_path / "mixed" / "000009.png", np.zeros((5, 5, 3), np.uint8))
    with pytest.raises(ValueError, match="first frame"):
        list(iter_frames(tmp_path / "mixed"))
    assert frames


def test_video_round_trip(tmp_path):
    # odd sizes are padded to even ones for yuv420p
    frames = [np.full((31, 45, 3), (20 * i, 100, 200 - 20 * i), np.uint8) for i in range(8)]
    path = tmp_path / "clip.mp4"
    with VideoWriter(path, fps=12) as video:
        for f in frames:
            video.write(f)
    assert video.frames == 8
    assert count_frames(path) == 8
    assert frame_rate(path) == pytest.approx(12)
    got = list(iter_frames(path, start=2, stop=5))
    assert len(got) == 3 and got[0].shape == (32, 46, 3) and got[0].dtype == np.uint8
    # lossy, but the colour survives
    assert np.abs(got[0][:31, :45].astype(int) - frames[2]).mean() < 6


def test_video_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        list(iter_frames(tmp_path / "missing.mp4"))
    with pytest.raises(FileNotFoundError):
        count_frames(tmp_path / "missing.mp4")
    (tmp_path / "bad.mp4").write_bytes(b"\x00\x00\x00\x18ftypmp42" + b"junk" * 100)
    with pytest.raises(ValueError, match="bad.mp4 is a truncated video"):
        list(iter_frames(tmp_path / "bad.mp4"))
    with pytest.raises(ValueError, match="bad.mp4 is a truncated video"):
        count_frames(tmp_path / "bad.mp4")
    with pytest.raises(ValueError, match="start"):
        list(iter_frames(tmp_path, start=-1))
    with pytest.raises(ValueError, match="stop"):
        list(iter_frames(tmp_path, start=3, stop=2))
    with pytest.raises(ValueError, match="uint8"):
        with VideoWriter(tmp_path / "x.mp4", fps=5) as video:
            video.write(np.zeros((4, 4, 3), np.float32))
    with pytest.raises(FileNotFoundError):
        VideoWriter(tmp_path / "nowhere" / "x.mp4", fps=5)


def _keyed_clip(path, frames: int, key_every: int, fps: int = 25):
    """A 32x24 test pattern clip with a key frame exactly every ``key_every`` frames (x264, no
    scene-cut key frames)."""
    import subprocess

    import imageio_ffmpeg
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-y", "-f", "lavfi", "-i",
                    f"testsrc=size=32x24:rate={fps}", "-frames:v", str(frames), "-c:v", "libx264", "-g", str(key_every),
                    "-keyint_min", str(key_every), "-sc_threshold", "0", "-pix_fmt", "yuv420p", str(path)], check=True)
    return path


def test_sample_frames_reads_key_frames_of_a_long_video_and_fills_with_its_first_frames(tmp_path):
    clip = _keyed_clip(tmp_path / "clip.mp4", 300, 20)
    every = list(iter_frames(clip))                  # the reference: every frame decoded in order
    assert len(every) == 300

    def same(got, numbers):
        assert len(got) == len(numbers)
        for frame, n in zip(got, numbers):
            assert np.array_equal(frame, every[n]), n

    # key frames 0, 20, ..., 280 (15) among the first 300: 6 of them spread by order
    same(sample_frames(clip, 6, 300, lambda f: f, fps=25), [20 * k for k in (0, 3, 6, 8, 11, 14)])
    # only the first 100 frames (4 s): key frames 0..80, then the first frames after frame 0, every second one
    same(sample_frames(clip, 8, 100, lambda f: f, fps=25), [0, 20, 40, 60, 80, 1, 3, 5])
    # each frame goes through ``reduce`` as it is read
    assert [f.shape for f in sample_frames(clip, 3, 300, lambda f: f[::2, ::2], fps=25)] == [(12, 16, 3)] * 3
    # a short span (at most 4x the count), or no frame rate: chosen by number
    same(sample_frames(clip, 10, 40, lambda f: f, fps=25), sorted({int(i) for i in np.linspace(0, 39, 10).round()}))
    same(sample_frames(clip, 5, 300, lambda f: f), sorted({int(i) for i in np.linspace(0, 299, 5).round()}))
    with pytest.raises(ValueError, match="count"):
        sample_frames(clip, 0, 300, lambda f: f, fps=25)


@pytest.mark.shared_data
def test_real_video_frames(shared_data):
    path = shared_data / "video" / "intel_asl_no.mkv"
    assert count_frames(path) == 66
    assert frame_rate(path) == pytest.approx(30)
    frames = list(iter_frames(path, start=64))
    assert len(frames) == 2 and frames[0].shape == (480, 640, 3)
