"""ImagingConfig: defaults, validation, JSON."""
from __future__ import annotations

import dataclasses
import json

import pytest

from mocap.imaging import ImagingConfig


def test_json_round_trip(tmp_path):
    config = ImagingConfig(max_distance=12.5, edge_method="deriche", opening_size=5)
    path = tmp_path / "imaging.json"
    config.to_json(path)
    assert ImagingConfig.from_json(path) == config
    assert ImagingConfig.from_dict(config.to_dict()) == config
    assert set(json.loads(path.read_text())) == {f.name for f in dataclasses.fields(ImagingConfig)}


def test_missing_keys_take_defaults():
    assert ImagingConfig.from_dict({"max_distance": 9}) == ImagingConfig(max_distance=9.0)


def test_unknown_keys_are_rejected(tmp_path):
    with pytest.raises(ValueError, match="unknown ImagingConfig option.*max_distnace"):
        ImagingConfig.from_dict({"max_distnace": 9})
    path = tmp_path / "bad.json"
    path.write_text("[1, 2]")
    with pytest.raises(ValueError, match="JSON object"):
        ImagingConfig.from_json(path)
    path.write_text("{oops")
    with pytest.raises(ValueError, match="not valid JSON"):
        ImagingConfig.from_json(path)


@pytest.mark.parametrize("kwargs", [
    {"max_distance": 0}, {"max_distance": float("nan")}, {"change_threshold": -1},
    {"shadow_min_brightness": 1.5, "shadow_max_brightness": 1.2}, {"opening_size": 0},
    {"opening_size": 2.5}, {"edge_method": "sobel"}, {"distance_method": "l1"},
    {"edge_low_threshold": 0.3, "edge_high_threshold": 0.1}, {"min_object_fraction": 1.0},
    {"colour_threshold": "big"}, {"edge_dilation": True}, {"silhouette_edges": 1},
])
def test_invalid_values_are_rejected(kwargs):
    with pytest.raises(ValueError):
        ImagingConfig(**kwargs)


def test_config_is_immutable():
    with pytest.raises(dataclasses.FrozenInstanceError):
        ImagingConfig().max_distance = 3.0
