"""Damaged videos are found out: frames that do not decode, by number; ffmpeg failures in one sentence."""
from __future__ import annotations

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
import pytest

from mocap.io.video import count_frames, iter_frames
from mocap.io.video_check import check_video, format_frames

N_FRAMES = 30


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    """An intact 30-frame clip per container, the same cut in half, and with 1.5 kB of garbage inside."""
    folder = tmp_path_factory.mktemp("clips")
    rng = np.random.default_rng(0)
    frames = np.stack([np.full((48, 64, 3), 8 * i, np.uint8) + rng.integers(0, 40, (48, 64, 3), dtype=np.uint8)
                       for i in range(N_FRAMES)])
    for ext in ("mkv", "mp4"):
        iio.imwrite(folder / f"clip.{ext}", frames, plugin="FFMPEG", fps=10)
        data = (folder / f"clip.{ext}").read_bytes()
        (folder / f"half.{ext}").write_bytes(data[: len(data) // 2])
        garbage = bytearray(data)
        middle = len(data) // 2
        garbage[middle:middle + 1500] = rng.integers(0, 256, 1500, dtype=np.uint8).tobytes()
        (folder / f"garbage.{ext}").write_bytes(bytes(garbage))
    return folder


@pytest.mark.parametrize("ext", ["mkv", "mp4"])
def test_an_intact_video_passes(clips, ext):
    check = check_video(clips / f"clip.{ext}")
    assert (check.announced_frames, check.decoded, check.readable, check.fps) == (N_FRAMES, N_FRAMES, N_FRAMES, 10.0)
    assert not check.damaged and check.missing == check.corrupt == []


def test_a_cut_video_lists_the_frames_after_the_cut(clips):
    check = check_video(clips / "half.mkv")
    decoded = sum(1 for _ in iter_frames(clips / "half.mkv"))       # what the reader delivers
    assert 0 < decoded < N_FRAMES
    assert check.announced_frames == N_FRAMES and check.readable == decoded
    assert check.missing == list(range(decoded, N_FRAMES))
    assert check.damaged and f"frames {decoded}-{N_FRAMES - 1}" in check.describe("half.mkv")


@pytest.mark.parametrize("ext", ["mkv", "mp4"])
def test_garbage_inside_a_video_is_found(clips, ext):
    check = check_video(clips / f"garbage.{ext}")
    assert check.damaged and check.messages
    assert check.decoded == imageio_ffmpeg.count_frames_and_secs(str(clips / f"garbage.{ext}"))[0] < N_FRAMES
    assert len(check.missing) == N_FRAMES - check.decoded           # every frame is decoded or missing
    assert all(0 <= f < N_FRAMES for f in check.damaged_frames)


def test_ffmpeg_failures_are_one_sentence(clips, tmp_path):
    cases = {"half.mp4": (clips / "half.mp4").read_bytes(), "empty.mp4": b"", "text.mp4": b"hello, not a video\n",
             "text.mkv": b"hello, not a video\n", "header.mkv": (clips / "clip.mkv").read_bytes()[:200]}
    expected = {"half.mp4": "is a truncated video", "empty.mp4": "is empty (0 bytes): not a video",
                "text.mp4": "is not a video ffmpeg can read", "text.mkv": "is not a video ffmpeg can read",
                "header.mkv": "is a truncated or damaged video: it ends before its first frame"}
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        for read in (check_video, count_frames, lambda p: list(iter_frames(p))):
            with pytest.raises(ValueError) as info:
                read(tmp_path / name)
            message = str(info.value)
            assert expected[name] in message and "\n" not in message and "FFMPEG" not in message, message
    silent = tmp_path / "audio.mp4"
    ffmpeg = imageio_ffmpeg.get_ffmpeg_exe()
    import subprocess
    subprocess.run([ffmpeg, "-v", "error", "-f", "lavfi", "-i", "anullsrc", "-t", "0.5", "-y", str(silent)], check=True)
    with pytest.raises(ValueError, match="has no video stream"):
        check_video(silent)


def test_reader_messages_become_sentences():
    from mocap.io.video_check import ffmpeg_failure
    assert ffmpeg_failure("x.mp4", "could not convert string to float: 'N/A'") == "x.mp4 has no video frames"
    assert ffmpeg_failure("x.mp4", "FFMPEG call failed with 183:\nffmpeg version 9") == "x.mp4 could not be decoded as a video"
    assert ffmpeg_failure("x.mp4", "frame 3 has unsupported shape (2, 2)") == \
        "x.mp4 could not be decoded as a video (frame 3 has unsupported shape (2, 2))"


def test_frame_lists_read_like_text():
    assert format_frames([4]) == "frame 4"
    assert format_frames([3, 7, 8, 9, 12]) == "frames 3, 7-9 and 12"
    assert format_frames(list(range(0, 40, 2)), limit=3) == "frames 0, 2, 4 and 17 more ranges"
