"""Nothing lost, nothing silent: crash-exact resume, one writer per output folder.

The runs are real processes killed with SIGKILL at chosen points (:mod:`tests.killpoints`);
every resumed run must give bit for bit the poses of an uninterrupted one.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest

from mocap.cli import main
from mocap.io.lock import LOCK_FILE, FolderLock
from mocap.io.pose_table import PoseTable
from mocap.run.journal import STATE_FILE

from tests.conftest import REPO_ROOT, need_mediapipe

N_FRAMES = 8
#: No decoding lag: a row per frame, so the kill points below fall between known rows (a beam of
#: two still makes the checkpoint hold more than one pose); the lagged stream is checked after.
# --keypoints none: the killed runs are processes of their own, where tests/conftest.py's bare
# install (auto = none) does not reach
TRACK_ARGS = ["--iterations", "40", "--beam", "2", "--lag", "0", "--no-overlay", "--keypoints", "none"]
LAGGED_ARGS = ["--iterations", "40", "--beam", "2", "--lag", "3", "--no-overlay", "--keypoints", "none"]


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    from mocap.synth import generate_sequence
    return generate_sequence("gestures-2", tmp_path_factory.mktemp("seq") / "gestures-2", frames=N_FRAMES, seed=3,
                             progress=False)


@pytest.fixture(scope="module")
def uninterrupted(sequence, tmp_path_factory):
    out = tmp_path_factory.mktemp("uninterrupted") / "run"
    assert main(["track", str(sequence), "--out", str(out), *TRACK_ARGS]) == 0
    return PoseTable.read(out / "poses.csv")


def killed_run(mode: str, n: int, sequence, out, **popen) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "tests.killpoints", mode, str(n), "--", "track", str(sequence), "--out", str(out),
           *TRACK_ARGS]
    return subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True, timeout=300, **popen)


def journal_rows(out) -> int:
    path = out / "poses.csv"
    return len(path.read_text().splitlines()) - 1 if path.exists() else 0


@pytest.mark.slow
def test_resume_after_kill_9_anywhere_is_bit_identical(sequence, uninterrupted, tmp_path):
    """Killed runs checkpoint every 3 frames (:data:`tests.killpoints.CHECKPOINT_EVERY`): kills
    after the 1st, 2nd and 3rd row of an interval (before its checkpoint), after a checkpoint,
    half-way through a row, and after the last frame's checkpoint all resume to the
    uninterrupted run's poses, bit for bit."""
    from tests.killpoints import CHECKPOINT_EVERY

    assert CHECKPOINT_EVERY == 3
    out = tmp_path / "run"
    # 1.-3. killed after rows 1, 2 and 3 of the first interval, before its checkpoint: nothing
    #       exact to resume from yet, every run starts afresh
    for n in (1, 2, 3):
        proc = killed_run("after-row", n, sequence, out)
        assert proc.returncode == -9, proc.stderr
        assert journal_rows(out) == n and not (out / STATE_FILE).exists()
    assert (out / LOCK_FILE).exists()                     # the dead process's lock file stays behind
    # 4. killed right after the first checkpoint (frames 0-2)
    proc = killed_run("after-state", 1, sequence, out)
    assert proc.returncode == -9, proc.stderr
    assert journal_rows(out) == 3
    # 5. resumes at frame 3, killed half-way through writing its second row (frame 4)
    proc = killed_run("mid-row", 2, sequence, out)
    assert proc.returncode == -9, proc.stderr
    assert not (out / "poses.csv").read_text().endswith("\n")
    # 6. resumes at frame 3 (the partial row cut off), killed after the rows of frames 3-5, before
    #    their checkpoint: the third row of an interval
    proc = killed_run("after-row", 3, sequence, out)
    assert proc.returncode == -9, proc.stderr
    assert journal_rows(out) == 6
    # 7. resumes at frame 3 again (rows 3-5 done again), killed after its second checkpoint: the
    #    last frame's, before any final output is written
    proc = killed_run("after-state", 2, sequence, out)
    assert proc.returncode == -9, proc.stderr
    assert journal_rows(out) == N_FRAMES and not (out / "poses.bvh").exists()
    # 8. has no frame left to track: writes the outputs
    assert main(["track", str(sequence), "--out", str(out), *TRACK_ARGS]) == 0
    assert json.loads((out / "run.json").read_text())["resumed_from_frame"] == N_FRAMES
    resumed = PoseTable.read(out / "poses.csv")
    np.testing.assert_array_equal(resumed.frames, np.arange(N_FRAMES))
    np.testing.assert_array_equal(resumed.poses, uninterrupted.poses)
    np.testing.assert_array_equal(resumed.joints, uninterrupted.joints)
    for name in ("region_residual", "edge_residual", "failed", "evaluations", "time_s"):
        np.testing.assert_array_equal(resumed.extra[name], uninterrupted.extra[name])


@pytest.mark.slow
@pytest.mark.parametrize("keypoints", ["none", "mediapipe"])
def test_resume_with_a_decoding_lag_is_bit_identical(sequence, tmp_path, keypoints):
    """With a lag of 3 the first rows come out at the fourth frame: kills after a checkpoint
    (frames still undecided inside it), after a row, and after the last push's checkpoint (the
    held-back rows not written yet) all resume to the uninterrupted run's poses, with and
    without keypoints. The written poses are smoothed over the lag (:mod:`mocap.track.smooth`):
    the checkpoint carries the smoother's state and the window's images, so the smoothed poses
    and their residuals come back bit for bit. The threads change nothing either: the whole run
    on one thread, the killed ones on three and the last on two."""
    if keypoints == "mediapipe":
        pytest.importorskip("mediapipe")
    args = [*LAGGED_ARGS[:-1], keypoints]
    whole = tmp_path / "whole"
    assert main(["track", str(sequence), "--out", str(whole), *args, "--threads", "1"]) == 0
    out = tmp_path / "run"
    cmd = lambda mode, n: [sys.executable, "-m", "tests.killpoints", mode, str(n), "--", "track", str(sequence),
                           "--out", str(out), *args, "--threads", "3"]
    # checkpoints every 3 frames: after frames 2, 5 and 7
    for mode, n in (("after-state", 2), ("after-row", 2), ("after-state", 1)):
        proc = subprocess.run(cmd(mode, n), cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
        assert proc.returncode == -9, proc.stderr
    assert journal_rows(out) < N_FRAMES                      # frames still held back at the kill
    assert main(["track", str(sequence), "--out", str(out), *args, "--threads", "2"]) == 0
    a, b = PoseTable.read(whole / "poses.csv"), PoseTable.read(out / "poses.csv")
    np.testing.assert_array_equal(b.frames, np.arange(N_FRAMES))
    np.testing.assert_array_equal(b.poses, a.poses)
    np.testing.assert_array_equal(b.joints, a.joints)
    for name in ("hypothesis", "region_residual", "edge_residual", "keypoint_residual", "smoothed_mm", "failed"):
        np.testing.assert_array_equal(b.extra[name], a.extra[name])
    assert np.any(a.extra["smoothed_mm"] > 0)               # the smoother moved the poses written


@pytest.mark.slow
def test_resume_with_mediapipe_keypoints_is_bit_identical(sequence, tmp_path):
    """MediaPipe runs in image mode (no state carried from frame to frame), so a run killed
    anywhere resumes to the keypoints and the poses of an uninterrupted one, bit for bit:
    resumes at frame 3 (after a checkpoint, after a half-written row) and at frame 6; the
    keypoint journal ``keypoints.csv`` is the uninterrupted run's too."""
    need_mediapipe()
    from mocap.io.keypoints import read_keypoints
    from mocap.run.journal import KEYPOINTS_FILE

    args = [*TRACK_ARGS[:-1], "mediapipe"]
    whole = tmp_path / "whole"
    assert main(["track", str(sequence), "--out", str(whole), *args]) == 0
    out = tmp_path / "run"
    cmd = lambda mode, n: [sys.executable, "-m", "tests.killpoints", mode, str(n), "--", "track", str(sequence),
                           "--out", str(out), *args]
    # checkpoints every 3 frames: killed after frames 0-2's; resumed at 3 and killed half-way
    # through frame 4's row; resumed at 3 and killed after frames 3-5's; resumed at 6, killed after its row
    for mode, n, rows in (("after-state", 1, 3), ("mid-row", 2, 4), ("after-state", 1, 6), ("after-row", 1, 7)):
        proc = subprocess.run(cmd(mode, n), cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
        assert proc.returncode == -9, proc.stderr
        assert (out / "poses.csv").read_text().count("\n") - 1 == rows          # whole rows
    assert main(["track", str(sequence), "--out", str(out), *args]) == 0
    run = json.loads((out / "run.json").read_text())
    assert run["resumed_from_frame"] == 6 and "image mode" in run["settings"]["keypoints"]
    a, b = PoseTable.read(whole / "poses.csv"), PoseTable.read(out / "poses.csv")
    np.testing.assert_array_equal(b.frames, np.arange(N_FRAMES))
    np.testing.assert_array_equal(b.poses, a.poses)
    np.testing.assert_array_equal(b.joints, a.joints)
    for name in ("region_residual", "edge_residual", "failed", "evaluations", "time_s"):
        np.testing.assert_array_equal(b.extra[name], a.extra[name])
    assert (out / KEYPOINTS_FILE).read_bytes() == (whole / KEYPOINTS_FILE).read_bytes()
    assert sorted(read_keypoints(whole / KEYPOINTS_FILE)) == list(range(N_FRAMES))     # the person found in each


def test_a_held_output_folder_is_refused_at_once(sequence, tmp_path, capsys):
    out = tmp_path / "run"
    with FolderLock(out):
        assert main(["track", str(sequence), "--out", str(out), *TRACK_ARGS]) == 2
        err = capsys.readouterr().err
        assert f"pid {os.getpid()}" in err and "in use by another run" in err and len(err.strip().splitlines()) == 1
        assert sorted(p.name for p in out.iterdir()) == [LOCK_FILE]      # nothing written
        with pytest.raises(OSError, match="in use"):
            FolderLock(out).acquire()                 # a second lock in the same process, too
    FolderLock(out).acquire().release()               # released on leaving the block


@pytest.mark.slow
def test_two_runs_on_one_folder_one_refuses_the_other_is_exact(sequence, uninterrupted, tmp_path):
    out, paused = tmp_path / "run", tmp_path / "paused"
    first = subprocess.Popen([sys.executable, "-m", "tests.killpoints", "pause", "2", "--", "track", str(sequence),
                              "--out", str(out), *TRACK_ARGS], cwd=REPO_ROOT, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, env={**os.environ, "KILLPOINTS_PAUSED": str(paused)})
    try:
        deadline = time.monotonic() + 240
        while not paused.exists():                    # the first run is in the middle of its frames
            assert first.poll() is None and time.monotonic() < deadline, first.communicate()
            time.sleep(0.05)
        second = subprocess.run([sys.executable, "-m", "mocap", "track", str(sequence), "--out", str(out),
                                 *TRACK_ARGS], cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
        assert second.returncode == 2
        assert "in use by another run" in second.stderr and f"pid {first.pid}" in second.stderr
        paused.unlink()
        stdout, stderr = first.communicate(timeout=300)
        assert first.returncode == 0, stderr
    finally:
        if first.poll() is None:
            first.kill()
            first.wait()
    table = PoseTable.read(out / "poses.csv")
    np.testing.assert_array_equal(table.frames, np.arange(N_FRAMES))
    np.testing.assert_array_equal(table.poses, uninterrupted.poses)


@pytest.mark.slow
def test_a_damaged_video_stops_the_run_or_is_tracked_with_its_frames_marked(sequence, tmp_path, capsys):
    import imageio.v3 as iio

    from mocap.io.video import image_files
    frames = np.stack([iio.imread(f) for f in image_files(sequence / "frames")])
    clip, cut = tmp_path / "clip.mkv", tmp_path / "cut.mkv"
    iio.imwrite(clip, np.concatenate([frames, frames]), plugin="FFMPEG", fps=10, macro_block_size=8)   # 16 frames
    data = clip.read_bytes()
    cut.write_bytes(data[: len(data) * 9 // 10])
    common = ["--background", str(sequence / "background.png"), "--calibration", str(sequence / "calibration.json"),
              *TRACK_ARGS]
    assert main(["track", str(cut), "--out", str(tmp_path / "refused"), *common]) == 2
    err = capsys.readouterr().err.strip()
    assert "cut.mkv is damaged: 16 announced" in err and "--allow-damaged" in err and len(err.splitlines()) == 1
    missing = err.split("do not decode (frames ")[1].split(")")[0]                   # e.g. "9-15"
    first, last = (int(v) for v in missing.split("-"))
    assert 0 < first and last == 15
    assert not (tmp_path / "refused" / "poses.csv").exists()
    assert main(["track", str(cut), "--out", str(tmp_path / "allowed"), *common, "--allow-damaged"]) == 0
    assert f"warning: the video is damaged: frames {first}-15" in capsys.readouterr().err
    run = json.loads((tmp_path / "allowed" / "run.json").read_text())
    assert run["damaged_frames"] == list(range(first, 16)) and run["frames"] == first
    assert PoseTable.read(tmp_path / "allowed" / "poses.csv").frames.tolist() == list(range(first))


@pytest.mark.slow
def test_damage_the_check_finds_while_tracking_stops_the_run_and_leaves_no_results(sequence, tmp_path, capsys,
                                                                                   monkeypatch):
    """The damage check runs beside the run: held back here until 5 frames were read, its
    verdict must still stop the run with the frame numbers, remove what the run wrote and be
    all the run wrote to stderr (no progress bar before it, however late it comes)."""
    import imageio.v3 as iio

    from mocap.io.frames import VideoSource
    from mocap.io.video import image_files
    frames = np.stack([iio.imread(f) for f in image_files(sequence / "frames")])
    clip, cut = tmp_path / "clip.mkv", tmp_path / "cut.mkv"
    iio.imwrite(clip, np.concatenate([frames, frames]), plugin="FFMPEG", fps=10, macro_block_size=8)   # 16 frames
    data = clip.read_bytes()
    cut.write_bytes(data[: len(data) * 9 // 10])
    read, asked = [], []
    frames_of, checked = VideoSource.frames, VideoSource.checked

    def counted(self, *args, **kwargs):
        for frame in frames_of(self, *args, **kwargs):
            read.append(1)
            yield frame
    monkeypatch.setattr(VideoSource, "frames", counted)
    monkeypatch.setattr(VideoSource, "checked", property(lambda self: len(read) >= 5 and checked.fget(self)))
    damaged_frames = VideoSource.damaged_frames
    monkeypatch.setattr(VideoSource, "damaged_frames",
                        lambda self, allow=False: asked.append(len(read)) or damaged_frames(self, allow))
    out = tmp_path / "refused"
    assert main(["track", str(cut), "--out", str(out), "--background", str(sequence / "background.png"),
                 "--calibration", str(sequence / "calibration.json"), *TRACK_ARGS]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith("error: ") and "cut.mkv is damaged: 16 announced" in err and "--allow-damaged" in err
    assert asked and asked[0] >= 5                      # the verdict came while frames were tracked
    assert not (out / "poses.csv").exists() and not (out / "run.json").exists() and not (out / STATE_FILE).exists()


@pytest.mark.slow
def test_colours_are_learned_where_the_person_is_and_start_skips_frames(sequence, tmp_path, capsys):
    import shutil

    from mocap.io.video import image_files
    folder = tmp_path / "seq"
    shutil.copytree(sequence, folder)
    files = image_files(folder / "frames")
    for f in files[:2]:                                   # an empty room before the actor is in view
        shutil.copy(folder / "background.png", f)
    out = tmp_path / "run"
    assert main(["track", str(folder), "--out", str(out), *TRACK_ARGS]) == 0
    run = json.loads((out / "run.json").read_text())
    assert run["colour_model_frame"] == 2
    table = PoseTable.read(out / "poses.csv")
    assert table.extra["empty"].tolist() == [1, 1] + [0] * (N_FRAMES - 2)
    assert np.all(table.extra["region_residual"][2:] < 0.45)     # the colours fit the actor
    # --start: the first frames are not tracked at all
    started = tmp_path / "started"
    assert main(["track", str(folder), "--out", str(started), "--start", "3", "--max-frames", "2", *TRACK_ARGS]) == 0
    assert PoseTable.read(started / "poses.csv").frames.tolist() == [3, 4]
    run = json.loads((started / "run.json").read_text())
    assert run["colour_model_frame"] == 3 and run["settings"]["start_frame"] == 3
    capsys.readouterr()
    assert main(["track", str(folder), "--out", str(tmp_path / "late"), "--start", str(N_FRAMES), *TRACK_ARGS]) == 2
    assert f"start frame {N_FRAMES} is past the end" in capsys.readouterr().err
    # nobody in any frame: a clear error, not a colour model of the room
    for f in files:
        shutil.copy(folder / "background.png", f)
    assert main(["track", str(folder), "--out", str(tmp_path / "nobody"), *TRACK_ARGS]) == 2
    err = capsys.readouterr().err
    assert "shows the person to learn the colours from" in err and f"frame {N_FRAMES - 1} has 0 foreground pixels" in err
