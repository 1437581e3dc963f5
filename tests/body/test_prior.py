"""The pose prior: its density against scikit-learn's, the compiled energy, the shipped file."""
import json

import numpy as np
import pytest

from mocap.body import PARAMETER_INDEX as P, neutral_pose
from mocap.body.prior import PRIOR_INDEX, PRIOR_PARAMETERS, PosePrior, default_prior

sklearn_mixture = pytest.importorskip("sklearn.mixture", reason="scikit-learn is in the test extra")


def fitted_mixture(seed=0, k=3):
    rng = np.random.default_rng(seed)
    d = len(PRIOR_PARAMETERS)
    data = np.concatenate([rng.normal(rng.uniform(-1, 1, d), rng.uniform(0.1, 0.5, d), size=(200, d))
                           for _ in range(k)])
    return sklearn_mixture.GaussianMixture(k, covariance_type="full", random_state=seed).fit(data)


def poses_with(angles):
    q = np.tile(neutral_pose(), (len(angles), 1))
    q[:, PRIOR_INDEX] = angles
    return q


@pytest.mark.parametrize("seed", [0, 1])
def test_log_density_equals_scikit_learn(seed):
    gmm = fitted_mixture(seed)
    prior = PosePrior(gmm.weights_, gmm.means_, gmm.precisions_cholesky_)
    rng = np.random.default_rng(10 + seed)
    x = rng.normal(0.0, 0.8, size=(50, len(PRIOR_PARAMETERS)))
    q = poses_with(x)
    np.testing.assert_allclose(prior.log_density(q), gmm.score_samples(x), rtol=1e-10, atol=1e-9)
    # the compiled energy of one pose is the same number, negated
    np.testing.assert_allclose([prior.energy(p) for p in q], -gmm.score_samples(x), rtol=1e-10, atol=1e-9)


def test_prior_ignores_position_and_heading():
    prior = default_prior()
    q = neutral_pose()
    moved = q.copy()
    moved[[P["root_x"], P["root_z"], P["chest_yaw"]]] += (0.4, 1.0, 2.5)
    assert prior.energy(moved) == prior.energy(q)
    assert "chest_yaw" not in PRIOR_PARAMETERS and len(PRIOR_PARAMETERS) == 19


def test_shipped_prior_loads_with_its_checksum_and_attribution():
    prior = default_prior()
    assert prior.n_components >= 1
    assert "mocap.cs.cmu.edu" in prior.attribution
    # a typical posture (arms hanging) is far more likely than an arm twisted to its limits
    odd = neutral_pose()
    odd[[P["r_shoulder_flex"], P["r_shoulder_rot"], P["r_elbow_flex"]]] = (-1.0, 1.5, 2.6)
    assert prior.energy(odd) > prior.energy(neutral_pose()) + 5.0


def test_damaged_or_foreign_prior_files_are_refused(tmp_path):
    gmm = fitted_mixture()
    data = PosePrior(gmm.weights_, gmm.means_, gmm.precisions_cholesky_, "test").to_dict()
    assert PosePrior.from_dict(json.loads(json.dumps(data))).checksum == data["sha256"]
    tampered = json.loads(json.dumps(data))
    tampered["means"][0][0] += 1e-6
    with pytest.raises(ValueError, match="checksum"):
        PosePrior.from_dict(tampered)
    foreign = dict(data, parameters=list(PRIOR_PARAMETERS[::-1]))
    with pytest.raises(ValueError, match="parameters"):
        PosePrior.from_dict(foreign)
    with pytest.raises(ValueError, match="weights"):
        PosePrior(np.array([0.5, 0.4, 0.1 + 1e-3]), gmm.means_, gmm.precisions_cholesky_)


@pytest.mark.slow
@pytest.mark.shared_data
def test_fit_script_reproduces_the_shipped_prior(shared_data, tmp_path):
    """Refit at the shipped size on the trials the shipped prior's record lists (the 41 trials of six
    subjects the training folder held when it was fitted): the same mixture comes out, and the
    refit's record lists the same trials and poses."""
    from importlib import resources

    from experiments.fit_pose_prior import main

    shipped = default_prior()
    record = resources.files("mocap.body").joinpath("pose_prior.json")
    training = json.loads(record.read_text())["training"]
    assert len(training["trials"]) == 41 and sorted({t.split("_")[1] for t in training["trials"]}) == training["subjects"]
    out = tmp_path / "prior.json"
    assert main(["--train", str(shared_data / "mocap" / "train"), "--out", str(out),
                 "--components", str(shipped.n_components), "--trials-from", str(record)]) == 0
    refit_training = json.loads(out.read_text())["training"]
    assert refit_training["trials"] == training["trials"] and refit_training["poses"] == training["poses"]
    refit = PosePrior.from_json(out)
    np.testing.assert_allclose(refit.weights, shipped.weights, atol=1e-6)
    np.testing.assert_allclose(refit.means, shipped.means, atol=1e-6)
    np.testing.assert_allclose(refit.precisions_cholesky, shipped.precisions_cholesky, rtol=1e-5, atol=1e-4)
    assert json.loads(out.read_text())["sha256"] == refit.checksum


@pytest.mark.shared_data
def test_fit_script_refuses_a_record_without_trials_or_with_absent_ones(shared_data, tmp_path, capsys):
    from experiments.fit_pose_prior import main

    train = str(shared_data / "mocap" / "train")
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps({"training": {"subjects": ["02"]}}))
    absent = tmp_path / "absent.json"
    absent.write_text(json.dumps({"training": {"trials": ["cmu_99_01.amc"]}}))
    for record, message in ((bare, "lists no training trials"), (absent, "trials not in")):
        assert main(["--train", train, "--out", str(tmp_path / "p.json"), "--trials-from", str(record)]) == 2
        assert message in capsys.readouterr().err
    assert not (tmp_path / "p.json").exists()
