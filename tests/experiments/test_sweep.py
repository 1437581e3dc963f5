"""The sweep end to end: local processes, a Dask cluster, resuming, the command line."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from experiments.config import SweepConfig
from experiments.plan import data_spec, grid_specs, make_plan, policy_specs
from experiments.sweep import main as sweep_main, run_sweep
from experiments.units import FRAME_ARRAYS, RunSpec, load_unit, save_unit

from tests.conftest import REPO_ROOT


def stored_units(root):
    return sorted((root / "units").rglob("*.npz"))


def test_tiny_sweep_writes_every_planned_unit(tiny_results, tiny_config):
    plan = make_plan(tiny_config)
    specs = plan.runs + plan.timing
    assert len(stored_units(tiny_results)) == len(specs)
    for spec in specs:
        u = load_unit(spec.path(tiny_results))
        assert set(FRAME_ARRAYS) <= set(u)
        assert u["frame"].tolist() == list(range(tiny_config.frames))
        assert u["meta"]["spec"]["region"] == spec.region and u["meta"]["spec"]["edge"] == spec.edge
        assert np.all((u["region_residual"] >= 0) & (u["region_residual"] <= 1))
        assert np.isfinite(u["edge_residual"]).all() and np.isfinite(u["mpjpe_mm"]).all()
        assert u["joints"].shape == (tiny_config.frames, 10, 3) and u["poses"].shape == (tiny_config.frames, 23)
        assert np.all(u["evaluations"] <= spec.region + spec.edge)
    table2 = json.loads((tiny_results / "table2.json").read_text())
    assert [(r["width"], r["height"]) for r in table2["rows"]] == list(tiny_config.table2_sizes)
    log = json.loads((tiny_results / "sweep.json").read_text())
    assert log["invocations"][0]["computed"] == len(specs) + 1 and log["invocations"][0]["wall_s"] > 0


def test_budgets_are_spent_as_asked(tiny_results, tiny_config):
    spec = grid_specs(tiny_config, data_spec(tiny_config, "gestures-2"))
    none = load_unit(spec[(0, 0)].path(tiny_results))
    assert np.all(none["evaluations"] == 0)
    region_only = load_unit(spec[(30, 0)].path(tiny_results))
    assert np.all(region_only["edge_iterations"] == 0) and np.all(region_only["evaluations"] > 0)
    # no optimisation keeps the first (true) pose: every frame reports the same pose
    assert np.allclose(none["poses"], none["poses"][0])


def test_dask_local_cluster_gives_the_same_results(tiny_results, tiny_config, tmp_path):
    distributed = pytest.importorskip("distributed")
    config = tiny_config.with_changes({"sequences": ("gestures-2",), "timing_sequences": ("gestures-2",)})
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        summary = run_sweep(config, tmp_path, scheduler=cluster.scheduler_address, progress=False, table2=False)
    plan = make_plan(config)
    assert summary.errors == [] and summary.computed == len(plan.runs) + len(plan.timing)
    for spec in plan.runs:          # same data seed, same tracker: the same numbers as on local processes
        a, b = load_unit(spec.path(tiny_results)), load_unit(spec.path(tmp_path))
        np.testing.assert_array_equal(a["region_residual"], b["region_residual"])
        np.testing.assert_array_equal(a["poses"], b["poses"])
    assert "dask" in json.loads((tmp_path / "sweep.json").read_text())["invocations"][0]["backend"]


def test_interrupted_sweep_resumes_without_recomputing(tiny_config, tmp_path):
    config = tiny_config.with_changes({"sequences": ("gestures-2",), "timing_sequences": ("gestures-2",)})
    plan = make_plan(config)
    total = len(plan.runs) + len(plan.timing)
    first = run_sweep(config, tmp_path, workers=0, max_units=4, progress=False, table2=False)
    assert first.computed == 4 and first.remaining == total - 4
    done = {p: p.stat().st_mtime_ns for p in stored_units(tmp_path)}
    assert len(done) == 4
    # a half-written file of a killed run (the atomic writer's temp name) is not a finished unit
    stray = next(iter(done)).parent / ".r9999_e9999_ftol0.001.npz.abc.tmp"
    stray.write_bytes(b"partial")
    second = run_sweep(config, tmp_path, workers=0, progress=False, table2=False)
    assert second.computed == total - 4 and second.skipped == 4 and second.remaining == 0
    for p, mtime in done.items():
        assert p.stat().st_mtime_ns == mtime, f"{p.name} was recomputed"
    assert len(stored_units(tmp_path)) == total
    third = run_sweep(config, tmp_path, workers=0, progress=False, table2=False)
    assert third.computed == 0 and third.skipped == total
    log = json.loads((tmp_path / "sweep.json").read_text())
    assert [i["computed"] for i in log["invocations"]] == [4, total - 4, 0]


def test_units_are_shared_between_figures():
    config = SweepConfig.preset("quick")
    d = data_spec(config, "gestures-2")
    assert policy_specs(config, d)[("1:1", 200)].key == RunSpec(d, 100, 100, ftol=config.ftol).key
    assert policy_specs(config, d)[("auto", 40)] == policy_specs(config, d)[("1:0", 40)]
    # with one step idle the edge-step start does not matter: one unit
    assert RunSpec(d, 0, 50, edge_start="fresh") == RunSpec(d, 0, 50)
    plan = make_plan(config)
    keys = [(s.data.key, s.key) for s in plan.runs]
    assert len(keys) == len(set(keys))


def test_gradient_policy_twins_the_grid_and_fig4_only_where_the_step_runs():
    from mocap.track.config import gradient_budget

    config = SweepConfig.preset("quick")
    plain, with_gradient = make_plan(config), make_plan(config.with_changes({"gradient": True}))
    # the default sweep is unchanged: no unit with the gradient step, and all its units still planned
    assert not any(s.gradient for s in plain.runs + plain.timing)
    assert set(plain.runs) <= set(with_gradient.runs) and plain.timing == with_gradient.timing
    added = [s for s in with_gradient.runs if s not in set(plain.runs)]
    assert all(s.gradient and s.key.endswith("_gradient") for s in added)
    # per sequence: one twin per grid cell whose edge budget leaves the step evaluations, and Fig. 4's converged run
    cells = [(r, e) for r in config.region_budgets for e in config.edge_budgets if gradient_budget(e) > 0]
    assert len(added) == len(config.sequences) * (len(cells) + 1)
    d = data_spec(config, "gestures-2")
    twin = grid_specs(config, d, gradient=True)[(100, 250)]
    assert twin in added and twin.tracker_config().gradient_step and twin.tracker_config().evaluations == 350
    assert not grid_specs(config, d)[(100, 250)].tracker_config().gradient_step
    # an edge budget too small for the step (or none): the simplex unit itself, not run twice
    assert grid_specs(config, d, gradient=True)[(100, 0)] == grid_specs(config, d)[(100, 0)]
    assert RunSpec(d, 30, 30, gradient=True) == RunSpec(d, 30, 30)
    keys = [(s.data.key, s.key) for s in with_gradient.runs]
    assert len(keys) == len(set(keys))


def test_gradient_unit_drawn_as_the_second_row(tiny_results, tiny_config, tmp_path):
    """One gradient-step unit run into a copy of the tiny sweep: the twin surfaces read it, the figures draw it."""
    import shutil

    from experiments.figures import fig4, fig10
    from experiments.results import Results
    from experiments.sweep import CONFIG_FILE
    from experiments.units import run_unit

    root = tmp_path / "results"
    shutil.copytree(tiny_results, root)
    config = tiny_config.with_changes({"gradient": True, "edge_budgets": (0, 30, 40)})
    config.to_json(root / CONFIG_FILE)
    d = data_spec(config, "gestures-2")
    spec = grid_specs(config, d, gradient=True)[(30, 40)]
    assert spec.gradient
    save_unit(spec.path(root), run_unit(spec, str(root)))
    u = load_unit(spec.path(root))
    assert u["meta"]["tracker"]["gradient_step"] and np.all(u["evaluations"] <= 70)
    res = Results(root)
    rs, es, z = res.surface(d, "mean_D", gradient=True)
    assert z[list(rs).index(30), list(es).index(40)] == pytest.approx(np.mean(u["edge_residual"]))
    assert np.isnan(res.surface(d, "mean_D")[2][list(rs).index(30), list(es).index(40)])   # simplex: not run
    for module in (fig10, fig4):
        assert [p.suffix for p in module.main(res, tmp_path / "figures")] == [".png", ".pdf"]
    # the report section compares the one cell that has both runs (the simplex twin of (30, 40) was not run)
    from experiments.report import gradient_sweep_section

    assert "No cell with the gradient step" in gradient_sweep_section(res, "figs", "cmd")
    simplex = grid_specs(config, d)[(30, 40)]
    save_unit(simplex.path(root), run_unit(simplex, str(root)))
    text = gradient_sweep_section(Results(root), "figs", "cmd")
    row = [line for line in text.splitlines() if line.startswith("| 30 | 40 |")]
    assert len(row) == 1 and f"{np.mean(u['edge_residual']):.3f}" in row[0].split("|")[4]
    assert "Over 1 cells" in text


def test_save_unit_rejects_incomplete_results(tmp_path):
    with pytest.raises(ValueError, match="lacks"):
        save_unit(tmp_path / "u.npz", {"frame": np.arange(3)})
    assert not (tmp_path / "u.npz").exists()


@pytest.mark.parametrize("changes, match", [
    ({"sequences": ("gestures-9",)}, "unknown sequence"), ({"frames": 0}, "frames"),
    ({"region_budgets": (0, -5)}, "region_budgets"), ({"region_budgets": ()}, "empty"),
    ({"handoff_edge_budgets": (0, 600)}, "handoff_total"), ({"policies": ("2:x",)}, "split"),
    ({"figure_sequence": "turning", "sequences": ("gestures-1",)}, "figure_sequence"),
    ({"table2_sizes": ((8, 8),)}, "table2_sizes"), ({"figure_failure_f": 0}, "figure_failure_f"),
    ({"gradient": "yes"}, "gradient must be true or false"),
])
def test_bad_config_rejected(changes, match):
    with pytest.raises(ValueError, match=match):
        SweepConfig().with_changes(changes)


def test_config_json_round_trip_and_unknown_keys(tmp_path):
    SweepConfig.preset("quick").to_json(tmp_path / "c.json")
    assert SweepConfig.from_json(tmp_path / "c.json") == SweepConfig.preset("quick")
    data = json.loads((tmp_path / "c.json").read_text())
    data["frame"] = 3
    with pytest.raises(ValueError, match="unknown SweepConfig option"):
        SweepConfig.from_dict(data)


@pytest.mark.parametrize("argv, match", [
    (["--sequences", "nope"], "unknown sequence"), (["--region-budgets", "0,-1"], "region_budgets"),
    (["--workers", "-1"], "workers"), (["--max-units", "0"], "max_units"),
    (["--motion-dir", "/nonexistent/clips"], "motion folder"), (["--config", "/nonexistent.json"], "does not exist"),
])
def test_cli_bad_input_exits_2_with_one_line(argv, match, tmp_path, capsys):
    assert sweep_main([*argv, "--out", str(tmp_path / "r"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert match in err and len(err.splitlines()) == 1


def test_cli_runs_a_sweep_with_a_unit_limit(tiny_config, tmp_path):
    config = tiny_config.with_changes({"sequences": ("gestures-2",), "timing_sequences": ("gestures-2",)})
    config.to_json(tmp_path / "tiny.json")
    out = tmp_path / "r"
    cmd = [sys.executable, "-m", "experiments.sweep", "--config", str(tmp_path / "tiny.json"), "--out", str(out),
           "--workers", "1", "--max-units", "2", "--no-table2"]
    proc = subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "2 units computed" in proc.stdout
    assert len(stored_units(out)) == 2


@pytest.mark.shared_data
def test_motion_dir_drives_the_actors_with_every_clip(shared_data, tiny_config, tmp_path):
    clips = tmp_path / "clips"
    clips.mkdir()
    (clips / "walk.bvh").symlink_to(shared_data / "mocap" / "cmu_12_01_walk.bvh")
    (clips / "notes.txt").write_text("not a clip")
    config = tiny_config.with_changes({"sequences": ("gestures-2",), "timing_sequences": ("gestures-2",),
                                       "motion_actors": ("gestures-1",)})
    summary = run_sweep(config, tmp_path / "r", workers=0, motion_dir=clips, progress=False, table2=False)
    assert summary.errors == []
    folders = sorted(p.name for p in (tmp_path / "r" / "units").iterdir())
    assert folders == ["gestures-1+walk-s0-max3f-160x120", "gestures-2-s0-3f-160x120"]
    clip_units = sorted((tmp_path / "r" / "units" / folders[0]).glob("*.npz"))
    assert len(clip_units) == len(config.motion_budgets) ** 2
    u = load_unit(clip_units[0])
    assert u["frame"].size == 3 and u["meta"]["motion"]["file"] == "walk.bvh"
    assert json.loads((tmp_path / "r" / "sweep.json").read_text())["clips"] == [str(clips / "walk.bvh")]
