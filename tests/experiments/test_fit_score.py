"""The score's weight fit (experiments.fit_score): reproducible, and right where the answer is known."""
import numpy as np
import pytest

from experiments.fit_score import (TERMS, Candidates, choose, default_weights, fit_weights, in_tracker_units,
                                   informative, tracker_config)
from experiments.fit_score.fit import _frames_held_out
from mocap.track import TrackerConfig
from mocap.track.score import REGION_WEIGHT

#: Weights that make the synthetic candidates' best by construction (one per term).
TRUE_WEIGHTS = np.array([50.0, 2.0, 1.5, 0.05, 0.8, 0.6, 0.9, 1.2])


def synthetic(frames=300, per_frame=6, seed=0, noise=0.0):
    """Frames whose candidates' error about the neck rises with their score under ``TRUE_WEIGHTS``
    (so the best candidate of every frame is the lowest-scored one), each term on its own scale."""
    rng = np.random.default_rng(seed)
    scales = np.array([0.05, 1.0, 2.0, 20.0, 3.0, 3.0, 2.0, 2.0])
    x = rng.normal(size=(frames * per_frame, len(TERMS))) * scales + 3 * scales
    score = x @ TRUE_WEIGHTS + noise * rng.normal(size=len(x))
    frame = np.repeat(np.arange(frames), per_frame)
    best = np.minimum.reduceat(score, np.arange(0, len(x), per_frame))
    error = 20.0 + 8.0 * (score - np.repeat(best, per_frame))
    return Candidates(frame=frame, features=x, error_mm=error, camera_error_mm=error + 5.0,
                      origin=np.array(["tracked"] * len(x)))


def naive_choose(c: Candidates, w, threshold=100.0):
    chosen, best = [], []
    for f in np.unique(c.frame):
        rows = np.flatnonzero(c.frame == f)
        s = [sum(w[j] * (0.0 if np.isnan(c.features[r, j]) else c.features[r, j]) for j in range(len(w))) for r in rows]
        chosen.append(c.error_mm[rows[int(np.argmin(s))]])
        best.append(c.error_mm[rows].min())
    chosen, best = np.array(chosen), np.array(best)
    return chosen.mean(), np.mean(chosen > threshold), np.mean((chosen > threshold) & (best <= threshold))


def test_the_fit_recovers_weights_that_pick_the_best_candidate_known_by_construction():
    data = synthetic()
    w = fit_weights(data)
    assert np.all(w >= 0)
    picked = choose(data, w)
    assert picked.mean_error_mm == pytest.approx(20.0, abs=0.2)      # the best (error 20) on (nearly) every frame
    truth = choose(data, TRUE_WEIGHTS)
    assert truth.mean_error_mm == pytest.approx(20.0)
    # the direction of the true weights, term by term (relative to F's)
    np.testing.assert_allclose(in_tracker_units(w), TRUE_WEIGHTS, rtol=0.15)
    # and the default weights, which weigh the terms otherwise, do worse on these frames
    assert choose(data, default_weights()).mean_error_mm > picked.mean_error_mm + 1.0


def test_the_fit_is_reproducible_for_a_seed():
    data = synthetic(noise=5.0, seed=3)
    held = _frames_held_out(data, 0.3, seed=7)
    np.testing.assert_array_equal(held, _frames_held_out(data, 0.3, seed=7))
    assert not np.array_equal(held, _frames_held_out(data, 0.3, seed=8))
    a = fit_weights(informative(data.subset(~held)))
    b = fit_weights(informative(data.subset(~_frames_held_out(data, 0.3, seed=7))))
    np.testing.assert_array_equal(a, b)


def test_choose_equals_a_loop_and_reads_missing_terms_as_zero():
    data = synthetic(frames=40, per_frame=5, seed=1, noise=30.0)
    features = data.features.copy()
    features[::7, 2] = np.nan                      # a term that does not apply adds nothing
    data = Candidates(frame=data.frame, features=features, error_mm=data.error_mm + 60.0,
                      camera_error_mm=data.camera_error_mm, origin=data.origin)
    for w in (TRUE_WEIGHTS, default_weights(), np.array([1.0, 0, 0, 0, 0, 0, 0, 0])):
        c = choose(data, w)
        mean, failing, missed = naive_choose(data, w)
        assert c.mean_error_mm == pytest.approx(mean)
        assert c.failure_rate == pytest.approx(failing) and c.miss_rate == pytest.approx(missed)


def test_weights_in_tracker_units_make_a_config():
    w = np.array([25.0, 1.0, 1.0, 0.1, 0.25, 0.5, 0.5, 0.5])
    config = tracker_config(w)
    assert config == TrackerConfig(edge_weight=2.0, keypoint_weight=2.0, prior_weight=0.2, lifter_weight=0.5,
                                   labelling_weight=1.0, detector_3d_weight=1.0, motion_weight=1.0)
    np.testing.assert_allclose(default_weights(), [REGION_WEIGHT, 2.0, 2.0, 0.05, 0.5, 1.0, 1.0, 1.0])
    base = TrackerConfig(beam=5)                       # the other settings of a base config are kept
    assert tracker_config(w, base=base) == TrackerConfig(beam=5, edge_weight=2.0, keypoint_weight=2.0,
                                                         prior_weight=0.2, lifter_weight=0.5, labelling_weight=1.0,
                                                         detector_3d_weight=1.0, motion_weight=1.0)
    with pytest.raises(ValueError):
        in_tracker_units(np.zeros(8))


def test_decompose_splits_the_failing_frames_into_their_four_causes():
    from experiments.fit_score import decompose, score_miss_frames

    # five frames of two candidates each; the score is the first term (F) alone
    features = np.zeros((10, len(TERMS)))
    features[:, 0] = [0, 1, 0, 1, 0, 1, 0, 1, 0, 1]      # the first candidate of each frame is chosen
    error = np.array([50, 150, 150, 150, 150, 50, 50, 150, 150, 150], dtype=float)
    c = Candidates(frame=np.repeat(np.arange(5), 2), features=features, error_mm=error, camera_error_mm=error,
                   origin=np.array(["tracked", "lifter"] * 5))
    lifter = np.array([40.0, 40.0, 40.0, 40.0, 300.0])
    tracked = np.array([50.0, 150.0, 150.0, 150.0, 150.0])
    r = decompose(c, lifter, tracked, np.r_[1.0, np.zeros(len(TERMS) - 1)])
    # frame 0 within; 1: no candidate within (not refined); 2: a candidate within, not chosen;
    # 3: the chosen within, not decided; 4: no lifter hypothesis within
    assert (r.failing, r.not_refined, r.score_misses, r.decoder_misses, r.lifter_misses) == (0.8, 0.2, 0.2, 0.2, 0.2)
    np.testing.assert_array_equal(score_miss_frames(c, lifter, tracked, np.r_[1.0, np.zeros(len(TERMS) - 1)]), [2])
    with pytest.raises(ValueError):
        decompose(c, lifter[:4], tracked, np.ones(len(TERMS)))


def test_offline_decoding_equals_the_best_of_every_path():
    import itertools

    from experiments.fit_score import decode_offline
    from mocap.track.score import MOTION_SIGMA_M

    rng = np.random.default_rng(4)
    sizes = [2, 3, 2, 3]
    frame = np.repeat(np.arange(len(sizes)), sizes)
    n = len(frame)
    features = rng.uniform(0, 1, size=(n, len(TERMS)))
    joints = rng.normal(0, 0.05, size=(n, 10, 3))
    c = Candidates(frame=frame, features=features, error_mm=np.zeros(n), camera_error_mm=np.zeros(n),
                   origin=np.array(["tracked"] * n))
    w = np.array([50.0, 2.0, 2.0, 0.05, 0.5, 1.0, 1.0, 1.5])
    rows = np.split(np.arange(n), np.cumsum(sizes)[:-1])

    def cost(path):
        total = sum(features[r, :-1] @ w[:-1] for r in path)
        for a, b in zip(path[:-1], path[1:]):
            total += w[-1] * min(0.5 * np.mean(np.sum((joints[a] - joints[b]) ** 2, axis=1)) / MOTION_SIGMA_M ** 2, 3.0)
        return total

    best = min(itertools.product(*rows), key=cost)
    np.testing.assert_array_equal(decode_offline(c, joints, w, motion_cap=3.0), best)


def test_depth_over_frames_keeps_the_projection_and_the_pose_about_the_neck():
    from experiments.fit_score import smooth_depth

    rng = np.random.default_rng(2)
    joints = rng.normal(0.0, 0.2, size=(15, 10, 3))
    joints[..., 2] += 3.0
    np.testing.assert_array_equal(smooth_depth(joints, 1), joints)
    out = smooth_depth(joints, 5)
    np.testing.assert_allclose(out[:, 1, :2] / out[:, 1, 2:], joints[:, 1, :2] / joints[:, 1, 2:])   # the neck's pixel
    np.testing.assert_allclose(out - out[:, 1:2], joints - joints[:, 1:2], atol=1e-12)                # the pose about it
    np.testing.assert_allclose(out[7, 1, 2], np.median(joints[5:10, 1, 2]))                         # the window's median
    np.testing.assert_allclose(out[0, 1, 2], np.median(joints[0:3, 1, 2]))                          # shorter at the ends
    with pytest.raises(ValueError):
        smooth_depth(joints, 4)


def test_a_term_that_never_applied_keeps_its_default_weight():
    from experiments.fit_score import keep_unseen

    features = np.ones((4, len(TERMS)))
    features[:, [2, 4, 5, 6]] = np.nan               # no keypoints: no keypoint, lifter, labelling or 3D term
    w = keep_unseen(np.array([25.0, 1.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.5]), features)
    np.testing.assert_allclose(in_tracker_units(w), [50.0, 2.0, 2.0, 0.2, 0.5, 1.0, 1.0, 1.0])


def write_record(path, frames=12, per_frame=3, seed=0):
    """A record in :func:`experiments.fit_score.record_sequence`'s format, made up: candidates near
    a truth walking in front of the camera, the first of each frame the decided one."""
    import io

    from mocap.io.files import write_bytes_atomic

    rng = np.random.default_rng(seed)
    truth = rng.normal(0.0, 0.2, size=(frames, 10, 3)) + [0.0, 0.0, 3.0]
    joints = np.repeat(truth, per_frame, axis=0) + rng.normal(0.0, 0.05, size=(frames * per_frame, 10, 3))
    error = 1e3 * np.linalg.norm((joints - joints[:, 1:2]) - np.repeat(truth - truth[:, 1:2], per_frame, axis=0),
                                 axis=2).mean(axis=1)
    features = rng.uniform(0.0, 1.0, size=(frames * per_frame, len(TERMS)))
    features[:, 0] = error / 1e3                      # F rises with the error: the fit gives it a weight
    tracked = joints[::per_frame]
    buffer = io.BytesIO()
    np.savez_compressed(buffer, frame=np.repeat(np.arange(frames), per_frame), features=features, error_mm=error,
                        camera_error_mm=error + 10.0, origin=np.array(["tracked", "jump", "lifter"] * frames),
                        lifter_best_mm=np.full(frames, 50.0), joints=joints, truth=truth,
                        lifted_joints=rng.normal(0.0, 0.2, size=(frames, 10, 10, 3)),
                        lifted_probabilities=np.full((frames, 10), 0.1), tracked_joints=tracked,
                        tracked_poses=np.zeros((frames, 23)), tracked_error_mm=error[::per_frame],
                        tracked_camera_error_mm=error[::per_frame] + 10.0, config=np.array("{}"),
                        sigma_px=np.array(2.0))
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bytes_atomic(path, buffer.getvalue())


def test_every_subcommand_reads_the_records_it_names(tmp_path, capsys):
    """``python -m experiments.fit_score`` fit / decompose / decode / depth on two made-up records:
    each runs, ``fit --write`` writes the weights fitted on every frame, a missing record is an error."""
    from experiments.fit_score import load_records, record_path
    from experiments.fit_score.cli import main

    for i, sequence in enumerate(("gestures-2", "turning")):
        write_record(record_path(tmp_path, sequence, 5), seed=i)
    common = ["--seeds", "5", "--sequences", "gestures-2,turning", "--out", str(tmp_path)]
    written = tmp_path / "fitted.json"
    assert main(["fit", *common, "--write", str(written)]) == 0
    every = load_records([record_path(tmp_path, q, 5) for q in ("gestures-2", "turning")])
    assert TrackerConfig.from_json(written) == tracker_config(fit_weights(informative(every)))
    for command in ("decompose", "decode", "depth"):
        capsys.readouterr()
        assert main([command, *common]) == 0
        assert "|---" in capsys.readouterr().out
    assert main(["decode", "--seeds", "6", "--sequences", "turning", "--out", str(tmp_path)]) == 2
    assert "no record" in capsys.readouterr().err
