"""``python -m experiments.tracking_diff BASE NEW``: which units of two tracking runs differ.

A change to the tracker is judged by running :mod:`experiments.tracking` in both trees, each
with its own ``--out`` (a unit's file name holds its configuration, sequence and seed, not the
code, so two trees' units of one configuration would overwrite each other in one folder). Link
the new folder's ``data`` to the base folder's, so that both runs read the very same generated
sequences and the detector's cached keypoints, and nothing is generated twice::

    mkdir -p NEW && ln -s "$(realpath BASE)/data" NEW/data
    python -m experiments.tracking --configs mediapipe-keypoints --seeds 0,1,2,3,4 --unseen-seeds 97,101 --out NEW
    python -m experiments.tracking_diff BASE NEW --unseen-seeds 97,101

Units are matched by configuration name, sequence and seed, not by file name: a file's name holds
the configuration's key, which a change adding a :class:`~mocap.track.TrackerConfig` field
changes. Where a folder holds several units of one (configuration, sequence, seed), written under
other settings of that configuration, the newest file is taken and the others are counted. The new
folder's units that the base one lacks are counted, not compared. Printed (Markdown): every
matched unit whose MPJPE, heading error or evaluations differ, base → new (MPJPE and the median error about the neck in mm, the share of frames
turned round, lost, evaluations a frame); then, per configuration and seed set (the seeds tuned
on, and ``--unseen-seeds`` apart), how many units are the same to the bit of these figures, how
many changed, the turned-round and lost counts (:func:`experiments.tracking.failure_marks`)
and the mean evaluations a frame, base → new; and the paired comparison (:func:`paired_table`:
the medians over units, how many units got better or worse, and the Wilcoxon signed-rank test
of the units' differences), so that a change is judged on its units, not on two medians alone.
With ``--null NULL`` (a folder of :mod:`experiments.tracking` ``--null-offset-px`` runs: every
keypoint moved a sub-pixel distance, which moves every unit; may be given again), the same paired
table of BASE against each null follows.

Last, every draw: a unit's plain run and its null runs are draws of one noisy figure (a 0.01 px
offset moves a unit by 10 mm at the median, docs/research-log.md 2026-11-30). The base's draws
are BASE's units of every offset and the ``--null`` folders' null units; the change's, NEW's units
of every offset (run ``--null-offset-px`` into NEW too). :func:`draws_table` compares them with
:func:`stratified_rank_sum`, whose ``cluster_p`` (each seed's units one cluster) is the p value to
judge a change by: the units of one seed may move together (they seemed to under the null), and
the units-independent p of the paired table is then too small. Nothing is recomputed: the units
hold it all.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from experiments.tracking import failure_marks


@dataclass(frozen=True)
class Unit:
    """One measured (configuration, sequence, seed) of :mod:`experiments.tracking`."""

    name: str                   # the configuration's name in experiments.tracking.CONFIGS
    sequence: str
    seed: int
    mpjpe_mm: float             # mean over frames, camera coordinates
    about_neck_mm: float        # median over frames of the root-relative error
    turned_round_rate: float    # share of frames whose chest heading is over 90 degrees off
    turned_round: bool
    lost: bool
    evaluations_per_frame: float
    heading_error_deg: tuple[float, ...]

    def same_as(self, other: "Unit") -> bool:
        """The same figures to the bit (MPJPE, heading errors, evaluations)."""
        return (self.mpjpe_mm == other.mpjpe_mm and self.heading_error_deg == other.heading_error_deg
                and self.evaluations_per_frame == other.evaluations_per_frame)


#: A unit's key in :func:`read_units`: (configuration name, sequence, seed).
UnitKey = tuple[str, str, int]


def read_units(folder: str | Path, null: bool = False) -> tuple[dict[UnitKey, Unit], int]:
    """The units of an :mod:`experiments.tracking` results folder, by (configuration name,
    sequence, seed); the newest file of each, and how many older files were passed over. Only
    the null's units (``--null-offset-px``: their record's ``null_offset_px`` not 0) where
    ``null``, else only the others, so that a null run in the same folder is never compared as
    the base.

    Raises
    ------
    ValueError
        When ``folder`` holds no ``units`` folder.
    """
    out, passed_over = {}, 0
    for offset, key, unit in _read(folder):
        if bool(offset) != null:
            continue
        passed_over += key in out
        out[key] = unit
    return out, passed_over


def read_draws(folder: str | Path) -> dict[UnitKey, dict[float, Unit]]:
    """Every draw of each unit of an :mod:`experiments.tracking` results folder, by
    (configuration name, sequence, seed), then by the keypoints' null offset in pixels (0.0: the
    plain run; the others ``--null-offset-px`` runs); the newest file of each.

    Raises
    ------
    ValueError
        When ``folder`` holds no ``units`` folder.
    """
    out: dict[UnitKey, dict[float, Unit]] = {}
    for offset, key, unit in _read(folder):
        out.setdefault(key, {})[offset] = unit
    return out


def _read(folder: str | Path):
    """``(null offset in pixels, key, Unit)`` of each unit file of ``folder``, oldest first (the
    record's ``null_offset_px``; 0, or a record from before it was written: not a null run)."""
    units_dir = Path(folder) / "units"
    if not units_dir.is_dir():
        raise ValueError(f"{folder} is not an experiments.tracking results folder (no units/ in it)")
    for path in sorted(units_dir.glob("*.json"), key=lambda p: (p.stat().st_mtime_ns, p.name)):
        record = json.loads(path.read_text())
        offset = float(record.get("null_offset_px", 0.0))
        row = record["result"]
        marks = failure_marks(row)
        key = (record["name"], row["sequence"], int(record["seed"]))
        yield offset, key, Unit(record["name"], row["sequence"], int(record["seed"]), float(row["mpjpe_mm"]),
                                float(row.get("median_frame_root_relative_mm", np.nan)),
                                float(marks["turned_round_rate"]) if marks["turned_round_rate"] is not None else np.nan,
                                bool(marks["turned_round"]), bool(marks["lost"]),
                                float(row.get("evaluations_per_frame", np.nan)),
                                tuple(float(h) for h in row.get("frame_heading_error_deg", ())))


def diff_table(base: dict[UnitKey, Unit], new: dict[UnitKey, Unit], unseen: set[int]) -> str:
    """The Markdown of the changed units and the per-configuration summary (see the module)."""
    matched = sorted(set(base) & set(new), key=lambda k: (new[k].name, new[k].seed in unseen, new[k].seed,
                                                          new[k].sequence))
    lines = ["| configuration | sequence | seed | MPJPE mm | about the neck mm | turned round | lost | evaluations a frame |",
             "|---|---|---|---|---|---|---|---|"]
    for key in matched:
        a, b = base[key], new[key]
        if not a.same_as(b):
            lines.append(f"| {b.name} | {b.sequence} | {b.seed} | {a.mpjpe_mm:.1f} → {b.mpjpe_mm:.1f} | "
                         f"{a.about_neck_mm:.1f} → {b.about_neck_mm:.1f} | "
                         f"{100 * a.turned_round_rate:.1f} → {100 * b.turned_round_rate:.1f} % | "
                         f"{_yes(a.lost)} → {_yes(b.lost)} | {a.evaluations_per_frame:.0f} → {b.evaluations_per_frame:.0f} |")
    if len(lines) == 2:
        lines = ["Every matched unit is the same."]
    lines += ["", "| configuration | seeds | units same / changed | turned round | lost | evaluations a frame |",
              "|---|---|---|---|---|---|"]
    for name, label, keys in _groups(new, matched, unseen):
        same = sum(base[k].same_as(new[k]) for k in keys)
        count = lambda units, field: sum(getattr(units[k], field) for k in keys)
        evaluations = lambda units: np.mean([units[k].evaluations_per_frame for k in keys])
        lines.append(f"| {name} | {label} | {same} / {len(keys) - same} | "
                     f"{count(base, 'turned_round')} → {count(new, 'turned_round')} of {len(keys)} | "
                     f"{count(base, 'lost')} → {count(new, 'lost')} | "
                     f"{evaluations(base):.0f} → {evaluations(new):.0f} ({evaluations(new) / evaluations(base):.3f}x) |")
    lines += ["", paired_table(base, new, matched, unseen)]
    only = len(set(new) - set(base))
    if only:
        lines += ["", f"{only} unit(s) of the new folder not in the base one, not compared."]
    return "\n".join(lines)


#: A unit counts as better or worse in :func:`paired_table` when its MPJPE moved by more than this (mm).
PAIRED_MARGIN_MM = 5.0


def paired_table(base: dict[UnitKey, Unit], new: dict[UnitKey, Unit], keys: list[UnitKey],
                 unseen: set[int]) -> str:
    """The Markdown of the paired comparison of the units ``keys`` (in both folders), per
    configuration and seed set: the median over units of the MPJPE and of the median error about
    the neck (mm), base → new; how many units' MPJPE fell or rose by more than
    :data:`PAIRED_MARGIN_MM`; and the two-sided Wilcoxon signed-rank test of the units' paired
    differences (:func:`scipy.stats.wilcoxon`; exact for fewer than 50 units without ties), for
    the MPJPE and for the error about the neck ("–" where every difference is 0); and the median
    and 90th percentile of the units' absolute MPJPE differences (mm), to set beside the null's."""
    from scipy.stats import wilcoxon

    def p_value(differences: np.ndarray) -> str:
        kept = differences[np.isfinite(differences)]
        return "–" if not np.any(kept != 0) else f"{wilcoxon(kept).pvalue:.3f}"

    lines = ["| configuration | seeds | units | median MPJPE mm | median about the neck mm | "
             f"better / worse by > {PAIRED_MARGIN_MM:g} mm | Wilcoxon p: MPJPE, about the neck | "
             "MPJPE change, median / p90 of its size, mm |",
             "|---|---|---|---|---|---|---|---|"]
    for name, label, picked in _groups(new, keys, unseen):
        field = lambda units, f: np.array([getattr(units[k], f) for k in picked], dtype=np.float64)
        mpjpe = field(new, "mpjpe_mm") - field(base, "mpjpe_mm")
        neck = field(new, "about_neck_mm") - field(base, "about_neck_mm")
        lines.append(f"| {name} | {label} | {len(picked)} | "
                     f"{np.median(field(base, 'mpjpe_mm')):.1f} → {np.median(field(new, 'mpjpe_mm')):.1f} | "
                     f"{np.nanmedian(field(base, 'about_neck_mm')):.1f} → "
                     f"{np.nanmedian(field(new, 'about_neck_mm')):.1f} | "
                     f"{int(np.sum(mpjpe < -PAIRED_MARGIN_MM))} / {int(np.sum(mpjpe > PAIRED_MARGIN_MM))} | "
                     f"{p_value(mpjpe)}, {p_value(neck)} | "
                     f"{np.median(np.abs(mpjpe)):.1f} / {np.percentile(np.abs(mpjpe), 90):.1f} |")
    return "\n".join(lines)


@dataclass(frozen=True)
class RankTest:
    """The stratified rank-sum comparison of two sets of draws over units (:func:`stratified_rank_sum`)."""

    units: int              # strata (units) with at least one draw on each side
    below_share: float      # over every (new draw, base draw) pair of a unit: the share the new one is lower (ties 1/2)
    z: float                # the standardised sum of the units' Mann-Whitney counts (0: no information)
    p: float                # two-sided, normal approximation, units independent (1.0: every unit's draws tied)
    clusters: int = 0       # clusters given (0: none)
    cluster_p: float = math.nan   # two-sided, the clusters' signs flipped (NaN without clusters)


#: Clusters up to this many are sign-flipped exhaustively in :func:`stratified_rank_sum`; more, at random.
EXACT_CLUSTERS = 16
#: Random sign patterns drawn where there are more clusters (a fixed generator: the same p each call).
CLUSTER_FLIPS = 1 << 16


def stratified_rank_sum(pairs: list[tuple[np.ndarray, np.ndarray]], clusters: list | None = None) -> RankTest:
    """Whether ``new`` draws lie below ``base`` draws within units more often than chance (the
    stratified Wilcoxon rank-sum test of van Elteren, 1960, unweighted).

    Each unit is a stratum: under the null hypothesis its draws, new and base, are exchangeable
    (as :mod:`experiments.tracking`'s ``--null-offset-px`` runs are with the base's), so the
    test needs no assumption on how a unit's draws are spread, skewed or shared out between
    units. A unit's count U is the number of (new, base) pairs whose new draw is the lower (ties
    1/2); its mean under the null is ``m n / 2`` and its variance, with ties,
    ``m n / 12 ((N + 1) - sum(t^3 - t) / (N (N - 1)))`` (``m``, ``n`` draws, ``N = m + n``,
    ``t`` the sizes of its tied groups). The sum over units is compared with its mean in
    standard deviations (``p``: units independent). Units where either side has no draw are left
    out.

    Units that share something may move together from one draw to the next (under the
    keypoints' null a draw's changes clustered by seed, Kruskal-Wallis p 0.08, and subsets of a
    few seeds gave units-independent p down to 0.001: docs/research-log.md 2026-11-30). With
    ``clusters`` (one label a unit, for example its seed), ``cluster_p`` treats each cluster's
    sum of ``U - m n / 2`` as one observation, symmetric about 0 under the null, and flips their
    signs: exhaustively up to :data:`EXACT_CLUSTERS` clusters, else :data:`CLUSTER_FLIPS` random
    patterns. It needs no independence within a cluster; with few clusters it cannot be small
    (five clusters: at least 2 / 32).

    Parameters
    ----------
    pairs : list of (new, base)
        Each unit's draws of a figure (for example MPJPE, mm), shapes (m,) and (n,), float.
    clusters : list, optional
        A hashable label per unit of ``pairs``.

    Returns
    -------
    RankTest
    """
    from scipy.stats import norm, rankdata

    if clusters is not None and len(clusters) != len(pairs):
        raise ValueError(f"one cluster label a unit: {len(clusters)} labels for {len(pairs)} units")
    count = mean = variance = pairs_total = 0.0
    units = 0
    centred: dict = {}
    for i, (new, base) in enumerate(pairs):
        new, base = np.asarray(new, dtype=np.float64), np.asarray(base, dtype=np.float64)
        m, n = len(new), len(base)
        if m == 0 or n == 0:
            continue
        units += 1
        both = np.concatenate([new, base])
        total = m + n
        # U of the new draws being lower = m n + m (m + 1) / 2 - (their rank sum), ranks ascending, ties averaged
        u = m * n + m * (m + 1) / 2 - rankdata(both)[:m].sum()
        count += u
        mean += m * n / 2
        _, tied = np.unique(both, return_counts=True)
        ties = float(np.sum(tied ** 3 - tied)) / (total * (total - 1))
        variance += m * n / 12 * ((total + 1) - ties)
        pairs_total += m * n
        if clusters is not None:
            centred[clusters[i]] = centred.get(clusters[i], 0.0) + u - m * n / 2
    if units == 0:
        raise ValueError("no unit has draws on both sides")
    cluster_p = math.nan if clusters is None else _sign_flip_p(np.array(list(centred.values())))
    z = 0.0 if variance <= 0 else (count - mean) / math.sqrt(variance)
    p = 1.0 if variance <= 0 else float(2 * norm.sf(abs(z)))
    return RankTest(units, count / pairs_total, z, p, len(centred), cluster_p)


def _sign_flip_p(sums: np.ndarray) -> float:
    """Two-sided p of ``|sum(sums)|`` among the sums of ``sums`` with their signs flipped (every
    pattern, or :data:`CLUSTER_FLIPS` random ones past :data:`EXACT_CLUSTERS`); 1.0 when all are 0."""
    observed = abs(sums.sum())
    if observed == 0:
        return 1.0
    if len(sums) <= EXACT_CLUSTERS:
        patterns = (np.arange(1 << len(sums))[:, None] >> np.arange(len(sums))) & 1
    else:
        patterns = np.random.default_rng(0).integers(0, 2, (CLUSTER_FLIPS, len(sums)))
    flipped = np.abs((1 - 2 * patterns) @ sums)
    return float(np.mean(flipped >= observed * (1 - 1e-12)))


def draws_table(base: dict[UnitKey, list[Unit]], new: dict[UnitKey, list[Unit]], unseen: set[int]) -> str:
    """The Markdown of the comparison over every draw of the units in both (see the module), per
    configuration and seed set: the units, the draws a unit on each side (median), the median over
    units of each side's mean MPJPE over its draws (mm), the median spread of the base's draws
    of a unit (their standard deviation, mm; over units with at least two), the units turned
    round or lost counted per draw (each unit adds the share of its draws that are: the count
    one draw is expected to give), and :func:`stratified_rank_sum` of the MPJPE: the share of
    (new, base) draw pairs of a unit where the new one is lower, and its two-sided p with the
    units independent and with each seed's units a cluster (the one to judge by)."""
    keys = sorted(set(base) & set(new), key=lambda k: (k[0], k[2] in unseen, k[2], k[1]))
    lines = ["| configuration | seeds | units | draws a unit, base / new | median MPJPE over units (mean of its draws) mm | "
             "spread of a unit's base draws, median SD mm | turned round or lost, per draw | "
             "new draw below a base draw | stratified rank-sum p: units, seeds as clusters |",
             "|---|---|---|---|---|---|---|---|---|"]
    first = {k: new[k][0] for k in keys}
    for name, label, picked in _groups(first, keys, unseen):
        mpjpe = lambda draws: np.array([u.mpjpe_mm for u in draws])
        failed = lambda draws: float(np.mean([u.turned_round or u.lost for u in draws]))
        spreads = [np.std(mpjpe(base[k]), ddof=1) for k in picked if len(base[k]) > 1]
        test = stratified_rank_sum([(mpjpe(new[k]), mpjpe(base[k])) for k in picked], clusters=[k[2] for k in picked])
        spread = f"{np.median(spreads):.1f}" if spreads else "–"
        lines.append(f"| {name} | {label} | {len(picked)} | "
                     f"{np.median([len(base[k]) for k in picked]):g} / {np.median([len(new[k]) for k in picked]):g} | "
                     f"{np.median([mpjpe(base[k]).mean() for k in picked]):.1f} → "
                     f"{np.median([mpjpe(new[k]).mean() for k in picked]):.1f} | {spread} | "
                     f"{sum(failed(base[k]) for k in picked):.1f} → {sum(failed(new[k]) for k in picked):.1f} | "
                     f"{100 * test.below_share:.1f} % | {test.p:.3f}, {test.cluster_p:.3f} |")
    return "\n".join(lines)


def _groups(units: dict[UnitKey, Unit], keys: list[UnitKey], unseen: set[int]):
    """``(configuration, seed set, keys)`` for each configuration of ``keys`` and each of its seed
    sets ("tuned on": seeds not in ``unseen``; "never used") that holds units."""
    for name in sorted({units[k].name for k in keys}):
        for label, pick in (("tuned on", lambda u: u.seed not in unseen), ("never used", lambda u: u.seed in unseen)):
            picked = [k for k in keys if units[k].name == name and pick(units[k])]
            if picked:
                yield name, label, picked


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.tracking_diff", description=__doc__.split("\n\n")[0])
    p.add_argument("base", type=Path, help="the results folder compared against (its units/)")
    p.add_argument("new", type=Path, help="the results folder of the change")
    p.add_argument("--unseen-seeds", default="", help="comma-separated seeds never used for tuning: summed apart")
    p.add_argument("--null", type=Path, action="append", default=[],
                   help="a results folder of the null (experiments.tracking --null-offset-px; may be given "
                        "again): its paired table against BASE is printed under the change's, and its units "
                        "join BASE's draws")
    args = p.parse_args(argv)
    try:
        unseen = {int(s) for s in args.unseen_seeds.split(",") if s.strip()}
        (base, base_older), (new, new_older) = read_units(args.base), read_units(args.new)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for folder, older in ((args.base, base_older), (args.new, new_older)):
        if older:
            print(f"{folder}: {older} older unit file(s) of the same configuration, sequence and seed passed over "
                  "(the newest taken)", file=sys.stderr)
    if not set(base) & set(new):
        print(f"error: no unit of {args.new} is in {args.base} (same configurations, sequences and seeds?)",
              file=sys.stderr)
        return 2
    print(diff_table(base, new, unseen))
    # the base's draws: its folder's plain and null units, and the null units of each --null
    # folder (a folder given twice counts once)
    base_draws = {(args.base.resolve(), key, offset): u for key, draws in read_draws(args.base).items()
                  for offset, u in draws.items()}
    for folder in args.null:
        try:
            null, _ = read_units(folder, null=True)
        except ValueError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        keys = sorted(set(base) & set(null), key=lambda k: (k[0], k[2] in unseen, k[2], k[1]))
        if not keys:
            print(f"error: no null unit in {folder} matches {args.base} (run experiments.tracking "
                  "--null-offset-px with the same configurations, sequences and seeds)", file=sys.stderr)
            return 2
        print(f"\nThe null ({args.base} → {folder}: nothing changed but the keypoints' sub-pixel offset):\n")
        print(paired_table(base, null, keys, unseen))
        base_draws.update({(folder.resolve(), key, offset): u for key, draws in read_draws(folder).items()
                           for offset, u in draws.items() if offset})
    grouped: dict[UnitKey, list[Unit]] = {}
    for (_, key, _), unit in base_draws.items():
        grouped.setdefault(key, []).append(unit)
    print(f"\nEvery draw (the units' plain runs and their nulls; {args.base}"
          f"{''.join(f', {f}' for f in args.null)} against {args.new}):\n")
    print(draws_table(grouped, {k: list(d.values()) for k, d in read_draws(args.new).items()}, unseen))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
