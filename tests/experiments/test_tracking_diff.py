"""``python -m experiments.tracking_diff``: units matched by configuration, sequence and seed, the changed ones listed,
counted per configuration and seed set (made-up units with hand-counted answers)."""
import json

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
