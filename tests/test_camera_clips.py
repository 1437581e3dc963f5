"""What cameras record, through ``track``, ``calibrate`` and ``segment``: a variable frame
rate, a timestamp gap and a repeated timestamp are accepted (``poses.csv`` ``time_s`` is each
frame's own timestamp); a cut file and corrupt bytes mid-stream are refused with the frame
numbers (and tracked with ``--allow-damaged``). Clips made by ffmpeg from a synthetic sequence."""
from __future__ import annotations

import json
import subprocess

import imageio_ffmpeg
import numpy as np
import pytest

from mocap.cli import main
from mocap.io.pose_table import PoseTable

N_FRAMES = 8
TRACK_ARGS = ["--iterations", "30", "--beam", "1", "--lag", "0", "--no-overlay"]
#: Timestamps by hand, seconds: a variable rate (growing intervals), a 0.4 s pause after
#: frame 0 (the issue's phone clip), frame 5 stamped like frame 4.
TIMES = {"vfr": [n * n / 100 for n in range(N_FRAMES)],
         "gap": [0.0] + [(n + 10) / 25 for n in range(1, N_FRAMES)],
         "duplicate": [n / 25 for n in range(5)] + [4 / 25] + [n / 25 for n in range(6, N_FRAMES)]}


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    from mocap.synth import generate_sequence
    return generate_sequence("gestures-2", tmp_path_factory.mktemp("seq") / "g2", frames=N_FRAMES, seed=3,
                             progress=False)


def _encode(sequence, path, *, setpts: str | None = None, setts: str | None = None):
    """The sequence's frames as an MJPEG Matroska clip with the timestamps ``setpts`` gives
    (frame number N), or rewritten by the ``setts`` bitstream filter afterwards."""
    ffmpeg = imageio_ffmpeg.get_ffmpeg_exe()
    first = path.with_name(f"plain-{path.name}") if setts else path
    subprocess.run([ffmpeg, "-v", "error", "-y", "-framerate", "25", "-i", str(sequence / "frames" / "%06d.png"),
                    *(["-vf", f"settb=1/1000,setpts={setpts}"] if setpts else []), "-fps_mode", "passthrough",
                    "-enc_time_base", "1:1000", "-c:v", "mjpeg", "-q:v", "2", str(first)], check=True)
    if setts:
        subprocess.run([ffmpeg, "-v", "error", "-y", "-i", str(first), "-c", "copy", "-bsf:v",
                        f"setts=ts='{setts}'", str(path)], check=True)
    return path


@pytest.fixture(scope="module")
def clips(sequence, tmp_path_factory):
    folder = tmp_path_factory.mktemp("clips")
    made = {"vfr": _encode(sequence, folder / "vfr.mkv", setpts="N*N/(100*TB)"),
            "gap": _encode(sequence, folder / "gap.mkv", setpts="(N+10*gte(N\\,1))/(25*TB)"),
            "duplicate": _encode(sequence, folder / "dup.mkv", setts="if(eq(N,5),PREV_OUTPTS,PTS)")}
    plain = _encode(sequence, folder / "plain.mkv").read_bytes()
    made["cut"] = folder / "cut.mkv"
    made["cut"].write_bytes(plain[: len(plain) * 6 // 10])
    corrupt = bytearray(plain)
    middle = len(plain) // 2
    corrupt[middle:middle + 600] = np.random.default_rng(0).integers(0, 256, 600, dtype=np.uint8).tobytes()
    made["corrupt"] = folder / "corrupt.mkv"
    made["corrupt"].write_bytes(bytes(corrupt))
    return made


def _given(sequence):
    return ["--background", str(sequence / "background.png"), "--calibration", str(sequence / "calibration.json")]


@pytest.mark.slow
@pytest.mark.parametrize("case", ["vfr", "gap", "duplicate"])
def test_camera_timing_is_tracked_with_each_frames_own_time(sequence, clips, case, tmp_path):
    out = tmp_path / "run"
    assert main(["track", str(clips[case]), "--out", str(out), *_given(sequence), *TRACK_ARGS]) == 0
    table = PoseTable.read(out / "poses.csv")
    assert list(table.frames) == list(range(N_FRAMES))               # every frame once, none filled in
    np.testing.assert_allclose(table.extra["time_s"], TIMES[case], atol=1e-6)
    assert "damaged_frames" not in json.loads((out / "run.json").read_text())


@pytest.mark.parametrize("case", ["cut", "corrupt"])
def test_damage_is_refused_by_every_command_with_frame_numbers(sequence, clips, case, tmp_path, capsys):
    for command in (["track", str(clips[case]), "--out", str(tmp_path / "t"), *_given(sequence), *TRACK_ARGS],
                    ["calibrate", str(clips[case]), "--out", str(tmp_path / "c.json"),
                     "--background", str(sequence / "background.png")],
                    ["segment", str(clips[case]), "--out", str(tmp_path / "s"), "--no-background"]):
        assert main(command) == 2, command[0]
        err = capsys.readouterr().err.strip()
        assert f"{clips[case]} is damaged" in err and "frame" in err and "--allow-damaged" in err, err
        assert len(err.splitlines()) == 1
    assert not (tmp_path / "t" / "poses.csv").exists() and not (tmp_path / "c.json").exists()


@pytest.mark.slow
def test_a_cut_clip_is_tracked_up_to_the_cut_when_allowed(sequence, clips, tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["track", str(clips["cut"]), "--out", str(out), *_given(sequence), *TRACK_ARGS,
                 "--allow-damaged"]) == 0
    run = json.loads((out / "run.json").read_text())
    decoded = len(PoseTable.read(out / "poses.csv"))
    assert 0 < decoded < N_FRAMES and run["damaged_frames"] == list(range(decoded, N_FRAMES))
    assert "warning: the video is damaged" in capsys.readouterr().err
