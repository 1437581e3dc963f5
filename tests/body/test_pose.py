import numpy as np
import pytest
from hypothesis import given, strategies as st
from hypothesis.extra import numpy as hnp

from mocap.body import (JOINT_LIMITS, N_PARAMETERS, PARAMETER_INDEX, PARAMETER_NAMES, check_pose,
                        clamp_to_limits, neutral_pose, pose_from_dict, pose_to_dict, within_limits)

DESIGN_NAMES = (
    "root_x root_y root_z chest_yaw chest_pitch chest_roll head_flex head_tilt head_turn "
    "r_shoulder_flex r_shoulder_abd r_shoulder_rot r_elbow_flex r_forearm_twist r_wrist_flex r_wrist_dev "
    "l_shoulder_flex l_shoulder_abd l_shoulder_rot l_elbow_flex l_forearm_twist l_wrist_flex l_wrist_dev"
).split()


def test_names_follow_design_table():
    assert PARAMETER_NAMES == tuple(DESIGN_NAMES)
    assert N_PARAMETERS == 23
    assert [PARAMETER_INDEX[n] for n in DESIGN_NAMES] == list(range(23))


def test_limits_are_ordered_and_neutral_inside():
    assert JOINT_LIMITS.shape == (23, 2)
    assert np.all(JOINT_LIMITS[:, 0] < JOINT_LIMITS[:, 1])
    assert within_limits(neutral_pose())
    # a few biomechanical values, in degrees (AAOS)
    deg = np.rad2deg(JOINT_LIMITS)
    assert deg[PARAMETER_INDEX["r_elbow_flex"]].tolist() == pytest.approx([0, 150])
    assert deg[PARAMETER_INDEX["l_shoulder_flex"]].tolist() == pytest.approx([-60, 180])
    assert deg[PARAMETER_INDEX["head_turn"]].tolist() == pytest.approx([-80, 80])
    assert not JOINT_LIMITS.flags.writeable


def test_clamp_to_limits_clamps_each_side():
    q = neutral_pose()
    q[PARAMETER_INDEX["r_elbow_flex"]] = np.deg2rad(200)
    q[PARAMETER_INDEX["l_elbow_flex"]] = np.deg2rad(-30)
    c = clamp_to_limits(q)
    assert c[PARAMETER_INDEX["r_elbow_flex"]] == pytest.approx(np.deg2rad(150))
    assert c[PARAMETER_INDEX["l_elbow_flex"]] == 0.0
    assert within_limits(c) and not within_limits(q)
    untouched = [i for i in range(23) if PARAMETER_NAMES[i] not in ("r_elbow_flex", "l_elbow_flex")]
    np.testing.assert_array_equal(c[untouched], q[untouched])


def test_dict_round_trip_in_degrees():
    q = neutral_pose()
    d = pose_to_dict(q, degrees=True)
    assert d["r_shoulder_abd"] == pytest.approx(15.0)
    assert d["root_z"] == pytest.approx(q[2])  # metres stay metres
    np.testing.assert_allclose(pose_from_dict(d, degrees=True), q)
    with pytest.raises(ValueError, match="unknown"):
        pose_from_dict({**d, "tail_wag": 1.0})
    del d["head_turn"]
    with pytest.raises(ValueError, match="missing"):
        pose_from_dict(d)


@pytest.mark.parametrize("bad, match", [
    (np.zeros(22), "shape"), (np.zeros((23, 1)), "shape"), ([0.0] * 24, "shape"),
    (np.r_[np.nan, np.zeros(22)], "root_x"), (np.r_[np.zeros(22), np.inf], "l_wrist_dev"),
    ("twenty-three", "23 numbers|shape"), ([None] * 23, "non-finite"),
])
def test_bad_pose_raises_clear_error(bad, match):
    with pytest.raises(ValueError, match=match):
        check_pose(bad)


@given(hnp.arrays(np.float64, st.integers(0, 40), elements=st.floats(allow_nan=True, allow_infinity=True)))
def test_check_pose_never_crashes(values):
    if values.shape == (23,) and np.isfinite(values).all():
        np.testing.assert_array_equal(check_pose(values), values)
    else:
        with pytest.raises(ValueError):
            check_pose(values)
