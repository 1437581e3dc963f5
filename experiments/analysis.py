"""Numbers behind the paper's claims (sections 4-5), computed from stored results.

Each function returns plain dicts of numbers so that the report, the notebook and tests can
use them. Claims checked:

* **convergence** — the region step converges faster than the edge step (Figs. 9, 10);
* **precision** — the edge step is more precise than the region step (Figs. 6, 7);
* **stability** — the edge step is less stable (more failures) than the region step (Figs. 11, 12);
* **policy** — below 200 evaluations all should go to the region step, from 200 on 50/50 (section 5);
* **handoff** — starting the edge step from the region step's small final simplex beats a
  large fresh simplex (Fig. 8);
* **hardest** — the turning sequence (the paper's sequence 6) fails most.
"""
from __future__ import annotations

import math

import numpy as np

from experiments.plan import convergence_specs, handoff_specs, policy_specs
from experiments.results import Results
from mocap.track import split_budget

#: Fraction of the total improvement that counts as "converged" along a budget axis.
CONVERGED_FRACTION = 0.9


def _nanmean(values) -> float:
    a = np.asarray(values, dtype=float)
    return float(np.nanmean(a)) if np.isfinite(a).any() else math.nan


def named(res: Results):
    """Data specs of the named sequences."""
    return [res.data(n) for n in res.sequences]


def surface_minima(res: Results) -> dict:
    """Minimum of each surface (figure sequence and mean over sequences) and where it is.

    Returns
    -------
    dict
        ``{stat: {"figure": (value, R, E), "all": (value, R, E)}}`` for mean F, mean edge
        distance, failures of F, of edge distance, MPJPE and ground-truth failures (failures:
        frames on the figure sequence, percent of frames over all sequences).
    """
    out = {}
    for stat in ("mean_F", "mean_D", "fail_F", "fail_D", "mpjpe", "fail_gt"):
        entry = {}
        for key, (rs, es, z) in (("figure", res.surface(res.data(res.config.figure_sequence), stat)),
                                 ("all", res.mean_surface(named(res), stat))):
            if np.isfinite(z).any():
                i, j = np.unravel_index(np.nanargmin(z), z.shape)
                entry[key] = (float(z[i, j]), int(rs[i]), int(es[j]))
                entry[key + "_at_0_0"] = float(z[0, 0]) if rs[0] == 0 and es[0] == 0 else math.nan
            else:
                entry[key] = (math.nan, -1, -1)
                entry[key + "_at_0_0"] = math.nan
        out[stat] = entry
    return out


def budget_to_converge(budgets, values, fraction: float = CONVERGED_FRACTION) -> float:
    """Smallest budget whose value has made ``fraction`` of the total drop from ``values[0]``.

    NaN when there is no drop (or no data).
    """
    v = np.asarray(values, dtype=float)
    if not np.isfinite(v).all() or v.size < 2:
        return math.nan
    drop = v[0] - np.min(v)
    if drop <= 0:
        return math.nan
    reached = np.nonzero(v[0] - v >= fraction * drop)[0]
    return float(np.asarray(budgets)[reached[0]])


def convergence(res: Results) -> dict:
    """Claim "region converges faster": budgets to reach 90% of each cost's drop, and iterations.

    ``holds_budget``: the region axis reaches 90% of the drop of mean F at a smaller budget
    than the edge axis reaches 90% of the drop of mean edge distance. ``holds_iterations``:
    the region step meets the convergence test in fewer iterations (median) than the edge step
    started from a fresh simplex.

    Along the region axis (edge budget 0) for mean F, along the edge axis (region budget 0)
    for mean edge distance, on the mean over sequences; and the median iterations each step
    takes to meet the convergence test in the converged runs.
    """
    rs, es, zf = res.mean_surface(named(res), "mean_F")
    _, _, zd = res.mean_surface(named(res), "mean_D")
    r_curve, e_curve = zf[:, 0], zd[0, :]
    region_budget = budget_to_converge(rs, r_curve)
    edge_budget = budget_to_converge(es, e_curve)
    reg_it, edge_it, reg_ev = [], [], []
    for d in named(res):
        specs = convergence_specs(res.config, d)
        u = res.unit(specs["region_converged"])
        if u is not None:
            reg_it.append(u["region_iterations"])
            reg_ev.append(u["evaluations"])
        u = res.unit(specs["both_converged_fresh"])
        if u is not None:
            edge_it.append(u["edge_iterations"])
    med = lambda parts: float(np.median(np.concatenate(parts))) if parts else math.nan
    out = {"region_budget_90": region_budget, "edge_budget_90": edge_budget,
           "F_curve": (rs.tolist(), r_curve.tolist()), "D_curve": (es.tolist(), e_curve.tolist()),
           "region_iterations_median": med(reg_it), "edge_iterations_median": med(edge_it),
           "region_evaluations_median": med(reg_ev),
           "holds_budget": bool(np.isfinite(region_budget) and np.isfinite(edge_budget) and region_budget < edge_budget)}
    out["holds_iterations"] = bool(out["region_iterations_median"] < out["edge_iterations_median"])
    out["holds"] = out["holds_budget"] and out["holds_iterations"]
    return out


def precision(res: Results) -> dict:
    """Claim "edge step more precise": converged runs, edge distance and MPJPE after each step.

    The edge step of the converged runs starts from a fresh simplex (``both_converged_fresh``);
    the same numbers with the collapsed region simplex handed over are ``*_handoff``.
    """
    before, after, improved, frames = [], [], 0, 0
    mp_region, mp_both, handed, handed_it, mp_handed = [], [], [], [], []
    for d in named(res):
        specs = convergence_specs(res.config, d)
        h = res.unit(specs["both_converged"])
        if h is not None:
            handed.append(np.nanmean(h["edge_residual"]))
            handed_it.append(h["edge_iterations"])
            mp_handed.append(np.mean(h["mpjpe_mm"]))
        u = res.unit(specs["both_converged_fresh"])
        if u is not None:
            before.append(np.nanmean(u["edge_residual_after_region"]))
            after.append(np.nanmean(u["edge_residual"]))
            improved += int(np.count_nonzero(u["edge_residual"] < u["edge_residual_after_region"] - 1e-9))
            frames += u["frame"].size
            mp_both.append(np.mean(u["mpjpe_mm"]))
        u = res.unit(specs["region_converged"])
        if u is not None:
            mp_region.append(np.mean(u["mpjpe_mm"]))
    m = surface_minima(res)
    rs, es, zm = res.mean_surface(named(res), "mpjpe")
    best_no_edge = float(np.nanmin(zm[:, 0])) if np.isfinite(zm[:, 0]).any() else math.nan
    best_with_edge = float(np.nanmin(zm[:, 1:])) if np.isfinite(zm[:, 1:]).any() else math.nan
    out = {"D_after_region": _nanmean(before), "D_after_edge": _nanmean(after),
           "frames_improved": improved, "frames": frames,
           "mpjpe_region_converged": _nanmean(mp_region), "mpjpe_both_converged": _nanmean(mp_both),
           "D_after_edge_handoff": _nanmean(handed), "mpjpe_both_converged_handoff": _nanmean(mp_handed),
           "edge_iterations_handoff_median": float(np.median(np.concatenate(handed_it))) if handed_it else math.nan,
           "mpjpe_best_without_edge": best_no_edge, "mpjpe_best_with_edge": best_with_edge,
           "minima": m}
    out["holds_image"] = bool(out["D_after_edge"] < out["D_after_region"])
    out["holds_truth"] = bool(out["mpjpe_both_converged"] < out["mpjpe_region_converged"])
    return out


def stability(res: Results) -> dict:
    """Claim "edge step less stable": failures along each axis and ground-truth failures.

    Compares, over all sequences (percent of frames): failures of F with the region step
    alone (edge budget 0, region budget > 0) against failures of the edge distance with the
    edge step alone (region budget 0, edge budget > 0); and ground-truth failures and MPJPE of
    the all-region and all-edge policies at the same totals; and how often, along each axis,
    the failures rise although the budget rises (the paper reads instability off the bumps of
    Figs. 11 and 12).
    """
    _, _, ff = res.mean_surface(named(res), "fail_F")
    _, _, fd = res.mean_surface(named(res), "fail_D")
    _, _, fg = res.mean_surface(named(res), "fail_gt")
    out = {"fail_F_region_only": _nanmean(ff[1:, 0]), "fail_D_edge_only": _nanmean(fd[0, 1:]),
           "fail_gt_region_only": _nanmean(fg[1:, 0]), "fail_gt_edge_only": _nanmean(fg[0, 1:]),
           "fail_F_at_0_0": float(ff[0, 0]), "fail_D_at_0_0": float(fd[0, 0]), "fail_gt_at_0_0": float(fg[0, 0])}
    ups_f = ups_d = steps = 0
    for d in named(res):                 # "instability": failures that rise although the budget rises
        _, _, zf = res.surface(d, "fail_F")
        _, _, zd = res.surface(d, "fail_D")
        ups_f += int(np.count_nonzero(np.diff(zf[:, 0]) > 0))
        ups_d += int(np.count_nonzero(np.diff(zd[0, :]) > 0))
        steps += zf.shape[0] - 1
    out.update(rises_fail_F_region_axis=ups_f, rises_fail_D_edge_axis=ups_d, rises_steps=steps)
    pol = policy_summary(res)
    if "1:0" in pol and "0:1" in pol:
        out["policy_fail_gt_all_region"] = _nanmean(pol["1:0"]["fail_gt"])
        out["policy_fail_gt_all_edge"] = _nanmean(pol["0:1"]["fail_gt"])
        out["policy_mpjpe_all_region"] = _nanmean(pol["1:0"]["mpjpe"])
        out["policy_mpjpe_all_edge"] = _nanmean(pol["0:1"]["mpjpe"])
    out["holds_truth"] = bool(out["fail_gt_edge_only"] > out["fail_gt_region_only"])
    out["holds_image"] = bool(ups_d > ups_f)
    return out


def policy_summary(res: Results) -> dict:
    """``{policy: {stat: list over policy_totals}}``, means over sequences (failures in % of frames)."""
    cfg = res.config
    out = {}
    for policy in cfg.policies:
        row = {}
        for stat in ("mpjpe", "mean_F", "mean_D", "fail_F", "fail_D", "fail_gt", "ms_total", "ms_median"):
            vals = np.array([[res.stat(policy_specs(cfg, d)[(policy, t)], stat) for t in cfg.policy_totals]
                             for d in named(res)])
            if stat.startswith("fail_"):
                frames = np.array([[res.stat(policy_specs(cfg, d)[(policy, t)], "frames") for t in cfg.policy_totals]
                                   for d in named(res)])
                with np.errstate(all="ignore"):
                    row[stat] = (100.0 * np.nansum(vals, axis=0)
                                 / np.nansum(np.where(np.isnan(vals), np.nan, frames), axis=0)).tolist()
            else:
                row[stat] = [_nanmean(vals[:, k]) for k in range(vals.shape[1])]
        out[policy] = row
    return out


def policy(res: Results) -> dict:
    """Claim "the 200-evaluation policy": all-region vs 50/50 below and from 200 on.

    For each total: the best policy by MPJPE and by failures of F (the paper's criterion),
    and whether all-region beats 50/50 below 200 and 50/50 beats all-region from 200 on.
    """
    cfg = res.config
    pol = policy_summary(res)
    totals = list(cfg.policy_totals)
    rows = []
    for k, t in enumerate(totals):
        fixed = {p: pol[p]["mpjpe"][k] for p in pol if p != "auto" and np.isfinite(pol[p]["mpjpe"][k])}
        same = [p for p in pol if p != "auto" and split_budget(t, p) == split_budget(t, "auto")] if "auto" in pol else []
        rows.append({"total": t, "best_mpjpe": min(fixed, key=fixed.get) if fixed else None,
                     "auto_same_as": same[0] if same else None,
                     **{f"{p}_mpjpe": pol[p]["mpjpe"][k] for p in pol},
                     **{f"{p}_fail_F": pol[p]["fail_F"][k] for p in pol},
                     **{f"{p}_fail_gt": pol[p]["fail_gt"][k] for p in pol},
                     **{f"{p}_ms": pol[p]["ms_median"][k] for p in pol}})
    out = {"rows": rows, "summary": pol}
    if "1:0" in pol and "1:1" in pol:
        below = [k for k, t in enumerate(totals) if t < 200]
        above = [k for k, t in enumerate(totals) if t >= 200]
        d = lambda stat, ks: [pol["1:0"][stat][k] - pol["1:1"][stat][k] for k in ks]  # >0: 50/50 better
        out["below_region_better_mpjpe"] = sum(v < 0 for v in d("mpjpe", below))
        out["above_half_better_mpjpe"] = sum(v > 0 for v in d("mpjpe", above))
        out["below_region_better_fail_F"] = sum(v < 0 for v in d("fail_F", below))
        out["above_half_better_fail_F"] = sum(v > 0 for v in d("fail_F", above))
        out["n_below"], out["n_above"] = len(below), len(above)
        out["holds_truth"] = bool(out["below_region_better_mpjpe"] > len(below) / 2
                                  and out["above_half_better_mpjpe"] > len(above) / 2)
    if "auto" in pol:
        means = {p: _nanmean(pol[p]["mpjpe"]) for p in pol}
        out["mean_mpjpe_over_totals"] = means
        out["auto_rank"] = [1 + sum(pol[p]["mpjpe"][k] < pol["auto"]["mpjpe"][k] for p in pol if p != "auto")
                            for k in range(len(totals))]          # 1 = no fixed split is better
    return out


def handoff(res: Results) -> dict:
    """Claim "small-simplex hand-off beats a large one" (Fig. 8): mean over sequences per edge budget."""
    cfg = res.config
    es = [e for e in cfg.handoff_edge_budgets if 0 < e < cfg.handoff_total]   # both steps run: the start matters
    rows = []
    for e in es:
        row = {"edge": e}
        for start in ("region_simplex", "fresh"):
            for stat in ("mean_D", "mpjpe", "fail_gt"):
                row[f"{start}_{stat}"] = _nanmean([res.stat(handoff_specs(cfg, d)[(e, start)], stat) for d in named(res)])
        rows.append(row)
    wins_d = sum(r["region_simplex_mean_D"] < r["fresh_mean_D"] for r in rows)
    wins_m = sum(r["region_simplex_mpjpe"] < r["fresh_mpjpe"] for r in rows)
    return {"rows": rows, "wins_D": wins_d, "wins_mpjpe": wins_m, "n": len(rows),
            "mean_D_small": _nanmean([r["region_simplex_mean_D"] for r in rows]),
            "mean_D_fresh": _nanmean([r["fresh_mean_D"] for r in rows]),
            "mpjpe_small": _nanmean([r["region_simplex_mpjpe"] for r in rows]),
            "mpjpe_fresh": _nanmean([r["fresh_mpjpe"] for r in rows]),
            "holds_image": bool(rows) and wins_d > len(rows) / 2, "holds_truth": bool(rows) and wins_m > len(rows) / 2}


def hardest(res: Results) -> dict:
    """Claim "sequence 6 (turning) fails most": failures over the whole grid per sequence (% of frames)."""
    out = {}
    for name in res.sequences:
        d = res.data(name)
        row = {}
        for stat in ("fail_F", "fail_D", "fail_gt", "mpjpe"):
            _, _, z = res.surface(d, stat)
            if stat == "mpjpe":
                row[stat] = _nanmean(z)
            else:
                _, _, n = res.surface(d, "frames")
                row[stat] = 100.0 * float(np.nansum(z) / np.nansum(np.where(np.isnan(z), np.nan, n))) \
                    if np.isfinite(z).any() else math.nan
        out[name] = row
    rank = {stat: sorted(out, key=lambda s: -out[s][stat] if np.isfinite(out[s][stat]) else math.inf)
            for stat in ("fail_F", "fail_D", "fail_gt", "mpjpe")}
    return {"per_sequence": out, "rank": rank, "holds_truth": bool(rank["fail_gt"] and rank["fail_gt"][0] == "turning")}


def stalled_edge_share(res: Results, region: int, edge: int) -> float:
    """Share of frames (all sequences) in grid cell (region, edge) where the edge step made no iteration."""
    from experiments.plan import grid_specs
    parts = [u["edge_iterations"] for d in named(res)
             if (u := res.unit(grid_specs(res.config, d, (region,), (edge,))[(region, edge)])) is not None]
    return float(np.mean(np.concatenate(parts) == 0)) if parts else math.nan


def all_claims(res: Results) -> dict:
    """Every analysis above in one dict."""
    return {"minima": surface_minima(res), "convergence": convergence(res), "precision": precision(res),
            "stability": stability(res), "policy": policy(res), "handoff": handoff(res), "hardest": hardest(res)}
