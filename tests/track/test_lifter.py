"""The 2D->3D lifter (mocap.track.lifter) and its training (experiments.fit_lifter).

References: the PyTorch model the weights came from (the NumPy forward pass must give its
outputs), the compiled forward kinematics (the training's PyTorch twin must give its joints),
scipy's multivariate normal (the density), the ground truth of projected poses (the
hypotheses must contain it), and the training's own record (the shipped file's checksum).
"""
from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from mocap.body.model import BodyModel
from mocap.body.pose import JOINT_LIMITS, PARAMETER_INDEX, neutral_pose, within_limits
from mocap.body.skeleton import JOINT_INDEX, JOINT_NAMES
from mocap.render.camera import Camera
from mocap.synth.actor import random_dimensions
from mocap.track.lifter import (DENSITY_SIGMA_M, MIN_VISIBLE, N_FEATURES, Lifter, fit_roots, lifter_features,
                                relative_joints)

torch = pytest.importorskip("torch", reason="the lifter's training tests need the extra 'fit' (torch==2.13.0)")
fit = pytest.importorskip("experiments.fit_lifter")

#: NumPy (float32 matrix products) against PyTorch (its own float32 kernels): absolute tolerance
#: on outputs of order 1.
FORWARD_ATOL = 1e-4
#: Best-of-K distance (mm, joints about the neck) the shipped lifter must reach on the projected
#: joints of training poses (oracle 2D + 1 px), for the median frame and for 90 % of frames; with
#: three joints missing (the neck, one wrist, one hand).
#: (The shipped weights reach 34 / 44 mm and, with joints missing, 39 / 46 mm.)
COVER_MEDIAN_MM, COVER_P90_MM = 50.0, 70.0
MISSING_MEDIAN_MM, MISSING_P90_MM = 60.0, 85.0


def _random_poses(rng, n):
    lo = np.maximum(JOINT_LIMITS[:, 0], -np.pi)
    hi = np.minimum(JOINT_LIMITS[:, 1], np.pi)
    q = rng.uniform(lo, hi, (n, len(lo)))
    q[:, :3] = (0.1, 0.3, 2.0)
    return q


def test_torch_kinematics_equal_the_compiled_ones():
    rng = np.random.default_rng(1)
    models = [BodyModel.build(random_dimensions(rng)) for _ in range(3)]
    q = _random_poses(rng, 12)
    truth = np.stack([models[i % 3].joint_positions(p) for i, p in enumerate(q)])
    sk = [models[i % 3].skeleton for i in range(12)]
    got = fit.torch_joints(torch.tensor(q), torch.tensor(np.stack([s.offsets for s in sk])), sk[0].joint_segment,
                           torch.tensor(np.stack([s.joint_local for s in sk])))
    np.testing.assert_allclose(got.numpy(), truth, atol=1e-12)


def test_torch_features_equal_the_numpy_ones():
    rng = np.random.default_rng(2)
    camera = Camera.default(160, 120)
    model = BodyModel.build()
    for q in _random_poses(rng, 5):
        uv = camera.project(model.joint_positions(q))
        visible = rng.random(len(JOINT_NAMES)) < 0.7
        visible[:MIN_VISIBLE] = True
        xy = np.column_stack([(uv[:, 0] - camera.cx) / camera.fx, (uv[:, 1] - camera.cy) / camera.fy])
        got = fit.torch_features(torch.tensor(xy[None]), torch.tensor(visible[None]))[0].numpy()
        np.testing.assert_allclose(got, lifter_features(uv, visible, camera), atol=1e-6)


@pytest.fixture(scope="module")
def random_net():
    torch.manual_seed(0)
    return fit.make_net(fit.QUICK_HIDDEN).eval()


def test_numpy_forward_equals_the_torch_model_on_random_inputs(random_net):
    x = np.random.default_rng(3).normal(0.0, 1.0, (64, N_FEATURES)).astype(np.float32)
    lifter = Lifter(fit.export_weights(random_net))
    with torch.no_grad():
        expect = random_net(torch.from_numpy(x)).numpy()
    np.testing.assert_allclose(lifter.forward(x), expect, atol=FORWARD_ATOL)


def test_numpy_decode_equals_the_torch_decode():
    """:meth:`Lifter.decode` (NumPy, float64) against the training's :func:`decode_poses` (PyTorch):
    the same angles inside the limits, and the softmax of the same confidence logits."""
    lifter = Lifter(fit.export_weights(fit.make_net(fit.QUICK_HIDDEN)))
    out = np.random.default_rng(4).normal(0.0, 3.0, (5, lifter.n_hypotheses * 22))
    logits, poses = fit.decode_poses(torch.tensor(out), lifter.n_hypotheses)
    for i in range(len(out)):
        q, p = lifter.decode(out[i])
        np.testing.assert_allclose(q, poses[i].numpy(), atol=1e-12)
        np.testing.assert_allclose(p, torch.softmax(logits[i], dim=0).numpy(), atol=1e-12)


def test_the_shipped_lifters_numpy_forward_equals_its_torch_twin():
    """The shipped weights in the network its record names (``hidden``): NumPy and PyTorch give
    the same outputs on the features of random poses' projections, some joints missing."""
    lifter = Lifter.load()
    net = fit.make_net(tuple(lifter.provenance["hidden"]), lifter.n_hypotheses).eval()
    fit.load_weights(net, lifter.weights)
    rng = np.random.default_rng(5)
    camera, model = Camera.default(160, 120), BodyModel.build()
    rows = []
    for q in _random_poses(rng, 8):
        visible = rng.random(len(JOINT_NAMES)) < 0.8
        visible[:MIN_VISIBLE] = True
        rows.append(lifter_features(camera.project(model.joint_positions(q)), visible, camera))
    x = np.array(rows, dtype=np.float32)
    with torch.no_grad():
        expect = net(torch.from_numpy(x)).numpy()
    got = lifter.forward(x)
    np.testing.assert_allclose(got, expect, atol=FORWARD_ATOL * max(1.0, float(np.abs(expect).max())))


def test_the_stored_weights_are_the_models(random_net, tmp_path):
    """Saved (float16) and loaded, the NumPy pass equals a PyTorch model given the same weights."""
    path = tmp_path / "l.npz"
    Lifter(fit.export_weights(random_net)).save(path)
    lifter = Lifter.load(path)
    net = fit.make_net(fit.QUICK_HIDDEN).eval()
    fit.load_weights(net, lifter.weights)
    camera, model = Camera.default(160, 120), BodyModel.build()
    x = lifter_features(camera.project(model.joint_positions(neutral_pose())), np.ones(10, bool), camera)
    with torch.no_grad():
        expect = net(torch.from_numpy(x[None])).numpy()[0]
    np.testing.assert_allclose(lifter.forward(x), expect, atol=FORWARD_ATOL)


def test_log_density_is_the_mixture_of_gaussians():
    from scipy.stats import multivariate_normal

    lifter = Lifter.load()
    camera, model = Camera.default(160, 120), BodyModel.build()
    lifted = lifter.lift(camera.project(model.joint_positions(neutral_pose())), np.ones(10, bool), camera, model)
    x = lifted.joints[0] + np.random.default_rng(4).normal(0.0, 0.03, (10, 3))
    x[JOINT_INDEX["neck"]] = 0.0
    keep = [i for i in range(10) if i != JOINT_INDEX["neck"]]
    expect = np.log(sum(p * multivariate_normal(mu[keep].ravel(), DENSITY_SIGMA_M ** 2).pdf(x[keep].ravel())
                        for p, mu in zip(lifted.probabilities, lifted.joints)))
    assert lifter.log_density(lifted, x) == pytest.approx(expect, rel=1e-9)
    assert lifter.log_density(lifted, lifted.joints[0]) > lifter.log_density(lifted, lifted.joints[0] + 0.2)
    # the density at the top hypothesis, kept with the hypotheses: the same float as computed afresh
    top = np.log(sum(p * multivariate_normal(mu[keep].ravel(), DENSITY_SIGMA_M ** 2).pdf(lifted.joints[0][keep].ravel())
                     for p, mu in zip(lifted.probabilities, lifted.joints)))
    assert lifted.top_log_density == lifter.log_density(lifted, lifted.joints[0])
    assert lifted.top_log_density == pytest.approx(top, rel=1e-9)


def test_lift_gives_poses_inside_the_limits_on_the_body():
    lifter = Lifter.load()
    camera = Camera.default(160, 120)
    rng = np.random.default_rng(5)
    model = BodyModel.build(random_dimensions(rng))
    for q in _random_poses(rng, 4):
        lifted = lifter.lift(camera.project(model.joint_positions(q)), np.ones(10, bool), camera, model)
        assert len(lifted) == lifter.n_hypotheses == 10
        assert all(within_limits(p) for p in lifted.poses)
        assert lifted.probabilities.sum() == pytest.approx(1.0)
        assert (np.diff(lifted.probabilities) <= 0).all()
        np.testing.assert_allclose(lifted.joints, relative_joints([model.joint_positions(p) for p in lifted.poses]),
                                   atol=1e-12)


def test_fit_roots_recovers_the_root_and_minimises_the_pixel_error():
    """Exact keypoints: the true root (analytic); noisy ones: the minimum scipy's least squares finds."""
    from scipy.optimize import least_squares

    rng = np.random.default_rng(7)
    camera, model = Camera.default(160, 120), BodyModel.build()
    q = _random_poses(rng, 3)
    roots = np.array([(0.1, 0.5, 1.6), (-0.3, 0.4, 2.4), (0.2, 0.7, 3.5)])
    q[:, :3] = 0.0
    at_zero = np.stack([model.joint_positions(p) for p in q])
    for joints, root in zip(at_zero, roots):
        uv = camera.project(joints + root)
        np.testing.assert_allclose(fit_roots(joints[None], uv, camera)[0], root, atol=1e-9)
        noisy = uv + rng.normal(0.0, 2.0, uv.shape)
        expect = least_squares(lambda t: (camera.project(joints + t) - noisy).ravel(), root).x
        np.testing.assert_allclose(fit_roots(joints[None], noisy, camera)[0], expect, atol=1e-6)


def test_bad_keypoints_are_refused_clearly():
    lifter, camera, model = Lifter.load(), Camera.default(160, 120), BodyModel.build()
    uv = camera.project(model.joint_positions(neutral_pose()))
    few = np.zeros(10, bool)
    few[:MIN_VISIBLE - 1] = True
    with pytest.raises(ValueError, match=f"at least {MIN_VISIBLE} visible"):
        lifter.lift(uv, few, camera, model)
    with pytest.raises(ValueError, match="shape"):
        lifter.lift(uv[:5], np.ones(5, bool), camera, model)
    bad = uv.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match="finite"):
        lifter.lift(bad, np.ones(10, bool), camera, model)
    bad_visible = np.ones(10, bool)
    bad_visible[3] = False                            # a missing joint may be anything
    assert len(lifter.lift(bad, bad_visible, camera, model)) == 10


def test_a_damaged_file_is_refused_with_one_line(tmp_path):
    shipped = Lifter.load()
    path = tmp_path / "lifter.npz"
    shipped.save(path)
    with zipfile.ZipFile(path) as z:
        members = {n: z.read(n) for n in z.namelist()}
    altered = bytearray(members["a0.npy"])
    altered[-1] ^= 0x40
    members["a0.npy"] = bytes(altered)
    with zipfile.ZipFile(path, "w") as z:
        for name, data in members.items():
            z.writestr(name, data)
    with pytest.raises(ValueError, match="damaged") as info:
        Lifter.load(path)
    assert "\n" not in str(info.value) and "fit_lifter" in str(info.value)
    path.write_bytes(path.read_bytes()[:1000])
    with pytest.raises(ValueError, match="not a readable lifter file"):
        Lifter.load(path)
    with pytest.raises(FileNotFoundError):
        Lifter.load(tmp_path / "absent.npz")


def test_the_shipped_file_is_what_training_wrote():
    record = json.loads((fit.RECORD).read_text())
    lifter = Lifter.load()                           # verifies the arrays against the file's checksum
    assert lifter.checksum == record["sha256"]
    assert "mocap.cs.cmu.edu" in lifter.attribution
    assert fit.SHIPPED.stat().st_size <= 10e6


@pytest.fixture(scope="module")
def quick_runs(shared_data, tmp_path_factory):
    out = tmp_path_factory.mktemp("quick")
    for name in ("a", "b"):
        assert fit.main(["--quick", "--train", str(shared_data / "mocap" / "train"), "--out", str(out / f"{name}.npz")]) == 0
    return out / "a.npz", out / "b.npz"


@pytest.mark.shared_data
def test_two_quick_trainings_with_one_seed_are_identical(quick_runs):
    a, b = (Lifter.load(p) for p in quick_runs)
    assert a.checksum == b.checksum
    assert all(np.array_equal(x, y) for x, y in zip(a.weights, b.weights))


@pytest.mark.shared_data
def test_numpy_forward_equals_the_quick_model_on_fixed_keypoints(quick_runs):
    lifter = Lifter.load(quick_runs[0])
    net = fit.make_net(fit.QUICK_HIDDEN).eval()
    fit.load_weights(net, lifter.weights)
    camera, model = Camera.default(160, 120), BodyModel.build()
    q = neutral_pose()
    q[PARAMETER_INDEX["r_shoulder_flex"]] = 1.2
    x = lifter_features(camera.project(model.joint_positions(q)), np.ones(10, bool), camera)
    with torch.no_grad():
        expect = net(torch.from_numpy(x[None])).numpy()[0]
    np.testing.assert_allclose(lifter.forward(x), expect, atol=FORWARD_ATOL)


@pytest.mark.shared_data
def test_training_poses_are_among_the_hypotheses(shared_data):
    """Projected joints of training poses (random heading, oracle 2D + 1 px): a hypothesis near the truth;
    with three joints missing, still near (a larger distance)."""
    from mocap.metrics import root_relative_mpjpe
    from mocap.synth.retarget import load_clip, retarget

    poses = retarget(load_clip(shared_data / "mocap" / "train" / "cmu_14_05.amc"))[::25][:24]
    rng = np.random.default_rng(6)
    lifter, camera = Lifter.load(), Camera.default(160, 120)
    model = BodyModel.build(random_dimensions(rng))
    missing = np.ones(10, bool)
    missing[[JOINT_INDEX["neck"], JOINT_INDEX["r_wrist"], JOINT_INDEX["l_hand"]]] = False
    best = {"all": [], "missing": []}
    for q in poses:
        q = q.copy()
        q[:3] = (0.05, 0.55, 1.9)
        q[PARAMETER_INDEX["chest_yaw"]] = rng.uniform(-np.pi, np.pi)
        truth = model.joint_positions(q)
        uv = camera.project(truth) + rng.normal(0.0, 1.0, (10, 2))
        for key, visible in (("all", np.ones(10, bool)), ("missing", missing)):
            lifted = lifter.lift(uv, visible, camera, model)
            best[key].append(root_relative_mpjpe(lifted.joints, np.repeat(truth[None], 10, 0), per_frame=True).min())
    for key, (median, p90) in (("all", (COVER_MEDIAN_MM, COVER_P90_MM)), ("missing", (MISSING_MEDIAN_MM, MISSING_P90_MM))):
        assert np.median(best[key]) <= median, (key, np.round(best[key]))
        assert np.percentile(best[key], 90) <= p90, (key, np.round(best[key]))
