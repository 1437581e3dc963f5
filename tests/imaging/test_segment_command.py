"""``python -m mocap segment`` end to end on a tiny synthetic clip, and its errors."""
from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

from mocap.cli import main
from mocap.imaging import ColourModel, ImagingConfig
from mocap.imaging.colour import skin_box_of_face
from mocap.imaging.testing import synthetic_scene_with_labels
from mocap.io.video import count_frames, read_image

from tests.conftest import need_mediapipe


@pytest.fixture()
def clip(tmp_path):
    """Folder of 4 synthetic frames (one empty) and the background image."""
    frames = tmp_path / "frames"
    frames.mkdir()
    scenes = [synthetic_scene_with_labels(96, 72, seed) for seed in range(3)]
    for i, scene in enumerate(scenes):
        iio.imwrite(frames / f"{i:06d}.png", scene.frame)
    iio.imwrite(frames / "000003.png", scenes[0].background)  # nobody in the scene
    iio.imwrite(tmp_path / "background.png", scenes[0].background)
    return tmp_path, scenes[0]


def _boxes(scene):
    s = skin_box_of_face(scene.face_box)
    c = scene.clothes_box
    return ["--skin-box", ",".join(map(str, s)), "--clothes-box", ",".join(map(str, c))]


def test_segment_writes_everything(clip, capsys):
    root, scene = clip
    out = root / "out"
    status = main(["segment", str(root / "frames"), "--background", str(root / "background.png"),
                   "--out", str(out), *_boxes(scene)])
    assert status == 0
    for sub in ("labels", "edges", "distance"):
        assert sorted(p.name for p in (out / sub).iterdir()) == [f"{i:06d}.png" for i in range(4)]
    labels = read_image(out / "labels" / "000000.png")
    assert labels.shape == (72, 96, 3)
    assert (labels.reshape(-1, 3) != 0).any(axis=1).mean() > 0.1  # a coloured person
    assert not read_image(out / "labels" / "000003.png").any()  # the empty frame
    assert count_frames(out / "segment.mp4") == 4
    assert ColourModel.from_json(out / "colour_model.json").names == ("skin", "clothes")
    assert ImagingConfig.from_json(out / "imaging.json") == ImagingConfig()
    printed = capsys.readouterr().out
    assert "segmented 4 frames (1 with nobody in them)" in printed


def test_segment_with_median_background_and_saved_model(clip):
    root, scene = clip
    first = root / "first"
    assert main(["segment", str(root / "frames"), "--background", str(root / "background.png"),
                 "--out", str(first), "--max-frames", "1", *_boxes(scene)]) == 0
    second = root / "second"
    # frames 3..3 are the empty view; the colour model is reused
    assert main(["segment", str(root / "frames"), "--background-frames", "3:4", "--out",
                 str(second), "--colour-model", str(first / "colour_model.json"), "--start", "1",
                 "--max-frames", "2"]) == 0
    assert sorted(p.name for p in (second / "labels").iterdir()) == ["000001.png", "000002.png"]


@pytest.mark.parametrize("extra, message", [
    ([], "--background IMG"),
    (["--background", "missing.png"], "no such file"),
    (["--background", "corrupt.png"], "corrupt"),
    (["--background", "small.png"], "background is 40x30 but the video is 96x72"),
    (["--background", "gray.png"], "grayscale"),
    (["--background", "background.png", "--start", "99"], "past the end"),
    (["--background", "background.png", "--config", "bad.json"], "unknown ImagingConfig option"),
    (["--background", "background.png"], "no face found"),
])
def test_segment_errors_exit_2_with_one_line(clip, capsys, monkeypatch, extra, message):
    root, _ = clip
    monkeypatch.chdir(root)
    (root / "corrupt.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"x" * 50)
    iio.imwrite(root / "small.png", np.zeros((30, 40, 3), np.uint8))
    iio.imwrite(root / "gray.png", np.zeros((72, 96), np.uint8))
    (root / "bad.json").write_text('{"max_distnace": 3}')
    status = main(["segment", str(root / "frames"), "--out", str(root / "o"), *extra])
    assert status == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and message in err and "\n" not in err


def test_segment_rejects_malformed_boxes(clip):
    root, _ = clip
    with pytest.raises(SystemExit):
        main(["segment", str(root / "frames"), "--background", str(root / "background.png"),
              "--skin-box", "1,2,3"])


def test_interrupted_segment_resumes_where_it_stopped(clip, capsys, monkeypatch):
    import mocap.run.segment as segment
    root, scene = clip
    args = ["segment", str(root / "frames"), "--background", str(root / "background.png"), *_boxes(scene)]
    assert main([*args, "--out", str(root / "whole")]) == 0
    prepare, calls = segment.prepare_frame, []

    def interrupt_at_third(frame, *rest):
        calls.append(frame)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return prepare(frame, *rest)

    monkeypatch.setattr(segment, "prepare_frame", interrupt_at_third)
    out = root / "resumed"
    assert main([*args, "--out", str(out)]) == 130
    assert "run the same command again to resume" in capsys.readouterr().err
    assert sorted(p.name for p in (out / "distance").iterdir()) == ["000000.png", "000001.png"]
    calls.clear()
    assert main([*args, "--out", str(out)]) == 0
    assert len(calls) == 2                                 # frames 2 and 3 only
    assert "(1 with nobody in them; 2 kept from an interrupted run)" in capsys.readouterr().out
    for sub in ("labels", "edges", "distance"):
        for i in range(4):
            np.testing.assert_array_equal(read_image(out / sub / f"{i:06d}.png", allow_gray=True),
                                          read_image(root / "whole" / sub / f"{i:06d}.png", allow_gray=True))
    assert count_frames(out / "segment.mp4") == 4
    # other settings in the same folder: refused, nothing changed
    assert main([*args, "--out", str(out), "--start", "1"]) == 2
    assert "holds a segmentation with other settings" in capsys.readouterr().err


def test_colours_are_learned_on_the_first_frame_that_shows_the_person(clip, capsys):
    root, scene = clip
    frames = root / "frames"
    (frames / "000000.png").rename(root / "first.png")
    iio.imwrite(frames / "000000.png", scene.background)          # the room is empty at first
    assert main(["segment", str(frames), "--background", str(root / "background.png"), "--out", str(root / "o"),
                 *_boxes(scene)]) == 0
    assert "colours learned on frame 1, the first that shows the person" in capsys.readouterr().out


def test_a_segmentation_resumed_after_the_keypoints_extra_came_is_refused_with_why(clip, capsys, monkeypatch):
    """``--keypoints auto`` gave none (no extra); with the extra installed since, it would give
    MediaPipe: the folder's segment.json says otherwise, and the one-line refusal says why."""
    need_mediapipe()
    from mocap.io import mediapipe_keypoints

    root, scene = clip
    args = ["segment", str(root / "frames"), "--background", str(root / "background.png"), *_boxes(scene),
            "--out", str(root / "out")]
    assert main(args) == 0
    capsys.readouterr()
    monkeypatch.setattr(mediapipe_keypoints, "available", lambda: True)
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "made with keypoints None, this one's would be 'mediapipe'" in err
    assert "the optional extra 'keypoints' was installed or removed" in err and "another --out" in err


@pytest.mark.parametrize("command", ["segment", "calibrate"])
def test_segment_and_calibrate_end_their_keypoint_detectors_process(clip, monkeypatch, command):
    """The keypoint source (a detector in a process of its own) is closed when the command
    returns, whether it succeeded or stopped with its one-line error: its child has ended."""
    import mocap.run.options
    from mocap.io.keypoint_process import KeypointProcess
    from tests.io.detectors import BrightestPixel, to_keypoints

    root, scene = clip
    made = []

    def source(resolved, auto):
        made.append(KeypointProcess(BrightestPixel, to_keypoints))
        return made[-1]

    monkeypatch.setattr(mocap.run.options, "_source", source)
    out = ["--out", str(root / ("o" if command == "segment" else "calibration.json"))]
    extra = _boxes(scene) if command == "segment" else []
    main([command, str(root / "frames"), "--background", str(root / "background.png"), "--keypoints", "mediapipe",
          *out, *extra])
    assert len(made) == 1
    assert made[0]._process.poll() is not None, f"{command} left its keypoint detector's process running"
