import numpy as np
from experiments.ambiguity import ARM_JOINTS, flip_oracle, reflect_in_depth, table


def test_reflection_is_an_involution_that_keeps_the_ray_and_the_distance():
    rng = np.random.default_rng(0)
    pivot = np.array([0.2, -0.1, 1.8])
    pts = pivot + rng.normal(0, 0.3, (20, 3))
    back = reflect_in_depth(reflect_in_depth(pts, pivot), pivot)
    np.testing.assert_allclose(back, pts, atol=1e-12)
    mirrored = reflect_in_depth(pts, pivot)
    np.testing.assert_allclose(np.linalg.norm(mirrored - pivot, axis=1), np.linalg.norm(pts - pivot, axis=1))
    # a point on the camera ray through the pivot maps to its mirror on the same ray
    on_ray = np.array([pivot * 1.1])
    np.testing.assert_allclose(reflect_in_depth(on_ray, pivot), [pivot * 0.9], atol=1e-12)


def test_oracle_undoes_a_mirrored_forearm_and_keeps_a_correct_arm():
    rng = np.random.default_rng(1)
    truth = np.array([0.0, 0.0, 1.8]) + rng.normal(0, 0.3, (3, 10, 3))
    tracked = truth.copy()
    s, e, w, h = ARM_JOINTS["r"]
    tracked[1, [w, h]] = reflect_in_depth(truth[1, [w, h]], truth[1, e])
    tracked[2, [e, w, h]] = reflect_in_depth(truth[2, [e, w, h]], truth[2, s])
    out = flip_oracle(tracked, truth)
    np.testing.assert_allclose(out, truth, atol=1e-12)
    # never worse than as tracked, arm by arm; the head and shoulders are never touched
    noisy = truth + rng.normal(0, 0.05, truth.shape)
    picked = flip_oracle(noisy, truth)
    for idx in ARM_JOINTS.values():
        before = np.linalg.norm(noisy[:, idx] - truth[:, idx], axis=2).sum(1)
        after = np.linalg.norm(picked[:, idx] - truth[:, idx], axis=2).sum(1)
        assert (after <= before + 1e-12).all()
    np.testing.assert_array_equal(picked[:, [0, 1, s, ARM_JOINTS["l"][0]]], noisy[:, [0, 1, s, ARM_JOINTS["l"][0]]])


def test_table_has_a_median_row():
    row = dict(sequence="a", mpjpe_mm=100.0, failure_rate=0.5, reprojection_px=2.0, flip_oracle_mpjpe_mm=50.0,
               flip_oracle_failure_rate=0.1)
    text = table([row, {**row, "sequence": "b", "mpjpe_mm": 200.0}])
    assert "| **median** | 150 | 50 % | 2.0 | 50 | 10 % |" in text
