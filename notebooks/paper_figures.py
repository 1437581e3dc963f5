# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # The paper's figures from stored sweep results
#
# Regenerates every table and figure of the paper's experimental section (Tables 1-2,
# Figs. 4, 6, 8-12) and ours beyond it (MPJPE surfaces, split policies, thresholds, every
# sequence, motion-capture clips) from the results of `python -m experiments.sweep`, without
# running the tracker again.
#
# With no results in `experiments/results/quick/`, the next cell makes them first: it runs
# `python -m experiments.sweep --quick` (a few minutes on two cores; run it in a terminal to
# watch its progress). The full sweep: `python -m experiments.sweep --motion-dir ../shared/data/mocap`,
# then `MOCAP_RESULTS=experiments/results/full`. Set `MOCAP_RESULTS` to another results folder,
# `MOCAP_FIGURES_OUT` to another output folder and `MOCAP_FIGURES_ONLY` to a comma-separated
# subset of the figures (the tests run this notebook on a tiny sweep that way).

# %% tags=["parameters"]
import os
from pathlib import Path

from experiments import RESULTS_DIR
from experiments.sweep import CONFIG_FILE

RESULTS = Path(os.environ.get("MOCAP_RESULTS", RESULTS_DIR / "quick"))
OUT = Path(os.environ.get("MOCAP_FIGURES_OUT", RESULTS / "figures"))
ONLY = os.environ.get("MOCAP_FIGURES_ONLY", "")

if "MOCAP_RESULTS" not in os.environ and not (RESULTS / CONFIG_FILE).is_file():
    from experiments.sweep import main as sweep   # no results yet: the quick sweep, into RESULTS

    if sweep(["--quick", "--out", str(RESULTS)]) != 0:
        raise RuntimeError("the quick sweep failed (see above); run `python -m experiments.sweep --quick` "
                           "in a terminal")

# %% [markdown]
# ## What the sweep ran

# %%
from IPython.display import Image, Markdown, display

from experiments.results import Results

results = Results(RESULTS)
cfg = results.config
display(Markdown(
    f"- sequences: {', '.join(cfg.sequences)} ({cfg.frames} frames, {cfg.size[0]}x{cfg.size[1]})\n"
    f"- grid: region {list(cfg.region_budgets)} x edge {list(cfg.edge_budgets)} evaluations per frame\n"
    f"- failure thresholds: F > {cfg.figure_failure_f:g}, edge distance > {cfg.figure_failure_edge_px:g} px, "
    f"MPJPE > {cfg.mpjpe_failure_mm:g} mm\n"
    f"- clips: {len(results.clips)}; wall time so far: {results.wall_time_s() / 60:.1f} min"))

# %% [markdown]
# ## Every table and figure (PNG + PDF into `OUT`)

# %%
from experiments.figures import FIGURES, make_all

names = tuple(n.strip() for n in ONLY.split(",") if n.strip()) or FIGURES
written = make_all(results, OUT, names)
print(f"{len(written)} files written to {OUT}")

# %%
for name in names:
    display(Markdown(f"### {name}"))
    display(Image(filename=str(OUT / f"{name}.png")))

# %% [markdown]
# ## The paper's claims in numbers

# %%
from experiments import analysis

claims = analysis.all_claims(results)
conv, prec, hand = claims["convergence"], claims["precision"], claims["handoff"]
display(Markdown(
    f"- region step reaches 90% of its F drop at R={conv['region_budget_90']:g}; "
    f"edge step 90% of its edge-distance drop at E={conv['edge_budget_90']:g}\n"
    f"- converged: edge distance {prec['D_after_region']:.3f} px after region, {prec['D_after_edge']:.3f} px after edge\n"
    f"- hand-off at {cfg.handoff_total} evaluations: edge distance {hand['mean_D_small']:.3f} px (region simplex) vs "
    f"{hand['mean_D_fresh']:.3f} px (fresh simplex)"))
