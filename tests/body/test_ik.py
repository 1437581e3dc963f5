import numpy as np
import pytest

from mocap.body import JOINT_LIMITS, JOINT_NAMES, PARAMETER_INDEX as P, BodyModel, neutral_pose
from mocap.body.ik import REACH_PARAMETERS, REACH_REGULARIZATION, reach_arm
from tests.naive import naive_reach_arm

MODEL = BodyModel.build(resolution=6)
#: A hand this close to a reachable target counts as on it (metres).
REACHED_M = 0.01


def standing():
    q = neutral_pose()
    q[2] = 2.5
    return q


def random_arm(rng, q, side):
    out = q.copy()
    for name in REACH_PARAMETERS:
        i = P[f"{side}_{name}"]
        out[i] = rng.uniform(JOINT_LIMITS[i, 0], JOINT_LIMITS[i, 1])
    return out


@pytest.mark.parametrize("side", ["r", "l"])
def test_reaches_targets_made_by_forward_kinematics(side):
    rng = np.random.default_rng(3)
    hand = JOINT_NAMES.index(f"{side}_hand")
    start = standing()
    missed = 0
    for _ in range(40):
        target = MODEL.joint_positions(random_arm(rng, start, side))[hand]
        q = reach_arm(start, MODEL.skeleton, side, target)
        missed += np.linalg.norm(MODEL.joint_positions(q)[hand] - target) >= REACHED_M
        moved = [i for i in range(23) if q[i] != start[i]]
        assert set(moved) <= {P[f"{side}_{n}"] for n in REACH_PARAMETERS}
        assert np.all(q >= JOINT_LIMITS[:, 0]) and np.all(q <= JOINT_LIMITS[:, 1])
    assert missed <= 2          # 1-5 % of random reachable targets stall in a local minimum


def test_as_close_as_scipy_least_squares_on_the_same_objective():
    rng = np.random.default_rng(8)
    hand = JOINT_NAMES.index("r_hand")
    worse = 0
    for _ in range(20):
        start = random_arm(rng, standing(), "r")
        target = MODEL.joint_positions(random_arm(rng, standing(), "r"))[hand]
        ours = np.linalg.norm(MODEL.joint_positions(reach_arm(start, MODEL.skeleton, "r", target))[hand] - target)
        ref = naive_reach_arm(start, MODEL, "r", target, REACH_REGULARIZATION)
        theirs = np.linalg.norm(MODEL.joint_positions(ref)[hand] - target)
        worse += ours > theirs + REACHED_M
    assert worse <= 1


def test_out_of_reach_target_is_pointed_at():
    q = standing()
    joints = MODEL.joint_positions(q)
    shoulder, hand = joints[JOINT_NAMES.index("r_shoulder")], JOINT_NAMES.index("r_hand")
    target = shoulder + np.array([-2.0, 0.0, -1.0])           # out to the actor's right, towards the camera
    out = MODEL.joint_positions(reach_arm(q, MODEL.skeleton, "r", target))
    to_hand, to_target = out[hand] - shoulder, target - shoulder
    cos = to_hand @ to_target / np.linalg.norm(to_hand) / np.linalg.norm(to_target)
    assert cos > np.cos(np.radians(5.0))


def test_bad_input():
    q = standing()
    with pytest.raises(ValueError, match="side"):
        reach_arm(q, MODEL.skeleton, "x", np.zeros(3))
    with pytest.raises(ValueError, match="target"):
        reach_arm(q, MODEL.skeleton, "r", [0.0, np.nan, 1.0])
    with pytest.raises(ValueError, match="regularization"):
        reach_arm(q, MODEL.skeleton, "r", [0.0, 0.0, 2.0], regularization=-1.0)


@pytest.mark.parametrize("side", ["r", "l"])
def test_place_arm_puts_three_joints_made_by_forward_kinematics_back(side):
    """Every arm posture inside the limits, from a random other start: the elbow, wrist and hand
    are placed back on the points forward kinematics gave (the reference) within a micrometre."""
    from mocap.body.ik import ARM_JOINTS, ARM_PARAMETERS, place_arm

    rng = np.random.default_rng(5)
    rows = [JOINT_NAMES.index(f"{side}_{j}") for j in ARM_JOINTS]
    arm = [P[f"{side}_{n}"] for n in ARM_PARAMETERS]
    for _ in range(60):
        truth = standing()
        truth[3:6] = rng.uniform(-0.4, 0.4, 3)
        truth[arm] = rng.uniform(JOINT_LIMITS[arm, 0], JOINT_LIMITS[arm, 1])
        start = truth.copy()
        start[arm] = rng.uniform(JOINT_LIMITS[arm, 0], JOINT_LIMITS[arm, 1])
        target = MODEL.joint_positions(truth)[rows]
        placed = place_arm(start, MODEL.skeleton, side, target)
        got = MODEL.joint_positions(placed.pose)[rows]
        assert np.max(np.linalg.norm(got - target, axis=1)) < 1e-6
        assert placed.miss_m < 1e-6
        assert [i for i in range(23) if placed.pose[i] != start[i]] == [i for i in arm if placed.pose[i] != start[i]]
        assert np.all(placed.pose >= JOINT_LIMITS[:, 0]) and np.all(placed.pose <= JOINT_LIMITS[:, 1])


def test_place_arm_reports_an_unreachable_posture():
    """A wrist farther from the elbow than the forearm is long cannot be reached: the placement
    says by how much it stayed off (at least the excess length)."""
    from mocap.body.ik import place_arm

    q = standing()
    j = MODEL.joint_positions(q)
    rows = [JOINT_NAMES.index(f"r_{n}") for n in ("elbow", "wrist", "hand")]
    target = j[rows].copy()
    excess = np.linalg.norm(target[1] - target[0])
    target[1:] += target[1] - target[0]                  # the forearm twice its length
    placed = place_arm(q, MODEL.skeleton, "r", target)
    assert placed.miss_m > 0.5 * excess
    assert placed.miss_m == pytest.approx(np.max(np.linalg.norm(MODEL.joint_positions(placed.pose)[rows] - target,
                                                                axis=1)))
