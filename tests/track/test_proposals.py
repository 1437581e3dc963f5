"""The proposal stage: sources that read the current frame, placement, and their way into the beam."""
from __future__ import annotations

import numpy as np

from mocap.body import PARAMETER_INDEX as P
from mocap.io.pose_table import PoseTable
from mocap.track import place_by_silhouette
from tests.test_track import CAMERA, MODEL, lost_arm_frame


def test_placement_brings_a_shifted_pose_back_over_the_silhouette():
    truth, _, frame = lost_arm_frame()
    shifted = truth.copy()
    shifted[P["root_x"]] += 0.12
    shifted[P["root_y"]] -= 0.08
    placed = place_by_silhouette(shifted, frame.foreground, MODEL, CAMERA)
    assert abs(placed[P["root_x"]] - truth[P["root_x"]]) < 0.01       # metres
    assert abs(placed[P["root_y"]] - truth[P["root_y"]]) < 0.01
    assert placed[P["root_z"]] == shifted[P["root_z"]]


def test_origin_column_round_trips(tmp_path):
    table = PoseTable([0, 1], np.zeros((2, 23)), np.zeros((2, 10, 3)),
                      {"score": np.array([1.5, 2.0]), "origin": np.array(["tracked", "lifter"])})
    table.write(tmp_path / "poses.csv")
    back = PoseTable.read(tmp_path / "poses.csv")
    assert list(back.extra["origin"]) == ["tracked", "lifter"]
    np.testing.assert_array_equal(back.extra["score"], [1.5, 2.0])
