"""The throughput command's plumbing on a tiny clip: runs pinned to their cores, the JSON and the
table, the docs section replaced (no timing asserted)."""
from __future__ import annotations

import json
import os

import pytest

from experiments import throughput


@pytest.fixture(scope="module")
def tiny_clip(tmp_path_factory):
    """A synthetic sequence folder (six frames, 160x120, its own calibration and background)."""
    from mocap.synth import generate_sequence

    return generate_sequence("gestures-1", tmp_path_factory.mktemp("clip") / "seq", frames=6, seed=3, progress=False)


def test_the_runs_the_json_the_table_and_the_docs_section(tiny_clip, tmp_path, capsys):
    cores = (1, 2) if len(os.sched_getaffinity(0)) >= 2 else (1,)
    page = tmp_path / "results.md"
    page.write_text("# Measured results\n\n## Speed\n\nbench table\n\n## Throughput\n\nold\n\n## Accuracy\n\nkept\n")
    assert throughput.main(["--clip", str(tiny_clip), "--out", str(tmp_path / "out"), "--cores",
                            ",".join(map(str, cores)), "--keypoints", "none", "--max-frames", "3",
                            "--docs", str(page)]) == 0
    result = json.loads((tmp_path / "out" / "throughput.json").read_text())
    assert [(r["cores"], r["keypoints"]) for r in result["runs"]] == [(c, "none") for c in cores]
    for run in result["runs"]:
        assert run["frames"] == 3 and run["fps"] > 0 and run["end_to_end_fps"] > 0 and run["loop_fps"] > 0
        assert run["keypoints_ms_per_frame"] is None
        assert run["command"].startswith(f"taskset -c {throughput._cpu_list(run['cores'])} python -m mocap track ")
        run_json = json.loads((tmp_path / "out" / f"run-{run['cores']}core-none" / "run.json").read_text())
        assert run_json["frames"] == 3 and run_json["settings"]["keypoints"] == "none"
    assert result["size"] == "160x120" and "mediapipe_alone" not in result
    markdown = (tmp_path / "out" / "throughput.md").read_text()
    rows = [line for line in markdown.splitlines() if line.startswith("| ") and "none" in line]
    assert [row.split(" | ")[0] for row in rows] == [f"| {c}" for c in cores]
    text = page.read_text()
    assert text.count("## Throughput") == 1 and "old" not in text and rows[0] in text
    assert text.index("## Speed") < text.index("## Throughput") < text.index("## Accuracy") and "kept" in text
    # the same table again from the stored JSON, without measuring
    again = tmp_path / "again.md"
    assert throughput.main(["--from-json", str(tmp_path / "out" / "throughput.json"), "--docs", str(again)]) == 0
    assert throughput.section_of(again) == throughput.section_of(page) == markdown


def test_a_core_count_beyond_the_machine_is_refused():
    with pytest.raises(ValueError, match="cores asked for"):
        throughput.pinned(len(os.sched_getaffinity(0)) + 1)
