"""End to end through the CLI: a short synthetic sequence tracked, outputs checked, resumed."""
import json
import shutil

import imageio.v3 as iio
import numpy as np
import pytest

from mocap.cli import main
from mocap.io.bvh import read_bvh, read_pose_bvh
from mocap.io.pose_table import PoseTable
from mocap.io.video import count_frames
from mocap.metrics import mpjpe

from tests.conftest import need_mediapipe

#: Mean joint error bound on the short test sequence with the true calibration, millimetres.
SEQUENCE_MPJPE_BOUND_MM = 110.0
N_FRAMES = 16


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    from mocap.synth import generate_sequence
    return generate_sequence("gestures-2", tmp_path_factory.mktemp("seq") / "gestures-2", frames=N_FRAMES, seed=3)


@pytest.mark.slow
def test_track_cli_end_to_end(sequence, tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["track", str(sequence), "--out", str(out), "--iterations", "300"]) == 0
    printed = capsys.readouterr().out
    assert "MPJPE" in printed and "frames/s" in printed
    for name in ("poses.csv", "poses.bvh", "overlay.mp4", "residuals.png", "run.json", "colour_model.json"):
        assert (out / name).is_file(), name
    table = PoseTable.read(out / "poses.csv")
    truth = PoseTable.read(sequence / "ground_truth.csv")
    assert len(table) == N_FRAMES and list(table.frames) == list(range(N_FRAMES))
    assert mpjpe(table.joints, truth.joints) < SEQUENCE_MPJPE_BOUND_MM
    run = json.loads((out / "run.json").read_text())
    assert set(run["metrics"]) == {"mpjpe_mm", "root_relative_mpjpe_mm", "pa_mpjpe_mm", "angle_error_deg", "reprojection_px", "failure_rate", "fps"}
    assert run["metrics"]["mpjpe_mm"] == pytest.approx(mpjpe(table.joints, truth.joints))
    assert run["settings"]["tracker"]["evaluations"] == 300
    # the budget, plus recovery (a second budget) and hand re-acquisition (candidates and a third)
    assert np.all(table.extra["evaluations"] > 0) and np.all(table.extra["evaluations"] <= 3 * 300 + 50)
    # the BVH parses, has the skeleton, and gives the same poses back
    bvh = read_bvh(out / "poses.bvh")
    assert bvh.n_frames == N_FRAMES
    poses, fps = read_pose_bvh(out / "poses.bvh")
    np.testing.assert_allclose(poses, table.poses, atol=1e-6)
    assert count_frames(out / "overlay.mp4") == N_FRAMES
    assert iio.imread(out / "residuals.png").ndim == 3


@pytest.mark.slow
def test_interrupted_run_resumes_to_the_same_poses(sequence, tmp_path):
    fresh, resumed = tmp_path / "fresh", tmp_path / "resumed"
    args = ["--iterations", "150", "--no-overlay"]
    assert main(["track", str(sequence), "--out", str(fresh), *args]) == 0
    assert main(["track", str(sequence), "--out", str(resumed), "--max-frames", "6", *args]) == 0
    # simulate a kill while writing frame 6: a partial line at the end of the journal
    with (resumed / "poses.csv").open("a") as fh:
        fh.write("6,0.01,0.2")
    assert main(["track", str(sequence), "--out", str(resumed), *args]) == 0
    a, b = PoseTable.read(fresh / "poses.csv"), PoseTable.read(resumed / "poses.csv")
    assert list(b.frames) == list(range(N_FRAMES))
    np.testing.assert_array_equal(a.poses, b.poses)
    assert json.loads((resumed / "run.json").read_text())["resumed_from_frame"] == 6
    # other settings in the same folder: refused, nothing lost
    before = (resumed / "poses.csv").read_bytes()
    assert main(["track", str(sequence), "--out", str(resumed), "--iterations", "99"]) == 2
    assert (resumed / "poses.csv").read_bytes() == before


@pytest.mark.slow
def test_empty_frame_is_marked_and_the_pose_kept(sequence, tmp_path):
    folder = tmp_path / "seq"
    shutil.copytree(sequence, folder)
    shutil.copy(folder / "background.png", folder / "frames" / "000005.png")   # nobody in view
    out = tmp_path / "run"
    assert main(["track", str(folder), "--out", str(out), "--iterations", "100", "--max-frames", "8",
                 "--no-overlay"]) == 0
    table = PoseTable.read(out / "poses.csv")
    assert table.extra["empty"].tolist() == [0, 0, 0, 0, 0, 1, 0, 0]
    np.testing.assert_array_equal(table.poses[5], table.poses[4])
    assert np.isnan(table.extra["region_residual"][5])


def test_bad_input_gives_one_line_errors(sequence, tmp_path, capsys):
    def fails(args, match):
        assert main(args) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error:") and "\n" not in err and match in err

    fails(["track", str(tmp_path / "missing.mp4")], "no such video")
    fails(["track", str(sequence), "--camera", "0"], "not both")
    fails(["track"], "VIDEO or --camera")
    small = tmp_path / "small.png"
    iio.imwrite(small, np.zeros((60, 80, 3), np.uint8))
    fails(["track", str(sequence), "--background", str(small), "--out", str(tmp_path / "o1")], "background")
    other = json.loads((sequence / "calibration.json").read_text())
    other["camera"].update(width=320, height=240, cx=160.0, cy=120.0)
    (tmp_path / "cal320.json").write_text(json.dumps(other))
    fails(["track", str(sequence), "--calibration", str(tmp_path / "cal320.json"), "--out", str(tmp_path / "o2")],
          "calibrate for this video")
    broken = tmp_path / "broken.mp4"
    broken.write_bytes(b"\x00\x00\x00\x18ftypmp42 this is not a video")
    fails(["track", str(broken), "--background", str(sequence / "background.png"),
           "--calibration", str(sequence / "calibration.json"), "--out", str(tmp_path / "o3")], "video")
    fails(["track", str(sequence), "--split", "2:x", "--out", str(tmp_path / "o4")], "split")
    (tmp_path / "bad.json").write_text("{not json")
    fails(["track", str(sequence), "--calibration", str(tmp_path / "bad.json"), "--out", str(tmp_path / "o5")], "JSON")


def test_tracker_options_set_the_beam_the_lag_and_the_paper_method(tmp_path):
    import argparse

    from mocap.commands._common import add_tracker_options, tracker_config
    from mocap.track import TrackerConfig

    p = argparse.ArgumentParser()
    add_tracker_options(p)
    assert tracker_config(p.parse_args([])) == TrackerConfig()
    assert tracker_config(p.parse_args(["--paper", "--iterations", "200"])) == TrackerConfig.paper(evaluations=200)
    config = tracker_config(p.parse_args(["--beam", "5", "--lag", "0", "--offline"]))
    assert (config.beam, config.lag, config.offline) == (5, 0, True)
    TrackerConfig(beam=2).to_json(tmp_path / "c.json")
    with pytest.raises(ValueError, match="either --config or --paper"):
        tracker_config(p.parse_args(["--paper", "--config", str(tmp_path / "c.json")]))
    with pytest.raises(ValueError, match="beam"):
        tracker_config(p.parse_args(["--beam", "0"]))


def test_keypoint_file_through_track_and_a_malformed_one_is_one_line(sequence, tmp_path, capsys):
    from mocap.io.keypoints import Keypoints, write_keypoints
    from mocap.render.calibration import Calibration

    truth = PoseTable.read(sequence / "ground_truth.csv")
    camera = Calibration.from_json(sequence / "calibration.json").camera        # the input camera
    frames = {i: Keypoints(camera.project(j), np.ones(len(j))) for i, j in enumerate(truth.joints[:4])}
    good = tmp_path / "keypoints.csv"
    write_keypoints(good, frames)
    out = tmp_path / "with-keypoints"
    assert main(["track", str(sequence), "--out", str(out), "--iterations", "100", "--max-frames", "4",
                 "--no-overlay", "--keypoints", str(good)]) == 0
    run = json.loads((out / "run.json").read_text())
    assert run["settings"]["keypoints"].startswith("file ")
    table = PoseTable.read(out / "poses.csv")
    # the keypoint cue holds the projected joints near the true ones (2D, input pixels)
    uv = np.stack([np.stack([table.extra[f"{j}_u"], table.extra[f"{j}_v"]], axis=-1)
                   for j in ("r_elbow", "r_wrist", "l_elbow", "l_wrist")], axis=1)
    assert np.nanmax(np.abs(uv - camera.project(truth.joints[:4])[:, [3, 4, 7, 8]])) < 3.0
    bad = tmp_path / "bad.csv"
    bad.write_text("frame,joint,u,v,confidence\n0,r_elbow,10,20,0.5\n1,nose,1,2,1\n")
    capsys.readouterr()
    assert main(["track", str(sequence), "--out", str(tmp_path / "bad-run"), "--keypoints", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and "\n" not in err and "line 3: unknown joint 'nose'" in err


@pytest.mark.mediapipe                  # (the real import check, made to fail here)
def test_keypoints_auto_without_the_extra_tracks_as_before_and_says_so(sequence, tmp_path, capsys, monkeypatch):
    """The commands' default ``--keypoints auto`` where MediaPipe is not installed (its package
    made not to be found, and its import to fail): the same poses as ``--keypoints none``, and
    the output and run.json say so."""
    import builtins
    import importlib.util

    from mocap.io import mediapipe_keypoints
    from mocap.run import advice

    real_import, real_find_spec = builtins.__import__, importlib.util.find_spec

    def no_mediapipe(name, *args, **kwargs):
        if name.split(".")[0] == "mediapipe":
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_mediapipe)
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *args: None if name.split(".")[0] == "mediapipe" else real_find_spec(name, *args))
    monkeypatch.setattr(advice, "MOSTLY_FAILED", -1.0)     # every run ends with its advice
    assert not mediapipe_keypoints.available()
    args = ["--iterations", "60", "--max-frames", "3", "--no-overlay"]
    capsys.readouterr()
    assert main(["track", str(sequence), "--out", str(tmp_path / "auto"), *args]) == 0
    printed = capsys.readouterr().out
    assert "keypoints: none (auto: MediaPipe Pose, the optional extra 'keypoints', is not installed" in printed
    # the closing line names the extra (the option auto found no MediaPipe), not an option that cannot run
    assert f"frames were marked failed; try the keypoints extra ({advice.KEYPOINTS_EXTRA_INSTALL}:" in printed
    assert "--keypoints mediapipe" not in printed
    assert main(["track", str(sequence), "--out", str(tmp_path / "none"), "--keypoints", "none", *args]) == 0
    runs = {name: json.loads((tmp_path / name / "run.json").read_text()) for name in ("auto", "none")}
    assert runs["auto"]["settings"]["keypoints"] == runs["none"]["settings"]["keypoints"] == "none"
    # said once in run.json (settings.keypoints); the why of auto is the printed line's
    assert "keypoints" not in runs["auto"]["settings"]["own_video"]
    np.testing.assert_array_equal(PoseTable.read(tmp_path / "auto" / "poses.csv").poses,
                                  PoseTable.read(tmp_path / "none" / "poses.csv").poses)


@pytest.mark.mediapipe
def test_keypoints_auto_with_the_extra_uses_mediapipe(sequence, tmp_path, capsys, monkeypatch):
    need_mediapipe()
    from mocap.run import advice

    monkeypatch.setattr(advice, "MOSTLY_FAILED", -1.0)     # every run ends with its advice
    out = tmp_path / "auto"
    assert main(["track", str(sequence), "--out", str(out), "--iterations", "40", "--max-frames", "2",
                 "--no-overlay"]) == 0
    printed = capsys.readouterr().out
    assert "keypoints: mediapipe (auto: the optional extra 'keypoints' is installed)" in printed
    hint = [line for line in printed.splitlines() if "frames were marked failed" in line]
    assert len(hint) == 1 and "keypoints" not in hint[0]
    # the extra installed but not used: the closing line names the option, not the install
    assert main(["track", str(sequence), "--out", str(tmp_path / "none"), "--keypoints", "none", "--iterations", "40",
                 "--max-frames", "2", "--no-overlay"]) == 0
    hint = [line for line in capsys.readouterr().out.splitlines() if "frames were marked failed" in line]
    assert len(hint) == 1 and "failed; try --keypoints mediapipe (2D keypoints" in hint[0] and "extra" not in hint[0]
    run = json.loads((out / "run.json").read_text())
    assert run["settings"]["keypoints"].startswith("mediapipe ") and run["settings"]["keypoints"].endswith(
        "(--keypoints auto)")
    assert run["keypoints_ms_per_frame"] > 0


def test_an_old_run_folder_is_refused_with_why_and_what_to_do(sequence, tmp_path, capsys, monkeypatch):
    """A folder tracked before ``settings.keypoints`` existed, and folders resumed after the
    keypoints extra was installed (``auto`` was none) or removed (``auto`` was MediaPipe): one
    line each, saying why and what to do; nothing in the folder changes."""
    from mocap.io import mediapipe_keypoints

    args = ["--iterations", "20", "--beam", "1", "--max-frames", "2", "--no-overlay"]

    def refused(out, why: str) -> None:
        before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
        capsys.readouterr()
        assert main(["track", str(sequence), "--out", str(out), *args]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and why in err and "--overwrite" in err, err
        assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before

    old = tmp_path / "old"
    assert main(["track", str(sequence), "--out", str(old), *args, "--keypoints", "none"]) == 0
    run = json.loads((old / "run.json").read_text())
    del run["settings"]["keypoints"]                  # as written before settings.keypoints existed
    (old / "run.json").write_text(json.dumps(run))
    refused(old, "holds a run of an earlier mocap (its run.json has no settings.keypoints)")

    need_mediapipe()            # "installed since" makes the detector (without MediaPipe: refused for that)
    bare = tmp_path / "bare"                          # --keypoints auto without the extra: none
    assert main(["track", str(sequence), "--out", str(bare), *args]) == 0
    monkeypatch.setattr(mediapipe_keypoints, "available", lambda: True)       # the extra installed since
    refused(bare, "the optional extra 'keypoints' was installed or removed")
    extra = tmp_path / "extra"                        # --keypoints auto with the extra: MediaPipe
    assert main(["track", str(sequence), "--out", str(extra), *args]) == 0
    monkeypatch.setattr(mediapipe_keypoints, "available", lambda: False)      # the extra removed since
    refused(extra, "the optional extra 'keypoints' was installed or removed")


def test_keypoints_with_left_and_right_swapped_give_the_same_poses(sequence, tmp_path):
    """A keypoint file whose left and right are swapped on every frame, or on a run of frames (a
    detector that does not see the face), gives the same poses as the right file: the tolerance
    is none (the labelling is part of each hypothesis, scored under both labellings in the
    model's joint order). ``poses.csv`` says which labelling each frame's pose read, and
    ``keypoints.csv`` keeps the detector's own labels."""
    from mocap.io.keypoints import Keypoints, read_keypoints, write_keypoints
    from mocap.render.calibration import Calibration

    n = 6
    truth = PoseTable.read(sequence / "ground_truth.csv")
    camera = Calibration.from_json(sequence / "calibration.json").camera
    rng = np.random.default_rng(5)
    right = [Keypoints(camera.project(j) + rng.normal(0.0, 1.0, (len(j), 2)), np.ones(len(j))) for j in truth.joints[:n]]
    runs = {"right": np.zeros(n, bool), "every": np.ones(n, bool), "run": np.isin(np.arange(n), [2, 3, 4])}
    tables = {}
    for name, swapped in runs.items():
        given = {i: k.swapped() if s else k for i, (k, s) in enumerate(zip(right, swapped))}
        write_keypoints(tmp_path / f"{name}.csv", given)
        out = tmp_path / name
        assert main(["track", str(sequence), "--out", str(out), "--iterations", "100", "--max-frames", str(n),
                     "--no-overlay", "--keypoints", str(tmp_path / f"{name}.csv")]) == 0
        tables[name] = PoseTable.read(out / "poses.csv")
        np.testing.assert_array_equal(tables[name].extra["labels_swapped"], swapped.astype(float))
        kept = read_keypoints(out / "keypoints.csv")
        for i in range(n):
            np.testing.assert_array_equal(kept[i].uv, given[i].uv)
    for name in ("every", "run"):
        np.testing.assert_array_equal(tables[name].poses, tables["right"].poses)
        np.testing.assert_array_equal(tables[name].joints, tables["right"].joints)
    # the right labels' poses are the truth's arms, not a body turned around
    arms = [2, 3, 4, 5, 6, 7, 8, 9]
    about_neck = lambda j: j[:, arms] - j[:, 1:2]
    assert np.linalg.norm(about_neck(tables["right"].joints) - about_neck(truth.joints[:n]), axis=2).mean() < 0.08
