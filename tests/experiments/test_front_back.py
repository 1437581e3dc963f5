"""Issue 49's front/back audit: the truth's heading, the tabulation's bins and counts, the
observers' geometry on hand-made frames."""
import math

import numpy as np
import pytest

from experiments.front_back import (AWAY, FACING, NO_ANSWER, FrameRecord, HeadBox, apply_thresholds,
                                    balanced_accuracy, binned_table, count, fit_threshold, head_box_of_pose,
                                    head_colour_score, heading_bin, mediapipe_observations, relative_heading_deg)
from mocap.body import BodyDimensions, BodyModel, PARAMETER_INDEX as P, neutral_pose
from mocap.render import Camera


def _pose(yaw_deg: float, x: float = 0.0, z: float = 2.0) -> np.ndarray:
    q = neutral_pose((x, 0.25, z))
    q[P["chest_yaw"]] = math.radians(yaw_deg)
    return q


@pytest.mark.parametrize("yaw, expected", [(0, 0), (30, 30), (-100, -100), (180, 180), (-180, 180),
                                           (370, 10), (-450, -90), (540, 180)])
def test_relative_heading_wraps_the_unwrapped_yaw(yaw, expected):
    assert relative_heading_deg(_pose(yaw)) == pytest.approx(expected, abs=1e-9)


def test_relative_heading_counts_where_the_camera_is_seen_from():
    # at x = z the camera lies 45 degrees to the body's side: a chest turned 45 degrees (its face to
    # -x, towards the camera's side) faces it squarely
    assert relative_heading_deg(_pose(45.0, x=2.0, z=2.0)) == pytest.approx(0.0, abs=1e-9)
    assert relative_heading_deg(_pose(0.0, x=2.0, z=2.0)) == pytest.approx(-45.0, abs=1e-9)


@pytest.mark.parametrize("heading, label", [(0, "0-45"), (-44.9, "0-45"), (45, "45-90"), (-89.99, "45-90"),
                                            (90, "90-135"), (-135, "135-180"), (180, "135-180")])
def test_heading_bins_by_absolute_heading_in_45_degree_steps(heading, label):
    assert heading_bin(heading) == label


def _record(heading, decision, seed=0, size="160x120", material="face"):
    return FrameRecord(material, "turning", seed, size, 0, heading, {"obs": decision}, {}, {})


def test_counts_and_balanced_accuracy_on_known_decisions():
    records = [_record(10, FACING), _record(20, FACING), _record(30, AWAY), _record(50, NO_ANSWER),   # facing
               _record(100, AWAY), _record(170, FACING), _record(-150, AWAY), _record(-120, NO_ANSWER)]
    cell = count(records, "obs")
    assert (cell.frames, cell.said_facing, cell.said_away, cell.no_answer, cell.truth_facing) == (8, 3, 3, 2, 4)
    assert cell.right == 2 + 2                      # two facing said facing, two away said away
    right_facing, right_away, balanced = balanced_accuracy(records, "obs")
    assert right_facing == pytest.approx(50.0)      # no answer counts as not right
    assert right_away == pytest.approx(50.0)
    assert balanced == pytest.approx(50.0)
    table = binned_table(records, ["obs"], ["160x120"], "face")
    row = table[2].split(" | ")
    assert row[2] == "67 / 0 (3)"                  # 0-45: 2 of 3 said facing
    assert row[3] == "0 / 100 (1)"                 # 45-90: the one frame unanswered
    assert row[4] == "0 / 50 (2)"                  # 90-135: one away, one unanswered
    assert row[5] == "50 / 0 (2)"                  # 135-180: one facing, one away


def test_threshold_is_fitted_on_balanced_accuracy_and_applied():
    scores = np.array([1.0, 2.0, 3.0, 10.0, 11.0, 12.0, np.nan])
    facing = np.array([False, False, False, True, True, True, True])
    t = fit_threshold(scores, facing)
    assert 3.0 < t < 10.0
    records = [FrameRecord("face", "s", 0, "160x120", i, 0.0 if f else 180.0, {}, {"c": float(s)}, {})
               for i, (s, f) in enumerate(zip(scores, facing))]
    apply_thresholds(records, {"c": t})
    assert [r.decisions["c"] for r in records] == [AWAY] * 3 + [FACING] * 3 + [NO_ANSWER]
    with pytest.raises(ValueError):
        fit_threshold(np.array([1.0, 2.0]), np.array([True, True]))


def test_head_colour_sees_skin_under_hair_and_not_hair_alone():
    hair, skin = (40, 30, 25), (220, 170, 140)
    box = HeadBox(u=20.0, v=20.0, half_width=7.0, half_height=10.0)
    front = np.zeros((40, 40, 3), dtype=np.uint8) + np.array(hair, dtype=np.uint8)
    front[17:30, 13:27] = skin                      # the face below the hairline (rows 10 to 30 are the head)
    back = np.zeros_like(front) + np.array(hair, dtype=np.uint8)
    assert head_colour_score(front, box) > 20.0
    assert head_colour_score(back, box) == pytest.approx(0.0, abs=1e-6)
    # the crown's hair half as bright (shading) is not a face: lightness is left out, the chroma
    # moves a little with it
    shaded = back.copy()
    shaded[:17] = (20, 15, 12)
    assert head_colour_score(shaded, box) < 0.25 * head_colour_score(front, box)
    assert math.isnan(head_colour_score(front, HeadBox(-50.0, -50.0, 5.0, 5.0)))     # outside: no answer
    assert math.isnan(head_colour_score(front, None))


def test_true_head_box_lies_on_the_head():
    model = BodyModel.build(BodyDimensions(), resolution=8)
    camera = Camera.default(320, 240)
    q = _pose(0.0)
    box = head_box_of_pose(q, model, camera)
    neck = camera.project(model.joint_positions(q)[1])
    assert box.v < neck[1]                          # the head above the neck (image rows grow down)
    assert box.half_height > box.half_width > 0
    assert box.half_height == pytest.approx(0.5 * model.dims["head"].length * camera.fy / 2.0, rel=0.05)


def _landmarks(facing: bool) -> tuple[np.ndarray, np.ndarray]:
    """33 landmarks of a frontal (or turned-round) head and shoulders: the person's left on the
    image's right, the nose nearer than the ears, when facing."""
    image = np.zeros((33, 4))
    image[:, 3] = 1.0
    world = np.zeros((33, 4))
    world[:, 3] = 1.0
    side = 1.0 if facing else -1.0
    image[11, 0], image[12, 0] = 0.5 + side * 0.1, 0.5 - side * 0.1       # shoulders
    image[7, 0], image[8, 0] = 0.5 + side * 0.04, 0.5 - side * 0.04       # ears
    world[0, 2] = -0.1 * side                                             # the nose's depth
    return image, world


def test_mediapipe_observers_read_order_and_depth():
    decisions, _ = mediapipe_observations(*_landmarks(True))
    assert decisions["mediapipe-order"] == FACING and decisions["mediapipe-depth"] == FACING
    decisions, _ = mediapipe_observations(*_landmarks(False))
    assert decisions["mediapipe-order"] == AWAY and decisions["mediapipe-depth"] == AWAY
    image, world = _landmarks(True)
    world[0, 2] = -0.005                             # the nose level with the ears: no answer
    assert mediapipe_observations(image, world)[0]["mediapipe-depth"] == NO_ANSWER
    assert set(mediapipe_observations(None, None)[0].values()) == {NO_ANSWER}
