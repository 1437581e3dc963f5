"""``python -m experiments.tracking_diff``: units matched by configuration, sequence and seed, the changed ones listed,
counted per configuration and seed set (made-up units with hand-counted answers)."""
import json

import numpy as np
import pytest

from experiments import tracking_diff


def _unit(folder, name, sequence, seed, mpjpe, heading, about_neck=50.0, evaluations=1000.0, key="k", null=0.0):
    row = {"sequence": sequence, "mpjpe_mm": mpjpe, "median_frame_root_relative_mm": about_neck,
           "frame_heading_error_deg": list(heading), "evaluations_per_frame": evaluations}
    path = folder / "units" / f"{sequence}-s{seed}-{key}{f'-null{null:g}px' if null else ''}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"config": {}, "name": name, "seed": seed, "code": "c", "null_offset_px": null,
                                "result": row}))
    return path


def test_changed_units_are_listed_and_counted(tmp_path, capsys):
    base, new = tmp_path / "base", tmp_path / "new"
    facing, turned = [10.0] * 10, [170.0] * 3 + [10.0] * 7            # 30 % of frames over 90 degrees
    for folder in (base, new):
        _unit(folder, "mediapipe-keypoints", "gestures-1", 0, 80.0, facing)      # the same in both
    _unit(base, "mediapipe-keypoints", "turning", 0, 120.0, turned)
    _unit(new, "mediapipe-keypoints", "turning", 0, 90.0, facing, evaluations=1100.0)
    _unit(base, "mediapipe-keypoints", "turning", 97, 70.0, facing)
    _unit(new, "mediapipe-keypoints", "turning", 97, 75.0, facing, about_neck=400.0)   # lost
    _unit(new, "mediapipe-keypoints", "gestures-2", 0, 60.0, facing)                  # new only
    assert tracking_diff.main([str(base), str(new), "--unseen-seeds", "97"]) == 0
    out = capsys.readouterr().out
    assert "| mediapipe-keypoints | turning | 0 | 120.0 → 90.0 | 50.0 → 50.0 | 30.0 → 0.0 % | no → no | 1000 → 1100 |" in out
    assert "| mediapipe-keypoints | turning | 97 | 70.0 → 75.0 | 50.0 → 400.0 | 0.0 → 0.0 % | no → yes | 1000 → 1000 |" in out
    assert "gestures-1 | 0" not in out                                 # unchanged units are not listed
    assert "| mediapipe-keypoints | tuned on | 1 / 1 | 1 → 0 of 2 | 0 → 0 | 1000 → 1050 (1.050x) |" in out
    assert "| mediapipe-keypoints | never used | 0 / 1 | 0 → 0 of 1 | 0 → 1 | 1000 → 1000 (1.000x) |" in out
    assert "1 unit(s) of the new folder not in the base one" in out


def test_a_folder_without_units_is_refused(tmp_path, capsys):
    (tmp_path / "new" / "units").mkdir(parents=True)
    assert tracking_diff.main([str(tmp_path / "nothing"), str(tmp_path / "new")]) == 2
    assert "not an experiments.tracking results folder" in capsys.readouterr().err
    with pytest.raises(ValueError, match="no units/"):
        tracking_diff.read_units(tmp_path / "nothing")
    (tmp_path / "base" / "units").mkdir(parents=True)          # folders with nothing in common
    _unit(tmp_path / "base", "default", "turning", 0, 90.0, [0.0])
    assert tracking_diff.main([str(tmp_path / "base"), str(tmp_path / "new")]) == 2
    assert "no unit of" in capsys.readouterr().err


def test_the_paired_comparison_counts_units_and_tests_their_differences(tmp_path, capsys):
    """Six units all 10 mm better: the exact two-sided signed-rank p is 2 / 2**6 (only the
    all-negative and all-positive sign patterns are as extreme); one unit in six worse, with the
    smallest difference: the rank sum of the positive side is 1, p = 2 * 2 / 2**6."""
    base, new = tmp_path / "base", tmp_path / "new"
    facing = [10.0] * 10
    for i, sequence in enumerate(("gestures-1", "gestures-2", "gestures-3", "arms-crossing", "not-facing", "turning")):
        _unit(base, "mediapipe-keypoints", sequence, 0, 100.0 + i, facing, about_neck=80.0 + i)
        _unit(new, "mediapipe-keypoints", sequence, 0, 90.0 + i - i / 10, facing, about_neck=80.0 + i)
        _unit(base, "mediapipe-keypoints", sequence, 97, 100.0 + 10 * i, facing)
        _unit(new, "mediapipe-keypoints", sequence, 97, 100.0 + 10 * i + (1.0 if i == 0 else -2.0 - i), facing)
    assert tracking_diff.main([str(base), str(new), "--unseen-seeds", "97"]) == 0
    out = capsys.readouterr().out
    # tuned on: medians 102.5 -> 92.25 (differences -10 .. -10.5), none worse; about the neck unchanged
    assert (f"| mediapipe-keypoints | tuned on | 6 | 102.5 → 92.2 | 82.5 → 82.5 | 6 / 0 | {2 / 2 ** 6:.3f}, – | "
            "10.2 / 10.5 |") in out                                    # |differences| 10.0 .. 10.5 mm
    # never used: differences +1, -3, -4, -5, -6, -7 mm: two better by more than 5 mm, none worse
    assert (f"| mediapipe-keypoints | never used | 6 | 125.0 → 120.5 | 50.0 → 50.0 | 2 / 0 | {4 / 2 ** 6:.3f}, – | "
            "4.5 / 6.5 |") in out                                      # |differences| 1, 3, 4, 5, 6, 7 mm


def test_units_are_matched_across_configuration_keys_and_the_newest_of_a_folder_is_taken(tmp_path, capsys):
    """A change that adds a TrackerConfig field writes its units under another key (file name):
    they are still compared; of two files of one unit in a folder, the newer is taken."""
    import os

    base, new = tmp_path / "base", tmp_path / "new"
    facing = [10.0] * 10
    old = _unit(base, "mediapipe-keypoints", "turning", 0, 500.0, facing, key="oldkey")
    newest = _unit(base, "mediapipe-keypoints", "turning", 0, 120.0, facing, key="basekey")
    os.utime(old, ns=(1_000_000_000, 1_000_000_000))
    os.utime(newest, ns=(2_000_000_000, 2_000_000_000))
    _unit(new, "mediapipe-keypoints", "turning", 0, 90.0, facing, key="variantkey")
    assert tracking_diff.main([str(base), str(new)]) == 0
    captured = capsys.readouterr()
    assert "| mediapipe-keypoints | turning | 0 | 120.0 → 90.0 |" in captured.out
    assert "1 older unit file(s) of the same configuration, sequence and seed passed over" in captured.err
    assert "not in the base one" not in captured.out


def test_the_null_is_tabled_beside_the_change_and_never_taken_for_the_base(tmp_path, capsys):
    """Null units (experiments.tracking --null-offset-px) in the base folder are not read as the
    base; with --null their paired table against the base follows the change's."""
    base, new = tmp_path / "base", tmp_path / "new"
    facing = [10.0] * 10
    for i, sequence in enumerate(("gestures-1", "gestures-2", "turning")):
        _unit(base, "mediapipe-keypoints", sequence, 97, 100.0, facing)
        _unit(new, "mediapipe-keypoints", sequence, 97, 90.0, facing)
        _unit(base, "mediapipe-keypoints", sequence, 97, 100.0 + (i + 1) * (-1) ** i * 4.0, facing, null=0.01)
    base_units, _ = tracking_diff.read_units(base)
    null_units, _ = tracking_diff.read_units(base, null=True)
    assert {u.mpjpe_mm for u in base_units.values()} == {100.0}
    assert sorted(u.mpjpe_mm for u in null_units.values()) == [92.0, 104.0, 112.0]
    assert tracking_diff.main([str(base), str(new), "--unseen-seeds", "97", "--null", str(base)]) == 0
    out = capsys.readouterr().out
    change, null = out.split("The null")
    assert "| mediapipe-keypoints | never used | 3 | 100.0 → 90.0 | 50.0 → 50.0 | 3 / 0 | 0.250, – | 10.0 / 10.0 |" in change
    # null differences +4, -8, +12: medians 100 -> 104, one better and one worse by > 5 mm; exact
    # two-sided signed-rank p: positive rank sum 4 of ranks 1-3, P(T+ <= 2) = 3/8, doubled 0.75
    assert "| mediapipe-keypoints | never used | 3 | 100.0 → 104.0 | 50.0 → 50.0 | 1 / 1 | 0.750, – | 8.0 / 11.2 |" in null
    assert tracking_diff.main([str(base), str(new), "--null", str(new)]) == 2        # no null units there
    assert "no null unit" in capsys.readouterr().err


def test_the_stratified_rank_sum_is_mann_whitney_on_one_unit():
    """One unit without ties: the count and p are scipy's Mann-Whitney U (asymptotic, no continuity
    correction), which the stratified test reduces to."""
    from scipy.stats import mannwhitneyu

    new, base = np.array([3.0, 7.5, 1.0, 9.0]), np.array([4.0, 8.0, 2.0, 10.0, 11.0, 6.0])
    test = tracking_diff.stratified_rank_sum([(new, base)])
    reference = mannwhitneyu(base, new, alternative="two-sided", method="asymptotic", use_continuity=False)
    assert test.units == 1
    assert test.below_share == pytest.approx(reference.statistic / (len(new) * len(base)))   # base's U: pairs base > new
    assert test.p == pytest.approx(reference.pvalue)


def test_the_stratified_rank_sum_has_the_moments_of_every_relabelling():
    """With ties and unequal draws, its standardised count equals the one computed from the exact
    distribution over every relabelling of each unit's draws (enumerated: the null hypothesis)."""
    import itertools

    units = [(np.array([1.0, 2.0]), np.array([2.0, 3.0, 3.0])), (np.array([5.0]), np.array([5.0, 7.0])),
             (np.array([4.0, 4.0, 0.5]), np.array([4.0]))]

    def count(new, base):
        return sum((a < b) + 0.5 * (a == b) for a in new for b in base)

    per_unit = []
    for new, base in units:
        values = np.concatenate([new, base])
        counts = []
        for chosen in itertools.combinations(range(len(values)), len(new)):
            rest = [i for i in range(len(values)) if i not in chosen]
            counts.append(count(values[list(chosen)], values[rest]))
        per_unit.append(np.array(counts))
    mean = sum(c.mean() for c in per_unit)
    variance = sum(c.var() for c in per_unit)                 # units relabelled independently
    observed = sum(count(new, base) for new, base in units)
    test = tracking_diff.stratified_rank_sum(units)
    assert test.z == pytest.approx((observed - mean) / np.sqrt(variance))
    assert test.below_share == pytest.approx(observed / sum(len(n) * len(b) for n, b in units))
    with pytest.raises(ValueError, match="no unit"):
        tracking_diff.stratified_rank_sum([(np.array([1.0]), np.array([]))])
    assert tracking_diff.stratified_rank_sum([(np.array([2.0]), np.array([2.0, 2.0]))]).p == 1.0   # all tied


def test_the_stratified_rank_sum_keeps_its_size_where_the_mean_of_draws_does_not():
    """Skewed, unit-specific draws (a lognormal spread, and now and then a unit lost), three base
    draws and two new ones of the same distribution: the test rejects at 5 % about 5 % of the time;
    a 10 mm shift is found. The signed-rank test of one new draw against the mean of the base's
    draws is not valid there (the mean of a skewed draw lies above its median)."""
    from scipy.stats import wilcoxon

    rng = np.random.default_rng(7)

    def draws(location, count, shift=0.0):
        spread = 12.0 * rng.lognormal(0.0, 1.0, count)
        lost = 300.0 * (rng.random(count) < 0.05)
        return location + spread + lost - shift

    rejected = rejected_naive = found = 0
    trials = 200
    for _ in range(trials):
        locations = rng.uniform(40.0, 200.0, 96)
        units = [(draws(loc, 2), draws(loc, 3)) for loc in locations]
        rejected += tracking_diff.stratified_rank_sum(units).p < 0.05
        rejected_naive += wilcoxon([new[0] - base.mean() for new, base in units]).pvalue < 0.05
        shifted = [(draws(loc, 2, shift=10.0), draws(loc, 3)) for loc in locations]
        test = tracking_diff.stratified_rank_sum(shifted)
        found += test.p < 0.05 and test.below_share > 0.5
    assert 0.02 <= rejected / trials <= 0.09
    assert rejected_naive / trials > 0.25
    assert found / trials > 0.9


def test_every_draw_of_base_its_nulls_and_the_change_is_compared(tmp_path, capsys):
    """Two units, each with three base draws (the plain run and a null in BASE, a null of the other
    sign in a --null folder) and two of the change, every change draw below every base draw: per
    unit U = 6 of mean 3 and variance 2 * 3 / 12 * 6 = 3; z = 6 / sqrt(6); p = 2 (1 - Phi(2.449))."""
    from scipy.stats import norm

    base, null, new = tmp_path / "base", tmp_path / "null", tmp_path / "new"
    facing = [10.0] * 10
    for sequence, shift in (("gestures-1", 0.0), ("turning", 50.0)):
        _unit(base, "mediapipe-keypoints", sequence, 97, 100.0 + shift, facing)
        _unit(base, "mediapipe-keypoints", sequence, 97, 104.0 + shift, facing, null=0.01)
        _unit(null, "mediapipe-keypoints", sequence, 97, 96.0 + shift, facing, null=-0.01)
        _unit(null, "mediapipe-keypoints", sequence, 97, 500.0, facing)         # a plain unit there: not a draw
        _unit(new, "mediapipe-keypoints", sequence, 97, 90.0 + shift, facing)
        _unit(new, "mediapipe-keypoints", sequence, 97, 92.0 + shift, facing, null=0.01)
    draws = tracking_diff.read_draws(base)
    assert sorted(draws[("mediapipe-keypoints", "turning", 97)]) == [0.0, 0.01]
    assert tracking_diff.main([str(base), str(new), "--unseen-seeds", "97", "--null", str(null),
                               "--null", str(base)]) == 0
    out = capsys.readouterr().out.split("Every draw")[1]
    p = 2 * norm.sf(6 / np.sqrt(6))
    # medians over the two units of their draws' means: (100, 150) -> 125; (91, 141) -> 116; SD of 96, 100, 104 = 4
    # one seed: one cluster, whose sign flipped is as far from 0 (p 1)
    assert (f"| mediapipe-keypoints | never used | 2 | 3 / 2 | 125.0 → 116.0 | 4.0 | 0.0 → 0.0 | 100.0 % | "
            f"{p:.3f}, 1.000 |") in out


def test_with_one_unit_a_cluster_and_one_draw_a_side_the_clusters_sign_flip_is_the_sign_test():
    """Each cluster's centred count is then +1/2, -1/2 or 0 (a tie): flipping signs exhaustively
    is the exact two-sided sign test of the untied units (scipy's binomial test); past
    EXACT_CLUSTERS, the random patterns come near it."""
    from scipy.stats import binomtest

    rng = np.random.default_rng(3)
    for count in (9, 14, 30):
        new = rng.normal(0.0, 1.0, count) - 0.4
        base = rng.normal(0.0, 1.0, count)
        base[0] = new[0]                                                    # one tie: no information
        test = tracking_diff.stratified_rank_sum([(np.array([a]), np.array([b])) for a, b in zip(new, base)],
                                                 clusters=list(range(count)))
        reference = binomtest(int(np.sum(new < base)), count - 1).pvalue
        assert test.clusters == count
        if count <= tracking_diff.EXACT_CLUSTERS:
            assert test.cluster_p == pytest.approx(reference)
        else:
            assert test.cluster_p == pytest.approx(reference, abs=0.01)
    with pytest.raises(ValueError, match="one cluster label a unit"):
        tracking_diff.stratified_rank_sum([(np.array([1.0]), np.array([2.0]))], clusters=[0, 1])


def test_clusters_keep_the_size_where_a_seeds_units_move_together():
    """Twelve seeds of six units; each draw of a seed moves all its units alike (a shared draw
    effect, as the keypoints' null did): the units-independent p rejects far too often, the
    clusters' sign flip keeps about its 5 %."""
    rng = np.random.default_rng(11)
    rejected = rejected_clustered = 0
    trials = 200
    for _ in range(trials):
        pairs, labels = [], []
        shared_new, shared_base = rng.normal(0.0, 8.0, (12, 2)), rng.normal(0.0, 8.0, (12, 3))
        for seed in range(12):
            for _ in range(6):
                location = rng.uniform(40.0, 200.0)
                pairs.append((location + shared_new[seed] + rng.normal(0.0, 3.0, 2),
                              location + shared_base[seed] + rng.normal(0.0, 3.0, 3)))
                labels.append(seed)
        test = tracking_diff.stratified_rank_sum(pairs, clusters=labels)
        rejected += test.p < 0.05
        rejected_clustered += test.cluster_p < 0.05
    assert rejected / trials > 0.3
    assert rejected_clustered / trials <= 0.09
