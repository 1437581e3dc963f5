"""Own video: 2D keypoints in input pixels, the fake camera, ``track VIDEO`` with no options,
and the peer-comparison metrics (hand-computed)."""
from __future__ import annotations

import json
import shutil

import imageio.v3 as iio
import numpy as np
import pytest

from mocap.calibrate import Calibration
from mocap.cli import main
from mocap.io.pose_table import PoseTable
from mocap.metrics import pck_2d
from mocap.render import Camera

N_FRAMES = 4


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    from mocap.synth import generate_sequence
    return generate_sequence("gestures-2", tmp_path_factory.mktemp("seq") / "g2", frames=N_FRAMES, seed=1,
                             progress=False)


def test_pck_2d_against_hand_computed_values():
    ref = np.array([[[0.0, 0.0], [10.0, 0.0]], [[0.0, 0.0], [10.0, 0.0]]])
    pred = np.array([[[3.0, 4.0], [10.0, 6.0]], [[0.0, 5.0], [np.nan, 0.0]]])
    width = np.array([12.0, 10.0])                 # thresholds 6 px and 5 px
    # frame 0: distances 5 (hit) and 6 (hit, <=); frame 1: 5 (hit), NaN (left out)
    assert pck_2d(pred, ref, width) == pytest.approx(3 / 3)
    assert pck_2d(pred, ref, width, fraction=0.45) == pytest.approx(1 / 3)   # 5.4 px and 4.5 px
    np.testing.assert_allclose(pck_2d(pred, ref, width, fraction=0.45, per_frame=True), [0.5, 0.0])
    with pytest.raises(ValueError, match="shape"):
        pck_2d(pred[:, :1], ref, width)


def test_arm_pa_mpjpe_against_hand_computed_values():
    from experiments.peers import arm_pa_mpjpe

    rng = np.random.default_rng(0)
    true = rng.normal(0, 0.3, (3, 6, 3))
    angle = 0.7
    rot = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    moved = 2.0 * true @ rot.T + np.array([1.0, -2.0, 3.0])        # a similarity: 0 mm after alignment
    assert arm_pa_mpjpe(moved, true) == pytest.approx(0.0, abs=1e-6)
    # a frame where MediaPipe found nobody (NaN) is left out, not counted as an error
    off = true[0] + np.array([0.0, 0.0, 0.0])
    off[2] += [0.03, 0.04, 0.0]                               # one joint 50 mm off
    from mocap.metrics import pa_mpjpe
    alone = pa_mpjpe(off[None], true[:1])
    assert 0 < alone <= 50.0 / 6 * 1.6                         # the similarity fit spreads it, never removes it
    both = arm_pa_mpjpe(np.stack([off, np.full((6, 3), np.nan)]), true[:2])
    assert both == pytest.approx(alone)
    assert np.isnan(arm_pa_mpjpe(np.full((2, 6, 3), np.nan), true[:2]))


@pytest.mark.slow
def test_uv_columns_are_the_camera_projection_in_input_pixels(sequence, tmp_path):
    # the clip at twice its size: the tracker works at 160x120 (factor 2), the columns are in 320x240 pixels
    big = tmp_path / "big"
    big.mkdir()
    for f in sorted((sequence / "frames").iterdir()):
        iio.imwrite(big / f"{f.stem}.png", np.repeat(np.repeat(iio.imread(f), 2, 0), 2, 1))
    background = tmp_path / "background.png"
    iio.imwrite(background, np.repeat(np.repeat(iio.imread(sequence / "background.png"), 2, 0), 2, 1))
    out = tmp_path / "run"
    assert main(["track", str(big), "--background", str(background), "--calibration",
                 str(sequence / "calibration.json"), "--out", str(out), "--iterations", "60"]) == 0
    table = PoseTable.read(out / "poses.csv")
    camera = Calibration.from_json(sequence / "calibration.json").camera
    from mocap.body.skeleton import JOINT_NAMES
    for k, joint in enumerate(JOINT_NAMES):
        uv = 2.0 * camera.project(table.joints[:, k])
        np.testing.assert_allclose(table.extra[f"{joint}_u"], uv[:, 0], atol=1e-9)
        np.testing.assert_allclose(table.extra[f"{joint}_v"], uv[:, 1], atol=1e-9)
    run = json.loads((out / "run.json").read_text())
    assert run["settings"]["working_resolution"]["factor"] == 2
    assert run["settings"]["own_video"]["background"]["mode"] == "image"
    # the overlay is drawn on the input's own frames, at their size (not the working 160x120)
    from mocap.io.video import iter_frames
    assert next(iter_frames(out / "overlay.mp4")).shape == (240, 320, 3)


@pytest.mark.slow
def test_fake_camera_gives_the_same_poses_as_the_file(sequence, tmp_path):
    from mocap.io.frames import CameraSource, VideoSource
    from mocap.io.video import VideoWriter, iter_frames, read_image
    from mocap.run import OwnVideoOptions
    from mocap.run.loop import RunParams, track_frames
    from mocap.run.setup import SetupRequest, find_setup
    from mocap.track import TrackerConfig

    video = tmp_path / "clip.mp4"
    with VideoWriter(video, 10) as writer:
        for frame in iter_frames(sequence / "frames"):
            writer.write(frame)
    calibration = Calibration.from_json(sequence / "calibration.json")
    background = read_image(sequence / "background.png")
    poses = []
    for name, source in (("file", VideoSource(video)), ("camera", CameraSource.replaying(video))):
        found = find_setup(source, SetupRequest(factor=1, background_mode="image", background_image=background,
                                                 calibration=calibration, progress=False))
        setup, consumed = found.setup, found.consumed
        if source.live:
            assert 1 <= len(consumed) <= N_FRAMES          # read by the set-up, tracked first
            source.hold(consumed)
        options = OwnVideoOptions(tracker=TrackerConfig(evaluations=60), overlay=False, keypoints="none")
        track_frames(source, setup, tmp_path / name, RunParams(options=options, progress=False))
        poses.append(PoseTable.read(tmp_path / name / "poses.csv").poses)
    assert poses[0].shape == (N_FRAMES, 23)
    np.testing.assert_array_equal(poses[0], poses[1])
    assert (tmp_path / "camera" / "overlay.mp4").is_file()       # a live run writes its overlay as it goes
    # a replayed file waits to be read (no frame dropped); the latency is reported
    live = json.loads((tmp_path / "camera" / "run.json").read_text())["live"]
    assert live["dropped_frames"] == 0 and 0 < live["latency_ms"]["median"] <= live["latency_ms"]["p90"]
    assert "live" not in json.loads((tmp_path / "file" / "run.json").read_text())


@pytest.mark.slow
def test_track_synthetic_clip_without_background_or_calibration(tmp_path):
    from mocap.synth import generate_sequence

    seq = generate_sequence("gestures-1", tmp_path / "seq", frames=6, seed=0, size=(320, 240), progress=False)
    frames = tmp_path / "frames"
    shutil.copytree(seq / "frames", frames)                  # the frames alone: no background, no calibration
    out = tmp_path / "run"
    assert main(["track", str(frames), "--out", str(out), "--iterations", "100", "--no-overlay"]) == 0
    run = json.loads((out / "run.json").read_text())
    own = run["settings"]["own_video"]
    assert own["background"]["mode"] == "auto" and not own["background"]["used"]   # the actor stands still: colour-only
    assert own["calibration"]["from"] == "automatic" and own["calibration"]["face_input_px"] is not None
    table = PoseTable.read(out / "poses.csv")
    truth = PoseTable.read(seq / "ground_truth.csv")
    camera = Calibration.from_json(seq / "calibration.json").camera
    true_head = camera.project(truth.joints[:, 0])
    ours_head = np.stack([table.extra["head_u"], table.extra["head_v"]], axis=1)
    assert np.median(np.linalg.norm(ours_head - true_head, axis=1)) < 25.0     # input pixels (320x240)
    # calibrate alone, as track found it: written at the input size, and track takes it back
    calibration = tmp_path / "calibration.json"
    assert main(["calibrate", str(frames), "--out", str(calibration), "--height", "1.8"]) == 0
    written = Calibration.from_json(calibration)
    assert written.camera.shape == (240, 320)
    assert written.camera.fx == pytest.approx(Camera.default(320, 240).fx)
    assert written.dims["torso"].length > 0.5 * 1.8 / 1.75 * 0.75          # scaled to the stature, then fitted
    assert main(["track", str(frames), "--calibration", str(calibration), "--out", str(tmp_path / "again"),
                 "--iterations", "60", "--no-overlay", "--max-frames", "2"]) == 0


@pytest.mark.slow
def test_track_real_clip_with_no_options(shared_data, tmp_path, capsys):
    clip = shared_data / "video" / "intel_asl_sister.mkv"
    out = tmp_path / "run"
    assert main(["track", str(clip), "--out", str(out), "--max-frames", "5", "--iterations", "100",
                 "--no-overlay"]) == 0
    printed = capsys.readouterr().out
    assert "background:" in printed and "calibration: automatic" in printed
    table = PoseTable.read(out / "poses.csv")
    assert len(table) == 5
    u, v = table.extra["r_shoulder_u"], table.extra["r_shoulder_v"]
    assert np.all((u > 0) & (u < 640) & (v > 0) & (v < 480))
    run = json.loads((out / "run.json").read_text())
    assert run["settings"]["own_video"]["background"]["mode"] == "auto"     # estimated and used, or not
    assert run["settings"]["own_video"]["hfov_deg"] == 60.0


@pytest.mark.slow
def test_dark_and_empty_frames_are_marked_and_tracking_goes_on(sequence, tmp_path, capsys):
    folder = tmp_path / "seq"
    shutil.copytree(sequence, folder)
    frame = folder / "frames" / "000002.png"
    iio.imwrite(frame, (iio.imread(frame) * 0.03).astype(np.uint8))              # lights out
    shutil.copy(folder / "background.png", folder / "frames" / "000003.png")     # nobody in view
    out = tmp_path / "run"
    assert main(["track", str(folder), "--out", str(out), "--iterations", "60", "--no-overlay"]) == 0
    table = PoseTable.read(out / "poses.csv")
    assert list(table.frames) == list(range(N_FRAMES))
    assert list(table.extra["dark"]) == [0, 0, 1, 0]
    assert table.extra["empty"][3] == 1
    printed = capsys.readouterr().out
    assert "1 frames with nobody in view" in printed and "1 very dark frames" in printed


@pytest.mark.slow
def test_bench_video_stage_runs_the_whole_path_on_a_640x480_clip():
    from mocap.bench import video_rows

    rows = video_rows(frames=3)
    assert [r.stage for r in rows] == ["video_640x480", "video_640x480_cpu"]
    for r in rows:
        assert (r.width, r.height, r.runs) == (640, 480, 3)
        assert r.median_us > 0 and r.triangles > 0


def test_compiled_overlay_drawer_equals_numpy_on_the_render():
    """ModelDrawer (render and blend compiled, in the model's box, buffers reused) draws the
    picture of the NumPy twin on render()'s labels and edges, bit for bit, for varied poses, a
    pose out of view and two sizes, and leaves its buffers clean."""
    from mocap.bench import _poses
    from mocap.body import BodyModel
    from mocap.render import Camera, render
    from mocap.run.overlay import ModelDrawer
    from tests.naive import naive_draw_model

    rng = np.random.default_rng(5)
    model = BodyModel.build()
    away = _poses(1, seed=9)[0].copy()
    away[:3] = (5.0, 0.0, -3.0)                      # behind the camera: nothing drawn
    for size in ((160, 120), (320, 240)):
        camera = Camera.default(*size)
        frame = rng.integers(0, 256, (size[1], size[0], 3), dtype=np.uint8)
        kept = frame.copy()
        drawer = ModelDrawer(model, camera)
        for pose in [*_poses(6, seed=3), away]:
            r = render(pose, model, camera)
            expected = naive_draw_model(frame, r.labels, r.edges, model.n_classes, class_names=model.class_names)
            np.testing.assert_array_equal(drawer.draw(frame, pose), expected)
            assert not drawer.buffers.part_ids.any() and not drawer.buffers.inverse_depth.any()
            assert not drawer.marks.any()
        np.testing.assert_array_equal(frame, kept)


def test_blend_table_is_numpys_float32_blend():
    from mocap.imaging.visual import blend_table
    f, c = np.meshgrid(np.arange(256), np.arange(256), indexing="ij")
    for alpha in (0.0, 0.35, 1.0):
        expected = np.clip((1 - alpha) * f.astype(np.float32) + alpha * c.astype(np.float32), 0, 255).astype(np.uint8)
        np.testing.assert_array_equal(blend_table(alpha), expected)
    with pytest.raises(ValueError):
        blend_table(1.5)


def test_overlay_drawn_in_the_model_box_equals_the_whole_frame():
    """draw_model looks at the model's box only: the same picture as blending the whole frame
    (tests/naive.py), with edges beyond the silhouette and with nothing drawn."""
    from mocap.run.overlay import draw_model
    from tests.naive import naive_draw_model
    rng = np.random.default_rng(2)
    frame = rng.integers(0, 256, (48, 64, 3), dtype=np.uint8)
    labels = np.zeros((48, 64), np.uint8)
    labels[10:30, 20:41] = rng.integers(0, 5, (20, 21))
    labels[12, 22] = 255
    edges = np.zeros((48, 64), bool)
    edges[9, 18:44] = edges[5, 50] = True
    names = ("skin", "clothes", "hair", "lower_body")
    for lab, edg in ((labels, edges), (labels, np.zeros_like(edges)), (np.zeros_like(labels), edges),
                     (np.zeros_like(labels), np.zeros_like(edges))):
        np.testing.assert_array_equal(draw_model(frame, lab, edg, 4, class_names=names),
                                      naive_draw_model(frame, lab, edg, 4, class_names=names))


@pytest.mark.slow
def test_colour_face_is_honoured_where_the_run_learns_the_colours_and_refused_elsewhere(tmp_path, capsys):
    """``--colour face`` with a given calibration and background: the run learns the colours from
    the detected face (at the input size, where the face is big enough to find; run.json says
    so, and they are not the calibration's); with an automatic
    calibration, which learns them inside its own fit, it is refused in one line before a frame
    is tracked."""
    from mocap.synth import generate_sequence

    seq = generate_sequence("gestures-1", tmp_path / "seq", frames=3, seed=0, size=(320, 240), progress=False)
    frames = tmp_path / "frames"
    shutil.copytree(seq / "frames", frames)                  # no background, no calibration: automatic
    args = ["--iterations", "30", "--no-overlay", "--keypoints", "none", "--max-frames", "2"]
    capsys.readouterr()
    assert main(["track", str(frames), "--out", str(tmp_path / "auto"), "--colour", "face", *args]) == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]          # after the set-up's face search bar
    assert last.startswith("error: --colour face") and "automatic calibration" in last and "--calibration" in last
    assert not (tmp_path / "auto" / "poses.csv").exists()
    models = {}
    for colour in ("face", "calibration"):
        out = tmp_path / colour
        assert main(["track", str(seq), "--out", str(out), "--colour", colour, "--work-width", "320", *args]) == 0
        assert json.loads((out / "run.json").read_text())["settings"]["colour_model_from"] == colour
        models[colour] = (out / "colour_model.json").read_text()
    assert models["face"] != models["calibration"]
