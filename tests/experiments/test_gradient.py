import json

from experiments.gradient import bench_ratios, main, truth_table, verdict


def _row(median, edge, region, ms, failures=0):
    return {"frames": 10, "start_median_mm": 9.0, "median_mm": median, "mean_mm": median + 1, "failure_rate": 0.0,
            "edge_residual_px": edge, "region_residual": region, "residual_failures": failures, "ms_per_frame": ms}


def test_verdict_reads_the_targets_off_the_numbers():
    truth = {"off": _row(23.0, 0.53, 0.165, 12.0), "on": _row(25.0, 0.50, 0.160, 15.0)}
    at_truth = {"edge_residual_px": 0.6, "region_residual": 0.19}
    lines = verdict(truth, at_truth, None, {"edge": 2.5, "edge_us": 95.0, "edge_cost_us": 38.0})
    text = "\n".join(lines)
    assert "0.94x at 1.25x the CPU time" in text                      # 0.50 / 0.53, 15 / 12
    assert "25.0 mm with the step, 23.0 mm without" in text
    assert "eq. (2) 2.50x" in text
    assert "better than the true poses (5.350)" in text               # 0.6 + 25 * 0.19
    assert "true poses" in truth_table(truth, at_truth)


def test_bench_ratios_and_bad_input(tmp_path):
    rows = [{"stage": s, "width": 160, "height": 120, "median_us": v}
            for s, v in (("cost_edge", 40.0), ("gradient_edge", 100.0), ("cost_region", 30.0))]
    path = tmp_path / "bench.json"
    path.write_text(json.dumps({"rows": rows}))
    assert bench_ratios(path) == {"edge": 2.5, "edge_us": 100.0, "edge_cost_us": 40.0}
    assert main(["--seeds", "1", "--unseen-seeds", "1"]) == 2        # an unseen seed among the others
    assert main(["--bench", str(tmp_path / "none.json")]) == 2
