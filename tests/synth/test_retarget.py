"""Retargeting clips onto our 23 parameters: rest poses, known rotations, our own files, CMU clips."""
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mocap.body import ANGLE_NAMES, JOINT_LIMITS, PARAMETER_INDEX, BodyDimensions, BodyModel, neutral_pose
from mocap.body.skeleton import SEGMENT_NAMES
from mocap.io.bvh import read_bvh, write_bvh
from mocap.synth.retarget import (JOINT_MAPS, RetargetConfig, clip_from_bvh, load_clip, retarget)

CENTRE = (0.0, 0.6, 1.7)
ANGLES = [PARAMETER_INDEX[n] for n in ANGLE_NAMES]


def _angles_deg(pose):
    return {n: math.degrees(pose[PARAMETER_INDEX[n]]) for n in ANGLE_NAMES}


def _edited(bvh, edits, frames=2):
    """The clip's hierarchy with all channels zero, and ``edits`` {(joint, channel): degrees} in
    the last frame."""
    motion = np.zeros((frames, bvh.motion.shape[1]))
    for (joint, channel), value in edits.items():
        j = bvh.joint_index(joint)
        motion[-1, bvh.channel_start(j) + bvh.joints[j].channels.index(channel)] = value
    return bvh.with_motion(motion)


@pytest.fixture(scope="module")
def max_clip(shared_data):
    return read_bvh(shared_data / "mocap" / "cmu_131_01_start_walk_stop_max.bvh", max_frames=2)


@pytest.fixture(scope="module")
def mb_clip(shared_data):
    return read_bvh(shared_data / "mocap" / "cmu_12_01_walk.bvh", max_frames=2)


def test_rest_pose_maps_to_the_neutral_upright_pose(max_clip):
    # The 3dsMax-named CMU skeleton rests upright, facing forwards, arms hanging: every joint
    # angle of ours is zero and the root sits at the centre asked for.
    out = retarget(clip_from_bvh(_edited(max_clip, {})), RetargetConfig(fps=120, centre=CENTRE))
    np.testing.assert_allclose(out[:, ANGLES], 0.0, atol=1e-9)
    np.testing.assert_allclose(out[:, :3], [CENTRE, CENTRE], atol=1e-12)


def test_t_pose_rest_maps_to_arms_raised_sideways(mb_clip):
    # The MotionBuilder-named CMU skeleton rests in a T-pose: shoulders abducted 90 degrees.
    out = retarget(clip_from_bvh(_edited(mb_clip, {})), RetargetConfig(fps=120))
    deg = _angles_deg(out[0])
    assert deg.pop("r_shoulder_abd") == pytest.approx(90.0, abs=1e-6)
    assert deg.pop("l_shoulder_abd") == pytest.approx(90.0, abs=1e-6)
    assert max(abs(v) for v in deg.values()) < 1e-6


def test_our_neutral_pose_written_as_bvh_comes_back(tmp_path):
    write_bvh(tmp_path / "n.bvh", np.tile(neutral_pose(CENTRE), (3, 1)), BodyDimensions(), 25.0)
    out = retarget(load_clip(tmp_path / "n.bvh"), RetargetConfig(face_camera=False, max_offset_m=None))
    np.testing.assert_allclose(out, np.tile(neutral_pose(CENTRE), (3, 1)), atol=1e-6)


@pytest.mark.parametrize("edit, expected", [
    # clip world: y up, the actor faces +z, his left is +x
    ((("RightShoulder", "Xrotation"), -60.0), {"r_shoulder_flex": 60.0}),   # arm swings forwards
    ((("RightShoulder", "Zrotation"), -40.0), {"r_shoulder_abd": 40.0}),    # right arm out to -x
    ((("LeftShoulder", "Zrotation"), 40.0), {"l_shoulder_abd": 40.0}),      # left arm out to +x
    ((("RightShoulder", "Yrotation"), 30.0), {"r_shoulder_rot": -30.0}),    # inwards: internal
    ((("RightElbow", "Xrotation"), -90.0), {"r_elbow_flex": 90.0}),
    ((("LeftElbow", "Xrotation"), -45.0), {"l_elbow_flex": 45.0}),
    ((("rhand", "Xrotation"), -30.0), {"r_wrist_flex": 30.0}),
    ((("Chest2", "Xrotation"), 20.0), {"chest_pitch": 20.0}),               # leans forwards
    ((("Hips", "Yrotation"), 30.0), {"chest_yaw": -30.0}),                  # turns to his left
    ((("Head", "Xrotation"), 20.0), {"head_flex": 20.0}),                   # nods
    ((("Head", "Yrotation"), 40.0), {"head_turn": -40.0}),                  # looks to his left
    ((("Head", "Zrotation"), 15.0), {"head_tilt": -15.0}),                  # towards his right shoulder
])
def test_known_clip_rotation_maps_to_the_expected_angle(max_clip, edit, expected):
    out = retarget(clip_from_bvh(_edited(max_clip, dict([edit]))), RetargetConfig(fps=120, face_camera=False))
    got = {n: v for n, v in _angles_deg(out[-1]).items() if abs(v) > 1e-6}
    assert got.keys() == expected.keys()
    for name, value in expected.items():
        assert got[name] == pytest.approx(value, abs=1e-6)


def test_face_camera_removes_the_initial_heading(max_clip):
    clip = clip_from_bvh(_edited(max_clip, {("Hips", "Yrotation"): 70.0}, frames=1))
    out = retarget(clip, RetargetConfig(fps=120))
    assert out[0, PARAMETER_INDEX["chest_yaw"]] == pytest.approx(0.0, abs=1e-9)


def test_our_own_files_round_trip_through_the_generic_retargeting(tmp_path):
    rng = np.random.default_rng(7)
    lo, hi = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    poses = np.tile(neutral_pose(), (40, 1))
    poses[:, 3:] = rng.uniform(0.85 * lo[3:], 0.85 * hi[3:], size=(40, 20))
    write_bvh(tmp_path / "r.bvh", poses, BodyDimensions(), 25.0)
    out = retarget(load_clip(tmp_path / "r.bvh"), RetargetConfig(fps=25.0, face_camera=False, max_offset_m=None))
    diff = out - poses
    diff[:, 3:] = (diff[:, 3:] + np.pi) % (2 * np.pi) - np.pi
    assert np.abs(diff).max() < 1e-5


def _clip_bone_directions(bvh, frames, face_camera=True):
    """Upper-arm and forearm directions of the clip by the reader's own kinematics, in camera axes."""
    jm = JOINT_MAPS[bvh.convention]
    rot, pos = bvh.global_transforms()
    chest = bvh.joint_index(jm["chest"])
    heading = np.eye(3)
    if face_camera:
        fwd = rot[0, chest] @ [0.0, 0.0, 1.0]
        heading = Rotation.from_rotvec([0.0, -math.atan2(fwd[0], fwd[2]), 0.0]).as_matrix()
    flip = np.diag([1.0, -1.0, -1.0])
    p = pos[frames] @ (flip @ heading).T
    out = {}
    for side in "rl":
        a, b, c = (p[:, bvh.joint_index(jm[f"{side}_{x}"])] for x in ("upper_arm", "forearm", "hand"))
        out[f"{side}_upper_arm"] = (b - a) / np.linalg.norm(b - a, axis=1, keepdims=True)
        out[f"{side}_forearm"] = (c - b) / np.linalg.norm(c - b, axis=1, keepdims=True)
    return out


@pytest.mark.parametrize("name", ["cmu_131_01_start_walk_stop_max.bvh", "cmu_12_01_walk.bvh"])
def test_cmu_clip_bones_point_where_the_clip_bones_point(shared_data, name):
    bvh = read_bvh(shared_data / "mocap" / name)
    poses = retarget(clip_from_bvh(bvh), RetargetConfig(fps=24.0))   # 120 / 24: output frame k = clip frame 5k
    assert np.isfinite(poses).all()
    assert (poses >= JOINT_LIMITS[:, 0]).all() and (poses <= JOINT_LIMITS[:, 1]).all()
    frames = np.arange(len(poses)) * 5
    frames = frames[frames < bvh.n_frames]
    clip_dirs = _clip_bone_directions(bvh, frames)
    model = BodyModel.build()
    ours = np.stack([model.segment_transforms(q) for q in poses[:len(frames)]])
    for segment, directions in clip_dirs.items():
        mine = ours[:, SEGMENT_NAMES.index(segment), :, 1]            # segment long axis (+y)
        angle = np.degrees(np.arccos(np.clip((mine * directions).sum(axis=1), -1.0, 1.0)))
        # exact but where a joint limit or our hinge elbow clamps the clip's motion
        assert np.median(angle) < 2.0, segment
        assert np.percentile(angle, 80) < 5.0, segment


def test_cmu_turning_clip_keeps_the_actor_in_view(shared_data):
    poses = retarget(load_clip(shared_data / "mocap" / "cmu_01_01_jumps_turn_around.bvh"),
                     RetargetConfig(centre=CENTRE))
    assert len(poses) == 574                                      # 2752 frames at 120 fps -> 25 fps
    offset = np.abs(poses[:, :3] - np.array(CENTRE))
    assert (offset <= np.array(RetargetConfig().max_offset_m) + 1e-9).all()
    yaw = np.unwrap(poses[:, PARAMETER_INDEX["chest_yaw"]])
    assert np.degrees(yaw.max() - yaw.min()) > 170.0              # turns around


def test_cmu_amc_clip(shared_data):
    poses = retarget(load_clip(shared_data / "mocap" / "cmu_charleston1.amc"))
    assert poses.shape == (int(505 / 120 * 25) + 1, 23)
    assert (poses >= JOINT_LIMITS[:, 0]).all() and (poses <= JOINT_LIMITS[:, 1]).all()
    # a dance: the arms move a lot
    assert np.degrees(np.ptp(poses[:, PARAMETER_INDEX["l_elbow_flex"]])) > 30.0


def test_load_clip_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_clip(tmp_path / "none.bvh")
    (tmp_path / "clip.txt").write_text("x")
    with pytest.raises(ValueError, match=".bvh or .amc"):
        load_clip(tmp_path / "clip.txt")
    (tmp_path / "lonely.amc").write_text(":FULLY-SPECIFIED\n1\n")
    with pytest.raises(FileNotFoundError, match="skeleton"):
        load_clip(tmp_path / "lonely.amc")
    (tmp_path / "odd.bvh").write_text("HIERARCHY\nROOT Pelvis\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation "
                                      "Zrotation\n}\nMOTION\nFrames: 1\nFrame Time: 0.01\n0 0 0\n")
    with pytest.raises(ValueError, match="convention"):
        load_clip(tmp_path / "odd.bvh")
