"""Damaged videos are found out: frames that do not decode, by number; ffmpeg failures in one sentence."""
from __future__ import annotations

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
import pytest

from mocap.io.video import count_frames, iter_frames
from mocap.io.video_check import check_video, format_frames, parse_check_log

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
    assert (check.announced_frames, check.decoded, check.fps) == (N_FRAMES, N_FRAMES, 10.0)
    np.testing.assert_allclose(check.times, np.arange(N_FRAMES) / 10.0, atol=1e-3)
    assert not check.damaged and check.missing == check.corrupt == []


def test_a_cut_video_lists_the_frames_after_the_cut(clips):
    check = check_video(clips / "half.mkv")
    decoded = sum(1 for _ in iter_frames(clips / "half.mkv"))       # what the reader delivers
    assert 0 < decoded < N_FRAMES
    assert check.announced_frames == N_FRAMES and check.decoded == decoded
    assert check.missing == list(range(decoded, N_FRAMES))
    assert check.damaged and f"frames {decoded}-{N_FRAMES - 1}" in check.describe("half.mkv")


@pytest.mark.parametrize("ext", ["mkv", "mp4"])
def test_garbage_inside_a_video_is_found(clips, ext):
    check = check_video(clips / f"garbage.{ext}")
    assert check.damaged and check.messages
    assert check.decoded == sum(1 for _ in iter_frames(clips / f"garbage.{ext}")) < N_FRAMES
    assert all(0 <= f < N_FRAMES for f in check.damaged_frames)


#: ffmpeg's log of a damaged clip as a loaded machine prints it (lines from a real run, cut short):
#: the demuxer's and the decoder's messages glued, without their own prefix, to showinfo's lines.
GLUED_LOG = """Input #0, matroska,webm, from 'garbage.mkv':
  Duration: 00:00:00.50, start: 0.000000, bitrate: 66 kb/s
  Stream #0:0: Video: h264 (High), yuv420p(tv, progressive), 64x48, 10 fps, 10 tbr, 1k tbn
[Parsed_showinfo_0 @ 0x7f1] n:   0 pts:      0 pts_time:0       duration:    100 duration_time:0.1     \
fmt:yuv420p cl:left sar:0/1 s:64x48 i:P iskey:1 type:I 
[Parsed_showinfo_0 @ 0x7f1] color_range:tv color_space:unknown color_primaries:unknown color_trc:unknown
[Parsed_showinfo_0 @ 0x7f1] n:   1 pts:    100 pts_time:0.1     duration:    100 duration_time:0.1     \
fmt:yuv420p cl:left sar:0/1 s:64x48 i:P iskey:0 type:P Element at 0x3270 ending at 0xc226c exceeds containing \
master element ending at 0x60c8
[Parsed_showinfo_0 @ 0x7f1] color_range:tv color_space:unknown color_primaries:unknown color_trc:unknown
[Parsed_showinfo_0 @ 0x7f1] n:   2 pts:    200 pts_time:0.2     duration:    100 duration_time:0.1     \
fmt:yuv420p cl:left sar:0/1 s:64x48 i:P iskey:0 type:P 
[Parsed_showinfo_0 @ 0x7f1] color_range:tv color_space:unknowncorrupt decoded frame
[Parsed_showinfo_0 @ 0x7f1]  color_primaries:unknown color_trc:unknown
[Parsed_showinfo_0 @ 0x7f1] n:   3 pts:    300 pts_time:0.3     duration:    100 duration_time:0.1     \
fmt:yuv420p cl:left sar:0/1 s:64x48 i:P iskey:0 type:P 
[Parsed_showinfo_0 @ 0x7f1] color_range:tv color_space:unknown color_primaries:unknown color_trc:unknown
[Parsed_showinfo_0 @ 0x7f1] n:   4 pts:    400 pts_time:0.4     duration:    100 duration_time:0.1     \
fmt:yuv420p cl:left sar:0/1 s:64x48 i:P iskey:0 type:P 
[Parsed_showinfo_0 @ 0x7f1] color_range:tv color_space:unknown color_primaries:unknown color_trc:unknown
[Parsed_showinfo_0 @ 0x7f1] n:   5 pts:    400 pts_time:0.4     duration:    100 duration_time:0.1     \
fmt:yuv420p cl:left sar:0/1 s:64x48 i:P iskey:0 type:P Application provided invalid, non monotonically increasing \
dts to muxer in stream 0: 4 >= 4
[null @ 0x55b] Application provided invalid, non monotonically increasing dts to muxer in stream 0: 4 >= 4
"""


def test_messages_glued_to_showinfo_lines_are_read():
    # each message belongs to the next frame put out; the output side's complaint about a repeated
    # timestamp (frame 5 stamped with frame 4's time) is not damage, glued or on its own line
    check = parse_check_log("garbage.mkv", GLUED_LOG)
    assert check.times == [0.0, 0.1, 0.2, 0.3, 0.4, 0.4] and check.missing == []
    assert check.corrupt == [2, 3]
    assert [m.split("type:P ")[-1] for m in check.messages] == [
        "Element at 0x3270 ending at 0xc226c exceeds containing master element ending at 0x60c8",
        "[Parsed_showinfo_0 @ 0x7f1] color_range:tv color_space:unknowncorrupt decoded frame"]


def _clip(folder, name: str, *, setpts: str | None = None, setts: str | None = None, frames: int = 12):
    """A 64x48 MJPEG clip of ffmpeg's test pattern (every frame different) with the timestamps
    ``setpts`` gives (an expression of the frame number N), or rewritten afterwards by ``setts``."""
    import subprocess

    ffmpeg = imageio_ffmpeg.get_ffmpeg_exe()
    path = folder / name
    steps = [[ffmpeg, "-v", "error", "-y", "-f", "lavfi", "-i", "testsrc=size=64x48:rate=25", "-frames:v",
              str(frames), *(["-vf", f"settb=1/1000,setpts='{setpts}'"] if setpts else []), "-fps_mode", "passthrough",
              "-enc_time_base", "1:1000",
              "-c:v", "mjpeg", "-q:v", "3", str(path)]]
    if setts:
        steps.append([ffmpeg, "-v", "error", "-y", "-i", str(path), "-c", "copy", "-bsf:v", f"setts=ts='{setts}'",
                      str(folder / f"re-{name}")])
    for step in steps:
        subprocess.run(step, check=True)
    return folder / f"re-{name}" if setts else path


@pytest.mark.parametrize("case", ["vfr", "gap", "duplicate"])
def test_what_cameras_record_is_accepted_with_exact_times(tmp_path, case):
    # the expected times by hand: squares of the frame number in centiseconds; a 0.4 s pause
    # after frame 0; frame 5 stamped with frame 4's time
    clip, expected = {
        "vfr": (lambda: _clip(tmp_path, "vfr.mkv", setpts="N*N/(100*TB)"), [n * n / 100 for n in range(12)]),
        "gap": (lambda: _clip(tmp_path, "gap.mkv", setpts="(N+10*gte(N,1))/(25*TB)"),
                [0.0] + [(n + 10) / 25 for n in range(1, 12)]),
        "duplicate": (lambda: _clip(tmp_path, "dup.mkv", setts="if(eq(N,5),PREV_OUTPTS,PTS)"),
                      [n / 25 for n in range(5)] + [4 / 25] + [n / 25 for n in range(6, 12)]),
    }[case]
    path = clip()
    check = check_video(path)
    assert not check.damaged, check.describe(path)
    np.testing.assert_allclose(check.times, expected, atol=1e-6)
    frames = list(iter_frames(path))
    assert len(frames) == 12 == count_frames(path)
    # every frame once: the test pattern moves, so neighbours differ (no frame repeated to fill a gap)
    assert not any(np.array_equal(a, b) for a, b in zip(frames, frames[1:]))
    picked = list(iter_frames(path, indices=[2, 7]))
    np.testing.assert_array_equal(picked[1], frames[7])


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


def test_frames_chosen_by_number_are_those_of_a_full_read(tmp_path):
    """Regular steps (one ``select`` term), a few frames, and an irregular set too long for one
    ffmpeg expression (read as a range, the rest skipped) all give the full read's frames."""
    path = _clip(tmp_path, "long.mkv", frames=260)
    every = list(iter_frames(path))
    rng = np.random.default_rng(1)
    for wanted in (list(range(1, 260, 3)), [5, 6, 7, 200], sorted(set(rng.integers(0, 260, 150).tolist()))):
        got = list(iter_frames(path, indices=wanted))
        assert len(got) == len(wanted)
        for index, frame in zip(wanted, got):
            np.testing.assert_array_equal(frame, every[index])
