import numpy as np
import pytest

from mocap.body import PARAMETER_INDEX, BodyModel, JOINT_NAMES, neutral_pose
from mocap.body.posture import arm_behind_penalty

MODEL = BodyModel.build(resolution=6)


def bone(a, b):
    j = MODEL.joint_positions(neutral_pose())
    return float(np.linalg.norm(j[JOINT_NAMES.index(a)] - j[JOINT_NAMES.index(b)]))


def test_arms_in_front_or_at_the_sides_cost_nothing():
    q = neutral_pose()
    assert arm_behind_penalty(q, MODEL.skeleton) == 0.0
    for side in "rl":
        q[PARAMETER_INDEX[f"{side}_shoulder_flex"]] = np.radians(80.0)      # pointing forwards
    assert arm_behind_penalty(q, MODEL.skeleton) == 0.0


@pytest.mark.parametrize("chest_yaw_deg", [0.0, 90.0, 180.0])
def test_straight_arm_swung_back_costs_the_hand_computed_amount(chest_yaw_deg):
    # a straight right arm extended 60 degrees backwards, abduction 0: the elbow lies
    # upper_arm * sin(60) behind the shoulder and the wrist (upper_arm + forearm) * sin(60);
    # the chest's yaw turns the whole body and must not change the penalty
    q = neutral_pose()
    q[PARAMETER_INDEX["chest_yaw"]] = np.radians(chest_yaw_deg)
    for name in ("r_shoulder_abd", "r_shoulder_rot", "r_elbow_flex", "r_forearm_twist"):
        q[PARAMETER_INDEX[name]] = 0.0
    q[PARAMETER_INDEX["r_shoulder_flex"]] = np.radians(-60.0)
    upper, fore = bone("r_shoulder", "r_elbow"), bone("r_elbow", "r_wrist")
    s = np.sin(np.radians(60.0))
    margin, sigma = 0.05, 0.1
    expected = ((upper * s - margin) / sigma) ** 2 + (((upper + fore) * s - margin) / sigma) ** 2
    assert arm_behind_penalty(q, MODEL.skeleton, margin_m=margin, sigma_m=sigma) == pytest.approx(expected, rel=1e-9)
    # a margin beyond the wrist's distance makes it free
    assert arm_behind_penalty(q, MODEL.skeleton, margin_m=upper + fore) == 0.0


@pytest.mark.parametrize("kwargs", [{"margin_m": -0.1}, {"sigma_m": 0.0}, {"sigma_m": float("nan")}])
def test_bad_parameters_raise(kwargs):
    with pytest.raises(ValueError, match="_m must be"):
        arm_behind_penalty(neutral_pose(), MODEL.skeleton, **kwargs)
