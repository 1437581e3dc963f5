"""The keypoint type and the keypoint file (mocap.io.keypoints)."""
from __future__ import annotations

import numpy as np
import pytest

from mocap.body.skeleton import JOINT_NAMES
from mocap.io.keypoints import (KeypointFile, Keypoints, append_keypoints, parse_keypoints, read_keypoints,
                                write_keypoints)


def random_keypoints(rng, absent=()):
    uv = rng.uniform(0, 640, (len(JOINT_NAMES), 2))
    conf = rng.uniform(0.05, 1.0, len(JOINT_NAMES))
    for name in absent:
        conf[JOINT_NAMES.index(name)] = 0.0
    return Keypoints(uv, conf)


def test_a_keypoint_file_round_trips_exactly(tmp_path):
    rng = np.random.default_rng(0)
    frames = {0: random_keypoints(rng), 3: random_keypoints(rng, absent=("neck", "l_hand")), 17: random_keypoints(rng)}
    write_keypoints(tmp_path / "k.csv", frames)
    back = read_keypoints(tmp_path / "k.csv")
    assert sorted(back) == [0, 3, 17]
    for f, k in frames.items():
        np.testing.assert_array_equal(back[f].confidence, k.confidence)
        np.testing.assert_array_equal(back[f].uv, k.uv)          # NaN where absent, equal as arrays
    assert "neck" not in back[3].as_mapping()


def test_a_keypoint_journal_appended_frame_by_frame_is_the_file_written_at_once(tmp_path):
    """``keypoints.csv`` of a run (appended as frames are pushed) is byte for byte the keypoint
    file of the same frames; a frame without a present joint adds no row."""
    rng = np.random.default_rng(1)
    frames = {0: random_keypoints(rng), 1: Keypoints.empty(), 2: random_keypoints(rng, absent=("head",))}
    for f, k in frames.items():
        append_keypoints(tmp_path / "journal.csv", f, k)
    write_keypoints(tmp_path / "whole.csv", frames)
    assert (tmp_path / "journal.csv").read_bytes() == (tmp_path / "whole.csv").read_bytes()
    assert sorted(read_keypoints(tmp_path / "journal.csv")) == [0, 2]
    append_keypoints(tmp_path / "empty.csv", 5, Keypoints.empty())         # the header alone: a keypoint file
    assert read_keypoints(tmp_path / "empty.csv") == {}


def test_missing_and_nan_joints_are_absent_and_change_nothing_else():
    text = ("frame,joint,u,v,confidence\n"
            "0,r_elbow,10.5,20.25,0.9\n"
            "0,l_elbow,nan,3,1\n"          # NaN position: absent
            "0,r_wrist,1,2,\n"              # empty confidence: absent
            "0,head,5,6,NaN\n"              # NaN confidence: absent
            "2,neck,,,\n")                  # nothing at all: the frame is left out
    frames = parse_keypoints(text)
    assert list(frames) == [0]
    assert frames[0].as_mapping() == {"r_elbow": (10.5, 20.25, 0.9)}
    alone = parse_keypoints("frame,joint,u,v,confidence\n0,r_elbow,10.5,20.25,0.9\n")
    np.testing.assert_array_equal(frames[0].uv, alone[0].uv)
    np.testing.assert_array_equal(frames[0].confidence, alone[0].confidence)


def test_file_source_gives_empty_keypoints_for_frames_it_lacks(tmp_path):
    path = tmp_path / "k.csv"
    path.write_text("frame,joint,u,v,confidence\n1,head,4,5,1\n")
    source = KeypointFile(path)
    assert not source.keypoints(0, None).present.any()
    assert source.keypoints(1, None).as_mapping() == {"head": (4.0, 5.0, 1.0)}


@pytest.mark.parametrize("text, match", [
    ("frame,joint,u,v\n0,head,1,2\n", "first line"),
    ("frame,joint,u,v,confidence\n0,nose,1,2,1\n", "line 2: unknown joint 'nose'"),
    ("frame,joint,u,v,confidence\nx,head,1,2,1\n", "line 2: frame 'x' is not an integer"),
    ("frame,joint,u,v,confidence\n-1,head,1,2,1\n", "negative"),
    ("frame,joint,u,v,confidence\n0,head,one,2,1\n", "u 'one' is not a number"),
    ("frame,joint,u,v,confidence\n0,head,1,2,1.5\n", "outside"),
    ("frame,joint,u,v,confidence\n0,head,1,2\n", "expected 5 fields"),
    ("frame,joint,u,v,confidence\n0,head,inf,2,1\n", "finite"),
    ("frame,joint,u,v,confidence\n0,head,1,2,1\n0,head,1,2,1\n", "line 3: frame 0 gives joint 'head' twice"),
])
def test_a_malformed_file_is_a_clear_error(text, match):
    with pytest.raises(ValueError, match=match):
        parse_keypoints(text)


def test_scaling_follows_the_camera():
    from mocap.render.camera import Camera

    cam = Camera.default(640, 480)
    small = cam.scaled(160, 120)
    point = np.array([[0.1, -0.2, 2.0]])
    k = Keypoints.from_mapping({"head": (*cam.project(point)[0], 1.0)}).scaled(160 / 640, 120 / 480)
    np.testing.assert_allclose(k.uv[JOINT_NAMES.index("head")], small.project(point)[0], atol=1e-12)


def test_keypoints_reject_bad_values():
    with pytest.raises(ValueError, match="shape"):
        Keypoints(np.zeros((3, 2)), np.zeros(3))
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        Keypoints(np.zeros((len(JOINT_NAMES), 2)), np.full(len(JOINT_NAMES), 2.0))
    with pytest.raises(ValueError, match="unknown joint"):
        Keypoints.from_mapping({"nose": (1.0, 2.0, 1.0)})


def test_a_file_with_the_detectors_3d_reads_back_exactly(tmp_path):
    """``x,y,z`` columns (MediaPipe's world joints) round-trip bit for bit, absent ones stay NaN,
    and a file without them reads as keypoints without 3D."""
    from mocap.io.keypoints import KEYPOINT_WORLD_COLUMNS, Keypoints, append_keypoints, read_keypoints, write_keypoints

    rng = np.random.default_rng(1)
    uv = rng.uniform(0, 100, (10, 2))
    uv[1] = np.nan                                            # the neck: absent in 2D, so in 3D too
    world = rng.normal(0, 0.3, (10, 3))
    world[4] = np.nan                                         # a joint with 2D but no 3D
    k = Keypoints(uv, np.where(np.isnan(uv[:, 0]), 0.0, 0.7), world)
    assert np.isnan(k.world[1]).all() and np.isnan(k.world[4]).all()
    path = tmp_path / "k.csv"
    write_keypoints(path, {3: k, 5: Keypoints(uv, np.full(10, 0.5))})
    assert path.read_text().splitlines()[0] == ",".join(KEYPOINT_WORLD_COLUMNS)
    back = read_keypoints(path)
    np.testing.assert_array_equal(back[3].world, k.world)
    np.testing.assert_array_equal(back[3].uv, k.uv)
    assert np.isnan(back[5].world).all()                      # a frame given without 3D: none
    np.testing.assert_array_equal(back[3].scaled(2.0, 2.0).world, k.world)     # 3D is not in pixels
    journal = tmp_path / "j.csv"
    append_keypoints(journal, 0, k)
    append_keypoints(journal, 1, k)
    np.testing.assert_array_equal(read_keypoints(journal)[1].world, k.world)
    plain = tmp_path / "plain.csv"
    write_keypoints(plain, {0: Keypoints(uv, np.full(10, 0.5))})
    assert read_keypoints(plain)[0].world is None
    bad = tmp_path / "bad.csv"
    bad.write_text(",".join(KEYPOINT_WORLD_COLUMNS) + "\n0,head,1,2,0.5,0.1,inf,0.3\n")
    with pytest.raises(ValueError, match="line 2"):
        read_keypoints(bad)
