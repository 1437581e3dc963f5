"""``python -m experiments.docs`` writes docs/results.md from what it measured (tiny run)."""
import json

import pytest

from experiments.docs import main, render_page
from mocap.io.pose_table import PoseTable


@pytest.mark.slow
def test_page_reports_the_runs_it_made(tmp_path):
    out = tmp_path / "results.md"
    assert main(["--work", str(tmp_path / "work"), "--out", str(out), "--only", "gestures-1", "--frames", "3",
                 "--evaluations", "10,20", "--no-bench", "--no-auto-calibration"]) == 0
    m = json.loads((tmp_path / "work" / "measurements.json").read_text())
    assert [r["label"] for r in m["tracking"]] == ["10", "20"]
    # the row is the run's own metrics (one sequence: the median is that run)
    run = m["per_sequence"]["gestures-1-10"]
    assert m["tracking"][0]["mpjpe_mm"] == run["mpjpe_mm"]
    assert len(PoseTable.read(tmp_path / "work" / "runs" / "gestures-1-10" / "poses.csv").poses) == 3
    page = out.read_text()
    assert f"| 10 | {run['mpjpe_mm']:.0f} ({run['mpjpe_mm']:.0f}–{run['mpjpe_mm']:.0f}) |" in page
    assert "do not edit by hand" in page and "## Speed" not in page
    # rewriting from the stored measurements gives the same page
    again = tmp_path / "again.md"
    assert main(["--from-json", str(tmp_path / "work" / "measurements.json"), "--out", str(again)]) == 0
    assert again.read_text() == page
    # the throughput section (python -m experiments.throughput --docs) is measured apart: kept as it is
    again.write_text(page + "\n## Throughput\n\n| cores | ... |\n")
    assert main(["--from-json", str(tmp_path / "work" / "measurements.json"), "--out", str(again)]) == 0
    assert again.read_text() == page + "\n## Throughput\n\n| cores | ... |\n"


def test_speed_table_from_bench_rows():
    rows = [{"stage": s, "width": 160, "height": 120, "median_us": v}
            for s, v in (("cost_region", 20.0), ("cost_edge", 25.0), ("render", 16.0), ("llvmpipe_render", 64.0),
                         ("prepare_frame", 1500.0), ("frame_500", 10000.0))]
    m = {"date": "2026-01-01", "commit": "abc", "sequences": ["gestures-1"], "frames": None, "seed": 0,
         "size": [160, 120], "tracking": [], "per_sequence": {}, "bench": {"rows": rows, "cpu": "test"},
         "demo": {"mpjpe_mm": 50.0, "pa_mpjpe_mm": 30.0, "reprojection_px": 1.0, "failure_rate": 0.1, "fps": 90.0}}
    page = render_page(m)
    assert "| one evaluation, render + F (µs) | 20.0 | 1,050 |" in page        # paper Table 2: 1.05 ms
    assert "| llvmpipe / ours | 4.0x | |" in page
    assert "| image side, `prepare_frame` (ms) | 1.5 | 92 |" in page
    assert "10.0 ms (100 frames per second)" in page
    assert "MPJPE 50 mm" in page and "10 % of frames over 100 mm" in page
