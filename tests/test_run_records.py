"""Records crossing the run boundary: keyword-only, typed, written and read back the same; one
table of the run's file names."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from mocap.run import OwnVideoOptions, RunSummary, files, track
from mocap.run.loop import RunParams
from mocap.run.setup import BackgroundAccount, CalibrationAccount, SetupAccount, SetupRequest
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
    ({"mode": "image", "reason": "given"}, {"from": "given"}),
    ({"mode": "frames", "frames": [0, 5], "reason": "median of the given empty frames"},
     {"from": "automatic", "frame": 3, "face_input_px": [10, 12, 30, 36], "depth_m": 2.412}),
    ({"mode": "none", "sample_frames": 60, "evidence": {"frames_with_person": 0.1}, "reason": "hardly moves"},
     {"from": "automatic", "frame": 0, "face_input_px": None, "depth_m": 1.9})])
def test_the_setup_account_is_run_json_s_own_video_record_key_for_key(background, calibration):
    """``settings.own_video`` as written before the account was typed (keys in the same order)
    reads into the account and back unchanged."""
    record = {"hfov_deg": 60.0, "height_m": None, "background": background, "working_factor": 2,
              "calibration": calibration, "keypoints": "none"}
    account = SetupAccount.from_dict(record)
    assert json.dumps(account.to_dict()) == json.dumps(record)
    assert account.background_mode == background["mode"] and account.calibration_from == calibration["from"]
    without = {k: v for k, v in record.items() if k != "keypoints"}
    assert json.dumps(dataclasses.replace(account, keypoints=None).to_dict()) == json.dumps(without)
    if calibration["from"] == "automatic":                 # a newcomer's segments[].found
        assert CalibrationAccount.from_dict(calibration).to_dict(source=False) == \
            {k: v for k, v in calibration.items() if k != "from"}
    assert BackgroundAccount.from_dict(background).to_dict() == background


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
    read = RunSummary.read(out)
    assert read == dataclasses.replace(summary, setup=dataclasses.replace(
        summary.setup, input_width=None, input_height=None, working_width=None, working_height=None), advice=None)
    assert (read.frames, read.failures, read.wall_s) == (run["frames"], run["failures"],
                                                         run["wall_seconds_this_session"])
    # an unfinished, a missing or a damaged run.json reads as no summary
    (out / files.RUN_JSON).write_text(json.dumps({**run, "status": "running"}))
    assert RunSummary.read(out) is None
    (out / files.RUN_JSON).write_text("{")
    assert RunSummary.read(out) is None and RunSummary.read(tmp_path / "nowhere") is None
