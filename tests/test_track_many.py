"""``python -m mocap track-many``: every input as its own ``track`` run, failures kept apart, reruns resume.

Each tracked video is compared with its own single ``python -m mocap track`` run (timing columns
aside); every summary row with the video's ``run.json`` and ``poses.csv``.
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys

import numpy as np
import pytest

from mocap.cli import main
from mocap.io.pose_table import PoseTable
from mocap.run import files
from mocap.run.many import SUMMARY_COLUMNS, read_summary

from tests.conftest import REPO_ROOT, need_mediapipe
from tests.dask_cluster import cluster_env, local_cluster, make_certificates, tls_client_env, wait_for
from tests.killpoints import CHECKPOINT_EVERY

N_FRAMES = 6
#: Few evaluations, no decoding lag (a row per frame: the kill points fall between known rows).
# --keypoints none: the workers are processes of their own, where tests/conftest.py's bare install
# (auto = none) does not reach
TRACK_ARGS = ["--iterations", "40", "--beam", "2", "--lag", "0", "--no-overlay", "--keypoints", "none"]
NAMES = ("gestures-1", "gestures-2", "turning")


@pytest.fixture(scope="session")
def clips(tmp_path_factory):
    """Three synthetic sequence folders of six 160x120 frames."""
    from mocap.synth import generate_sequence
    root = tmp_path_factory.mktemp("clips")
    return [generate_sequence(name, root / name, frames=N_FRAMES, seed=1, progress=False) for name in NAMES]


@pytest.fixture(scope="session")
def single_runs(clips, tmp_path_factory):
    """Each clip's own ``python -m mocap track`` run: name -> output folder."""
    root = tmp_path_factory.mktemp("single")
    for clip in clips:
        assert main(["track", str(clip), "--out", str(root / clip.name), *TRACK_ARGS]) == 0
    return {clip.name: root / clip.name for clip in clips}


def assert_same_track(a, b) -> None:
    """The same poses.csv, timing columns (ms_*) aside."""
    ta, tb = PoseTable.read(a / files.POSES_CSV), PoseTable.read(b / files.POSES_CSV)
    np.testing.assert_array_equal(ta.frames, tb.frames)
    np.testing.assert_array_equal(ta.poses, tb.poses)
    np.testing.assert_array_equal(ta.joints, tb.joints)
    assert set(ta.extra) == set(tb.extra)
    for name in ta.extra:
        if not name.startswith("ms_"):
            np.testing.assert_array_equal(ta.extra[name], tb.extra[name], err_msg=name)


def assert_summary_matches_runs(out, inputs) -> list[dict]:
    """summary.csv: one row per input in order, each finished row as its run.json and poses.csv say."""
    rows = read_summary(out)
    assert list(rows[0]) == list(SUMMARY_COLUMNS)
    assert [r["input"] for r in rows] == [str(i) for i in inputs]
    for row in rows:
        if row["status"] != "finished":
            continue
        run = json.loads((out / row["output"] / files.RUN_JSON).read_text())
        table = PoseTable.read(out / row["output"] / files.POSES_CSV)
        assert run["status"] == "finished" and row["reason"] == ""
        assert int(row["frames"]) == run["frames"] == len(table)
        assert int(row["failed_frames"]) == run["failures"] == int(table.extra["failed"].sum())
        assert float(row["fps"]) == pytest.approx(run["fps"], abs=0.006)
        assert float(row["time_s"]) == pytest.approx(run["wall_seconds_this_session"], abs=0.006)
        assert row["background"] == run["settings"]["own_video"]["background"]["mode"]
        assert row["calibration"] == run["settings"]["own_video"]["calibration"]["from"]
    assert (out / files.SUMMARY_PNG).stat().st_size > 0
    return rows


def test_name_clashes_and_missing_inputs_are_refused_before_anything_runs(tmp_path, capsys):
    for folder in ("a/clip", "b/clip"):
        (tmp_path / folder).mkdir(parents=True)
    (tmp_path / "x.mp4").write_bytes(b"")
    (tmp_path / "X.avi").write_bytes(b"")
    out = tmp_path / "out"
    assert main(["track-many", str(tmp_path / "*" / "clip"), "--out", str(out), "--workers", "0"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "same output folder name" in err
    assert f"{tmp_path / 'a' / 'clip'} and {tmp_path / 'b' / 'clip'} (both clip)" in err
    assert main(["track-many", str(tmp_path / "x.mp4"), str(tmp_path / "X.avi"), "--out", str(out)]) == 2
    assert "(both x)" in capsys.readouterr().err            # names compared as a case-blind file system would
    assert main(["track-many", str(tmp_path / "a" / "clip"), str(tmp_path / "nothing*"), "--out", str(out)]) == 2
    assert "nothing* matches no file or folder" in capsys.readouterr().err
    (tmp_path / "summary.csv.mp4").write_bytes(b"")
    assert main(["track-many", str(tmp_path / "summary.csv.mp4"), "--out", str(out)]) == 2
    assert "a folder named summary.csv, the name of a file track-many writes" in capsys.readouterr().err
    assert not out.exists()                                  # nothing written, no cluster started


@pytest.mark.slow
def test_an_interrupted_run_resumes_without_retracking_finished_videos(clips, single_runs, tmp_path):
    out = tmp_path / "out"
    a, b = clips[:2]
    # in this process (--workers 0), killed by SIGKILL at the second video's first checkpoint
    per_video = -(-N_FRAMES // CHECKPOINT_EVERY)                 # checkpoints of a whole video
    cmd = [sys.executable, "-m", "tests.killpoints", "after-state", str(per_video + 1), "--",
           "track-many", str(a), str(b), "--out", str(out), "--workers", "0", "--no-progress", *TRACK_ARGS]
    proc = subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == -9, proc.stderr
    assert json.loads((out / a.name / files.RUN_JSON).read_text())["status"] == "finished"
    assert json.loads((out / b.name / files.RUN_JSON).read_text())["status"] == "running"
    assert not (out / files.SUMMARY_CSV).exists()
    finished = {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in (out / a.name).iterdir()}
    proc = subprocess.run([sys.executable, "-m", "mocap", "track-many", str(a), str(b), "--out", str(out),
                           "--workers", "0", "--no-progress", *TRACK_ARGS],
                          cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "2 of 2 inputs finished (1 already were), 0 failed" in proc.stdout
    assert {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in (out / a.name).iterdir()} == finished
    assert json.loads((out / b.name / files.RUN_JSON).read_text())["resumed_from_frame"] == CHECKPOINT_EVERY
    for clip in (a, b):
        assert_same_track(out / clip.name, single_runs[clip.name])
    assert [r["status"] for r in assert_summary_matches_runs(out, [a, b])] == ["finished", "finished"]
    # other options on the same folder: refused, not mixed
    proc = subprocess.run([sys.executable, "-m", "mocap", "track-many", str(a), "--out", str(out), "--workers", "0",
                           "--iterations", "41"], cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and "tracked with other options" in proc.stderr


@pytest.mark.slow
def test_a_damaged_input_fails_alone_with_its_reason(clips, single_runs, tmp_path, capsys):
    import imageio.v3 as iio

    from mocap.io.video import image_files
    good = clips[:2]
    damaged = tmp_path / "damaged"                 # a sequence folder whose video is cut short
    damaged.mkdir()
    for name in ("background.png", "calibration.json"):
        shutil.copy(clips[0] / name, damaged / name)
    frames = np.stack([iio.imread(f) for f in image_files(clips[0] / "frames")])
    iio.imwrite(tmp_path / "whole.mkv", np.concatenate([frames, frames]), plugin="FFMPEG", fps=10,
                macro_block_size=8)
    data = (tmp_path / "whole.mkv").read_bytes()
    (damaged / "video.mp4").write_bytes(data[: len(data) * 9 // 10])
    # what the single run says about it
    assert main(["track", str(damaged), "--out", str(tmp_path / "single"), *TRACK_ARGS]) == 2
    reason = capsys.readouterr().err.strip().removeprefix("error: ")
    assert "is damaged" in reason

    inputs = [good[0], damaged, good[1]]
    out = tmp_path / "out"
    assert main(["track-many", *map(str, inputs), "--out", str(out), "--workers", "1", "--no-progress",
                 *TRACK_ARGS]) == 1
    captured = capsys.readouterr()
    assert "2 of 3 inputs finished (0 already were), 1 failed" in captured.out
    assert f"failed: {damaged}: {reason}" in captured.err
    rows = assert_summary_matches_runs(out, inputs)
    assert [r["status"] for r in rows] == ["finished", "failed", "finished"]
    assert rows[1]["reason"] == reason and rows[1]["frames"] == ""
    for clip in good:
        assert_same_track(out / clip.name, single_runs[clip.name])


@pytest.mark.slow
@pytest.mark.parametrize("keypoints", ["none", "mediapipe"])
def test_a_killed_worker_s_video_resumes_elsewhere_and_every_video_is_its_single_run(clips, single_runs, keypoints,
                                                                                    tmp_path):
    """A scheduler and two workers on 127.0.0.1; worker b, at its first checkpoint (after frame
    :data:`tests.killpoints.CHECKPOINT_EVERY` of a video), announces itself and waits
    (:func:`tests.killpoints.install`), and is killed there by SIGKILL. Without keypoints and
    with MediaPipe's (the resumed video's keypoints and poses are its single run's too)."""
    pytest.importorskip("distributed")
    args = [*TRACK_ARGS[:-1], keypoints]
    if keypoints != "none":
        need_mediapipe()
        single_runs = {clip.name: tmp_path / "single" / clip.name for clip in clips}
        for clip in clips:
            assert main(["track", str(clip), "--out", str(single_runs[clip.name]), *args]) == 0
    out, paused, pause_at = tmp_path / "out", tmp_path / "paused", 1
    assert CHECKPOINT_EVERY < N_FRAMES                  # the first checkpoint is in the middle of a video
    workers = {"worker-a": {}, "worker-b": {"prelude": f"from tests.killpoints import install; install('pause', "
                                                       f"{pause_at}); ", "env": {"KILLPOINTS_PAUSED": str(paused)}}}
    # paths relative to the command's folder, which is not the workers' (they run in REPO_ROOT)
    inputs = [os.path.relpath(clip, tmp_path) for clip in clips]
    with local_cluster(tmp_path, workers) as (address, processes):
        many = subprocess.Popen([sys.executable, "-m", "mocap", "track-many", *inputs, "--out", "out",
                                 "--scheduler", address, "--no-progress", *args],
                                cwd=tmp_path, env=cluster_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)
        processes["track-many"] = many
        wait_for(paused.exists, 300, "worker-b in the middle of a video", processes.values())
        os.kill(processes["worker-b"].pid, signal.SIGKILL)
        processes["worker-b"].wait(timeout=30)
        stdout, stderr = many.communicate(timeout=300)
        assert many.returncode == 0, stderr
    assert processes["worker-b"].returncode == -signal.SIGKILL
    assert "3 of 3 inputs finished (0 already were), 0 failed, " in stdout and f"on dask {address}" in stdout
    resumed = [json.loads((out / clip.name / files.RUN_JSON).read_text())["resumed_from_frame"] for clip in clips]
    assert sorted(resumed) == [0, 0, CHECKPOINT_EVERY]  # the killed worker's video went on from its checkpoint
    for clip in clips:
        assert_same_track(out / clip.name, single_runs[clip.name])
        if keypoints != "none":
            assert (out / clip.name / "keypoints.csv").read_bytes() == \
                (single_runs[clip.name] / "keypoints.csv").read_bytes()
    assert [r["status"] for r in assert_summary_matches_runs(out, inputs)] == ["finished"] * 3


#: Tries to reach a TLS scheduler with the cluster's credentials and without them, three ways; one line each.
_UNINVITED = """
import socket, ssl, sys
from distributed import Client
from distributed.security import Security
address, ca, cert, key = sys.argv[1:5]
host, port = address.removeprefix("tls://").split(":")

def bare_tls():                      # trusts the scheduler, shows no certificate of its own
    context = ssl.create_default_context(cafile=ca)
    with context.wrap_socket(socket.create_connection((host, int(port)), timeout=5), server_hostname=host) as s:
        s.sendall(b"hello")
        s.recv(1)

def dask_client(certificate, key):
    Client(address, timeout=5, security=Security(tls_ca_file=ca, tls_client_cert=certificate, tls_client_key=key,
                                                 require_encryption=True)).close()

attempts = {"the cluster's certificate": lambda: dask_client(*sys.argv[5:7]),      # the control: served
            "another authority's certificate": lambda: dask_client(cert, key),
            "no certificate": bare_tls,
            "plain TCP": lambda: Client(address.replace("tls://", "tcp://"), timeout=5).close()}
for what, attempt in attempts.items():
    try:
        attempt()
        print(what, "ACCEPTED")
    except Exception as exc:
        print(what, "refused:", type(exc).__name__, str(exc).replace(chr(10), " ")[:200])
"""


def test_track_many_runs_on_a_tls_cluster_that_refuses_clients_without_its_credentials(clips, single_runs, tmp_path):
    """docs/cluster.md's TLS recipe on 127.0.0.1: a scheduler and a worker speaking only TLS with
    certificates of the test's own authority; ``track-many`` gets its credentials from
    ``DASK_DISTRIBUTED__COMM__TLS__*`` and tracks as a single run does; a client with another
    authority's certificate, with none, or on plain TCP is refused by the scheduler."""
    pytest.importorskip("distributed")
    pytest.importorskip("cryptography")
    certificates, stranger = make_certificates(tmp_path), make_certificates(tmp_path, "stranger")
    inputs = [os.path.relpath(clips[0], tmp_path)]
    with local_cluster(tmp_path, {"worker-a": {}}, certificates) as (address, processes):
        assert address.startswith("tls://")
        uninvited = subprocess.run([sys.executable, "-c", _UNINVITED, address, str(certificates["ca"]),
                                    str(stranger["cert"]), str(stranger["key"]), str(certificates["cert"]),
                                    str(certificates["key"])],
                                   capture_output=True, text=True, env=cluster_env(), timeout=120)
        many = subprocess.run([sys.executable, "-m", "mocap", "track-many", *inputs, "--out", "out", "--scheduler",
                               address, "--no-progress", *TRACK_ARGS], cwd=tmp_path, capture_output=True, text=True,
                              env={**cluster_env(), **tls_client_env(certificates)}, timeout=300)
    # (how a refusal shows on the client's side depends on when the scheduler's TLS alert arrives)
    assert [line.split(" refused: ")[0] for line in uninvited.stdout.splitlines()] == [
        "the cluster's certificate ACCEPTED", "another authority's certificate", "no certificate", "plain TCP"], \
        uninvited.stdout + uninvited.stderr
    assert many.returncode == 0, many.stderr
    assert "1 of 1 inputs finished" in many.stdout and f"on dask {address}" in many.stdout
    assert_same_track(tmp_path / "out" / clips[0].name, single_runs[clips[0].name])


def test_hung_workers_are_those_holding_a_video_whose_heartbeat_stopped_for_the_timeout():
    """:class:`mocap.run.many.HungWorkers` on a hand-made clock and scheduler views."""
    from mocap.run.many import HungWorkers

    now = [0.0]
    hung = HungWorkers(6.0, clock=lambda: now[0])

    def look(t, seen, busy=("a", "b", "c")):
        now[0] = t
        return hung.look({w: {"last_seen": s} for w, s in seen.items()}, set(busy))

    assert look(0, {"a": 1.0, "b": 1.0, "c": 1.0, "idle": 1.0}, busy="abc") == []
    assert look(5.5, {"a": 1.0, "b": 6.5, "c": 1.0, "idle": 1.0}, busy="abc") == []
    # a: no heartbeat for 6 s; b's came at 5.5; c's last one is unchanged but c holds no video now;
    # an idle worker is never hung
    assert look(6.0, {"a": 1.0, "b": 6.5, "c": 1.0, "idle": 1.0}, busy="ab") == ["a"]
    assert look(11.0, {"a": 1.0, "b": 6.5, "c": 1.0, "idle": 1.0}, busy="abc") == ["c"]
    assert look(11.5, {"a": 1.0, "b": 6.5, "c": 1.0, "idle": 1.0}, busy="abc") == ["b"]
    # each once: a worker reported is watched afresh (a restarted worker has a new address anyway)
    assert look(12.0, {"a": 1.0, "b": 6.5, "c": 1.0}) == []
    assert look(16.5, {"a": 1.0}) == []              # b and c gone from the cluster: forgotten
    assert look(17.0, {"a": 1.0, "b": 6.5}) == ["a"]     # a: watched afresh since 11.0
    assert look(22.5, {"b": 6.5}) == []                  # b: since 17.0, not since 12.0
    assert look(23.0, {"b": 6.5}) == ["b"]


@pytest.mark.slow
def test_a_hung_worker_s_video_is_resumed_elsewhere_after_the_timeout_and_reported(clips, single_runs, tmp_path):
    """A scheduler and two workers under nannies on 127.0.0.1; worker b's process stops itself
    (SIGSTOP) right after its first checkpoint (:func:`tests.killpoints.install`, mode ``stop``,
    preloaded into the worker's process), holding its video's folder. With ``--hung-after 6``
    track-many restarts it through its nanny (the stopped process killed, its lock with it) and
    the video is resumed elsewhere from its checkpoint.

    The timeout only decides when a worker is taken for hung: a healthy worker taken for one on
    a slow machine would be restarted too and its video resumed from its checkpoint to the same
    rows, so what is asserted (every video its single run, the stopped one reported) holds
    either way."""
    pytest.importorskip("distributed")
    out, stopped = tmp_path / "out", tmp_path / "stopped"
    stop = {"KILLPOINTS_MODE": "stop", "KILLPOINTS_N": "1", "KILLPOINTS_PAUSED": str(stopped)}
    workers = {"worker-a": {"nanny": True}, "worker-b": {"nanny": True, "preload": "tests.killpoints", "env": stop}}
    inputs = [os.path.relpath(clip, tmp_path) for clip in clips]
    with local_cluster(tmp_path, workers) as (address, processes):
        many = subprocess.run([sys.executable, "-m", "mocap", "track-many", *inputs, "--out", "out",
                               "--scheduler", address, "--no-progress", "--hung-after", "6", *TRACK_ARGS],
                              cwd=tmp_path, env=cluster_env(), capture_output=True, text=True, timeout=600)
    assert many.returncode == 0, many.stderr
    held = stopped.read_text()                           # the folder of the video the stopped process held
    name = os.path.basename(held)
    assert "3 of 3 inputs finished (0 already were), 0 failed, " in many.stdout
    rows = {r["output"]: r for r in assert_summary_matches_runs(out, inputs)}
    assert [r["status"] for r in rows.values()] == ["finished"] * 3
    assert int(rows[name]["hung_restarts"]) >= 1
    assert f"{rows[name]['input']}: a worker it was on stopped responding and was restarted" in many.stdout
    assert json.loads((out / name / files.RUN_JSON).read_text())["resumed_from_frame"] == CHECKPOINT_EVERY
    for clip in clips:
        assert_same_track(out / clip.name, single_runs[clip.name])


def test_local_workers_share_the_cores_between_the_clips_and_their_threads(monkeypatch):
    """On 8 cores, 2 local workers give each clip 4 threads (3 with MediaPipe in its own
    process), 8 workers one each; threads asked for are kept; in this process (no workers) the
    run's own default applies."""
    from mocap.run import OwnVideoOptions
    from mocap.run import many

    monkeypatch.setattr(many, "default_workers", lambda: 8)
    monkeypatch.setattr(many, "resolve_keypoints", lambda name: (None if name == "none" else "mediapipe", ""))
    threads = lambda options, workers: many._checked(options, workers, 60.0)[0].threads
    assert threads(OwnVideoOptions(keypoints="none"), 2) == 4
    assert threads(OwnVideoOptions(keypoints="mediapipe"), 2) == 3
    assert threads(OwnVideoOptions(keypoints="none"), 8) == 1
    assert threads(OwnVideoOptions(keypoints="none", threads=5), 2) == 5
    assert threads(OwnVideoOptions(keypoints="none"), 0) is None        # this process: run's own default
