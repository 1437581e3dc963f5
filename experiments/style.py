"""One look for every figure and table, and one way to save them (PNG + PDF).

Figures are :class:`matplotlib.figure.Figure` objects made without pyplot, so nothing global
(backend, current figure) is touched: the same code runs in scripts, tests and notebooks.
Files carry no time stamps, so the same results give the same PNG bytes.
"""
from __future__ import annotations

from pathlib import Path
from types import MappingProxyType

import matplotlib
from matplotlib.figure import Figure

#: Seed of anything random in figures (jitter, sampling).
SEED = 0
#: rcParams of every figure.
STYLE = MappingProxyType({
    "font.size": 8.5, "axes.titlesize": 9, "axes.labelsize": 8.5, "legend.fontsize": 7.5,
    "xtick.labelsize": 7.5, "ytick.labelsize": 7.5, "axes.grid": True, "grid.alpha": 0.3,
    "axes.spines.top": False, "axes.spines.right": False, "lines.linewidth": 1.2,
    "figure.dpi": 100, "savefig.dpi": 130, "savefig.bbox": "tight", "pdf.fonttype": 42,
})
#: The paper's line colours: black at convergence / with the hand-off, grey otherwise.
BLACK, GREY = "#000000", "#8c8c8c"
#: Colours of the split policies (colour-blind safe).
POLICY_COLOURS = MappingProxyType({"auto": "#000000", "1:1": "#0072B2", "1:0": "#D55E00", "0:1": "#009E73"})
#: Colour map of surfaces and heat maps.
CMAP = "viridis"
#: File formats written for every figure and table.
FORMATS = ("png", "pdf")


def new_figure(width_in: float, height_in: float) -> Figure:
    """A figure in the shared style (the style is applied when the figure is drawn and saved)."""
    with matplotlib.rc_context(STYLE):
        return Figure(figsize=(width_in, height_in), layout="constrained")


def style_context():
    """Context manager applying :data:`STYLE` (wrap the drawing code of a figure in it)."""
    return matplotlib.rc_context(STYLE)


def save(fig: Figure, out: str | Path, name: str) -> list[Path]:
    """Write ``fig`` as ``out/name.png`` and ``out/name.pdf``.

    Returns
    -------
    list of Path
        The files written.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    with matplotlib.rc_context(STYLE):
        for fmt in FORMATS:
            path = out / f"{name}.{fmt}"
            metadata = {"Software": None} if fmt == "png" else {"Creator": None, "Producer": None, "CreationDate": None}
            fig.savefig(path, format=fmt, metadata=metadata)
            if fmt == "png":
                _shrink_png(path)
            paths.append(path)
    return paths


def _shrink_png(path: Path) -> None:
    """Re-encode a PNG with a 256-colour palette (figures have few colours; files get ~3x smaller)."""
    from PIL import Image

    with Image.open(path) as image:
        small = image.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    small.save(path, format="PNG", optimize=True)


def placeholder(ax, text: str) -> None:
    """Write ``text`` in the middle of an empty axes (missing results)."""
    ax.set_axis_off()
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, wrap=True, color=GREY)
