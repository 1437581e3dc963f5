"""Depth alternatives (:mod:`mocap.track.branches`) against an independent reference: the joints
projected with the camera and the bone lengths measured on the joints."""
import numpy as np
import pytest

from mocap.body import JOINT_LIMITS, JOINT_NAMES, PARAMETER_INDEX as P, BodyModel, neutral_pose
from mocap.render.camera import Camera
from mocap.track.branches import DepthAlternative, depth_alternatives

MODEL = BodyModel.build(resolution=6)
CAMERA = Camera.default()
BONES = {"upper_arm": ("shoulder", "elbow"), "forearm": ("elbow", "wrist"), "hand": ("wrist", "hand")}
ARM = ("shoulder_flex", "shoulder_abd", "shoulder_rot", "elbow_flex", "forearm_twist", "wrist_flex", "wrist_dev")


def random_pose(rng):
    q = neutral_pose()
    q[3] = rng.uniform(-0.8, 0.8)
    q[4:6] = rng.uniform(-0.2, 0.2, 2)
    for side in "rl":
        idx = [P[f"{side}_{n}"] for n in ARM]
        q[idx] = rng.uniform(JOINT_LIMITS[idx, 0], JOINT_LIMITS[idx, 1])
    return q


def other_intersection_depth(joints, parent, child):
    """Distance from the camera of the other point where the child's ray meets the sphere of the
    bone's length about the parent (the quadratic's other root)."""
    ray = joints[child] / np.linalg.norm(joints[child])
    return 2.0 * ray @ joints[parent] - np.linalg.norm(joints[child])


def test_a_depth_alternative_keeps_every_projection_and_bone_length():
    rng = np.random.default_rng(11)
    kept = 0
    for _ in range(30):
        q = random_pose(rng)
        joints = MODEL.joint_positions(q)
        pixels = CAMERA.project(joints)
        for alt in depth_alternatives(q, MODEL, CAMERA):
            assert isinstance(alt, DepthAlternative)
            kept += 1
            got = MODEL.joint_positions(alt.pose)
            np.testing.assert_allclose(got, alt.joints)
            assert np.max(np.linalg.norm(CAMERA.project(got) - pixels, axis=1)) <= 0.5
            for parent, child in BONES.values():
                for side in "rl":
                    a, b = JOINT_NAMES.index(f"{side}_{parent}"), JOINT_NAMES.index(f"{side}_{child}")
                    assert np.linalg.norm(got[b] - got[a]) == pytest.approx(np.linalg.norm(joints[b] - joints[a]),
                                                                           abs=1e-9)
            # only that arm's angles moved, inside the limits
            other = "l" if alt.side == "r" else "r"
            idx = [P[f"{other}_{n}"] for n in ARM] + list(range(9))
            np.testing.assert_array_equal(alt.pose[idx], q[idx])
            assert np.all(alt.pose >= JOINT_LIMITS[:, 0]) and np.all(alt.pose <= JOINT_LIMITS[:, 1])
            # the first flipped bone's child really is at the other intersection (its parent did not move)
            first = next(b for b in BONES if b in alt.flipped)
            parent, child = (JOINT_NAMES.index(f"{alt.side}_{j}") for j in BONES[first])
            assert np.linalg.norm(got[child]) == pytest.approx(other_intersection_depth(joints, parent, child),
                                                               abs=0.01)
    assert kept >= 30            # about 2.5 a pose: the limits allow many


def test_bad_input():
    q = neutral_pose()
    with pytest.raises(ValueError, match="max_shift_px"):
        depth_alternatives(q, MODEL, CAMERA, max_shift_px=-1.0)


@pytest.mark.slow
def test_started_with_both_arms_mirrored_the_tracker_is_back_at_the_default_weights():
    """A still clip with keypoints (1 px noise): started with both arms mirrored in depth about
    their shoulders (the same silhouette and 2D), the tracker at the default settings (online,
    lag 0 so that each frame's pose is its own decision; its written poses smoothed, as by
    default) is within 10 cm of the truth (mean joint error about the neck) from the fourth frame
    on (the lag-0 smoother trails the switch by about a frame: 0.101 m on the third frame, 0.094
    m without it). Without the mirrors it is still lost on the fourth to sixth frames (the
    reference: the same tracker, the stage off)."""
    from mocap.body.jumps import arm_jumps
    from mocap.track import TrackerConfig
    from tests.track.test_lifter_in_tracker import BACK_M, MODEL as LIFTER_MODEL, reaching_pose, tracked_errors

    truth = reaching_pose()
    start = arm_jumps(arm_jumps(truth, LIFTER_MODEL.skeleton, "r")["both"], LIFTER_MODEL.skeleton, "l")["both"]
    with_mirrors = tracked_errors(TrackerConfig(lag=0), start, truth, None, n=6)
    without = tracked_errors(TrackerConfig(lag=0, mirrors=False), start, truth, None, n=6)
    assert with_mirrors[0] > 2 * BACK_M                      # it did start lost
    assert with_mirrors[3:].max() < BACK_M
    assert without[3:6].min() > BACK_M


def test_without_keypoints_the_mirrors_change_nothing():
    """The stage runs on frames with keypoints only: without them the tracker's poses, scores and
    origins are bit-identical with the stage on and off (the silhouette-only tracker is unchanged)."""
    from mocap.body.jumps import arm_jumps
    from mocap.track import Tracker, TrackerConfig
    from tests.track.test_lifter_in_tracker import CAMERA as STILL_CAMERA, MODEL as STILL_MODEL, reaching_pose, still_clip

    truth = reaching_pose()
    start = arm_jumps(truth, STILL_MODEL.skeleton, "l")["both"]
    frames, _ = still_clip(truth, 3)

    def track(mirrors):
        tracker = Tracker(STILL_MODEL, STILL_CAMERA, TrackerConfig(lag=1, mirrors=mirrors, evaluations=200), start)
        out = [r for i, f in enumerate(frames) for r in tracker.push(i, f)] + tracker.finish()
        return [(r.pose, r.score, r.origin) for r in out]

    on, off = track(True), track(False)
    assert len(on) == len(off) == 3
    for (p, s, o), (q, t, u) in zip(on, off):
        np.testing.assert_array_equal(p, q)
        assert s == t and o == u != "mirror"
