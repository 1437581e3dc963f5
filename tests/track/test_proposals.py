"""The proposal stage: what its poses carry into poses.csv."""
from __future__ import annotations

import numpy as np

from mocap.io.pose_table import PoseTable


def test_origin_column_round_trips(tmp_path):
    table = PoseTable([0, 1], np.zeros((2, 23)), np.zeros((2, 10, 3)),
                      {"score": np.array([1.5, 2.0]), "origin": np.array(["tracked", "lifter"])})
    table.write(tmp_path / "poses.csv")
    back = PoseTable.read(tmp_path / "poses.csv")
    assert list(back.extra["origin"]) == ["tracked", "lifter"]
    np.testing.assert_array_equal(back.extra["score"], [1.5, 2.0])
