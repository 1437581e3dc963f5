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
keypoint moved a sub-pixel distance, which moves every unit), the same paired table of BASE
against the null follows: a change is real only where it stands out of that noise
(docs/research-log.md, 2026-11-30). Nothing is recomputed: the units hold it all.
"""
from __future__ import annotations

import argparse
import json
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
    units_dir = Path(folder) / "units"
    if not units_dir.is_dir():
        raise ValueError(f"{folder} is not an experiments.tracking results folder (no units/ in it)")
    out, passed_over = {}, 0
    for path in sorted(units_dir.glob("*.json"), key=lambda p: (p.stat().st_mtime_ns, p.name)):
        record = json.loads(path.read_text())
        if (bool(record.get("null_offset_px", 0.0)) or "-null" in path.stem) != null:
            continue
        row = record["result"]
        marks = failure_marks(row)
        key = (record["name"], row["sequence"], int(record["seed"]))
        passed_over += key in out
        out[key] = Unit(record["name"], row["sequence"], int(record["seed"]), float(row["mpjpe_mm"]),
                        float(row.get("median_frame_root_relative_mm", np.nan)),
                        float(marks["turned_round_rate"]) if marks["turned_round_rate"] is not None else np.nan,
                        bool(marks["turned_round"]), bool(marks["lost"]),
                        float(row.get("evaluations_per_frame", np.nan)),
                        tuple(float(h) for h in row.get("frame_heading_error_deg", ())))
    return out, passed_over


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
    p.add_argument("--null", type=Path, default=None,
                   help="a results folder of the null (experiments.tracking --null-offset-px): its paired "
                        "table against BASE is printed under the change's, the noise to judge it by")
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
    if args.null is not None:
        try:
            null, _ = read_units(args.null, null=True)
        except ValueError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        keys = sorted(set(base) & set(null), key=lambda k: (k[0], k[2] in unseen, k[2], k[1]))
        if not keys:
            print(f"error: no null unit in {args.null} matches {args.base} (run experiments.tracking "
                  "--null-offset-px with the same configurations, sequences and seeds)", file=sys.stderr)
            return 2
        print(f"\nThe null ({args.base} → {args.null}: nothing changed but the keypoints' sub-pixel offset):\n")
        print(paired_table(base, null, keys, unseen))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
