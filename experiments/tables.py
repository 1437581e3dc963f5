"""Tables 1 and 2: our numbers beside the paper's, as rows, Markdown, and rendered PNG/PDF.

Table 1 (time per frame vs total evaluations, 50/50 split) comes from the timing runs, which
prepare their frames afresh and run alone (one unit at a time), over every frame of the
``timing_sequences``. Table 2 (image processing and one evaluation of each cost vs
resolution) comes from ``table2.json``.
"""
from __future__ import annotations

from pathlib import Path
from types import MappingProxyType

import numpy as np

from experiments.plan import timing_specs
from experiments.results import Results
from experiments.style import new_figure, save, style_context

#: The paper's Table 1: total -> (platform 1 mean, std, platform 2 mean, std), milliseconds.
PAPER_TABLE1 = MappingProxyType({40: (22.34, 6.58, 88.18, 9.16), 100: (35.61, 6.68, 137.24, 16.07), 200: (57.99, 6.84, 223.30, 27.51),
                300: (78.69, 6.90, 300.13, 32.74), 400: (97.25, 7.12, 370.06, 35.81), 500: (100.59, 9.80, 436.21, 48.72)})
#: The paper's Table 2: (width, height) -> (image processing, F, edge distance), milliseconds.
#: The paper prints "326 x 240"; we read it as 320 x 240.
PAPER_TABLE2 = MappingProxyType({(160, 120): (92.45, 1.05, 0.97), (256, 256): (323.53, 1.89, 1.86), (320, 240): (381.19, 2.08, 2.09),
                (480, 480): (1187.92, 3.09, 3.05), (512, 512): (1353.84, 3.74, 3.82), (640, 480): (1581.86, 5.29, 5.58)})

TABLE1_HEADER = ("evaluations (R+E)", "ours: frame ms\n(mean ± sd)", "ours: registration ms\n(mean ± sd)",
                 "ours: evaluations\nused (mean)", "paper P1 ms\n(mean ± sd)", "paper P2 ms\n(mean ± sd)")
TABLE2_HEADER = ("resolution", "triangles", "ours: image\nprocessing ms", "mocap bench\nprepare_frame ms",
                 "ours: F\neval ms", "ours: edge\neval ms", "paper: image\nprocessing ms", "paper:\nF ms", "paper:\nedge ms")


def table1_rows(results: Results) -> list[dict]:
    """Per total: mean and standard deviation of the time per frame (whole, and registration only).

    Frames of every timing sequence are pooled. Totals without stored results are left out.
    """
    cfg = results.config
    rows = []
    for total in cfg.table1_totals:
        frames, reg, evals, seqs = [], [], [], []
        for name in cfg.timing_sequences:
            u = results.unit(timing_specs(cfg, results.data(name))[total])
            if u is not None:
                frames.append(u["ms_total"])
                reg.append(u["ms_region"] + u["ms_edge"])
                evals.append(u["evaluations"])
                seqs.append(name)
        if not frames:
            continue
        f, r, e = np.concatenate(frames), np.concatenate(reg), np.concatenate(evals)
        rows.append({"total": total, "frame_mean": float(f.mean()), "frame_std": float(f.std()),
                     "reg_mean": float(r.mean()), "reg_std": float(r.std()), "evaluations_mean": float(e.mean()),
                     "frames": int(f.size), "sequences": seqs, "paper": PAPER_TABLE1.get(total)})
    return rows


def table1_cells(rows: list[dict]) -> list[tuple[str, ...]]:
    out = []
    for r in rows:
        p = r["paper"]
        out.append((str(r["total"]), f"{r['frame_mean']:.2f} ± {r['frame_std']:.2f}",
                    f"{r['reg_mean']:.2f} ± {r['reg_std']:.2f}", f"{r['evaluations_mean']:.0f}",
                    f"{p[0]:.2f} ± {p[1]:.2f}" if p else "–", f"{p[2]:.2f} ± {p[3]:.2f}" if p else "–"))
    return out


def table2_rows(results: Results) -> list[dict]:
    """Rows of ``table2.json`` with the paper's numbers at the same resolution."""
    t2 = results.table2()
    if t2 is None:
        return []
    bench = {(b["width"], b["height"]): b["median_us"] / 1e3 for b in (t2.get("bench") or {}).get("rows", [])
             if b["stage"] == "prepare_frame"}
    return [{**r, "paper": PAPER_TABLE2.get((r["width"], r["height"])), "bench_prepare_ms": bench.get((r["width"], r["height"]))}
            for r in t2["rows"]]


def table2_cells(rows: list[dict]) -> list[tuple[str, ...]]:
    out = []
    for r in rows:
        p = r["paper"]
        b = r.get("bench_prepare_ms")
        out.append((f"{r['width']} x {r['height']}", str(r["triangles"]), f"{r['prepare_ms_mean']:.2f}",
                    f"{b:.2f}" if b is not None else "–", f"{r['cost_region_ms_mean']:.3f}", f"{r['cost_edge_ms_mean']:.3f}",
                    *((f"{p[0]:.2f}", f"{p[1]:.2f}", f"{p[2]:.2f}") if p else ("–", "–", "–"))))
    return out


def markdown(header, cells) -> str:
    """A Markdown table."""
    header = [h.replace("\n", " ") for h in header]
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in cells]
    return "\n".join(lines)


def render(header, cells, title: str, note: str, out: str | Path, name: str) -> list[Path]:
    """Draw a table as a figure and save it as ``name.png`` and ``name.pdf``."""
    with style_context():
        import textwrap
        note = "\n".join(textwrap.fill(par, 150) for par in note.split("\n"))
        n = max(1, len(cells))
        note_lines = note.count("\n") + 1
        height = 0.5 + 0.24 * (n + 2) + 0.16 * note_lines
        fig = new_figure(10.0, height)
        ax = fig.add_subplot(1, 1, 1)
        ax.set_axis_off()
        note_share = 0.16 * note_lines / height
        if cells:
            table = ax.table(cellText=[list(c) for c in cells], colLabels=list(header), cellLoc="center",
                             bbox=[0.0, note_share + 0.02, 1.0, 1.0 - note_share - 0.02])
            table.auto_set_font_size(False)
            table.set_fontsize(7.5)
            for (row, _), cell in table.get_celld().items():
                if row == 0:
                    cell.set_text_props(weight="bold", fontsize=7)
                    cell.set_facecolor("#eeeeee")
        else:
            ax.text(0.5, 0.5, "no results", ha="center", va="center")
        ax.set_title(title)
        ax.text(0.0, note_share, note, fontsize=7, va="top", ha="left", transform=ax.transAxes)
        return save(fig, out, name)


def table1_note(results: Results, rows: list[dict]) -> str:
    seqs = ", ".join(results.config.timing_sequences)
    n = rows[0]["frames"] if rows else 0
    return (f"Our rows: {n} frames pooled over {seqs} at {results.config.size[0]}x{results.config.size[1]}, one unit "
            "running at a time on this CPU;\nframe = image processing + registration; evaluations used can be below "
            "the budget when the simplex converges (ftol). Paper: P1 Pentium 4 3.6 GHz + Quadro FX 1400, "
            "P2 Pentium M 1.4 GHz + GeForce 4200 Go.")


def table2_note(results: Results) -> str:
    t2 = results.table2() or {}
    return (f"Ours: mean of timed calls on {t2.get('frames', '?')} frame(s) of {t2.get('sequence', '?')} per resolution, "
            f"CPU only ({t2.get('cpu', '?')}); one evaluation = render the model + the cost; 'mocap bench': median of "
            "its own prepare_frame rows (synthetic test scene, one pinned core), a cross-check.\nPaper: Pentium 4 3.0 GHz "
            "+ GeForce 9600 GT (rendering on the GPU); its '326 x 240' row is read as 320 x 240.")
