"""BVH reader and writer, ASF/AMC reader: hand-made files, our model's kinematics, the CMU clips."""
import math
import time

import numpy as np
import pytest

from mocap.body import BodyDimensions, BodyModel, JOINT_LIMITS, PARAMETER_INDEX, neutral_pose
from mocap.body.skeleton import JOINT_NAMES
from mocap.io.asf_amc import read_amc, read_asf
from mocap.io.bvh import CAMERA_TO_BVH, pose_channels, read_bvh, read_pose_bvh, write_bvh

SMALL_BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Arm
  {
    OFFSET 0 0 1
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 2 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.04
1 2 3 0 0 0 0 0 0
1 2 3 0 0 90 90 0 0
"""


def _random_poses(n, seed=0):
    rng = np.random.default_rng(seed)
    lo, hi = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    poses = np.tile(neutral_pose(), (n, 1))
    poses[:, 3:] = rng.uniform(0.9 * lo[3:], 0.9 * hi[3:], size=(n, 20))
    poses[:, :3] += rng.normal(0.0, 0.2, size=(n, 3))
    return poses


def test_small_file_hierarchy_and_hand_computed_kinematics(tmp_path):
    path = tmp_path / "small.bvh"
    path.write_text(SMALL_BVH)
    bvh = read_bvh(path)
    assert bvh.names == ("Hips", "Arm", "Arm_end")
    assert list(bvh.parents) == [-1, 0, 1]
    assert bvh.joints[2].end_site and bvh.joints[2].channels == ()
    assert bvh.joints[0].channels[3:] == ("Zrotation", "Xrotation", "Yrotation")
    assert bvh.n_frames == 2 and bvh.frame_time == 0.04 and bvh.fps == pytest.approx(25.0)
    assert bvh.channel_values("Arm")[1].tolist() == [90.0, 0.0, 0.0]
    rot, pos = bvh.global_transforms()
    # frame 0: nothing rotated; root at (1, 2, 3), arm 1 forward, end 2 above it
    assert pos[0].tolist() == [[1, 2, 3], [1, 2, 4], [1, 4, 4]]
    # frame 1: root Yrotation 90 turns +z into +x: the arm sits at (2, 2, 3); the arm's
    # Zrotation 90 turns its +y into -x (in the arm frame), and the root's Ry(90) leaves -x as
    # +z: the end is 2 further along +z
    np.testing.assert_allclose(pos[1], [[1, 2, 3], [2, 2, 3], [2, 2, 5]], atol=1e-12)
    c, s = 0.0, 1.0
    ry = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    np.testing.assert_allclose(rot[1, 1], ry @ rz, atol=1e-12)
    np.testing.assert_allclose(bvh.rest_positions(), [[0, 0, 0], [0, 0, 1], [0, 2, 1]])


def test_max_frames_reads_a_prefix(tmp_path):
    path = tmp_path / "small.bvh"
    path.write_text(SMALL_BVH)
    assert read_bvh(path, max_frames=1).n_frames == 1


@pytest.mark.parametrize("text, message", [
    ("HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\n", "MOTION"),
    (SMALL_BVH.replace("Frames: 2", "Frames: 3"), "announces 3 frames"),
    (SMALL_BVH.replace("Zrotation Xrotation Yrotation\n    End", "Zrotation Xrotation Wobble\n    End"), "Wobble"),
    (SMALL_BVH.replace("1 2 3 0 0 90 90 0 0", "1 2 3 0 0 90 90 0"), "values"),
    (SMALL_BVH.replace("OFFSET 0 0 1", "OFFSET 0 zero 1"), "number"),
    (SMALL_BVH.replace("Frame Time: 0.04", "Frame Time: 0"), "frame time"),
])
def test_malformed_files_name_the_file_and_the_problem(tmp_path, text, message):
    path = tmp_path / "bad.bvh"
    path.write_text(text)
    with pytest.raises(ValueError, match=message) as info:
        read_bvh(path)
    assert "bad.bvh" in str(info.value)


def test_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_bvh(tmp_path / "none.bvh")


def test_writer_channels_follow_the_documented_table():
    pose = neutral_pose()
    pose[PARAMETER_INDEX["chest_yaw"]] = math.radians(30.0)
    pose[PARAMETER_INDEX["r_shoulder_abd"]] = math.radians(40.0)
    pose[PARAMETER_INDEX["l_shoulder_abd"]] = math.radians(40.0)
    ch = pose_channels(pose[None])[0]
    # chest: X Y Z position, then Y X Z rotation; root_y and root_z change sign (y up, z to viewer)
    assert ch[:3].tolist() == pytest.approx([0.0, -0.25, -1.8])
    assert ch[3] == pytest.approx(-30.0)
    # head has 3 channels (6..8); right upper arm X Z Y (9..11); forearm (12..14); hand (15..17)
    assert ch[10] == pytest.approx(-40.0)           # right arm: -m * abd with m = +1
    assert ch[19] == pytest.approx(40.0)            # left arm: m = -1


def test_written_file_has_our_hierarchy_and_its_kinematics(tmp_path):
    dims = BodyDimensions().scaled(1.07)
    poses = _random_poses(20)
    write_bvh(tmp_path / "poses.bvh", poses, dims, 25.0)
    bvh = read_bvh(tmp_path / "poses.bvh")
    assert bvh.convention == "mocap" and bvh.fps == pytest.approx(25.0) and bvh.n_frames == 20
    # forward kinematics of the file (reader) = our model's joints (body package), y up z to viewer
    _, pos = bvh.global_transforms()
    model = BodyModel.build(dims)
    joints = np.stack([model.joint_positions(q) for q in poses]) @ CAMERA_TO_BVH.T
    pairs = {"neck": "head", "r_shoulder": "r_upper_arm", "r_elbow": "r_forearm", "r_wrist": "r_hand",
             "l_shoulder": "l_upper_arm", "l_elbow": "l_forearm", "l_wrist": "l_hand"}
    for joint, bvh_joint in pairs.items():
        np.testing.assert_allclose(pos[:, bvh.joint_index(bvh_joint)], joints[:, JOINT_NAMES.index(joint)],
                                   atol=2e-6)


@pytest.mark.filterwarnings("ignore:Importing PyGLM:PendingDeprecationWarning")
def test_poses_bvh_joint_positions_read_by_an_independent_parser(tmp_path):
    # bvhio (PyPI, not ours: its own parser and hierarchy maths, float32 PyGLM) reads the file the
    # tracker writes; its world joint positions must be our model's joints in the BVH frame
    import bvhio

    dims = BodyDimensions().scaled(0.93)
    poses = _random_poses(12, seed=3)
    write_bvh(tmp_path / "poses.bvh", poses, dims, 25.0)
    hierarchy = bvhio.readAsHierarchy(str(tmp_path / "poses.bvh"))
    joints = {joint.Name: joint for joint, _, _ in hierarchy.layout()}
    assert sorted(joints) == sorted(("chest", "head", "r_upper_arm", "r_forearm", "r_hand", "l_upper_arm",
                                     "l_forearm", "l_hand"))
    model = BodyModel.build(dims)
    pairs = {"neck": "head", "r_shoulder": "r_upper_arm", "r_elbow": "r_forearm", "r_wrist": "r_hand",
             "l_shoulder": "l_upper_arm", "l_elbow": "l_forearm", "l_wrist": "l_hand"}
    for frame, q in enumerate(poses):
        hierarchy.loadPose(frame)
        expect = model.joint_positions(q) @ CAMERA_TO_BVH.T
        for joint, bvh_joint in pairs.items():
            got = np.array(tuple(joints[bvh_joint].PositionWorld))
            np.testing.assert_allclose(got, expect[JOINT_NAMES.index(joint)], atol=2e-5,
                                       err_msg=f"frame {frame}, {joint}")


def test_write_read_round_trip(tmp_path):
    poses = _random_poses(30, seed=4)
    write_bvh(tmp_path / "p.bvh", poses, BodyDimensions(), 30.0)
    back, fps = read_pose_bvh(tmp_path / "p.bvh")
    assert fps == pytest.approx(30.0)
    np.testing.assert_allclose(back, poses, atol=2e-6)


def test_read_pose_bvh_refuses_other_skeletons(tmp_path):
    path = tmp_path / "small.bvh"
    path.write_text(SMALL_BVH)
    with pytest.raises(ValueError, match="not a mocap pose BVH"):
        read_pose_bvh(path)


@pytest.mark.parametrize("call", [
    lambda p: write_bvh(p, np.zeros((0, 23)), BodyDimensions(), 25.0),
    lambda p: write_bvh(p, np.zeros((2, 22)), BodyDimensions(), 25.0),
    lambda p: write_bvh(p, np.full((1, 23), np.nan), BodyDimensions(), 25.0),
    lambda p: write_bvh(p, neutral_pose()[None], BodyDimensions(), 0.0),
    lambda p: write_bvh(p, neutral_pose()[None], {"torso": 1}, 25.0),
])
def test_writer_rejects_bad_input(tmp_path, call):
    with pytest.raises(ValueError):
        call(tmp_path / "x.bvh")


# --- the CMU clips in ../shared/data -------------------------------------------------------------

def test_cmu_motionbuilder_names(shared_data):
    start = time.perf_counter()
    bvh = read_bvh(shared_data / "mocap" / "cmu_12_01_walk.bvh")
    assert time.perf_counter() - start < 2.0
    assert bvh.convention == "motionbuilder"
    assert bvh.n_frames == 524 and bvh.fps == pytest.approx(120.0, rel=1e-4)
    assert len([j for j in bvh.joints if not j.end_site]) == 31
    assert bvh.joints[0].name == "Hips" and len(bvh.joints[0].channels) == 6
    # rest pose is a T-pose: the left hand is straight out along +x from the left arm
    rest = bvh.rest_positions()
    arm = rest[bvh.joint_index("LeftHand")] - rest[bvh.joint_index("LeftArm")]
    assert arm[0] > 7.0 and abs(arm[1]) < 1e-6 and abs(arm[2]) < 1e-6


def test_cmu_3dsmax_names(shared_data):
    bvh = read_bvh(shared_data / "mocap" / "cmu_131_01_start_walk_stop_max.bvh", max_frames=300)
    assert bvh.convention == "3dsmax" and bvh.n_frames == 300
    assert bvh.joints[bvh.joint_index("LeftShoulder")].channels == ("Zrotation", "Xrotation", "Yrotation")
    # rest pose has the arms hanging: the left wrist below the left shoulder
    rest = bvh.rest_positions()
    arm = rest[bvh.joint_index("LeftWrist")] - rest[bvh.joint_index("LeftShoulder")]
    assert arm[1] < -7.0 and abs(arm[0]) < 1e-6


def test_cmu_asf_amc(shared_data):
    asf = read_asf(shared_data / "mocap" / "cmu_charleston.asf")
    assert asf.names[0] == "root" and len(asf.names) == 31
    assert asf.bones[asf.names.index("lradius")].dofs == ("rx",)
    assert asf.names[asf.parents[asf.names.index("lhand")]] == "lwrist"
    amc = read_amc(shared_data / "mocap" / "cmu_charleston1.amc", asf)
    assert amc.n_frames == 506
    assert amc.root_positions().shape == (506, 3)
    rot = amc.local_rotations()
    assert rot.shape == (506, 31, 3, 3)
    np.testing.assert_allclose(rot @ np.swapaxes(rot, -1, -2), np.broadcast_to(np.eye(3), rot.shape), atol=1e-9)
    # first frame's root values, from the file
    np.testing.assert_allclose(amc.values["root"][0], [-1.11547, 18.0116, -1.1819, 23.2783, -81.4298, -19.3678])
