"""People change: when the tracked person leaves and someone else comes, the track ends its
segment and calibrates the newcomer afresh (``run.json`` ``segments``, ``poses.csv``
``segment``). The clip: two synthetic actors in one scene, one after the other."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from mocap.cli import main
from mocap.io.pose_table import PoseTable

SIZE = (320, 240)
PERSON_FRAMES, EMPTY_FRAMES = 6, 12


@pytest.fixture(scope="module")
def two_people(tmp_path_factory):
    """Frames of actor A, the empty scene, then actor B (another body and clothes) in A's scene;
    the folder, the background image and the first frame of each person."""
    import imageio.v3 as iio

    from mocap.synth.sequence import sequence_poses, setup_sequence

    first = setup_sequence("gestures-1", seed=0, size=SIZE)
    other = dataclasses.replace(first, actor=setup_sequence("gestures-3", seed=5, size=SIZE).actor)
    folder = tmp_path_factory.mktemp("two") / "frames"
    folder.mkdir()
    frames = [first.frame(p, i) for i, p in enumerate(sequence_poses(first, frames=PERSON_FRAMES)[0])]
    frames += [first.background_frame()] * EMPTY_FRAMES
    poses_b = sequence_poses(dataclasses.replace(other, name="gestures-3", seed=5), frames=PERSON_FRAMES)[0]
    frames += [other.frame(p, i) for i, p in enumerate(poses_b)]
    for i, frame in enumerate(frames):
        iio.imwrite(folder / f"{i:06d}.png", frame)
    background = folder.parent / "background.png"
    iio.imwrite(background, first.background_frame())
    return folder, background


ARGS = ["--iterations", "40", "--beam", "1", "--lag", "0", "--no-overlay"]


@pytest.fixture(scope="module")
def whole_run(two_people, tmp_path_factory):
    folder, background = two_people
    out = tmp_path_factory.mktemp("whole") / "run"
    assert main(["track", str(folder), "--background", str(background), "--out", str(out), *ARGS]) == 0
    return out


@pytest.mark.slow
def test_two_people_one_after_the_other_make_two_segments(whole_run):
    out = whole_run
    run = json.loads((out / "run.json").read_text())
    segments = run["segments"]
    newcomer = PERSON_FRAMES + EMPTY_FRAMES
    assert len(segments) == 2, segments
    assert segments[0]["first_frame"] == 0 and segments[0]["last_frame"] == PERSON_FRAMES - 1
    # found on the first frame that shows the newcomer (frames are looked at every third)
    assert newcomer <= segments[1]["first_frame"] < newcomer + 3
    assert segments[1]["found"]["frame"] == segments[1]["first_frame"]
    assert segments[1]["last_frame"] == newcomer + PERSON_FRAMES - 1
    assert segments[0]["calibration"] != segments[1]["calibration"]       # calibrated afresh
    table = PoseTable.read(out / "poses.csv")
    assert list(table.frames) == list(range(newcomer + PERSON_FRAMES))
    assert list(table.extra["segment"]) == [0] * segments[1]["first_frame"] + \
        [1] * (newcomer + PERSON_FRAMES - segments[1]["first_frame"])


@pytest.mark.slow
def test_a_run_stopped_in_the_second_segment_resumes_to_the_same_poses(two_people, whole_run, tmp_path):
    folder, background = two_people
    out = tmp_path / "run"
    stop = PERSON_FRAMES + EMPTY_FRAMES + 4                 # inside the newcomer's segment
    given = ["--background", str(background), "--out", str(out), *ARGS]
    assert main(["track", str(folder), *given, "--max-frames", str(stop)]) == 0
    assert main(["track", str(folder), *given]) == 0          # resumes: the newcomer is found again
    run = json.loads((out / "run.json").read_text())
    assert run["resumed_from_frame"] == stop
    assert run["segments"] == json.loads((whole_run / "run.json").read_text())["segments"]
    a, b = PoseTable.read(whole_run / "poses.csv"), PoseTable.read(out / "poses.csv")
    np.testing.assert_array_equal(b.poses, a.poses)
    np.testing.assert_array_equal(b.extra["segment"], a.extra["segment"])
