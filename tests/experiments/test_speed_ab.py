"""``experiments.speed_ab``: the alternated schedule, the ratios and their spread against
hand-computed values, the load warning, and a cut command resumed without re-running its runs
(the bench itself stands in: its runs are the benchmark's business, not a test's)."""
from __future__ import annotations

import json
import time

import numpy as np
import pytest

from experiments import speed_ab


def _result(medians: dict[str, float]) -> dict:
    return {"rows": [{"stage": stage, "width": 160, "height": 120, "triangles": 1000, "median_us": us,
                      "p10_us": us, "p90_us": us, "runs": 300} for stage, us in medians.items()],
            "versions": {}, "cpu": "test", "notes": [], "clock": "thread_cpu"}


def test_the_schedule_alternates_the_order_from_pair_to_pair():
    assert speed_ab.schedule(3) == [(0, "old"), (0, "new"), (1, "new"), (1, "old"), (2, "old"), (2, "new")]


def test_ratio_is_the_fastest_new_over_the_fastest_old_and_the_spread_the_per_pair_ratios():
    old = [_result({"render": 10.0, "cost_edge": 20.0}), _result({"render": 12.0, "cost_edge": 20.0}),
           _result({"render": 11.0, "cost_edge": 20.0})]
    new = [_result({"render": 9.0, "cost_edge": 30.0, "only_new": 1.0}), _result({"render": 12.0, "cost_edge": 10.0}),
           _result({"render": 10.0, "cost_edge": 20.0})]
    rows = {r.stage: r for r in speed_ab.compare(old, new)}
    assert set(rows) == {"render", "cost_edge"}             # a row of one tree alone is not compared
    assert rows["render"].ratio == pytest.approx(9.0 / 10.0)
    assert (rows["render"].low, rows["render"].high) == pytest.approx((0.9, 1.0))
    assert rows["cost_edge"].ratio == pytest.approx(0.5)
    assert (rows["cost_edge"].low, rows["cost_edge"].high) == pytest.approx((0.5, 1.5))
    table = speed_ab.format_table(list(rows.values()), "abc1234", "worktree")
    assert "| render | 160x120 | 10.0 | 9.0 | 0.90 | 0.90-1.00 |" in table


def test_a_cut_command_resumes_without_rerunning_and_warns_on_a_busy_machine(tmp_path, monkeypatch, capsys):
    calls = []
    medians = {"old": 10.0, "new": 8.0}

    def fake_bench(tree, groups, quick=False):
        side = "old" if tree == tmp_path / "old" else "new"
        calls.append((side, quick))
        if len([c for c in calls if not c[1]]) == 4 and not quick:
            raise ValueError("the bench failed in the test: cut here")
        return _result({"render": medians[side]})

    monkeypatch.setattr(speed_ab, "resolve", lambda ref: ("a" * 40, "aaaaaaa") if ref else ("b" * 40, "worktree"))
    monkeypatch.setattr(speed_ab, "tree_of", lambda sha, trees: tmp_path / ("new" if sha is None else "old"))
    for side in ("old", "new"):
        (tmp_path / side / "mocap").mkdir(parents=True)
        (tmp_path / side / "mocap" / "bench.py").write_text("same")
    monkeypatch.setattr(speed_ab, "run_bench", fake_bench)
    monkeypatch.setattr(speed_ab, "load_average", lambda: 3.0)
    out = tmp_path / "out"
    assert speed_ab.main(["HEAD~1", "--pairs", "3", "--out", str(out)]) == 1           # the fourth timed run fails
    err = capsys.readouterr().err
    assert "load average 3.00" in err and "cut here" in err
    assert sorted(p.name for p in (out / "runs").iterdir()) == ["0-new.json", "0-old.json", "1-new.json"]
    calls.clear()
    monkeypatch.setattr(speed_ab, "load_average", lambda: 0.2)
    assert speed_ab.main(["HEAD~1", "--pairs", "3", "--out", str(out)]) == 0
    assert [c for c in calls if not c[1]] == [("old", False), ("old", False), ("new", False)]   # the rest only
    summary = json.loads((out / "speed_ab.json").read_text())
    assert summary["rows"][0]["ratio"] == pytest.approx(0.8) and summary["clock"] == "thread_cpu"
    assert "warning" not in capsys.readouterr().err
    with pytest.raises(SystemExit):
        speed_ab.main(["HEAD~1", "--pairs", "2", "--out", str(out)])


def test_a_row_whose_work_runs_in_another_thread_is_timed_with_it():
    """The bench's process clock counts a worker thread's CPU time, the thread clock leaves it
    out (why the llvmpipe row, whose rasterizer runs in a thread of its own, is timed in process
    CPU time: issue 50); and the llvmpipe row is one of those rows."""
    import threading

    from mocap.bench import clock_of, time_calls

    def spin_elsewhere(i):
        def spin():
            end = time.thread_time() + 0.02           # 20 ms of CPU on the worker thread
            while time.thread_time() < end:
                pass
        worker = threading.Thread(target=spin)
        worker.start()
        worker.join()

    thread = time_calls(spin_elsewhere, min_runs=3, min_seconds=0.0, clock="thread_cpu")
    process = time_calls(spin_elsewhere, min_runs=3, min_seconds=0.0, clock="process_cpu")
    assert np.median(process) >= 19e3 and np.median(thread) < 5e3      # microseconds
    assert clock_of("llvmpipe_render") == "process_cpu" and clock_of("render") == "thread_cpu"
    with pytest.raises(ValueError, match="clock"):
        time_calls(spin_elsewhere, min_runs=1, min_seconds=0.0, clock="wall")
