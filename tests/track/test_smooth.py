"""The written trajectory's fixed-lag smoother (mocap.track.smooth) on trajectories whose answer is known."""
import math

import numpy as np
import pytest

from mocap.body.pose import N_PARAMETERS, PARAMETER_INDEX, neutral_pose
from mocap.body.skeleton import JOINT_INDEX
from mocap.track import TrackerConfig
from mocap.track.smooth import MOVED_JOINTS, Smoother, SmootherConfig

LAG = TrackerConfig().lag
ELBOW = PARAMETER_INDEX["r_elbow_flex"]


def fixed_lag(smoother: Smoother, poses, joints, weights=None, lag: int = LAG) -> np.ndarray:
    """The poses written online with ``lag``, as the tracker calls the smoother (the last ``lag``
    frames at the end, in one pass)."""
    n = len(poses)
    weights = np.ones((n, N_PARAMETERS)) if weights is None else weights
    out = [smoother.smooth(poses[i - lag:i + 1], joints[i - lag:i + 1], weights[i - lag:i + 1])[0]
           for i in range(lag, n)]
    if lag == 0:
        return np.array(out)
    return np.concatenate([out, smoother.smooth(poses[n - lag:], joints[n - lag:], weights[n - lag:], lag)])


def elbow_trajectory(values) -> tuple[np.ndarray, np.ndarray]:
    """Poses with the right elbow's flexion at ``values`` (radians) and joints whose wrist moves
    by 0.3 m per radian of it (what the break detector reads)."""
    values = np.asarray(values, dtype=np.float64)
    poses = np.tile(neutral_pose(), (len(values), 1))
    poses[:, ELBOW] = values
    joints = np.zeros((len(values), 10, 3))
    joints[:, JOINT_INDEX["r_wrist"], 0] = 0.3 * values
    return poses, joints


def test_a_noise_free_constant_velocity_is_returned_exactly():
    # analytic reference: a line has no acceleration, the constant-velocity model's own motion
    values = 0.5 + 0.01 * np.arange(120)
    poses, joints = elbow_trajectory(values)
    written = fixed_lag(Smoother(SmootherConfig()), poses, joints)
    assert np.abs(written[40:, ELBOW] - values[40:]).max() < 1e-6
    assert np.abs(written[:, ELBOW] - values).max() < 0.01            # the start's zero velocity decays


def test_a_heading_observed_wrapped_is_smoothed_on_the_circle():
    """A turn at a constant 3 degrees a frame through 180 degrees, observed wrapped to [-180, 180)
    (as the lifter's proposals give it; the joints the same as unwrapped, so no restart): the
    written heading is the unwrapped line (the reference: the turn itself), exactly once the
    start's zero velocity has decayed, never a sweep back through a whole turn. Unwrapped against
    each prediction, it is the noise-free line of the test above."""
    heading = PARAMETER_INDEX["chest_yaw"]
    values = math.radians(120.0) + math.radians(3.0) * np.arange(120)
    poses = np.tile(neutral_pose(), (len(values), 1))
    poses[:, heading] = (values + math.pi) % (2 * math.pi) - math.pi
    assert np.abs(np.diff(poses[:, heading])).max() > math.pi            # the observations do wrap
    written = fixed_lag(Smoother(SmootherConfig()), poses, np.zeros((len(values), 10, 3)))[:, heading]
    assert np.abs(written[40:] - values[40:]).max() < 1e-6
    assert np.abs(written - values).max() < 0.01
    assert np.abs(np.diff(written)).max() < math.radians(4.0)


def test_a_noisy_constant_velocity_comes_back_within_a_third_of_the_noise():
    """Noise of the configured level (5 degrees) on a line: the written poses are within 0.35 of
    the noise's RMS of the line (measured 0.27 at this seed), and their acceleration (about
    sqrt(6) times the noise on the raw input) is under a tenth of the input's."""
    rng = np.random.default_rng(7)
    sigma = math.radians(SmootherConfig().angle_noise_deg)
    values = 0.6 + 0.004 * np.arange(400)
    noisy = values + rng.normal(0.0, sigma, len(values))
    poses, joints = elbow_trajectory(noisy)
    joints[:] = 0.0                                  # no break: the noise is not a branch switch
    written = fixed_lag(Smoother(SmootherConfig()), poses, joints)[:, ELBOW]
    rms = math.sqrt(np.mean((written[30:] - values[30:]) ** 2))
    assert rms < 0.35 * sigma
    accel = lambda x: np.abs(np.diff(x, 2)).mean()
    assert accel(written) < 0.1 * accel(noisy)


def test_a_step_settles_within_the_lag():
    """A step of 0.2 rad (the wrist moves 6 cm: a motion, not a branch switch) at frame 30: the
    written poses are at the old level until the lag brings the step into view, and within 5 % of
    the step of the new level from frame 30 + lag on."""
    step, at = 0.2, 30
    values = np.where(np.arange(80) < at, 0.8, 0.8 + step)
    poses, joints = elbow_trajectory(values)
    written = fixed_lag(Smoother(SmootherConfig()), poses, joints)[:, ELBOW]
    np.testing.assert_allclose(written[:at - LAG], 0.8, atol=1e-12)
    assert np.abs(written[at + LAG:] - (0.8 + step)).max() < 0.05 * step
    assert 0.2 < (written[at] - 0.8) / step < 0.8               # smoothed across it, not followed at once


def test_a_branch_switch_is_never_blended():
    """A jump of 1.5 rad (the wrist moves 45 cm, more than ``break_m``): every written pose is one
    branch or the other, none in between, online and offline."""
    values = np.where(np.arange(60) < 30, 0.3, 1.8)
    poses, joints = elbow_trajectory(values)
    online = fixed_lag(Smoother(SmootherConfig()), poses, joints)[:, ELBOW]
    offline = Smoother(SmootherConfig()).smooth(poses, joints, np.ones((60, N_PARAMETERS)), 60)[:, ELBOW]
    for written in (online, offline):
        np.testing.assert_allclose(written, values, atol=1e-12)


def test_lag_0_is_the_kalman_filter_less_smooth_than_the_lag():
    rng = np.random.default_rng(3)
    values = 0.6 + 0.004 * np.arange(200)
    poses, joints = elbow_trajectory(values + rng.normal(0.0, 0.05, len(values)))
    joints[:] = 0.0
    live = fixed_lag(Smoother(SmootherConfig()), poses, joints, lag=0)[:, ELBOW]
    lagged = fixed_lag(Smoother(SmootherConfig()), poses, joints)[:, ELBOW]
    error = lambda x: math.sqrt(np.mean((x[30:] - values[30:]) ** 2))
    assert error(lagged) < error(live) < 0.05


def test_low_confidence_is_smoothed_more():
    """The elbow's weight is the mean confidence of the wrist and the hand (what it moves); a
    frame whose wrist and hand the detector doubts pulls the written pose less."""
    assert MOVED_JOINTS["r_elbow_flex"] == ("r_wrist", "r_hand")
    smoother = Smoother(SmootherConfig())
    confidence = np.ones(10)
    confidence[[JOINT_INDEX["r_wrist"], JOINT_INDEX["r_hand"]]] = [0.2, 0.4]
    weights = smoother.weights(confidence)
    assert weights[ELBOW] == pytest.approx(0.3) and weights[PARAMETER_INDEX["l_elbow_flex"]] == 1.0
    assert smoother.weights(np.zeros(10))[ELBOW] == SmootherConfig().min_weight
    values = np.full(30, 0.8)
    values[20] = 0.9                                  # an outlier (a 3 cm wrist move: no break)
    poses, joints = elbow_trajectory(values)
    pulled = {}
    for name, w in (("sure", 1.0), ("doubted", 0.3)):
        w_all = np.ones((30, N_PARAMETERS))
        w_all[20, ELBOW] = w
        pulled[name] = fixed_lag(Smoother(SmootherConfig()), poses, joints, w_all)[20, ELBOW] - 0.8
    assert 0 < pulled["doubted"] < 0.5 * pulled["sure"]


def test_the_state_resumes_bit_for_bit():
    rng = np.random.default_rng(5)
    poses, joints = elbow_trajectory(0.6 + 0.01 * np.arange(40) + rng.normal(0, 0.05, 40))
    whole = fixed_lag(Smoother(SmootherConfig()), poses, joints)
    first = Smoother(SmootherConfig())
    out = [first.smooth(poses[i - LAG:i + 1], joints[i - LAG:i + 1], np.ones((LAG + 1, N_PARAMETERS)))[0]
           for i in range(LAG, 20)]
    import json
    second = Smoother(SmootherConfig())
    second.restore(json.loads(json.dumps(first.state())))
    out += list(fixed_lag(second, poses[20 - LAG:], joints[20 - LAG:]))
    np.testing.assert_array_equal(np.array(out), whole)


def test_an_empty_frame_writes_the_pose_written_before_it():
    # nobody in view: the tracker keeps the pose, and so does what is written (the reference:
    # the smoother's own previous output), while the frames after it are smoothed as before
    values = 0.5 + 0.02 * np.arange(12)
    poses, joints = elbow_trajectory(values)
    smoother = Smoother(SmootherConfig())
    empty = np.zeros(len(values), dtype=bool)
    empty[5] = True
    written = [smoother.smooth(poses[i:i + 3], joints[i:i + 3], np.ones((3, N_PARAMETERS)), 1,
                               empty=empty[i:i + 3])[0] for i in range(len(values) - 2)]
    np.testing.assert_array_equal(written[5], written[4])
    assert written[6][ELBOW] != written[5][ELBOW]
    with pytest.raises(ValueError, match="empty"):
        smoother.smooth(poses[:3], joints[:3], np.ones((3, N_PARAMETERS)), 1, empty=[True])


@pytest.mark.parametrize("bad", [{"angle_noise_deg": 0.0}, {"break_m": -1.0}, {"min_weight": 1.5}, {"on": 1}])
def test_bad_settings_are_value_errors(bad):
    with pytest.raises(ValueError):
        SmootherConfig(**bad)
    with pytest.raises(ValueError):
        TrackerConfig.from_dict({"smoothing": bad})
