"""The tracking ablation's summaries, table, figure and report section, on made-up results."""
import numpy as np
import pytest

from experiments.report import generated_sections, replace_section
from experiments.tracking import CONFIGS, config_of, summarise, table
from mocap.track import TrackerConfig


def row(sequence, errors, eq=0.0):
    errors = np.asarray(errors, dtype=float)
    return {"sequence": sequence, "frames": len(errors), "mpjpe_mm": float(errors.mean()),
            "root_relative_mpjpe_mm": float(errors.mean()) / 2, "pa_mpjpe_mm": float(errors.mean()) / 3,
            "frame_mpjpe_mm": errors.tolist(), "beam_oracle_failure_rate": 0.0, "cost_equivalent_both_rate": eq,
            "tracking_ms_per_frame": 20.0, "prepare_ms_per_frame": 5.0}


def test_summary_pools_frames_and_takes_medians_over_sequences():
    rows = [row("a", [10, 20, 30]), row("b", [200, 200, 50, 50, 50]), row("c", [60])]
    s = summarise(rows)
    assert s["median_mpjpe_mm"] == pytest.approx(60.0)             # medians of 20, 110, 60
    assert s["failure_rate"] == pytest.approx(2 / 9)               # two of nine frames over 100 mm
    assert s["worst_mpjpe_mm"] == pytest.approx(110.0)
    assert s["ms_per_frame"] == pytest.approx(25.0)
    text = table({"default": s})
    assert "| default | 60 | 30 | 20 | 22.2 % | - | 110 | 0.0 % | - | - | - | - | 0.0 % | - | 25.0 (40) |" in text
    assert all(line.count("|") == text.splitlines()[0].count("|") for line in text.splitlines())


def test_summary_takes_the_median_acceleration_error_over_sequences():
    accel = lambda a, d, n: {"accel_mm": a, "decoded_accel_mm": d, "naive_accel_mm": n, "accel_arms_pa_mm": a / 2}
    rows = [row("a", [10]) | accel(3.0, 40.0, 5.0), row("b", [20]) | accel(9.0, 50.0, 6.0),
            row("c", [30]) | accel(5.0, 60.0, 4.0)]
    s = summarise(rows)
    assert (s["median_accel_mm"], s["median_decoded_accel_mm"], s["median_naive_accel_mm"]) == (5.0, 50.0, 5.0)
    assert "| 5.0 (50.0, 5.0) |" in table({"default": s})


def test_summary_of_the_proposal_stage_weights_rates_by_frames():
    rows = [row("a", [10, 20, 30]) | {"proposal_oracle_failure_rate": 1 / 3, "proposal_catches_rate": 0.0},
            row("b", [200, 50, 50, 50, 50, 50]) | {"proposal_oracle_failure_rate": 0.5, "proposal_catches_rate": 0.5}]
    s = summarise(rows)
    assert s["proposal_oracle_failure_rate"] == pytest.approx(4 / 9)  # (1 + 3) of nine frames
    assert s["proposal_catches_rate"] == pytest.approx(3 / 9)
    assert "| 44.4 % | 33.3 % |" in table({"both": s})


def test_named_configurations():
    assert config_of("paper") == TrackerConfig.paper()
    assert config_of("default") == TrackerConfig()
    assert all(isinstance(config_of(n), TrackerConfig) for n in CONFIGS)


def test_report_sections_are_replaced_and_kept(tmp_path):
    path = tmp_path / "REPORT.md"
    path.write_text("# Report\n\nbody\n")
    replace_section(path, "tracking", "## old")
    replace_section(path, "peers", "## peers")
    replace_section(path, "tracking", "## new")
    text = path.read_text()
    assert text.startswith("# Report\n\nbody\n") and "## old" not in text
    assert text.index("## new") < text.index("## peers")
    kept = generated_sections(text)
    assert "## new" in kept and "## peers" in kept and "body" not in kept


def test_budget_figure_draws_the_configurations_with_an_evaluation_count(tmp_path):
    from experiments.figures import ext_proposal_budget
    summaries = {"default": {"evaluations_per_frame": 900.0, "median_mpjpe_mm": 111.0, "failure_rate": 0.52},
                 "both": {"evaluations_per_frame": 1400.0, "median_mpjpe_mm": 80.0, "failure_rate": 0.3},
                 "old": {"median_mpjpe_mm": 120.0, "failure_rate": 0.6}}        # no count: left out
    paths = ext_proposal_budget.main(summaries, tmp_path)
    assert paths and all(p.is_file() and p.stat().st_size > 1000 for p in paths)
