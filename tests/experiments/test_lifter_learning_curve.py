"""The lifter's learning curve: its run files and figure."""
import json

from experiments import lifter_learning_curve as curve
from experiments.figures import ext_lifter_learning_curve


def _run(budget, finished=True):
    points = [{"step": s, "train_s": 1.0, **{subject: {"top1": 0.3 + s / 1e5, "best_of_10": 0.8 + s / 1e5,
                                                         "median_top1_mm": 100.0, "median_best_mm": 60.0}
                                             for subject in ("14", "49")}}
              for s in range(budget // 2, budget + 1, budget // 2)]
    return {"budget": budget, "hold_out": ["14", "49"], "points": points, "finished": finished}


def test_runs_are_read_by_budget_and_drawn(tmp_path):
    for budget, finished in ((12000, False), (4000, True)):
        curve.run_file(tmp_path, budget).write_text(json.dumps(_run(budget, finished)))
    runs = curve.read_runs(tmp_path)
    assert [r["budget"] for r in runs] == [4000, 12000]
    assert [p.suffix for p in ext_lifter_learning_curve.main(runs, tmp_path / "fig")] == [".png", ".pdf"]
    assert curve.main(["--figure-only", "--out", str(tmp_path)]) == 0
    assert curve.main(["--figure-only", "--out", str(tmp_path / "empty")]) == 2
