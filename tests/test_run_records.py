"""Records crossing the run boundary: keyword-only, typed, written and read back the same; one
table of the run's file names."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from mocap.run import OwnVideoOptions, RunSummary, files, track
from mocap.run.accounts import BackgroundAccount, CalibrationAccount, SetupAccount
from mocap.run.journal import SETTINGS_FORMAT
from mocap.run.loop import RunParams
from mocap.run.setup import SetupRequest
from mocap.track import FrameResult, TrackerConfig


@pytest.mark.parametrize("make", [lambda: RunParams(TrackerConfig()), lambda: SetupRequest(1),
                                  lambda: SetupAccount(60.0, None),
                                  lambda: RunSummary("out", 3, 0, 10.0, None, 0),
                                  lambda: FrameResult(0, np.zeros(23), np.zeros((10, 3)), 0.1, 1.0, 1.0, False, False,
                                                      "tracked", 100, 10, 10)])
def test_records_crossing_the_run_boundary_are_keyword_only(make):
    with pytest.raises(TypeError, match="positional"):
        make()


@pytest.mark.parametrize("background, calibration", [
    ({"mode": "image", "used": True, "reason": "given"}, {"from": "given"}),
    ({"mode": "frames", "used": True, "frames": [0, 5], "reason": "median of the given empty frames"},
     {"from": "automatic", "frame": 3, "face_input_px": [10, 12, 30, 36], "depth_m": 2.412}),
    ({"mode": "auto", "used": False, "sample_frames": 60, "evidence": {"frames_with_person": 0.1},
      "reason": "hardly moves"},
     {"from": "automatic", "frame": 0, "face_input_px": None, "depth_m": 1.9})])
def test_the_setup_account_is_run_json_s_own_video_record_key_for_key(background, calibration):
    """``settings.own_video`` reads into the account and back unchanged (keys in the same order);
    the working factor and the sizes are ``settings.working_resolution``'s, said there only."""
    record = {"hfov_deg": 60.0, "height_m": None, "background": background, "calibration": calibration}
    sizes = {"factor": 2, "width": 160, "height": 120, "input_width": 320, "input_height": 240}
    account = SetupAccount.from_settings({"own_video": record, "working_resolution": sizes})
    assert json.dumps(account.to_dict()) == json.dumps(record)
    assert (account.working_factor, account.input_width, account.working_height) == (2, 320, 120)
    assert account.background_mode == background["mode"] and account.calibration_from == calibration["from"]
    assert json.dumps(dataclasses.replace(account, keypoints="mediapipe").to_dict()) == json.dumps(record)
    if calibration["from"] == "automatic":                 # a newcomer's segments[].found
        assert CalibrationAccount.from_dict(calibration).to_dict(source=False) == \
            {k: v for k, v in calibration.items() if k != "from"}
    assert BackgroundAccount.from_dict(background).to_dict() == background
    assert SetupAccount.from_settings({"working_resolution": sizes}) is None


@pytest.mark.parametrize("old, mode, used", [
    ({"mode": "image", "reason": "given"}, "image", True),
    ({"mode": "frames", "frames": [0, 5], "reason": "median"}, "frames", True),
    ({"mode": "estimated", "sample_frames": 60, "evidence": {"frames_with_person": 0.9}, "reason": "moves"},
     "auto", True),
    ({"mode": "none", "sample_frames": 60, "evidence": {"frames_with_person": 0.1}, "reason": "hardly moves"},
     "auto", False),
    ({"mode": "none", "reason": "asked for: colour-only foreground"}, "none", False)])
def test_a_run_json_of_the_earlier_layout_reads_in_the_options_words(old, mode, used):
    """Before ``settings.format`` the background's outcome was its mode (``estimated``) and
    ``own_video`` repeated the working factor and the keypoints: it still reads, the same."""
    own = {"hfov_deg": 60.0, "height_m": 1.7, "background": old, "working_factor": 4,
           "calibration": {"from": "given"}, "keypoints": "none"}
    sizes = {"factor": 4, "width": 160, "height": 120, "input_width": 640, "input_height": 480}
    account = SetupAccount.from_settings({"own_video": own, "working_resolution": sizes})
    assert (account.background.mode, account.background.used, account.working_factor) == (mode, used, 4)
    assert account.background.reason == old["reason"] and account.height_m == 1.7


def test_a_run_s_summary_is_what_its_run_json_reads_back_as_and_its_files_are_the_table_s(tmp_path):
    from mocap.synth import generate_sequence

    sequence = generate_sequence("gestures-1", tmp_path / "seq", frames=3, seed=2, progress=False)
    seen = []
    out = tmp_path / "run"
    summary = track(sequence, out, OwnVideoOptions(tracker=TrackerConfig(evaluations=40), keypoints="none"),
                    progress=False, on_setup=seen.append)
    assert sorted(p.name for p in out.iterdir()) == sorted((*files.RUN_OUTPUTS, files.STATE_FILE, files.LOCK_FILE))
    run = json.loads((out / files.RUN_JSON).read_text())
    assert seen == [summary.setup] and summary.setup.input_width == 160 and summary.setup.working_width == 160
    assert summary.setup.to_dict() == run["settings"]["own_video"]
    assert summary.setup.background_mode == "image" and summary.setup.calibration_from == "given"
    assert run["settings"]["format"] == SETTINGS_FORMAT and "keypoints" in run["settings"]
    read = RunSummary.read(out)          # the keypoints' line is printed, not kept
    assert summary.setup.keypoints == "none"
    assert read == dataclasses.replace(summary, setup=dataclasses.replace(summary.setup, keypoints=None), advice=None)
    assert (read.frames, read.failures, read.wall_s) == (run["frames"], run["failures"],
                                                         run["wall_seconds_this_session"])
    # an unfinished, a missing or a damaged run.json reads as no summary
    (out / files.RUN_JSON).write_text(json.dumps({**run, "status": "running"}))
    assert RunSummary.read(out) is None
    (out / files.RUN_JSON).write_text("{")
    assert RunSummary.read(out) is None and RunSummary.read(tmp_path / "nowhere") is None


def test_a_folder_of_the_earlier_run_json_layout_is_refused_in_one_line(tmp_path):
    """A run folder written before ``settings.format`` (``own_video`` repeating the keypoints
    and the working factor) does not resume: one line says why and what to do."""
    from mocap.run.journal import Journal, previous_run

    wanted = {"format": SETTINGS_FORMAT, "source": "clip.mp4", "own_video": {"hfov_deg": 60.0}, "keypoints": "none"}
    earlier = {"source": "clip.mp4", "own_video": {"hfov_deg": 60.0, "working_factor": 4, "keypoints": "none"},
               "keypoints": "none"}
    journal = Journal.in_folder(tmp_path)
    journal.path.write_text("frame\n0\n")
    (tmp_path / files.RUN_JSON).write_text(json.dumps({"status": "running", "settings": earlier}))
    with pytest.raises(ValueError) as refused:
        previous_run(journal, tmp_path / files.RUN_JSON, wanted, overwrite=False)
    line = str(refused.value)
    assert "\n" not in line and "holds a run of an earlier mocap" in line and "mocap-run-2" in line
    assert "--overwrite" in line and journal.path.read_text() == "frame\n0\n"      # nothing removed
    assert previous_run(journal, tmp_path / files.RUN_JSON, wanted, overwrite=True) is None
    assert not journal.path.exists()


def test_the_session_rate_is_frames_over_the_wall_clock_after_the_first():
    """run.json's fps (:func:`mocap.run.loop.session_fps`): from the end of the first frame to
    the end of the last; from the loop's start with fewer than three frames; None without."""
    from mocap.run.loop import SHOWN_RATE_FRAMES, StepClock, session_fps

    assert session_fps(0.0, 1.0, 5.0, 4) == pytest.approx(3 / 4)
    assert session_fps(1.0, 2.0, 5.0, 2) == pytest.approx(2 / 4)
    assert session_fps(0.0, None, None, 0) is None
    # the loop's clock: the same rate from what it keeps, and the bar's rate over the last frames,
    # in constant memory however many frames
    clock = StepClock()
    assert clock.session_fps(0.0) is None and clock.recent_fps() is None
    ends = [1.0, 2.0, 3.0, 5.0] + [5.0 + 0.5 * k for k in range(1, 100)]
    for end in ends:
        clock.tick(end)
    assert clock.session_fps(0.0) == pytest.approx((len(ends) - 1) / (ends[-1] - ends[0]))
    assert clock.recent_fps() == pytest.approx(2.0)
    assert len(clock.recent) == SHOWN_RATE_FRAMES + 1


def test_the_live_latency_quantiles_hold_to_half_a_percent_in_constant_memory():
    """run.json's ``live.latency_ms`` (:class:`mocap.run.loop.LatencyRecord`) against NumPy's exact
    inverted-CDF quantiles of the same latencies: within (r - 1) / (r + 1) relative; the bins do
    not grow with the number of frames once their range is covered."""
    from mocap.run.loop import LATENCY_BIN_RATIO, MIN_LATENCY_MS, LatencyRecord

    rng = np.random.default_rng(7)
    latencies = np.concatenate([rng.lognormal(np.log(120.0), 0.6, 20_000), [0.0, -3.0, 40.0, 40.0, 5e4]])
    record = LatencyRecord()
    with pytest.raises(ValueError, match="no latency"):
        record.quantile(0.5)
    for ms in latencies:
        record.add(ms)
    tolerance = (LATENCY_BIN_RATIO - 1) / (LATENCY_BIN_RATIO + 1)
    exact = np.maximum(latencies, MIN_LATENCY_MS)          # the record counts below its floor as the floor
    for q in (0.001, 0.1, 0.5, 0.9, 0.99, 1.0):
        expected = np.quantile(exact, q, method="inverted_cdf")
        assert abs(record.quantile(q) - expected) <= tolerance * expected * (1 + 1e-9), q
    assert record.count == len(latencies) and record.last_ms == 5e4
    bins = len(record.counts)
    for ms in rng.lognormal(np.log(120.0), 0.3, 20_000):         # the same range again: no new bin
        record.add(float(np.clip(ms, latencies.min(), 5e4)))
    assert len(record.counts) <= bins
    assert bins < 1.1 * np.log(5e4 / MIN_LATENCY_MS) / np.log(LATENCY_BIN_RATIO)
    with pytest.raises(ValueError, match="q must be"):
        record.quantile(0.0)
