"""The notebooks run end to end (small parameters) and their .py/.ipynb pairs agree."""
from pathlib import Path

import jupytext
import nbformat
import pytest
from nbclient import NotebookClient

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
WALKTHROUGH_AND_CALIBRATION = ["walkthrough", "calibration"]


@pytest.mark.parametrize("name", WALKTHROUGH_AND_CALIBRATION)
def test_paired_script_matches_notebook(name):
    script = jupytext.read(NOTEBOOKS / f"{name}.py")
    notebook = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    assert [c.source for c in script.cells] == [c.source for c in notebook.cells], \
        f"run: jupytext --sync notebooks/{name}.py"
    assert all(not c.get("outputs") for c in notebook.cells if c.cell_type == "code"), "commit notebooks without outputs"


@pytest.mark.slow
@pytest.mark.parametrize("name", WALKTHROUGH_AND_CALIBRATION)
def test_notebook_runs(name, tmp_path, monkeypatch):
    monkeypatch.setenv("MOCAP_NOTEBOOK_FRAMES", "8")
    monkeypatch.setenv("MOCAP_NOTEBOOK_OUT", str(tmp_path / "calibration.json"))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    notebook = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    NotebookClient(notebook, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    errors = [o for c in notebook.cells for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors
    if name == "calibration":
        assert (tmp_path / "calibration.json").is_file()
