"""Table 2: image processing and one evaluation of each cost vs resolution (the paper's six)."""
from __future__ import annotations

from pathlib import Path

from experiments.figures._common import as_results
from experiments.results import Results
from experiments.tables import TABLE2_HEADER, markdown, render, table2_cells, table2_note, table2_rows

NAME = "table2"


def main(results: Results | str | Path, out: str | Path) -> list[Path]:
    """Write ``table2.png``, ``table2.pdf`` and ``table2.md`` into ``out``."""
    res = as_results(results)
    cells = table2_cells(table2_rows(res))
    Path(out).mkdir(parents=True, exist_ok=True)
    (Path(out) / f"{NAME}.md").write_text(markdown(TABLE2_HEADER, cells) + "\n")
    return render(TABLE2_HEADER, cells, "Table 2 — average time of image processing and of one cost evaluation "
                  "vs resolution", table2_note(res), out, NAME)
