"""A pose placed onto 3D joints (MediaPipe's world landmarks), inside the joint limits."""
import numpy as np
import pytest

from mocap.body import JOINT_LIMITS, JOINT_NAMES, PARAMETER_INDEX as P, BodyModel, neutral_pose
from mocap.body.ik import FIT_MIN_JOINTS, fit_pose_to_joints
from mocap.io.mediapipe_keypoints import N_LANDMARKS, world_joints

MODEL = BodyModel.build(resolution=6)
#: A fitted joint this close to its landmark-given place counts as given back (metres).
JOINT_TOL_M = 0.005
#: An angle the joints fix, this close to the truth counts as given back (degrees).
ANGLE_TOL_DEG = 1.0
#: Angles the nine joints (no neck) fix: the torso's heading and roll, the arms' abduction, rotation
#: and elbow (the forearm's twist, the wrist and the head's turn are left free by single points).
FIXED = ("chest_yaw", "chest_roll", "r_shoulder_abd", "r_shoulder_rot", "r_elbow_flex",
         "l_shoulder_abd", "l_shoulder_rot", "l_elbow_flex")
#: The torso's pitch trades against the head's flexion and both shoulders' flexion (the same joints
#: within a millimetre, with neither neck nor hips): the pull towards the start decides, within this
#: of the truth (degrees; 0.9-1.5 measured on these poses).
PITCH_TOL_DEG = 2.5
PITCHED = ("chest_pitch", "r_shoulder_flex", "l_shoulder_flex")


def known_pose(rng):
    """Random torso heading and arm angles inside the limits (elbows bent: a straight arm leaves its
    rotation free); the rest neutral."""
    q = neutral_pose()
    q[P["chest_yaw"]] = rng.uniform(-np.pi, np.pi)
    for side in "rl":
        for name, lo_deg, hi_deg in (("shoulder_flex", -40, 150), ("shoulder_abd", -20, 150),
                                     ("shoulder_rot", -60, 80), ("elbow_flex", 30, 140)):
            q[P[f"{side}_{name}"]] = np.radians(rng.uniform(lo_deg, hi_deg))
    return q


def landmarks_of(joints, hips):
    """MediaPipe's 33 world landmarks that give these joints back (about ``hips``, metres): ears
    either side of the head joint, index and pinky such that their mean with the wrist is the hand."""
    lm = np.zeros((N_LANDMARKS, 3))
    j = {name: joints[k] - hips for k, name in enumerate(JOINT_NAMES)}
    lm[7], lm[8] = j["head"] + (0.07, 0.0, 0.0), j["head"] - (0.07, 0.0, 0.0)
    for side, (shoulder, elbow, wrist, pinky, index) in (("l", (11, 13, 15, 17, 19)), ("r", (12, 14, 16, 18, 20))):
        lm[shoulder], lm[elbow], lm[wrist] = j[f"{side}_shoulder"], j[f"{side}_elbow"], j[f"{side}_wrist"]
        rest = 3.0 * j[f"{side}_hand"] - j[f"{side}_wrist"]          # index + pinky
        lm[index], lm[pinky] = 0.5 * rest + (0.0, 0.0, 0.02), 0.5 * rest - (0.0, 0.0, 0.02)
    return lm


def check_within_limits(q):
    assert np.all(q[3:] >= JOINT_LIMITS[3:, 0]) and np.all(q[3:] <= JOINT_LIMITS[3:, 1])


@pytest.mark.parametrize("seed", range(6))
def test_a_known_poses_landmarks_give_back_that_pose(seed):
    rng = np.random.default_rng(seed)
    truth = known_pose(rng)
    joints = MODEL.joint_positions(truth)
    hips = joints[P["root_x"]] + (0.0, 0.5, 0.0)                # MediaPipe's origin: anywhere fixed
    targets, present = world_joints(landmarks_of(joints, hips), np.ones(N_LANDMARKS))
    assert not present[JOINT_NAMES.index("neck")] and present.sum() == 9
    np.testing.assert_allclose(targets[present], (joints - hips)[present], atol=1e-12)
    fit = fit_pose_to_joints(targets, present, MODEL.skeleton)
    check_within_limits(fit.pose)
    got = MODEL.joint_positions(fit.pose)
    assert np.linalg.norm(got[present] - targets[present], axis=1).max() < JOINT_TOL_M
    assert fit.rms_m < JOINT_TOL_M
    error = np.degrees(np.angle(np.exp(1j * (fit.pose - truth))))
    assert np.abs(error[[P[n] for n in FIXED]]).max() < ANGLE_TOL_DEG, dict(zip(FIXED, error[[P[n] for n in FIXED]]))
    assert np.abs(error[[P[n] for n in PITCHED]]).max() < PITCH_TOL_DEG


def test_missing_landmarks_leave_their_joints_out():
    rng = np.random.default_rng(11)
    truth = known_pose(rng)
    joints = MODEL.joint_positions(truth)
    landmarks, visibility = landmarks_of(joints, joints[1]), np.ones(N_LANDMARKS)
    visibility[15] = 0.2                       # the left wrist unseen: the left wrist and hand are absent
    landmarks[20] = np.nan                     # the right index lost: the right hand is absent
    targets, present = world_joints(landmarks, visibility)
    absent = {JOINT_NAMES[k] for k in np.flatnonzero(~present)}
    assert absent == {"neck", "l_wrist", "l_hand", "r_hand"} and np.isnan(targets[~present]).all()
    fit = fit_pose_to_joints(targets, present, MODEL.skeleton)
    check_within_limits(fit.pose)
    assert np.all(np.isfinite(fit.pose)) and np.array_equal(fit.present, present)
    got = MODEL.joint_positions(fit.pose)
    assert np.linalg.norm(got[present] - targets[present], axis=1).max() < JOINT_TOL_M
    # a NaN target counts as absent even where ``present`` says otherwise
    again = fit_pose_to_joints(targets, np.ones(len(JOINT_NAMES), bool), MODEL.skeleton)
    np.testing.assert_array_equal(again.present, present)
    # too few joints fix no orientation
    few = present.copy()
    few[np.flatnonzero(few)[FIT_MIN_JOINTS - 1:]] = False
    with pytest.raises(ValueError, match=f"at least {FIT_MIN_JOINTS} joints"):
        fit_pose_to_joints(targets, few, MODEL.skeleton)


def test_malformed_landmarks_are_refused():
    with pytest.raises(ValueError, match="shape"):
        world_joints(np.zeros((10, 3)), np.ones(10))
    with pytest.raises(ValueError, match="shape"):
        fit_pose_to_joints(np.zeros((9, 3)), np.ones(9, bool), MODEL.skeleton)
