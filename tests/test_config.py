"""Configuration is typed strictly: every field of every config class, from its type hints."""
from __future__ import annotations

import dataclasses
import json
import os
import stat
import typing

import pytest

from experiments.config import SweepConfig
from mocap.calibrate import Calibration
from mocap.cli import main
from mocap.imaging import ImagingConfig
from mocap.io.files import write_text_atomic
from mocap.track import TrackerConfig

from tests.conftest import REPO_ROOT

CONFIGS = (TrackerConfig, ImagingConfig, SweepConfig)
#: A JSON value of each plain type, and values of other types that must be refused for it.
GOOD = {bool: True, int: 3, float: 2.5, str: "x"}
BAD = {bool: ["no", "false", 0, 1, None], int: [True, 2.5, "3", None], float: [True, "1e-3", None, [1.0]],
       str: [1, True, None, ["a"]]}


def plain_fields(cls):
    hints = typing.get_type_hints(cls)
    return [(f.name, hints[f.name]) for f in dataclasses.fields(cls) if hints[f.name] in BAD]


@pytest.mark.parametrize("cls", CONFIGS)
def test_every_plain_field_refuses_other_json_types(cls):
    fields = plain_fields(cls)
    assert fields
    for name, hint in fields:
        for value in BAD[hint]:
            with pytest.raises(ValueError, match=f"{cls.__name__} option {name} must be"):
                cls.from_dict({name: value})


@pytest.mark.parametrize("cls", CONFIGS)
def test_defaults_survive_a_json_round_trip(cls):
    assert cls.from_dict(json.loads(json.dumps(cls().to_dict()))) == cls()


def test_the_issue_cases_and_tuple_fields():
    for text in ('"no"', '"false"', "0"):
        with pytest.raises(ValueError, match="recovery must be a JSON boolean"):
            TrackerConfig.from_dict({"recovery": json.loads(text)})
    assert TrackerConfig.from_dict({"recovery": False}).recovery is False
    assert TrackerConfig.from_dict({"angle_step_deg": 10}).angle_step_deg == 10      # an integer is a number
    assert SweepConfig.from_dict({"table2_sizes": [[160, 120]]}).table2_sizes == ((160, 120),)
    for bad in ([[160, "120"]], [[160]], [160, 120], "160x120"):
        with pytest.raises(ValueError, match="table2_sizes must be a list of"):
            SweepConfig.from_dict({"table2_sizes": bad})
    with pytest.raises(ValueError, match="sequences must be a list of"):
        SweepConfig.from_dict({"sequences": ["gestures-1", 2]})


def test_config_file_errors_name_the_file(tmp_path):
    path = tmp_path / "tracker.json"
    path.write_text('{"recovery": "no"}')
    with pytest.raises(ValueError, match=f"{path}: TrackerConfig option recovery"):
        TrackerConfig.from_json(path)


def test_calibration_angles_outside_the_joint_limits_are_refused():
    data = json.loads(json.dumps(Calibration().to_dict()))
    Calibration.from_dict(data)
    for name, value, limit in (("r_elbow_flex", 500.0, r"\[0, 150\] deg"), ("l_shoulder_rot", -71.0, r"\[-70, 90\] deg"),
                               ("root_z", 0.1, r"\[0.3, 10\] m")):
        bad = json.loads(json.dumps(data))
        bad["initial_pose_deg"][name] = value
        with pytest.raises(ValueError, match=f"{name} = {value:g}.*outside its joint limits {limit}"):
            Calibration.from_dict(bad)
    bad = json.loads(json.dumps(data))
    bad["initial_pose_deg"]["head_turn"] = "10"
    with pytest.raises(ValueError, match="head_turn must be a number"):
        Calibration.from_dict(bad)


def test_zero_iterations_are_refused_with_a_reason(tmp_path, capsys):
    sequence = str(REPO_ROOT / "data" / "default")
    assert main(["track", sequence, "--iterations", "0", "--out", str(tmp_path / "o")]) == 2
    assert "--iterations must be at least 1" in capsys.readouterr().err
    (tmp_path / "c.json").write_text('{"evaluations": 0}')
    assert main(["track", sequence, "--config", str(tmp_path / "c.json"), "--out", str(tmp_path / "o")]) == 2
    assert "evaluations must be at least 1" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_atomic_writes_follow_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        write_text_atomic(tmp_path / "a.txt", "x")
        with open(tmp_path / "b.txt", "w") as fh:         # what a plain write gives
            fh.write("x")
    finally:
        os.umask(old)
    mode = stat.S_IMODE((tmp_path / "a.txt").stat().st_mode)
    assert mode == stat.S_IMODE((tmp_path / "b.txt").stat().st_mode) == 0o666 & ~umask


def test_calibration_numbers_are_numbers():
    data = json.loads(json.dumps(Calibration().to_dict()))
    for where, key, value, match in (("camera", "fx", True, "camera fx must be a finite number"),
                                     ("camera", "width", 160.0, "camera width must be an integer"),
                                     ("camera", "cy", "60", "camera cy must be a finite number")):
        bad = json.loads(json.dumps(data))
        bad[where][key] = value
        with pytest.raises(ValueError, match=match):
            Calibration.from_dict(bad)
    bad = json.loads(json.dumps(data))
    part = next(iter(bad["dimensions"]["parts"]))
    bad["dimensions"]["parts"][part]["length"] = True
    with pytest.raises(ValueError, match=f"part '{part}' length must be a number of metres"):
        Calibration.from_dict(bad)


def test_threads_default_to_the_cores_less_the_detector_but_two_where_there_are_two():
    """``OwnVideoOptions.threads``: a positive integer or None; None resolves to the cores less
    one for MediaPipe's process, but never below two on a machine of two (the measured rule)."""
    from mocap.run.options import OwnVideoOptions, default_threads

    table = {(1, False): 1, (1, True): 1, (2, False): 2, (2, True): 2, (3, True): 2, (16, True): 15, (16, False): 16}
    assert {key: default_threads(key[1], cores=key[0]) for key in table} == table
    assert OwnVideoOptions(threads=3).threads == 3
    assert OwnVideoOptions.from_dict(json.loads(json.dumps(OwnVideoOptions(threads=2).to_dict()))).threads == 2
    for bad in (0, -2, True, 1.5):
        with pytest.raises(ValueError, match="threads"):
            OwnVideoOptions(threads=bad)
