"""``python -m experiments.peers --only cmu`` (issue 34, item 5): its plumbing.

References: the generated clip's own ground truth (a tracker that returned it scores 0 mm), a
MediaPipe stand-in whose 3D is the truth moved by a known similarity plus a known offset (its
PA-MPJPE is :func:`mocap.metrics.pa_mpjpe` of that), and the options handed to the library's
``mocap.run.track`` (the lifter file reaches the tracker's config). MediaPipe and the tracker
are stood in for: the real runs are the experiment's, not a test's.
"""
from __future__ import annotations

import json

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
    lifter = tmp_path / "lifter_no14.npz"
    out = tmp_path / "out"
    assert peers.main(["--only", "cmu", "--data", str(shared_data), "--trials", "14_24", "--cmu-frames", "4",
                       "--lifter", str(lifter), "--out", str(out)]) == 0
    assert seen["motion"].name == "cmu_14_24.amc" and seen["frames"] == 4 and seen["upscale"] == 1
    assert seen["lifter"] == lifter and seen["keypoints"] == "mediapipe"     # the run's own detector
    (row,) = json.loads((out / "results.json").read_text())["cmu"]
    truth = PoseTable.read(seen["sequence"] / "ground_truth.csv").joints[:, peers.arm_indices()]
    moved = truth.copy()
    moved[:, 0] += offset / 1.3
    assert row["clip"] == "14_24" and row["frames"] == 4 and row["lifter"] == lifter.name
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
    # trials of another subject than the held-out one are refused
    assert peers.main(["--only", "cmu", "--data", str(shared_data), "--trials", "02_01", "--out", str(out)]) == 2


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
