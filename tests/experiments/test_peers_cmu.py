"""``python -m experiments.peers --only cmu`` (issue 34, item 5; issue 49, item 6): its plumbing.

References: the generated clip's own ground truth (a tracker that returned it scores 0 mm), a
MediaPipe stand-in whose 3D is the truth moved by a known similarity plus a known offset (its
PA-MPJPE is :func:`mocap.metrics.pa_mpjpe` of that), the options handed to the library's
``mocap.run.track`` (the lifter file reaches the tracker's config), the rendered frames' head
pixels against the actor's hair and skin colours, and targets counted by hand. MediaPipe, the
tracker and the lifter's training are stood in for: the real runs are the experiment's, not a
test's.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

peers = pytest.importorskip("experiments.peers")


def test_the_cmu_group_renders_the_held_out_subjects_trial_and_passes_the_lifter_file(shared_data, tmp_path,
                                                                                      monkeypatch):
    from mocap.io.pose_table import PoseTable
    from mocap.metrics import pa_mpjpe

    offset = np.array([0.02, -0.01, 0.03])
    seen = {}

    def fake_mediapipe(frames, upscale=1):
        seen["frames"], seen["upscale"] = len(frames), upscale
        truth = PoseTable.read(seen["sequence"] / "ground_truth.csv").joints[:, peers.arm_indices()]
        world = 1.3 * truth + 0.5
        world[:, 0] += offset                               # the right shoulder off by 37 mm
        n = len(frames)
        return {"uv": np.zeros((n, 6, 2)), "world": world, "ms": np.ones(n),
                "world33": np.zeros((n, 33, 3)), "visibility33": np.ones((n, 33))}

    def fake_track(video, out, *, overlay, keypoints="none", lifter=None):
        """The truth as ours; as the run's detector, the truth projected, left and right
        exchanged on frame 1 and shifted 3 px on frame 2, nothing found on frame 3."""
        from mocap.calibrate import Calibration
        from mocap.io.keypoints import Keypoints, write_keypoints

        seen["sequence"], seen["lifter"], seen["keypoints"] = video, lifter, keypoints
        table = PoseTable.read(video / "ground_truth.csv")
        table.extra["ms_total"] = np.ones(len(table))
        camera = Calibration.from_json(video / "calibration.json").camera
        frames = {}
        for i, joints in enumerate(table.joints):
            k = Keypoints(camera.project(joints), np.ones(len(joints)))
            frames[i] = {1: k.swapped(),
                         2: Keypoints(k.uv + [3.0, 0.0], k.confidence),
                         3: Keypoints.empty()}.get(i, k)
        out.mkdir(parents=True, exist_ok=True)
        write_keypoints(out / "keypoints.csv", frames)
        return table

    real_generate = __import__("mocap.synth", fromlist=["generate_sequence"]).generate_sequence

    def generate(name, out_dir, **options):
        seen["sequence"] = out_dir
        seen["motion"] = options["motion"]
        return real_generate(name, out_dir, **options)

    monkeypatch.setattr("mocap.io.mediapipe_keypoints.available", lambda: True)     # stood in for: any Python
    monkeypatch.setattr(peers, "run_mediapipe", fake_mediapipe)
    monkeypatch.setattr(peers, "_track", fake_track)
    monkeypatch.setattr("mocap.synth.generate_sequence", generate)
    monkeypatch.setattr("experiments.fit_lifter.main", lambda argv: pytest.fail("a present lifter is trained again"))
    lifters = tmp_path / "lifters"
    lifters.mkdir()
    lifter = lifters / "lifter_no14.npz"
    lifter.write_bytes(b"stand-in")                     # present: used, not trained
    out = tmp_path / "out"
    assert peers.main(["--only", "cmu", "--data", str(shared_data), "--subjects", "14", "--trials", "14_24",
                       "--cmu-frames", "4", "--cmu-sizes", "160x120", "--faces", "face", "--lifters", str(lifters),
                       "--out", str(out)]) == 0
    assert seen["motion"].name == "cmu_14_24.amc" and seen["frames"] == 4 and seen["upscale"] == 1
    assert seen["lifter"] == lifter and seen["keypoints"] == "mediapipe"     # the run's own detector
    (row,) = json.loads((out / "results.json").read_text())["cmu"]
    truth = PoseTable.read(seen["sequence"] / "ground_truth.csv").joints[:, peers.arm_indices()]
    moved = truth.copy()
    moved[:, 0] += offset / 1.3
    assert row["clip"] == "14_24" and row["frames"] == 4 and row["lifter"] == lifter.name
    assert row["subject"] == "14" and row["face"] is True and row["size"] == "160x120"
    assert row["scene"] == peers.CMU_SCENES[0]
    assert row["ours_keypoints_pa_mpjpe_mm"] == pytest.approx(0.0, abs=1e-6)
    assert row["ours_keypoints_centred_mm"] == pytest.approx(0.0, abs=1e-6)
    assert row["ours_keypoints_labels_right"] == 1.0
    assert row["mediapipe_pa_mpjpe_mm"] == pytest.approx(pa_mpjpe(moved, truth), rel=1e-6)
    assert row["pa_ratio"] == pytest.approx(0.0, abs=1e-6)
    # MediaPipe's 3D about its centre: scaled by 1.3 (no alignment undoes it) and one joint moved
    centre = lambda x: x - x.mean(axis=1, keepdims=True)
    world = 1.3 * truth + 0.5
    world[:, 0] += offset
    assert row["mediapipe_centred_mm"] == pytest.approx(
        1e3 * np.linalg.norm(centre(world) - centre(truth), axis=2).mean(), rel=1e-6)
    # the detector: found on 3 of 4 frames, swapped on 1 of those 3, 2D error the median of
    # 0 px (frames 0, 1 under the better labelling) and 3 px (frame 2) over the 18 joints
    assert row["detector_found"] == pytest.approx(0.75) and row["detector_swapped"] == pytest.approx(1 / 3)
    assert row["detector_error_px"] == pytest.approx(0.0, abs=1e-6)
    assert "14_24" in (out / "peers.md").read_text()


def test_track_hands_the_lifter_file_to_the_tracker_config(tmp_path, monkeypatch):
    import mocap.run
    from mocap.track.config import TrackerConfig

    got = {}

    def fake(video, out, options):
        got["options"] = options
        raise RuntimeError("stop")

    monkeypatch.setattr(mocap.run, "track", fake)
    for lifter, expect in ((tmp_path / "l.npz", str(tmp_path / "l.npz")), (None, None)):
        with pytest.raises(RuntimeError, match="stop"):
            peers._track(tmp_path, tmp_path / "run", overlay=False, keypoints="none", lifter=lifter)
        assert got["options"].tracker == TrackerConfig(lifter_file=expect)
        assert got["options"].keypoints == "none"


def test_clips_cover_each_subject_size_and_head_in_order_with_their_file_tags():
    sizes = [(160, 120), (640, 480)]
    clips = peers.cmu_clips(["14", "02"], ["02_05", "14_06", "02_10"], sizes, (True, False))
    assert [(c.subject, c.trial, c.size, c.face) for c in clips] == [
        ("14", "14_06", s, f) for s in sizes for f in (True, False)] + [
        ("02", t, s, f) for t in ("02_05", "02_10") for s in sizes for f in (True, False)]
    # scenes cycle over each subject's own trials, in their order
    assert {c.trial: c.scene for c in clips} == {"14_06": peers.CMU_SCENES[0], "02_05": peers.CMU_SCENES[0],
                                                 "02_10": peers.CMU_SCENES[1]}
    # subject 14's default clips keep the scenes they had when 14 was the only subject
    default = peers.cmu_clips(["14"], None, [(160, 120)], (True,))
    assert [(c.trial, c.scene) for c in default] == [("14_02", "gestures-2"), ("14_06", "turning"),
                                                    ("14_20", "arms-crossing"), ("14_24", "not-facing")]
    tags = {(c.size, c.face): c.tag for c in clips}
    assert tags == {((160, 120), True): "", ((160, 120), False): "-noface",
                    ((640, 480), True): "-640x480", ((640, 480), False): "-640x480-noface"}
    with pytest.raises(ValueError, match="02_05"):
        peers.cmu_clips(["14"], ["02_05"], sizes, (True,))            # a trial of no held-out subject
    with pytest.raises(ValueError, match="subject 02"):
        peers.cmu_clips(["14", "02"], ["14_02"], sizes, (True,))      # a subject left without a trial
    with pytest.raises(ValueError, match="no default trials for subject 86"):
        peers.cmu_clips(["86"], None, sizes, (True,))


def test_a_missing_held_out_lifter_is_trained_once_where_it_is_then_reused(tmp_path, monkeypatch):
    calls = []

    def fake_fit(argv):
        calls.append(argv)
        Path(argv[argv.index("--out") + 1]).write_bytes(b"trained")
        return 0

    monkeypatch.setattr("experiments.fit_lifter.main", fake_fit)
    folder, train = tmp_path / "work", tmp_path / "train"
    assert peers.lifter_path(folder, "02") == folder / "lifter_no02.npz"
    path = peers.held_out_lifter("02", folder, train)
    assert path == folder / "lifter_no02.npz" and path.read_bytes() == b"trained"
    (argv,) = calls
    from experiments.fit_lifter import RECORD
    assert argv[argv.index("--exclude-subject") + 1] == "02"
    assert Path(argv[argv.index("--trials-from") + 1]) == RECORD       # the shipped lifter's trials, less 02's
    assert Path(argv[argv.index("--train") + 1]) == train
    assert peers.held_out_lifter("02", folder, train) == path and len(calls) == 1     # present: reused
    monkeypatch.setattr("experiments.fit_lifter.main", lambda argv: 2)
    with pytest.raises(RuntimeError, match="without subject 14"):
        peers.held_out_lifter("14", folder, train)


def test_target_summary_counts_issue_49s_targets_per_head():
    def row(face, pa, accel, labels):
        return {"face": face, "pa_ratio": pa, "accel_ratio": accel, "ours_keypoints_labels_right": labels}

    rows = [row(True, 0.7, 0.2, 1.0), row(True, 0.8, 0.4, 0.97), row(True, 0.95, 0.3, 0.99),
            row(False, 0.6, 0.1, 1.0), row(False, 1.2, 0.6, 0.90)]
    face, no_face, both = peers.target_summary(rows)
    assert (face["group"], face["clips"], no_face["group"], no_face["clips"], both["clips"]) == \
        ("face", 3, "no face", 2, 5)
    assert face["pa_ratio_max"] == 0.95 and face["pa_ratio_median"] == 0.8
    assert face["accel_ratio_max"] == 0.4 and face["labels_right_min"] == 0.97
    assert face["pa_ratio_max_met"] and face["pa_ratio_median_met"] and face["accel_ratio_max_met"] \
        and face["labels_right_min_met"]
    assert no_face["pa_ratio_median"] == pytest.approx(0.9)
    assert not (no_face["pa_ratio_max_met"] or no_face["pa_ratio_median_met"] or no_face["accel_ratio_max_met"]
                or no_face["labels_right_min_met"])
    assert both["pa_ratio_median"] == 0.8 and both["labels_right_min"] == 0.90
    nan = peers.target_summary([row(True, float("nan"), 0.2, 1.0)])[0]
    assert not nan["pa_ratio_max_met"] and nan["accel_ratio_max_met"]          # a NaN ratio is a miss


@pytest.mark.parametrize("argv, message", [
    (["--cmu-sizes", "160x120,big"], "--cmu-sizes"),
    (["--cmu-sizes", "8x6"], "--cmu-sizes"),
    (["--size", "320x240"], "--cmu-sizes"),                          # --size is the synthetic clips'
    (["--cmu-frames", "0"], "--cmu-frames"),
    (["--subjects", "14,14"], "--subjects"),
    (["--subjects", "14", "--trials", "02_05"], "02_05"),
    (["--subjects", "86"], "no default trials for subject 86"),
    (["--faces", "half"], "--faces"),
])
def test_bad_cmu_options_are_refused_before_any_work(argv, message, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("mocap.io.mediapipe_keypoints.available", lambda: True)
    monkeypatch.setattr(peers, "held_out_lifter", lambda *a: pytest.fail("work started"))
    with pytest.raises(SystemExit) as exit_:
        peers.main(["--only", "cmu", "--out", str(tmp_path / "out"), *argv])
    assert exit_.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_no_face_draws_hair_all_round_and_changes_nothing_but_the_head(shared_data, tmp_path, monkeypatch):
    """``--faces both``: each clip twice, the second drawn with hair all round the head; the two
    clips' frames differ only about the head (its box grown by a JPEG block, 16 px, for the sensor's
    blur and the compression's blocks). That the head then shows
    no skin, eyes or mouth is asserted on its rendered pixels in tests/synth/test_face.py."""
    from mocap.body.dimensions import PART_NAMES
    from mocap.io.pose_table import PoseTable
    from mocap.io.video import iter_frames
    from mocap.synth import setup_sequence
    from mocap.synth.shading import render_actor

    heads = []
    real_generate = __import__("mocap.synth", fromlist=["generate_sequence"]).generate_sequence

    def generate(name, out_dir, **options):
        heads.append((Path(out_dir).name, options["face"]))
        return real_generate(name, out_dir, **options)

    def fake_mediapipe(frames, upscale=1):
        n = len(frames)
        return {"uv": np.zeros((n, 6, 2)), "world": np.full((n, 6, 3), np.nan), "ms": np.ones(n),
                "world33": np.zeros((n, 33, 3)), "visibility33": np.ones((n, 33))}

    def fake_track(video, out, *, overlay, keypoints="none", lifter=None):
        from mocap.io.keypoints import write_keypoints

        out.mkdir(parents=True, exist_ok=True)
        write_keypoints(out / "keypoints.csv", {})
        table = PoseTable.read(video / "ground_truth.csv")
        table.extra["ms_total"] = np.ones(len(table))
        return table

    monkeypatch.setattr("mocap.io.mediapipe_keypoints.available", lambda: True)
    monkeypatch.setattr(peers, "run_mediapipe", fake_mediapipe)
    monkeypatch.setattr(peers, "_track", fake_track)
    monkeypatch.setattr(peers, "held_out_lifter", lambda subject, folder, train: folder / f"lifter_no{subject}.npz")
    monkeypatch.setattr("mocap.synth.generate_sequence", generate)
    out = tmp_path / "out"
    assert peers.main(["--only", "cmu", "--data", str(shared_data), "--subjects", "14", "--trials", "14_02",
                       "--cmu-frames", "2", "--cmu-sizes", "160x120", "--faces", "both", "--out", str(out)]) == 0
    assert heads == [("cmu_14_02", True), ("cmu_14_02-noface", False)]
    rows = json.loads((out / "results.json").read_text())["cmu"]
    assert [(r["clip"], r["face"]) for r in rows] == [("14_02", True), ("14_02", False)]
    assert "| no face |" in (out / "peers.md").read_text()
    work = out / "work"
    meta = {f: json.loads((work / name / "meta.json").read_text()) for name, f in heads}
    assert meta[False]["actor"]["appearance"]["face"] is False and "face" not in meta[True]["actor"]["appearance"]
    with_face, without = (np.stack([np.asarray(f, float) for f in iter_frames(work / name / "frames")])
                          for name, _ in heads)
    # the head's pixels on frame 0 (the truth's pose, the scene's own actor and camera)
    setup = setup_sequence(rows[0]["scene"], seed=0, size=(160, 120))
    pose = PoseTable.read(work / "cmu_14_02" / "ground_truth.csv").poses[0]
    _, parts = render_actor(setup.actor, pose, setup.camera, setup.light, setup.background_radiance)
    rows_, cols = np.nonzero(parts == PART_NAMES.index("head"))
    block = np.zeros(parts.shape, bool)
    block[max(rows_.min() - 16, 0):rows_.max() + 17, max(cols.min() - 16, 0):cols.max() + 17] = True
    differs = np.any(with_face[0] != without[0], axis=2)
    assert differs[parts == PART_NAMES.index("head")].mean() > 0.3      # the face is gone
    assert not (differs & ~block).any()                                  # body, clothes, scene the same
