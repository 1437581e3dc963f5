"""The tracking ablation's summaries, table, figure and report section, on made-up results."""
import numpy as np
import pytest

from experiments.report import generated_sections, replace_section
from experiments.tracking import CONFIGS, config_of, summarise, table
from mocap.track import TrackerConfig


def row(sequence, errors, eq=0.0):
    errors = np.asarray(errors, dtype=float)
    return {"sequence": sequence, "frames": len(errors), "mpjpe_mm": float(errors.mean()),
            "root_relative_mpjpe_mm": float(errors.mean()) / 2, "pa_mpjpe_mm": float(errors.mean()) / 3,
            "frame_mpjpe_mm": errors.tolist(), "beam_oracle_failure_rate": 0.0, "cost_equivalent_both_rate": eq,
            "tracking_ms_per_frame": 20.0, "prepare_ms_per_frame": 5.0}


def test_summary_pools_frames_and_takes_medians_over_sequences():
    rows = [row("a", [10, 20, 30]), row("b", [200, 200, 50, 50, 50]), row("c", [60])]
    s = summarise(rows)
    assert s["median_mpjpe_mm"] == pytest.approx(60.0)             # medians of 20, 110, 60
    assert s["failure_rate"] == pytest.approx(2 / 9)               # two of nine frames over 100 mm
    assert s["worst_mpjpe_mm"] == pytest.approx(110.0)
    assert s["ms_per_frame"] == pytest.approx(25.0)
    text = table({"default": s})
    # rows without headings or errors about the neck (made before issue 49): neither mark judged, a dash
    assert "| default | 60 | 30 | 20 | 22.2 % | - | 110 | - | - | 0.0 % | - | - | - | - | 0.0 % | - | 25.0 (40) |" in text
    assert all(line.count("|") == text.splitlines()[0].count("|") for line in text.splitlines())


def test_summary_takes_the_median_acceleration_error_over_sequences():
    accel = lambda a, d, n: {"accel_mm": a, "decoded_accel_mm": d, "naive_accel_mm": n, "accel_arms_pa_mm": a / 2}
    rows = [row("a", [10]) | accel(3.0, 40.0, 5.0), row("b", [20]) | accel(9.0, 50.0, 6.0),
            row("c", [30]) | accel(5.0, 60.0, 4.0)]
    s = summarise(rows)
    assert (s["median_accel_mm"], s["median_decoded_accel_mm"], s["median_naive_accel_mm"]) == (5.0, 50.0, 5.0)
    assert "| 5.0 (50.0, 5.0) |" in table({"default": s})


def test_summary_of_the_proposal_stage_weights_rates_by_frames():
    rows = [row("a", [10, 20, 30]) | {"proposal_oracle_failure_rate": 1 / 3, "proposal_catches_rate": 0.0},
            row("b", [200, 50, 50, 50, 50, 50]) | {"proposal_oracle_failure_rate": 0.5, "proposal_catches_rate": 0.5}]
    s = summarise(rows)
    assert s["proposal_oracle_failure_rate"] == pytest.approx(4 / 9)  # (1 + 3) of nine frames
    assert s["proposal_catches_rate"] == pytest.approx(3 / 9)
    assert "| 44.4 % | 33.3 % |" in table({"both": s})


def sequence_truth(frames=40):
    """A benchmark sequence's true poses and the body model that poses them (the generator's, not
    rendered), and the joints of each pose (N, 10, 3), metres."""
    from mocap.body import BodyModel
    from mocap.synth import sequence_poses, setup_sequence

    setup = setup_sequence("turning", seed=0)
    poses, _ = sequence_poses(setup, frames=frames)
    model = BodyModel.build(setup.actor.dims)
    return poses, model, np.array([model.joint_positions(q) for q in poses])


def measured_row(written_poses, true_poses, model, sequence="turning"):
    """The fields of an experiments.ambiguity.measure row the failure marks are judged on, from
    written poses against true ones (made through the same functions measure uses)."""
    from experiments.ambiguity import heading_error_deg, jitter

    joints = np.array([model.joint_positions(q) for q in written_poses])
    truth = np.array([model.joint_positions(q) for q in true_poses])
    errors = np.linalg.norm(joints - truth, axis=2).mean(axis=1) * 1e3
    return row(sequence, errors) | jitter(joints, joints, truth) | {
        "frame_heading_error_deg": heading_error_deg(written_poses, true_poses).tolist()}


def test_a_unit_turned_round_is_counted_and_the_truth_is_not():
    """Written poses that are the truth turned by 180 degrees in heading (the turning sequence,
    whose own heading sweeps through +-180 degrees): every frame is turned round, so the unit is,
    and the summary counts it; its arms on the wrong sides put it about 470 mm from the truth about
    the neck, so it is lost too. The truth itself, and the truth a whole turn on (the tracker's
    heading is unwrapped: the same body), are neither turned round nor lost."""
    from experiments.tracking import LOST_MM, failure_marks, summarise, table
    from mocap.body.pose import HEADING, PARAMETER_INDEX

    truth, model, _ = sequence_truth(120)
    turned, whole_turn = truth.copy(), truth.copy()
    turned[:, PARAMETER_INDEX[HEADING]] += np.pi
    whole_turn[:, PARAMETER_INDEX[HEADING]] -= 2 * np.pi
    rows = [measured_row(p, truth, model) for p in (turned, truth, whole_turn)]
    marks = [failure_marks(r) for r in rows]
    assert marks[0]["turned_round"] is True and marks[0]["turned_round_rate"] == 1.0
    assert np.allclose(np.abs(rows[0]["frame_heading_error_deg"]), 180.0)
    assert rows[0]["median_frame_root_relative_mm"] > LOST_MM and marks[0]["lost"] is True
    for m in marks[1:]:
        assert m == {"turned_round_rate": 0.0, "turned_round": False, "lost": False}
    s = summarise(rows)
    assert (s["units"], s["turned_round_units"], s["turned_round_judged"], s["lost_units"]) == (3, 1, 3, 1)
    assert "| 1 of 3 | 1 of 3 |" in table({"default": s})
    assert "| 0 of 2 | 0 of 2 |" in table({"default": summarise(rows[1:])})


def test_turned_round_needs_more_than_its_share_of_frames_on_the_circle():
    """Headings off by 100 degrees (and by 100 + 360, the same on the circle) on some frames:
    a unit is turned round when more than TURNED_ROUND_SHARE of its frames are; 170 degrees one
    way and 190 the other are 20 apart on the circle, not turned round."""
    from experiments.tracking import TURNED_ROUND_DEG, TURNED_ROUND_SHARE, failure_marks
    from mocap.body.pose import HEADING, PARAMETER_INDEX

    truth, model, _ = sequence_truth(20)
    i = PARAMETER_INDEX[HEADING]
    assert (TURNED_ROUND_DEG, TURNED_ROUND_SHARE) == (90.0, 0.2)
    for off, turned in ((range(0, 5), True), (range(0, 4), False)):       # 25 % and 20 % of 20 frames
        written = truth.copy()
        written[list(off), i] += np.radians([100.0, 460.0, -100.0, 100.0, -460.0][:len(off)])
        marks = failure_marks(measured_row(written, truth, model))
        assert marks["turned_round_rate"] == pytest.approx(len(off) / 20)
        assert marks["turned_round"] is turned
    written, shifted = truth.copy(), truth.copy()
    written[:, i] += np.radians(170.0)
    shifted[:, i] -= np.radians(190.0)
    assert failure_marks(measured_row(written, shifted, model))["turned_round_rate"] == 0.0


@pytest.mark.parametrize("shift_mm, lost", [(350.0, True), (310.0, False)])
def test_a_unit_is_lost_when_its_median_error_about_the_neck_is_over_the_threshold(shift_mm, lost):
    """Joints built with known offsets: on 11 of 20 frames every joint but the neck is moved
    ``shift_mm`` along x (about the neck: 9 of 10 joints off, 0.9 * shift_mm a frame), on the others
    nothing is; the whole body is also moved 1 m (nothing about the neck). The median error about
    the neck by hand (numpy: each joint less the frame's neck) is 315 or 279 mm against LOST_MM 300."""
    from experiments.ambiguity import jitter
    from experiments.tracking import LOST_MM, failure_marks, summarise
    from mocap.body.skeleton import JOINT_NAMES

    _, _, truth = sequence_truth(20)
    neck = JOINT_NAMES.index("neck")
    written = truth + np.array([1.0, 0.0, 0.0])
    moved = np.ones(len(JOINT_NAMES), bool)
    moved[neck] = False
    written[:11, moved] += np.array([shift_mm / 1e3, 0.0, 0.0])
    about_neck = lambda x: x - x[:, neck:neck + 1]
    by_hand = np.median(np.linalg.norm(about_neck(written) - about_neck(truth), axis=2).mean(axis=1)) * 1e3
    assert by_hand == pytest.approx(0.9 * shift_mm)
    assert bool(by_hand > LOST_MM) is lost
    measured = row("gestures-1", np.linalg.norm(written - truth, axis=2).mean(axis=1) * 1e3) | jitter(written, written, truth)
    assert failure_marks(measured)["lost"] is lost and failure_marks(measured)["turned_round"] is None
    # a row from before the median was kept: judged on its per-frame errors about the neck
    older = {k: v for k, v in measured.items() if k != "median_frame_root_relative_mm"}
    older["frame_root_relative_mm"] = (np.linalg.norm(about_neck(written) - about_neck(truth), axis=2).mean(axis=1)
                                       * 1e3).tolist()
    assert failure_marks(older)["lost"] is lost
    s = summarise([measured, row("b", [10.0])])
    assert (s["lost_units"], s["lost_judged"], s["units"]) == (int(lost), 1, 2)


def test_the_per_sequence_table_marks_each_unit():
    from experiments.tracking import jitter_table

    marked = {"sequence": "turning", "seed": 3, "frame_heading_error_deg": [180.0, 179.0, 10.0, -170.0],
              "median_frame_root_relative_mm": 420.0}
    text = jitter_table({"default": [marked, {"sequence": "old", "seed": 0}]})
    assert text.splitlines()[2].endswith("| yes (75.0 %) | yes |")
    assert text.splitlines()[3].endswith("| - | - |")
    assert all(line.count("|") == text.splitlines()[0].count("|") for line in text.splitlines())


def test_named_configurations():
    assert config_of("paper") == TrackerConfig.paper()
    assert config_of("default") == TrackerConfig()
    assert all(isinstance(config_of(n), TrackerConfig) for n in CONFIGS)


def test_report_sections_are_replaced_and_kept(tmp_path):
    path = tmp_path / "REPORT.md"
    path.write_text("# Report\n\nbody\n")
    replace_section(path, "tracking", "## old")
    replace_section(path, "peers", "## peers")
    replace_section(path, "tracking", "## new")
    text = path.read_text()
    assert text.startswith("# Report\n\nbody\n") and "## old" not in text
    assert text.index("## new") < text.index("## peers")
    kept = generated_sections(text)
    assert "## new" in kept and "## peers" in kept and "body" not in kept


def test_budget_figure_draws_the_configurations_with_an_evaluation_count(tmp_path):
    from experiments.figures import ext_proposal_budget
    summaries = {"default": {"evaluations_per_frame": 900.0, "median_mpjpe_mm": 111.0, "failure_rate": 0.52},
                 "both": {"evaluations_per_frame": 1400.0, "median_mpjpe_mm": 80.0, "failure_rate": 0.3},
                 "old": {"median_mpjpe_mm": 120.0, "failure_rate": 0.6}}        # no count: left out
    paths = ext_proposal_budget.main(summaries, tmp_path)
    assert paths and all(p.is_file() and p.stat().st_size > 1000 for p in paths)


def test_detector_keypoints_are_detected_once_and_read_back_with_the_world_joints(tmp_path, monkeypatch):
    """The benchmark's MediaPipe keypoints (experiments.keypoints.detector_keypoints): the run's
    detector on every frame (a stand-in here: MediaPipe need not be installed), written to the
    sequence's folder and read back exactly, world joints and frames without a person included;
    a second call reads the file and detects nothing."""
    from experiments import keypoints as source
    from mocap.io.keypoints import Keypoints

    rng = np.random.default_rng(0)
    made = [Keypoints(rng.uniform(0, 160, (10, 2)), rng.uniform(0.5, 1, 10), rng.normal(0, 0.3, (10, 3))),
            Keypoints.empty(), Keypoints(rng.uniform(0, 160, (10, 2)), np.ones(10), None)]
    seen = []

    class Detector:
        def __init__(self, *, image_mode=True):
            assert image_mode                              # as --keypoints mediapipe runs it

        def keypoints(self, index, image):
            seen.append(index)
            return made[index]

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            pass

    monkeypatch.setattr("mocap.io.mediapipe_keypoints.MediaPipeKeypoints", Detector)
    frames = [np.zeros((120, 160, 3), np.uint8)] * 3
    cache = tmp_path / source.DETECTOR_FILE
    for _ in range(2):
        got = source.detector_keypoints(frames, cache)
        assert len(got) == 3 and not got[1].present.any()
        for k, m in ((got[0], made[0]), (got[2], made[2])):
            np.testing.assert_array_equal(k.uv, m.uv)
            np.testing.assert_array_equal(k.confidence, m.confidence)
        np.testing.assert_array_equal(got[0].world, made[0].world)
    assert seen == [0, 1, 2]                                # detected on the first call only


def test_beside_detector_measures_ours_and_mediapipe_on_the_frames_it_found():
    """Ours and MediaPipe's own 3D compared on the same frames: MediaPipe's world joints are the
    truth's arms turned, scaled and moved (PA-MPJPE 0), missing on one frame; ours are the truth
    plus a fixed offset on one joint (PA-MPJPE by mocap.metrics over the frames MediaPipe found)."""
    from scipy.spatial.transform import Rotation

    from experiments.ambiguity import beside_detector
    from experiments.peers import arm_indices
    from mocap.io.keypoints import Keypoints
    from mocap.metrics import pa_mpjpe

    rng = np.random.default_rng(1)
    truth = rng.normal(0, 0.3, (6, 10, 3)) + np.array([0, 0, 3.0])
    ours = truth.copy()
    ours[:, 3] += np.array([0.05, -0.02, 0.1])            # the right elbow off
    turn = Rotation.from_euler("y", 30, degrees=True).as_matrix()
    keypoints = [Keypoints(np.zeros((10, 2)), np.ones(10), 0.8 * t @ turn.T + 1.0) for t in truth]
    keypoints[2] = Keypoints(np.zeros((10, 2)), np.ones(10), None)
    got = beside_detector(ours, keypoints, truth)
    arms, found = arm_indices(), np.array([True, True, False, True, True, True])
    assert got["mediapipe_found_rate"] == pytest.approx(5 / 6)
    assert got["mediapipe_arms_pa_mpjpe_mm"] == pytest.approx(0.0, abs=1e-6)
    assert got["arms_pa_mpjpe_mm"] == pytest.approx(pa_mpjpe(ours[found][:, arms], truth[found][:, arms]), rel=1e-9)
    assert got["arms_pa_mpjpe_mm"] > 1.0


def test_detector_table_gives_ours_over_mediapipes():
    from experiments.tracking import detector_table

    r = {"sequence": "turning", "seed": 3, "detector_swapped_rate": 0.25, "mediapipe_found_rate": 0.5,
         "arms_pa_mpjpe_mm": 40.0, "mediapipe_arms_pa_mpjpe_mm": 50.0, "arms_accel": 3.0, "mediapipe_arms_accel": 12.0}
    text = detector_table({"mediapipe-keypoints": [r], "default": [{"sequence": "turning"}]})
    assert "| mediapipe-keypoints | turning | 3 | 25.0 % | 50.0 % | 40 / 50 | 0.80 | 3.0 / 12.0 | 0.25 |" in text
    assert "| default |" not in text


def test_the_detector_configuration_needs_the_keypoints_extra(monkeypatch, capsys, tmp_path):
    from experiments.tracking import main

    monkeypatch.setattr("mocap.io.mediapipe_keypoints.available", lambda: False)
    assert main(["--configs", "mediapipe-keypoints", "--seeds", "0", "--out", str(tmp_path)]) == 2
    assert "mediapipe-keypoints" in capsys.readouterr().err and not (tmp_path / "units").exists()


def test_a_sequence_that_cannot_be_prepared_is_left_out_of_every_configuration(tmp_path, monkeypatch, capsys):
    import json

    from experiments.tracking import main
    from experiments.units import UnpreparableSequence

    calls = []

    def run_unit(out, name, sequence, seed, null_offset_px=0.0):
        calls.append((name, sequence, seed))
        if (sequence, seed) == ("gestures-2", 1):
            raise UnpreparableSequence("gestures-2-s1: the calibrated model covers only 7 foreground pixels")
        return row(sequence, [10.0 * (seed + 1) + (50.0 if name == "paper" else 0.0)] * 4)

    monkeypatch.setattr("experiments.tracking.run_unit", run_unit)
    argv = ["--configs", "default,paper", "--seeds", "0,1", "--sequences", "turning,gestures-2", "--out", str(tmp_path)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "left out, cannot be prepared: gestures-2 seed 1" in err
    assert ("paper", "gestures-2", 1) not in calls                 # not tried again for the next configuration
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["left_out"] == [{"sequence": "gestures-2", "seed": 1,
                                    "reason": "gestures-2-s1: the calibrated model covers only 7 foreground pixels"}]
    assert summary["per_sequence"] == {"default": {"turning-s0": 10.0, "gestures-2-s0": 10.0, "turning-s1": 20.0},
                                       "paper": {"turning-s0": 60.0, "gestures-2-s0": 60.0, "turning-s1": 70.0}}
    assert summary["summaries"]["default"]["units"] == summary["summaries"]["paper"]["units"] == 3
    assert summary["summaries"]["default"]["median_mpjpe_mm"] == 10.0


def test_a_first_frame_without_the_person_cannot_be_prepared_and_says_which(tmp_path):
    import shutil

    from experiments.units import DataSpec, UnpreparableSequence, data_folder, prepare_data
    from mocap.io.sequence import find_sequence

    spec = DataSpec("turning", None, 3, 0, 160, 120)
    folder = data_folder(spec, tmp_path)
    prepare_data(spec, str(tmp_path))                               # the generated sequence prepares
    (folder / "prepared.npz").unlink()
    paths = find_sequence(folder)
    first = sorted(paths.frames.iterdir())[0]
    shutil.copyfile(paths.background, first)                        # the person gone from the first frame
    with pytest.raises(UnpreparableSequence, match=f"{folder.name}: the calibrated model covers only 0"):
        prepare_data(spec, str(tmp_path))
    assert not (folder / "prepared.npz").exists()


def test_the_null_offset_moves_every_present_keypoint_and_keeps_the_rest():
    from experiments.keypoints import offset_keypoints
    from mocap.io.keypoints import Keypoints

    uv = np.arange(20, dtype=float).reshape(10, 2)
    confidence = np.linspace(0.1, 1.0, 10)
    confidence[3] = 0.0                                              # absent: stays absent
    world = np.ones((10, 3))
    moved = offset_keypoints([Keypoints(uv, confidence, world), None], 0.01)
    assert moved[1] is None
    expected = uv + [0.01, 0.0]
    expected[3] = np.nan
    np.testing.assert_array_equal(moved[0].uv, expected)
    np.testing.assert_array_equal(moved[0].confidence, confidence)
    np.testing.assert_array_equal(moved[0].world[np.arange(10) != 3], world[np.arange(10) != 3])


def test_a_null_run_writes_units_of_its_own_and_says_so(tmp_path, monkeypatch, capsys):
    import json

    from experiments.tracking import main, unit_path

    seen = []

    def run_unit(out, name, sequence, seed, null_offset_px=0.0):
        seen.append(null_offset_px)
        return row(sequence, [50.0, 60.0])

    monkeypatch.setattr("experiments.tracking.run_unit", run_unit)
    assert unit_path(tmp_path, "default", "turning", 0, 0.01).name.endswith("-null0.01px.json")
    assert unit_path(tmp_path, "default", "turning", 0) != unit_path(tmp_path, "default", "turning", 0, 0.01)
    argv = ["--configs", "default", "--seeds", "0", "--sequences", "turning", "--out", str(tmp_path)]
    assert main(argv + ["--null-offset-px", "0.01"]) == 0
    assert seen == [0.01]
    assert "keypoints moved 0.01 px to the right (a null perturbation)" in capsys.readouterr().out
    assert json.loads((tmp_path / "summary.json").read_text())["null_offset_px"] == 0.01
    assert main(argv + ["--null-offset-px", "3"]) == 2                 # not a null perturbation
    assert "under 1 pixel" in capsys.readouterr().err
    assert main(argv + ["--null-offset-px", "0.01", "--report"]) == 2  # never the report's figures
    assert "not written into the report" in capsys.readouterr().err
    assert seen == [0.01]
