"""Sequence folders: contents, determinism, not the tracker's own render, errors, the bundled default."""
import json

import imageio.v3 as iio
import numpy as np
import pytest
from scipy import ndimage

from mocap import cli
from mocap.body import PART_NAMES, BodyDimensions, BodyModel, JOINT_LIMITS
from mocap.calibrate import Calibration
from mocap.io.pose_table import PoseTable
from mocap.render import render
from mocap.synth import SEQUENCE_NAMES, generate_sequence, sequence_poses, setup_sequence
from mocap.synth.actor import ACTOR_PART_NAMES
from mocap.body.skeleton import MESH_PART_NAMES
from mocap.synth.datasets import DEFAULT_SEQUENCE, bundled_default_sequence, make_default_sequence
from mocap.synth.shading import _surface_samples
from tests.naive import naive_surface_samples

N = 10


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    return generate_sequence("arms-crossing", tmp_path_factory.mktemp("seq") / "arms", frames=N, seed=5,
                             progress=False)


def _files(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _iou(a, b):
    return (a & b).sum() / (a | b).sum()


def test_folder_holds_what_design_section_4_lists(sequence):
    assert sorted(p.name for p in sequence.iterdir()) == ["background.png", "calibration.json", "frames",
                                                        "ground_truth.csv", "meta.json"]
    frames = sorted(p.name for p in (sequence / "frames").iterdir())
    assert frames == [f"{i:06d}.png" for i in range(N)]
    image = iio.imread(sequence / "frames" / frames[0])
    assert image.shape == (120, 160, 3) and image.dtype == np.uint8
    meta = json.loads((sequence / "meta.json").read_text())
    assert meta["sequence"] == "arms-crossing" and meta["frames"] == N and meta["fps"] == 25.0
    assert meta["size"] == [160, 120] and meta["seed"] == 5
    assert {"fx", "fy", "cx", "cy"} <= set(meta["camera"])


def test_ground_truth_and_calibration_agree(sequence):
    gt = PoseTable.read(sequence / "ground_truth.csv")
    cal = Calibration.from_json(sequence / "calibration.json")
    assert gt.frames.tolist() == list(range(N))
    assert (gt.poses >= JOINT_LIMITS[:, 0] - 1e-9).all() and (gt.poses <= JOINT_LIMITS[:, 1] + 1e-9).all()
    np.testing.assert_allclose(cal.initial_pose, gt.poses[0], atol=1e-12)
    model = BodyModel.build(cal.dims)
    np.testing.assert_allclose(gt.joints, np.stack([model.joint_positions(q) for q in gt.poses]), atol=1e-12)
    # the actor is not the default body: the tracker has to be calibrated
    default = BodyDimensions()
    assert all(cal.dims[p] != default[p] for p in ("torso", "head", "r_upper_arm"))


def test_same_seed_same_bytes_other_seed_other_frames(sequence, tmp_path):
    again = generate_sequence("arms-crossing", tmp_path / "again", frames=N, seed=5, progress=False)
    assert _files(again) == _files(sequence)
    other = generate_sequence("arms-crossing", tmp_path / "other", frames=N, seed=6, progress=False)
    assert (other / "frames" / "000000.png").read_bytes() != (sequence / "frames" / "000000.png").read_bytes()
    # a longer sequence starts with the same frames
    longer = generate_sequence("arms-crossing", tmp_path / "longer", frames=N + 3, seed=5, progress=False)
    for i in range(N):
        name = f"frames/{i:06d}.png"
        assert (longer / name).read_bytes() == (sequence / name).read_bytes()


def test_foreground_matches_the_tracker_model_but_not_exactly():
    """The actor's silhouette against the tracker's model in the true pose and calibration: close
    (it is the same body) but never identical (another mesh, shape and tessellation)."""
    for name in ("gestures-1", "not-facing", "turning"):
        setup = setup_sequence(name, seed=2)
        poses, _ = sequence_poses(setup, frames=100)
        model = BodyModel.build(setup.actor.dims, part_class=setup.actor.appearance.part_class())
        for i in (0, 40, 70, 99):
            _, coverage = setup.radiance(poses[i])
            parts = render(poses[i], model, setup.camera).parts
            upper = (parts > 0) & (parts != MESH_PART_NAMES.index("lower_body") + 1)   # the coverage's parts
            iou = _iou(coverage >= 0.5, upper)
            assert 0.8 < iou < 0.98, (name, i, iou)


def test_written_frames_foreground_matches_the_tracker_model(sequence):
    """The same from the files alone: frame minus background.png, above the chest base (below it
    the actor's hips, which the model lacks, are foreground too)."""
    cal = Calibration.from_json(sequence / "calibration.json")
    gt = PoseTable.read(sequence / "ground_truth.csv")
    model = cal.body_model()
    background = iio.imread(sequence / "background.png").astype(float)
    for i in range(0, N, 3):
        frame = iio.imread(sequence / "frames" / f"{i:06d}.png").astype(float)
        fg = ndimage.binary_opening(np.abs(frame - background).max(axis=2) > 30)
        ref = render(gt.poses[i], model, cal.camera).labels > 0
        top = int(cal.camera.project(gt.poses[i, :3])[1]) - 2
        assert 0.8 < _iou(fg[:top], ref[:top]) < 0.98


def test_frames_are_shaded_textured_and_noisy(sequence):
    setup = setup_sequence("arms-crossing", seed=5)
    gt = PoseTable.read(sequence / "ground_truth.csv")
    model = BodyModel.build(setup.actor.dims)
    frame = iio.imread(sequence / "frames" / "000000.png").astype(float)
    torso = render(gt.poses[0], model, setup.camera).parts == PART_NAMES.index("torso") + 1
    inner = ndimage.binary_erosion(torso, iterations=2)
    assert inner.sum() > 50
    assert frame[inner].std(axis=0).mean() > 3.0                            # not a flat class colour
    background = iio.imread(sequence / "background.png").astype(float)
    assert background.std(axis=(0, 1)).mean() > 5.0                        # a textured scene
    # the empty scene has noise of its own: it differs from the frame where the actor is not
    away = ~ndimage.binary_dilation(render(gt.poses[0], model, setup.camera).labels > 0, iterations=6)
    away[int(setup.camera.project(gt.poses[0, :3])[1]) - 4:] = False        # hips
    diff = frame[away] - background[away]
    assert 0.5 < diff.std() < 8.0 and abs(diff.mean()) < 8.0


def test_appearance_varies_per_sequence_and_seed():
    looks = {(n, s): setup_sequence(n, seed=s).actor.appearance for n in SEQUENCE_NAMES[:3] for s in (0, 1)}
    assert len({a.skin for a in looks.values()}) > 2
    assert len({a.clothes for a in looks.values()}) == len(looks)
    assert looks[("gestures-3", 0)].bare_forearms and looks[("gestures-3", 0)].part_class()["r_forearm"] == "skin"


def test_actor_mesh_is_finer_than_the_tracker_mesh():
    setup = setup_sequence("gestures-1", seed=0)
    assert len(setup.actor.mesh.triangles) > 3 * BodyModel.build(resolution=24).mesh.n_triangles
    assert len(ACTOR_PART_NAMES) == 10                                      # with the lower body


def test_surface_kernel_matches_its_naive_twin():
    setup = setup_sequence("gestures-2", seed=1)
    poses, _ = sequence_poses(setup, frames=20)
    _, verts, normals = setup.actor.posed(poses[10])
    mesh = setup.actor.mesh
    from mocap.render import rasterize_mesh
    cam = setup.render_camera
    tri_ids = rasterize_mesh(verts, mesh.triangles, cam, triangle_ids=True).triangle_ids
    rows, cols = np.nonzero(tri_ids >= 0)
    pick = np.random.default_rng(0).choice(rows.size, 300, replace=False)
    rows, cols = rows[pick].astype(np.int64), cols[pick].astype(np.int64)
    tri = tri_ids[rows, cols]
    out = [np.empty((300, 3)), np.empty((300, 3)), np.empty((300, 3)), np.empty(300)]
    _surface_samples(rows, cols, tri, mesh.triangles, verts, normals, mesh.vertices, setup.actor.vertex_noise,
                     cam.as_array(), *out)
    ref = naive_surface_samples(rows, cols, tri, mesh.triangles, verts, normals, mesh.vertices,
                                setup.actor.vertex_noise, cam.as_array())
    for got, want in zip(out, ref):
        np.testing.assert_allclose(got, want, atol=1e-9)
    # the surface points lie on the pixel rays (within the rasterizer's 1/16-pixel vertex snapping)
    uv = cam.project(out[2])
    np.testing.assert_allclose(uv, np.stack([cols + 0.5, rows + 0.5], axis=1), atol=0.25)


# --- errors ------------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, message", [
    ({"name": "gestures-9"}, "unknown sequence 'gestures-9'; choose one of: gestures-1"),
    ({"frames": 0}, "frames must be an integer"),
    ({"frames": 2.5}, "frames must be an integer"),
    ({"seed": -1}, "seed must be a non-negative integer"),
    ({"size": (8, 8)}, "width and height"),
    ({"size": (160,)}, "size must be"),
    ({"frame_format": "gif"}, "frame format"),
])
def test_bad_arguments_are_clear_value_errors(tmp_path, kwargs, message):
    args = {"name": "gestures-1", "frames": 2, **kwargs}
    name = args.pop("name")
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        generate_sequence(name, tmp_path / "x", progress=False, **args)


def test_missing_motion_file_and_foreign_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such motion file"):
        generate_sequence("gestures-1", tmp_path / "x", frames=2, motion=tmp_path / "none.bvh", progress=False)
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "thesis.tex").write_text("precious")
    with pytest.raises(ValueError, match="holds no synthetic sequence"):
        generate_sequence("gestures-1", tmp_path / "mine", frames=2, progress=False)
    assert (tmp_path / "mine" / "thesis.tex").read_text() == "precious"


@pytest.mark.parametrize("argv, message", [
    (["synth", "walking"], "error: unknown sequence 'walking'; choose one of: gestures-1, gestures-2"),
    (["synth", "gestures-1", "--size", "160by120"], "error: --size must look like 160x120"),
    (["synth", "gestures-1", "--frames", "-3"], "error: frames must be an integer in [1, "),
    (["synth", "gestures-1", "--motion", "nowhere.bvh"], "error: no such motion file: nowhere.bvh"),
])
def test_cli_errors_are_one_line(tmp_path, capsys, argv, message):
    assert cli.main(argv + ["--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(message) and err.count("\n") == 1


def test_cli_writes_a_sequence(tmp_path, capsys):
    assert cli.main(["synth", "turning", "--frames", "3", "--seed", "2", "--size", "96x72", "--format", "jpg",
                     "--out", str(tmp_path / "t")]) == 0
    assert "wrote 3 frames of turning (96x72, seed 2)" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "t" / "frames").iterdir()) == ["000000.jpg", "000001.jpg", "000002.jpg"]
    assert iio.imread(tmp_path / "t" / "frames" / "000000.jpg").shape == (72, 96, 3)
    assert Calibration.from_json(tmp_path / "t" / "calibration.json").camera.width == 96


def test_motion_clip_drives_the_actor(shared_data, tmp_path):
    clip = shared_data / "mocap" / "cmu_131_01_start_walk_stop_max.bvh"
    out = generate_sequence("gestures-1", tmp_path / "clip", frames=6, motion=clip, progress=False)
    meta = json.loads((out / "meta.json").read_text())
    assert meta["motion"]["file"] == clip.name and meta["motion"]["convention"] == "3dsmax"
    assert len(meta["motion"]["sha256"]) == 64 and meta["motion"]["clip_frames"] == 994
    gt = PoseTable.read(out / "ground_truth.csv")
    assert len(gt) == 6 and (gt.poses >= JOINT_LIMITS[:, 0] - 1e-9).all()
    assert not any(p.suffix in (".bvh", ".amc", ".asf") for p in out.rglob("*"))
    with pytest.raises(ValueError, match="lasts 207 frames"):
        generate_sequence("gestures-1", tmp_path / "long", frames=500, motion=clip, progress=False)


# --- the bundled default sequence ---------------------------------------------------------------

def test_bundled_default_is_small_and_up_to_date(tmp_path):
    folder = bundled_default_sequence()
    size = sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())
    assert size < 500_000
    fresh = make_default_sequence(tmp_path / "default", progress=False)
    for name in ("ground_truth.csv", "calibration.json", "meta.json"):
        assert (fresh / name).read_bytes() == (folder / name).read_bytes(), \
            f"data/default/{name} is stale: run 'python -m mocap.synth.datasets --default'"
    frames = sorted((folder / "frames").iterdir())
    assert len(frames) == DEFAULT_SEQUENCE["frames"]
    for path in frames[::20] + [folder / "background.png"]:
        rel = path.relative_to(folder)
        a, b = iio.imread(path).astype(float), iio.imread(fresh / rel).astype(float)
        assert np.abs(a - b).mean() < 0.5, f"data/default/{rel} is stale"
