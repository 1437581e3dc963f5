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
    if len(cores) == 2:             # the one-core frames a second over the two-core ones, of this run
        ratio = result["runs"][0]["fps"] / result["runs"][1]["fps"]
        assert f"none: 2 cores / 1 **{ratio:.2f}** ({ratio:.2f}-{ratio:.2f}, 1 repeat(s))" in markdown
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


def test_the_ratios_are_taken_within_each_repeat():
    """Made-up runs of two repeats whose machine ran twice as fast in the second: each ratio is
    the same in both, whatever the drift; MediaPipe alone pairs with its own repeat."""
    runs = [{"repeat": i, "cores": c, "keypoints": k, "fps": fps * (1 + i)}
            for i in (0, 1) for (c, k, fps) in ((1, "none", 20.0), (2, "none", 25.0), (1, "mediapipe", 10.0),
                                                 (2, "mediapipe", 15.0))]
    alone = [{"repeat": 0, "ms_per_frame_median": 40.0}, {"repeat": 1, "ms_per_frame_median": 20.0}]
    found = {r.name: r for r in throughput.ratios({"runs": runs, "cores": [1, 2], "keypoints": ["none", "mediapipe"],
                                                    "mediapipe_alone_runs": alone})}
    assert set(found) == {"mediapipe / alone", "none: 2 cores / 1", "mediapipe: 2 cores / 1"}
    assert found["mediapipe / alone"].median == pytest.approx(0.6) and found["mediapipe / alone"].repeats == 2
    assert found["mediapipe / alone"].low == pytest.approx(found["mediapipe / alone"].high)
    assert found["none: 2 cores / 1"].median == pytest.approx(0.8)
    assert found["mediapipe: 2 cores / 1"].median == pytest.approx(10.0 / 15.0)
    # a JSON written before the runs carried their repeat: no ratios, no error
    assert throughput.ratios({"runs": [{k: v for k, v in r.items() if k != "repeat"} for r in runs],
                              "cores": [1, 2], "keypoints": ["none"]}) == []
