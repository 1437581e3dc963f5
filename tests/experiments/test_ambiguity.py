import json
import numpy as np
import pytest
from experiments.ambiguity import ARM_JOINTS, flip_oracle, reflect_in_depth, table


def test_reflection_is_an_involution_that_keeps_the_ray_and_the_distance():
    rng = np.random.default_rng(0)
    pivot = np.array([0.2, -0.1, 1.8])
    pts = pivot + rng.normal(0, 0.3, (20, 3))
    back = reflect_in_depth(reflect_in_depth(pts, pivot), pivot)
    np.testing.assert_allclose(back, pts, atol=1e-12)
    mirrored = reflect_in_depth(pts, pivot)
    np.testing.assert_allclose(np.linalg.norm(mirrored - pivot, axis=1), np.linalg.norm(pts - pivot, axis=1))
    # a point on the camera ray through the pivot maps to its mirror on the same ray
    on_ray = np.array([pivot * 1.1])
    np.testing.assert_allclose(reflect_in_depth(on_ray, pivot), [pivot * 0.9], atol=1e-12)


def test_oracle_undoes_a_mirrored_forearm_and_keeps_a_correct_arm():
    rng = np.random.default_rng(1)
    truth = np.array([0.0, 0.0, 1.8]) + rng.normal(0, 0.3, (3, 10, 3))
    tracked = truth.copy()
    s, e, w, h = ARM_JOINTS["r"]
    tracked[1, [w, h]] = reflect_in_depth(truth[1, [w, h]], truth[1, e])
    tracked[2, [e, w, h]] = reflect_in_depth(truth[2, [e, w, h]], truth[2, s])
    out = flip_oracle(tracked, truth)
    np.testing.assert_allclose(out, truth, atol=1e-12)
    # never worse than as tracked, arm by arm; the head and shoulders are never touched
    noisy = truth + rng.normal(0, 0.05, truth.shape)
    picked = flip_oracle(noisy, truth)
    for idx in ARM_JOINTS.values():
        before = np.linalg.norm(noisy[:, idx] - truth[:, idx], axis=2).sum(1)
        after = np.linalg.norm(picked[:, idx] - truth[:, idx], axis=2).sum(1)
        assert (after <= before + 1e-12).all()
    np.testing.assert_array_equal(picked[:, [0, 1, s, ARM_JOINTS["l"][0]]], noisy[:, [0, 1, s, ARM_JOINTS["l"][0]]])


def test_table_has_a_median_row():
    row = dict(sequence="a", mpjpe_mm=100.0, failure_rate=0.5, reprojection_px=2.0, flip_oracle_mpjpe_mm=50.0,
               flip_oracle_failure_rate=0.1, cost_equivalent_failure_rate=0.2, cost_equivalent_both_rate=0.1)
    text = table([row, {**row, "sequence": "b", "mpjpe_mm": 200.0, "cost_equivalent_both_rate": 0.0}])
    assert "| **median** | 150 | 50 % | 2.0 | 50 | 10 % | 20 % | 5 % |" in text


def test_cost_equivalent_rates_count_failing_frames_the_costs_prefer():
    import pytest

    from experiments.ambiguity import cost_equivalent_rates

    error = np.array([150.0, 150.0, 150.0, 50.0, 150.0, 100.0])
    truth = np.array([[0.10, 1.0]] * 6)
    tracked = np.array([[0.10, 1.0],       # fails, ties the truth on both costs: counts twice
                        [0.09, 1.5],       # fails, lower F but higher edge distance: F only
                        [0.20, 0.5],       # fails, higher F: neither
                        [0.05, 0.5],       # better by both costs but within 100 mm: not a failure
                        [np.nan, np.nan],  # empty frame: never equivalent
                        [0.05, 0.5]])      # exactly 100 mm is not a failure
    assert cost_equivalent_rates(error, tracked, truth) == (2 / 6, 1 / 6)
    assert cost_equivalent_rates(error, tracked, truth, threshold_mm=40.0) == (4 / 6, 3 / 6)
    with pytest.raises(ValueError, match="frames"):
        cost_equivalent_rates(error, tracked[:5], truth[:5])


def _clean_frames(poses, model, camera):
    """Prepared-frame stand-ins (labels and distance map) rendered from the model itself."""
    from types import SimpleNamespace

    from scipy import ndimage

    from mocap.render import render

    frames = []
    for q in poses:
        r = render(q, model, camera)
        distance = np.minimum(ndimage.distance_transform_edt(~r.edges), 20.0).astype(np.float32)
        frames.append(SimpleNamespace(labels=r.labels, distance=distance))
    return frames


def test_register_from_truth_starts_each_frame_from_the_lagged_truth():
    import pytest

    from experiments.ambiguity import register_from_truth
    from mocap.body import PARAMETER_INDEX as P, BodyModel, neutral_pose
    from mocap.render import Camera
    from mocap.track import TrackerConfig

    model, camera = BodyModel.build(resolution=8), Camera.default()
    poses = np.tile(neutral_pose(), (5, 1))
    poses[:, P["r_shoulder_abd"]] += np.radians(np.arange(5) * 6.0)    # the right arm rises 6 degrees a frame
    frames = _clean_frames(poses, model, camera)
    config = TrackerConfig(evaluations=200)
    index, out = register_from_truth(frames, model, camera, poses, config, lag=2, every=2)
    np.testing.assert_array_equal(index, [0, 2, 4])
    err = [np.linalg.norm(model.joint_positions(q) - model.joint_positions(poses[f]), axis=1).mean()
           for q, f in zip(out, index)]
    start = [np.linalg.norm(model.joint_positions(poses[max(f - 2, 0)]) - model.joint_positions(poses[f]),
                            axis=1).mean() for f in index]
    # frame 0 starts on its own truth, where F is 0, and stays there exactly; the others start 12
    # degrees of arm motion (31 mm of mean joint error) away and end closer, but not exactly there
    assert err[0] < 1e-9
    for k in (1, 2):
        assert 1e-4 < err[k] < start[k] and err[k] < 0.035, (err, start)
    # frames never see later ones: registering frame 4 alone from frame 2's truth gives the same pose
    _, alone = register_from_truth(frames[:5], model, camera, poses, config, lag=2, every=4)
    np.testing.assert_array_equal(alone[1], out[2])
    for lag, every in ((-1, 1), (0, 0)):
        with pytest.raises(ValueError, match="lag"):
            register_from_truth(frames, model, camera, poses, config, lag=lag, every=every)


def test_table_from_truth_has_a_median_row():
    from experiments.ambiguity import table_from_truth

    row = dict(sequence="a", lag1_start_mpjpe_mm=10.0, lag1_mpjpe_mm=20.0, lag1_failure_rate=0.0)
    text = table_from_truth([row, {**row, "sequence": "b", "lag1_mpjpe_mm": 40.0, "lag1_failure_rate": 0.1}], (1,))
    assert "| **median** | 10 | 30 | 5 % |" in text


def test_from_truth_option_rejects_bad_lags(capsys):
    from experiments.ambiguity import main

    assert main(["--from-truth", "1,x"]) == 2
    assert "--from-truth" in capsys.readouterr().err


def test_lower_region_cost_keeps_the_better_track_frame_by_frame():
    from types import SimpleNamespace

    import pytest

    from experiments.ambiguity import lower_region_cost

    track = lambda name, values: [SimpleNamespace(name=name, region_residual=v) for v in values]
    forward = track("f", [0.1, 0.3, 0.2, np.nan, 0.4])
    backward = track("b", [0.2, 0.1, 0.2, 0.5, np.nan])
    # lower F wins; a tie keeps forward; a number beats NaN (an empty frame) on either side
    assert [r.name for r in lower_region_cost(forward, backward)] == ["f", "b", "f", "b", "f"]
    with pytest.raises(ValueError, match="same frames"):
        lower_region_cost(forward, backward[:4])


def test_two_way_option_cannot_go_with_from_truth(capsys):
    from experiments.ambiguity import main

    assert main(["--two-way", "--from-truth", "1"]) == 2
    assert "--two-way" in capsys.readouterr().err


def test_pooled_table_weighs_rates_by_frames_and_takes_the_median_mpjpe():
    from experiments.ambiguity import pooled_table
    base = {"failure_rate": 0.0, "cost_equivalent_failure_rate": 0.0}
    rows = [{**base, "sequence": "a", "seed": 0, "frames": 100, "mpjpe_mm": 50.0, "cost_equivalent_both_rate": 0.10},
            {**base, "sequence": "a", "seed": 1, "frames": 300, "mpjpe_mm": 90.0, "cost_equivalent_both_rate": 0.02},
            {**base, "sequence": "b", "seed": 0, "frames": 100, "mpjpe_mm": 70.0, "cost_equivalent_both_rate": 0.00}]
    lines = pooled_table(rows).splitlines()
    # a: (100 * 0.10 + 300 * 0.02) / 400 = 4 %; all: 16 / 500 = 3.2 %; medians 70 and 70
    assert lines[2] == "| a | 0,1 | 400 | 70 | 0.0 % | 0.0 % | 4.0 % |"
    assert lines[4] == "| **all** | 0,1 | 500 | 70 | 0.0 % | 0.0 % | 3.2 % |"


def test_seed_option_rejects_non_integers(capsys):
    from experiments.ambiguity import main
    assert main(["--seed", "0,x"]) == 2
    assert "--seed" in capsys.readouterr().err


def test_summary_pools_every_frame_of_every_sequence_and_seed():
    from experiments.ambiguity import summary

    rows = [{"sequence": "a", "seed": 0, "lag1_frame_mpjpe_mm": [10.0, 20.0, 200.0], "lag1_frame_start_mpjpe_mm": [1.0] * 3,
             "lag1_mpjpe_mm": 76.7, "lag1_ms_per_frame": 2.0, "lag1_edge_residual_px": 1.0, "lag1_region_residual": 0.1,
             "lag1_residual_failures": 1},
            {"sequence": "b", "seed": 29, "lag1_frame_mpjpe_mm": [30.0], "lag1_frame_start_mpjpe_mm": [5.0],
             "lag1_mpjpe_mm": 30.0, "lag1_ms_per_frame": 6.0, "lag1_edge_residual_px": 3.0, "lag1_region_residual": 0.3,
             "lag1_residual_failures": 2}]
    got = summary(rows, (1, 3))
    assert got["frames"] == 4 and got["median_mm"] == 25.0 and got["mean_mm"] == 65.0
    assert got["start_median_mm"] == 1.0 and got["failure_rate"] == 0.25
    assert got["ms_per_frame"] == 3.0 and got["edge_residual_px"] == 1.5 and got["residual_failures"] == 3   # frame-weighted
    assert [p["seed"] for p in got["per_sequence"]] == [0, 29]
    json.dumps(got)                                                   # one JSON object


def test_a_result_is_reused_only_with_the_code_it_was_measured_with(tmp_path, monkeypatch, capsys):
    """The cache's key holds the code: the same configuration measured by other code is measured again."""
    import experiments.ambiguity as ambiguity

    row = dict(sequence="gestures-1", mpjpe_mm=80.0, failure_rate=0.0, frames=2, frame_mpjpe_mm=[70.0, 90.0],
               tracking_ms_per_frame=1.0, cost_equivalent_failure_rate=0.0)
    measured = []

    def fake_measure(name, config, root, seed, two_way, without):
        measured.append(name)
        return {**row, "sequence": name}

    monkeypatch.setattr(ambiguity, "measure", fake_measure)
    argv = ["--sequences", "gestures-1", "--out", str(tmp_path), "--json"]
    for code, expected in (("aaaa", 1), ("aaaa", 1), ("bbbb", 2), ("bbbb", 2), ("aaaa", 3)):
        monkeypatch.setattr(ambiguity, "code_key", lambda code=code: code)
        assert ambiguity.main(argv) == 0
        assert len(measured) == expected, code
        assert json.loads(capsys.readouterr().out.strip().splitlines()[-1])["median_mm"] == 80.0
    stored = list((tmp_path / "units").glob("*.json"))
    assert len(stored) == 1 and json.loads(stored[0].read_text())["code"] == "aaaa"
    # a file from before code keys is measured again too
    data = json.loads(stored[0].read_text())
    del data["code"]
    stored[0].write_text(json.dumps(data))
    assert ambiguity.main(argv) == 0 and len(measured) == 4
    assert "measured with other code" in capsys.readouterr().err


def test_code_key_changes_with_any_source_or_model_and_ignores_caches(tmp_path):
    from experiments.ambiguity import code_key

    package = tmp_path / "pkg"
    (package / "sub" / "__pycache__").mkdir(parents=True)
    (package / "a.py").write_text("x = 1\n")
    (package / "sub" / "model.json").write_text("{}")
    module = tmp_path / "experiment.py"
    module.write_text("y = 2\n")
    key = code_key(package, (module,))
    assert key == code_key(package, (module,))
    (package / "sub" / "__pycache__" / "a.cpython-312.pyc").write_bytes(b"\0")
    (package / "sub" / "kernel.nbi").write_bytes(b"\0")
    assert code_key(package, (module,)) == key
    seen = {key}
    for path, text in ((package / "a.py", "x = 2\n"), (package / "sub" / "model.json", "{\"a\": 1}"),
                       (module, "y = 3\n")):
        path.write_text(text)
        seen.add(code_key(package, (module,)))
    (package / "sub" / "b.py").write_text("")          # a new, empty module
    seen.add(code_key(package, (module,)))
    (package / "a.py").rename(package / "c.py")         # the same bytes under another name
    seen.add(code_key(package, (module,)))
    assert len(seen) == 6


def test_choice_rates_count_frames_missed_while_a_lifter_hypothesis_was_within():
    from experiments.ambiguity import choice_rates

    tracked = np.array([50.0, 150.0, 150.0, 120.0, 80.0])
    lifter = np.array([40.0, 60.0, 130.0, np.inf, 200.0])
    failing, lifter_missing, missed = choice_rates(tracked, lifter)
    assert failing == pytest.approx(3 / 5)          # frames 1, 2, 3
    assert lifter_missing == pytest.approx(3 / 5)   # frames 2, 3 (none), 4
    assert missed == pytest.approx(1 / 5)           # frame 1 only
    with pytest.raises(ValueError):
        choice_rates(tracked, lifter[:4])


def test_written_against_decoded_reports_the_largest_stray_and_heading_step():
    """Hand-made trajectories: one joint of one written frame 0.3 m off its decoded place (the
    worst joint 300 mm, the mean over the 10 joints 30 mm), and written headings 0, 0.1, 0.5 rad
    (the largest step 0.4 rad)."""
    import math

    from experiments.ambiguity import written_against_decoded
    from mocap.body import PARAMETER_INDEX, neutral_pose

    decoded = np.zeros((3, 10, 3))
    written = decoded.copy()
    written[1, 4] = [0.0, 0.3, 0.0]
    poses = np.tile(neutral_pose(), (3, 1))
    poses[:, PARAMETER_INDEX["chest_yaw"]] = [0.0, 0.1, 0.5]
    row = written_against_decoded(poses, written, decoded)
    assert row["written_decoded_mm"] == pytest.approx(300.0)
    assert row["written_decoded_mean_mm"] == pytest.approx(30.0)
    assert row["heading_step_deg"] == pytest.approx(math.degrees(0.4))
