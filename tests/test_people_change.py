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


@pytest.mark.slow
def test_two_people_one_after_the_other_make_two_segments(two_people, tmp_path):
    folder, background = two_people
    out = tmp_path / "run"
    assert main(["track", str(folder), "--background", str(background), "--out", str(out), "--iterations", "40",
                 "--beam", "1", "--lag", "0", "--no-overlay"]) == 0
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
