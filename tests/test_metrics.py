"""Metrics of docs/design.md section 5 on cases worked out by hand."""
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mocap.body.pose import PARAMETER_INDEX, neutral_pose
from mocap.body.skeleton import JOINT_NAMES
from mocap.metrics import (SUMMARY_KEYS, acceleration_error, centred_mpjpe, failure_rate, joint_angle_error, mpjpe,
                           pa_mpjpe, reprojection_error, root_relative_mpjpe, summary)
from mocap.render.camera import Camera


def _frames_with_errors(errors_mm, n_joints=4):
    """True joints and predictions displaced by ``errors_mm[i]`` (along a 3-4-5 direction)."""
    rng = np.random.default_rng(0)
    true = rng.normal(size=(len(errors_mm), n_joints, 3)) + [0.0, 0.0, 3.0]
    direction = np.array([0.6, 0.8, 0.0])
    pred = true + np.asarray(errors_mm, float)[:, None, None] / 1000.0 * direction
    return pred, true


def test_mpjpe_constant_offset_is_its_length():
    true = np.zeros((2, 3, 3))
    pred = true + [0.003, 0.004, 0.0]              # 3-4-5 triangle: 5 mm
    assert mpjpe(pred, true) == pytest.approx(5.0)


def test_mpjpe_averages_joints_then_frames():
    true = np.zeros((2, 2, 3))
    pred = true.copy()
    pred[0, 1, 0] = 0.010                          # frame 0: errors 0 and 10 mm -> 5
    pred[1, :, 2] = 0.020                          # frame 1: both 20 mm -> 20
    assert mpjpe(pred, true, per_frame=True) == pytest.approx([5.0, 20.0])
    assert mpjpe(pred, true) == pytest.approx(12.5)


def test_pa_mpjpe_removes_similarity_transform():
    rng = np.random.default_rng(1)
    true = rng.normal(size=(3, 10, 3))
    rot = Rotation.from_euler("xyz", [30, -50, 70], degrees=True)
    pred = 1.7 * rot.apply(true.reshape(-1, 3)).reshape(true.shape) + [0.5, -1.0, 2.0]
    assert mpjpe(pred, true) > 100.0
    assert pa_mpjpe(pred, true) == pytest.approx(0.0, abs=1e-9)


def test_pa_mpjpe_hand_computed_scale_fit():
    # A cross: the prediction stretches the x arm to twice its length. By symmetry the best
    # rotation is the identity and the translation zero; the best scale is
    # s = sum(t.p) / sum(p.p) = (2 + 2 + 1 + 1) / (4 + 4 + 1 + 1) = 0.6, so the aligned points are
    # (+-1.2, 0, 0) and (0, +-0.6, 0): errors 0.2, 0.2, 0.4, 0.4 m, mean 300 mm.
    true = np.array([[[-1.0, 0, 0], [1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0]]])
    pred = np.array([[[-2.0, 0, 0], [2.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0]]])
    assert pa_mpjpe(pred, true) == pytest.approx(300.0)


def test_pa_mpjpe_does_not_reflect():
    # A mirror image cannot be undone by a proper rotation: the error stays large.
    true = np.array([[[1.0, 0, 0], [0, 2.0, 0], [0, 0, 3.0], [0.0, 0, 0]]])
    pred = true * [-1.0, 1.0, 1.0]
    assert pa_mpjpe(pred, true) > 100.0


def test_joint_angle_error_one_angle():
    true = np.tile(neutral_pose(), (2, 1))
    pred = true.copy()
    pred[:, PARAMETER_INDEX["r_elbow_flex"]] += math.radians(10.0)   # 10 deg on 1 of 20 angles
    pred[:, PARAMETER_INDEX["root_x"]] += 5.0                       # positions are ignored
    assert joint_angle_error(pred, true) == pytest.approx(0.5)


def test_joint_angle_error_wraps_around():
    true = np.tile(neutral_pose(), (1, 1))
    pred = true.copy()
    true[0, PARAMETER_INDEX["chest_yaw"]] = math.radians(179.0)
    pred[0, PARAMETER_INDEX["chest_yaw"]] = math.radians(-179.0)     # 2 degrees apart
    assert joint_angle_error(pred, true) == pytest.approx(2.0 / 20.0)


def test_reprojection_error_hand_computed():
    cam = Camera.default(160, 120)                  # f = 80 / tan(30 deg) = 138.564 px
    true = np.array([[[0.0, 0.0, 2.0], [0.0, 0.5, 2.0]]])
    pred = true + [0.2, 0.0, 0.0]                   # 0.2 m at 2 m: f * 0.1 px on both joints
    assert reprojection_error(pred, true, cam) == pytest.approx(80.0 / math.tan(math.radians(30.0)) * 0.1)


def test_failure_rate_counts_frames_strictly_above_threshold():
    pred, true = _frames_with_errors([50.0, 150.0, 99.0, 101.0])
    assert mpjpe(pred, true, per_frame=True) == pytest.approx([50.0, 150.0, 99.0, 101.0])
    assert failure_rate(pred, true) == pytest.approx(0.5)
    assert failure_rate(pred, true, threshold_mm=40.0) == pytest.approx(1.0)
    assert failure_rate(pred, true, threshold_mm=200.0) == 0.0


def test_root_relative_error_removes_the_neck_offset_only():
    n = len(JOINT_NAMES)
    true = np.zeros((2, n, 3)) + [0.0, 0.0, 2.0]
    pred = true + [0.0, 0.0, 0.25]                 # the whole body 25 cm too far: root-relative 0
    assert mpjpe(pred, true) == pytest.approx(250.0)
    assert root_relative_mpjpe(pred, true) == pytest.approx(0.0)
    pred[1, JOINT_NAMES.index("r_hand")] += [0.03, 0.04, 0.0]   # one hand 5 cm off in frame 1
    assert root_relative_mpjpe(pred, true, per_frame=True) == pytest.approx([0.0, 50.0 / n])
    moved_neck = true.copy()
    moved_neck[:, JOINT_NAMES.index("neck")] += [0.0, 0.01, 0.0]  # the neck 1 cm off: every other joint
    assert root_relative_mpjpe(moved_neck, true) == pytest.approx(10.0 * (n - 1) / n)
    with pytest.raises(ValueError, match="named joints"):
        root_relative_mpjpe(np.zeros((1, 3, 3)), np.zeros((1, 3, 3)))


def test_acceleration_error_hand_computed():
    # truth still; one joint of the prediction at x = (0, 0, 3, 0) mm over four frames:
    # a_1 = x2 - 2 x1 + x0 = 3, a_2 = x3 - 2 x2 + x1 = -6: |3| and |6| over 10 joints
    true = np.zeros((4, 10, 3))
    true[:, :, 2] = 3.0
    pred = true.copy()
    wrist = JOINT_NAMES.index("r_wrist")
    pred[2, wrist, 0] += 0.003
    per_frame = acceleration_error(pred, true, align="none", per_frame=True)
    assert per_frame == pytest.approx([3.0 / 10, 6.0 / 10])
    assert acceleration_error(pred, true, align="none") == pytest.approx(0.45)
    # about the neck: moving the whole skeleton (neck included) by the same shake changes nothing
    shaken = true + np.array([0.0, 0.0, 0.003, 0.0])[:, None, None]
    assert acceleration_error(shaken, true, align="neck") == pytest.approx(0.0, abs=1e-9)
    # (every joint shaken by (3, 3, 3) mm on frame 2: |a| = 3 sqrt(3) and 6 sqrt(3))
    assert acceleration_error(shaken, true, align="none") == pytest.approx(4.5 * math.sqrt(3))
    # after Procrustes alignment a rigid motion of the prediction is no error either
    rng = np.random.default_rng(1)
    true = rng.normal(size=(5, 6, 3)) * 0.3 + [0, 0, 3]
    moved = np.stack([Rotation.from_rotvec([0, 0.1 * i, 0]).apply(f) + [0.01 * i ** 2, 0, 0] for i, f in enumerate(true)])
    assert acceleration_error(moved, true, align="procrustes") == pytest.approx(0.0, abs=1e-6)
    assert acceleration_error(moved, true, align="none") > 5.0


def test_summary_has_exactly_the_run_json_keys():
    pred, true = _frames_with_errors([10.0, 20.0], n_joints=len(JOINT_NAMES))
    poses = np.tile(neutral_pose(), (2, 1))
    out = summary(poses, poses, pred, true, Camera.default())
    assert tuple(out) == SUMMARY_KEYS == ("mpjpe_mm", "root_relative_mpjpe_mm", "pa_mpjpe_mm", "angle_error_deg",
                                          "reprojection_px", "failure_rate")
    assert all(type(v) is float for v in out.values())
    assert out["mpjpe_mm"] == pytest.approx(15.0)
    assert out["root_relative_mpjpe_mm"] == pytest.approx(0.0, abs=1e-9)   # a rigid shift
    assert out["angle_error_deg"] == 0.0 and out["failure_rate"] == 0.0


@pytest.mark.parametrize("call", [
    lambda: mpjpe(np.zeros((2, 3, 3)), np.zeros((2, 4, 3))),
    lambda: mpjpe(np.zeros((3, 3)), np.zeros((3, 3))),
    lambda: mpjpe(np.zeros((0, 3, 3)), np.zeros((0, 3, 3))),
    lambda: mpjpe(np.full((1, 3, 3), np.nan), np.zeros((1, 3, 3))),
    lambda: pa_mpjpe(np.zeros((1, 2, 3)), np.zeros((1, 2, 3))),
    lambda: joint_angle_error(np.zeros((2, 22)), np.zeros((2, 22))),
    lambda: reprojection_error(np.zeros((1, 2, 3)), np.zeros((1, 2, 3)), Camera.default()),
    lambda: reprojection_error(np.ones((1, 2, 3)), np.ones((1, 2, 3)), "camera"),
    lambda: failure_rate(np.ones((1, 2, 3)), np.ones((1, 2, 3)), threshold_mm=-1.0),
    lambda: acceleration_error(np.ones((2, 10, 3)), np.ones((2, 10, 3))),
    lambda: acceleration_error(np.ones((3, 4, 3)), np.ones((3, 4, 3))),
    lambda: acceleration_error(np.ones((3, 10, 3)), np.ones((3, 10, 3)), align="hips"),
    lambda: summary(np.zeros((2, 23)), np.zeros((2, 23)), np.ones((3, 4, 3)), np.ones((3, 4, 3)),
                    Camera.default()),
])
def test_bad_input_is_a_value_error(call):
    with pytest.raises(ValueError):
        call()


def test_centred_mpjpe_ignores_a_shift_but_not_a_body_turned_around():
    """Two points 0.4 m apart (the hands): shifted, no error; their labels swapped (the body
    turned around about its centre), each is 0.4 m off, which PA-MPJPE's rotation undoes."""
    true = np.array([[[-0.2, 0.0, 2.0], [0.2, 0.0, 2.0], [0.0, 0.3, 2.0]]])
    assert centred_mpjpe(true + [0.1, -0.05, 0.3], true) == pytest.approx(0.0, abs=1e-9)
    turned = true[:, [1, 0, 2]]
    assert centred_mpjpe(turned, true) == pytest.approx(1000.0 * (0.4 + 0.4 + 0.0) / 3)
    assert pa_mpjpe(turned, true) < 1.0
    np.testing.assert_allclose(centred_mpjpe(np.concatenate([true, turned]), np.concatenate([true, true]),
                                             per_frame=True), [0.0, 800.0 / 3], atol=1e-9)
