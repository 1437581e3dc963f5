"""Figures, tables and the report from the tiny sweep's results; the notebook runs on them."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from experiments.figures import FIGURES, make_all
from experiments.figures.__main__ import main as figures_main
from experiments.report import write_report

from tests.conftest import REPO_ROOT


@pytest.fixture(scope="module")
def report(tiny_results, tmp_path_factory):
    """The report of the tiny sweep; writing it makes every figure into ``report/``."""
    out = tmp_path_factory.mktemp("report")
    return write_report(tiny_results, out / "REPORT.md", out / "report")


@pytest.fixture(scope="module")
def figures(report):
    return report.parent / "report"


@pytest.mark.parametrize("name", FIGURES)
def test_every_figure_written_as_png_and_pdf(figures, name):
    png, pdf = figures / f"{name}.png", figures / f"{name}.pdf"
    image = imread(png)
    assert image.ndim == 3 and image.shape[0] > 100 and image.shape[1] > 300
    assert (image[..., :3] < 0.75).any()                 # not blank
    assert pdf.read_bytes().startswith(b"%PDF")


def test_tables_as_markdown(figures, tiny_config):
    t1 = (figures / "table1.md").read_text().splitlines()
    assert len(t1) == 2 + len(tiny_config.table1_totals) and "22.34" in t1[-1]      # the paper's row beside ours
    t2 = (figures / "table2.md").read_text().splitlines()
    assert len(t2) == 2 + len(tiny_config.table2_sizes) and t2[2].startswith("| 160 x 120")


def test_failure_figures_state_their_thresholds(tiny_results):
    from experiments.figures._common import threshold_text
    from experiments.results import Results
    res = Results(tiny_results)
    assert threshold_text(res, "fail_F") == f"failure: F > {res.config.figure_failure_f:g}"
    assert "px" in threshold_text(res, "fail_D") and "mm" in threshold_text(res, "fail_gt")


def test_figures_cli(tiny_results, tmp_path):
    assert figures_main(["--results", str(tiny_results), "--out", str(tmp_path), "--only", "fig9,table1",
                         "--no-progress"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig9.pdf", "fig9.png", "table1.md", "table1.pdf",
                                                          "table1.png"]
    assert figures_main(["--results", str(tmp_path / "none"), "--no-progress"]) == 2
    assert figures_main(["--results", str(tiny_results), "--only", "fig99", "--no-progress"]) == 2


def test_report_generated(report):
    text = report.read_text()
    for needle in ("## Headline numbers", "## The paper's claims", "Table 1", "Fig. 12", "](report/fig9.png)",
                   "MPJPE", "F > 0.3"):
        assert needle in text
    assert "nan" not in text.lower().replace("n/a", "")


def test_notebook_regenerates_the_figures(tiny_results, tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    notebook = REPO_ROOT / "notebooks" / "paper_figures.ipynb"
    nb = nbformat.read(notebook, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), "commit the notebook without outputs"
    only = ("table1", "fig8", "fig9", "ext_policies")           # a subset keeps the test fast
    env = {"MOCAP_RESULTS": str(tiny_results), "MOCAP_FIGURES_OUT": str(tmp_path / "nb"),
           "MOCAP_FIGURES_ONLY": ",".join(only)}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                resources={"metadata": {"path": str(notebook.parent)}}).execute()
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    assert sorted(p.stem for p in Path(tmp_path / "nb").glob("*.png")) == sorted(only)
    errors = [o for c in nb.cells for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors
