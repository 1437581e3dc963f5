"""Table 1: time per frame vs total evaluations with a 50/50 split (mean and standard deviation)."""
from __future__ import annotations

from pathlib import Path

from experiments.figures._common import as_results
from experiments.results import Results
from experiments.tables import TABLE1_HEADER, markdown, render, table1_cells, table1_note, table1_rows

NAME = "table1"


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``table1.png``, ``table1.pdf`` and ``table1.md`` into ``out``."""
    res = as_results(results)
    rows = table1_rows(res)
    cells = table1_cells(rows)
    Path(out).mkdir(parents=True, exist_ok=True)
    (Path(out) / f"{NAME}.md").write_text(markdown(TABLE1_HEADER, cells) + "\n")
    return render(TABLE1_HEADER, cells, "Table 1 — computation time per frame vs evaluations (50% region, 50% edge)",
                  table1_note(res, rows), out, NAME)
