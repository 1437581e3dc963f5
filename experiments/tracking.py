"""``python -m experiments.tracking``: the tracker's ablation over the six benchmark sequences.

Every named configuration of :data:`CONFIGS` (the default tracker; the paper's method; the
beam width K, the decoding lag L, the pose prior, the kinematic jumps, online against offline
decoding) tracks each synthetic sequence (full length, 160x120, true calibration) for each
generator seed, through :func:`experiments.ambiguity.measure`: MPJPE, root-relative MPJPE
(about the neck), PA-MPJPE, frames over 100 mm, the flip-oracle and cost-equivalence shares,
the acceleration error of the written poses (about the neck; issue 39) beside the decoded
poses' (before the smoother) and the naive baseline's (a centred mean over +-4 frames of the
decoded joints), the tracking time per frame on one core, and the units (configuration, sequence,
seed) that failed as a whole (issue 49): "turned round", the written chest heading over
:data:`TURNED_ROUND_DEG` from the truth's on more than :data:`TURNED_ROUND_SHARE` of the frames,
and "lost", the median error about the neck over :data:`LOST_MM` (:func:`failure_marks`; counted
"N of M" per configuration). A second table gives each
sequence's acceleration errors and per-frame median errors, written / decoded / naive, how far
the written poses stray from the decoded ones (the largest joint distance, and the largest step of
the written heading from one frame to the next: issue 44), and whether it turned round or was lost.

``mediapipe-keypoints`` gives the tracker what a user has: MediaPipe Pose's keypoints on the
rendered frames, as ``--keypoints mediapipe`` runs it (image mode, at 160x120; detected once and
kept in the sequence's folder, :func:`experiments.keypoints.detector_keypoints`; needs the
keypoints extra). A third table then sets ours beside MediaPipe's own 3D on the same frames: the
detector's label swaps, and the arms' PA-MPJPE and acceleration error of both, with their ratios.

One JSON file per (configuration, sequence, seed) under ``--out`` (written atomically: an
interrupted run resumes where it stopped). Prints the Markdown table (medians over sequences,
failure shares over all frames pooled); with ``--report`` it also draws the ablation figure
(:mod:`experiments.figures.ext_tracking`) and writes both into ``experiments/REPORT.md`` between
the markers of :data:`REPORT_SECTION` (generated, never hand-edited; ``experiments.report``
keeps the section when it rewrites the rest).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from types import MappingProxyType

import numpy as np

from experiments import RESULTS_DIR
from mocap.io.files import write_json
from mocap.metrics import DEFAULT_FAILURE_MM
from mocap.synth import SEQUENCE_NAMES
from mocap.track import TrackerConfig

#: Name of the generated section of ``experiments/REPORT.md``.
REPORT_SECTION = "tracking"

#: A frame is turned round when its written chest heading is more than this from the truth's
#: (degrees, on the circle: :func:`experiments.ambiguity.heading_error_deg`) ...
TURNED_ROUND_DEG = 90.0
#: ... and a unit (configuration, sequence, seed) is turned round when more than this share of
#: its frames are (issue 49, item 6).
TURNED_ROUND_SHARE = 0.2
#: A unit is lost when the median over its frames of the error about the neck (root-relative
#: MPJPE, :func:`mocap.metrics.root_relative_mpjpe`) is over this (mm; issue 49, item 6).
LOST_MM = 300.0

#: Named tracker configurations: changes from the defaults (``"paper"`` is the paper's method;
#: ``"single"`` one hypothesis with recovery and hand re-acquisition, no jumps, no lag;
#: ``"two-class"`` the default tracker on the paper's two-class model).
CONFIGS = MappingProxyType({
    "default": {},
    "paper": None,
    "single": {"beam": 1, "jumps": False, "lag": 0},
    "K1": {"beam": 1},
    "K5": {"beam": 5},
    "L0": {"lag": 0},
    "L16": {"lag": 16},
    "offline": {"offline": True},
    "no-prior": {"prior_weight": 0.0},
    "no-jumps": {"jumps": False},
    "two-class": {},
    # given the oracle's 2D keypoints (ORACLE_KEYPOINTS): the default tracker (the learned lifter's
    # proposals and its score, issue 29), and without the lifter (lifter_weight 0 switches it off:
    # the keypoint term alone; issue 34)
    "oracle-keypoints": {},
    "oracle-no-lifter": {"lifter_weight": 0.0},
    "oracle-no-labelling": {"labelling_weight": 0.0},
    # every frame's lowest proposals refined, near the leader's pose or not (issue 50 item 6)
    "oracle-ungated": {"proposal_gate": None},
    # the beam's other hypotheses (and re-acquisition) refined with 100 evaluations, not 150 (issue 50 item 6;
    # did not pay with MediaPipe's keypoints: docs/research-log.md)
    "oracle-h100": {"hypothesis_evaluations": 100},
    # the body mesh at resolution 6 (264 triangles) instead of 160x120's 8 (416): issue 50 item 2
    "oracle-r6": {"mesh_resolution": 6},
    # the oracle's keypoints with left and right swapped on runs of half the frames, and on every
    # frame (SWAPPED_KEYPOINTS; a detector that does not see the face, issue 44)
    "oracle-swapped": {},
    "oracle-swapped-all": {},
    # MediaPipe Pose's keypoints on the rendered frames, as `--keypoints mediapipe` runs it (image mode,
    # 160x120): the detector a user has, its errors and labels as they come (DETECTOR_KEYPOINTS)
    "mediapipe-keypoints": {},
    # the same without the labelling term (issue 49: the detector's front against a swapped reading)
    "mediapipe-no-labelling": {"labelling_weight": 0.0},
    "mediapipe-ungated": {"proposal_gate": None},
    "mediapipe-h100": {"hypothesis_evaluations": 100},
    "mediapipe-r6": {"mesh_resolution": 6},
    # the leader's registration on 350 evaluations instead of 500 (issue 50: the 2-core rate with
    # MediaPipe is CPU-bound, and the leader is a third of a frame's CPU)
    "mediapipe-e350": {"evaluations": 350},
    "oracle-e350": {"evaluations": 350},
    # the written poses' smoother (issue 39): live (lag 0), offline, and off
    "oracle-L0": {"lag": 0},
    "oracle-offline": {"offline": True},
    "oracle-unsmoothed": {"smoothing": {"on": False}},
    "unsmoothed": {"smoothing": {"on": False}},
    # the score's weights fitted by experiments.fit_score (conditional logit, temperature 10 mm) on the
    # candidates recorded with oracle keypoints on seeds 0-1 (docs/research-log.md, issue 34)
    "oracle-fitted": {"edge_weight": 0.9433, "keypoint_weight": 6.353, "prior_weight": 0.2899,
                      "lifter_weight": 2.315, "motion_weight": 0.8179},
    # without keypoints, the weights fitted by experiments.fit_score on candidates recorded without
    # keypoints (seeds 0-1); and the same with the motion term kept (not shipped: docs/research-log.md).
    # Tracked without keypoints, so every frame is scored by them (the silhouette_* twins that held
    # them for such frames alone were removed in issue 39)
    "fitted-silhouette": {"edge_weight": 0.01516, "prior_weight": 0.00708, "motion_weight": 0.0},
    "silhouette-motion": {"edge_weight": 0.01516, "prior_weight": 0.00708},
    # the weights fitted without keypoints given to the frames with the oracle's keypoints too (did not pay)
    "oracle-fitted-silhouette": {"edge_weight": 0.01516, "prior_weight": 0.00708, "motion_weight": 0.0},
    # the default tracker with the gradient step (issue 30; off by default: docs/research-log.md)
    "gradient": {"gradient_step": True},
})
#: Configurations tracked with the paper's two-class model (skin and clothes: no hair region, no
#: lower body; :data:`experiments.units.EXTENSIONS` left out) instead of the default four classes.
TWO_CLASS_MODEL = frozenset({"paper", "two-class"})
#: Configurations given 2D keypoints: the oracle's noise in pixels (:mod:`experiments.keypoints`).
ORACLE_KEYPOINTS = MappingProxyType({name: 2.0 for name in ("oracle-keypoints", "oracle-no-lifter", "oracle-no-labelling",
                                                              "oracle-ungated", "oracle-h100", "oracle-r6", "oracle-e350",
                                                              "oracle-fitted",
                                                              "oracle-fitted-silhouette", "oracle-L0", "oracle-offline",
                                                              "oracle-unsmoothed", "oracle-swapped",
                                                              "oracle-swapped-all")})
#: Configurations given MediaPipe's keypoints on the rendered frames
#: (:func:`experiments.keypoints.detector_keypoints`; needs the keypoints extra).
DETECTOR_KEYPOINTS = frozenset({"mediapipe-keypoints", "mediapipe-no-labelling", "mediapipe-ungated",
                                "mediapipe-h100", "mediapipe-r6", "mediapipe-e350"})
#: Configurations whose oracle keypoints have left and right swapped: the share of frames
#: (:func:`experiments.keypoints.swap_runs`).
SWAPPED_KEYPOINTS = MappingProxyType({"oracle-swapped": 0.5, "oracle-swapped-all": 1.0})


def config_of(name: str) -> TrackerConfig:
    """The :class:`TrackerConfig` of a :data:`CONFIGS` name."""
    changes = CONFIGS[name]
    return TrackerConfig.paper() if changes is None else TrackerConfig.from_dict(changes)


def unit_path(out: Path, name: str, sequence: str, seed: int, null_offset_px: float = 0.0) -> Path:
    from experiments.ambiguity import config_key
    model = "-two-class" if name in TWO_CLASS_MODEL else ""
    keypoints = f"-oracle{ORACLE_KEYPOINTS[name]:g}px" if name in ORACLE_KEYPOINTS else ""
    keypoints += f"-swapped{SWAPPED_KEYPOINTS[name]:g}" if name in SWAPPED_KEYPOINTS else ""
    keypoints += "-mediapipe" if name in DETECTOR_KEYPOINTS else ""
    keypoints += f"-null{null_offset_px:g}px" if null_offset_px else ""
    return out / "units" / f"{sequence}-s{seed}-{config_key(config_of(name))}{model}{keypoints}.json"


def failure_marks(row: dict) -> dict:
    """Whether one unit's track failed as a whole (issue 49, item 6), from its measured row.

    ``turned_round_rate``: the share of frames whose written chest heading is over
    :data:`TURNED_ROUND_DEG` from the truth's (from ``frame_heading_error_deg``, degrees on the
    circle); ``turned_round``: that share over :data:`TURNED_ROUND_SHARE`; ``lost``: the median
    over frames of the error about the neck (``median_frame_root_relative_mm``, else the median of
    ``frame_root_relative_mm``; mm) over :data:`LOST_MM`. Each is None where the row does not hold
    what it is judged on (rows measured before it was recorded, made-up rows).
    """
    heading = row.get("frame_heading_error_deg")
    rate = float(np.mean(np.abs(heading) > TURNED_ROUND_DEG)) if heading is not None and len(heading) else None
    about_neck = row.get("median_frame_root_relative_mm")
    if about_neck is None and row.get("frame_root_relative_mm") is not None and len(row["frame_root_relative_mm"]):
        about_neck = float(np.median(row["frame_root_relative_mm"]))
    return {"turned_round_rate": rate, "turned_round": None if rate is None else bool(rate > TURNED_ROUND_SHARE),
            "lost": None if about_neck is None else bool(about_neck > LOST_MM)}


def run_unit(out: Path, name: str, sequence: str, seed: int, null_offset_px: float = 0.0) -> dict:
    """Measure one (configuration, sequence, seed), reusing its file when the same code measured it
    (:func:`experiments.ambiguity.cached_result`), the keypoints moved ``null_offset_px`` to the
    right (a null perturbation, :func:`experiments.keypoints.offset_keypoints`; its own file name);
    the row carries its :func:`failure_marks`,
    judged again on every call (this module is not part of the code key: a kept file is marked
    under the thresholds as they are now)."""
    from experiments.ambiguity import cached_result, code_key, measure
    from experiments.units import EXTENSIONS

    path = unit_path(out, name, sequence, seed, null_offset_px)
    code = code_key()
    row = cached_result(path, code, None)
    if row is not None:
        return row | failure_marks(row)
    config = config_of(name)
    row = measure(sequence, config, out, seed, without=EXTENSIONS if name in TWO_CLASS_MODEL else (),
                  oracle_sigma_px=ORACLE_KEYPOINTS.get(name), swap_share=SWAPPED_KEYPOINTS.get(name),
                  detector=name in DETECTOR_KEYPOINTS, null_offset_px=null_offset_px)
    row |= failure_marks(row)
    write_json(path, {"config": config.to_dict(), "name": name, "seed": seed, "code": code,
                      "null_offset_px": null_offset_px, "result": row})
    return row


def summarise(rows: list[dict]) -> dict:
    """Medians over sequences, failure share over all frames pooled, worst sequence, time, and the
    units turned round and lost (:func:`failure_marks`): ``units`` (all), ``turned_round_units``
    and ``lost_units`` (how many are), ``turned_round_judged`` and ``lost_judged`` (how many could
    be judged: rows that hold what the mark is judged on)."""
    errors = np.concatenate([r["frame_mpjpe_mm"] for r in rows])
    marks = [failure_marks(r) for r in rows]
    counts = {f"{key}_{what}": sum(m[key] is not None and (what == "judged" or m[key]) for m in marks)
              for key in ("turned_round", "lost") for what in ("units", "judged")}
    return {"median_mpjpe_mm": float(np.median([r["mpjpe_mm"] for r in rows])),
            "median_root_relative_mm": float(np.median([r["root_relative_mpjpe_mm"] for r in rows])),
            "median_pa_mpjpe_mm": float(np.median([r["pa_mpjpe_mm"] for r in rows])),
            "failure_rate": float(np.mean(errors > DEFAULT_FAILURE_MM)),
            "worst_mpjpe_mm": float(max(r["mpjpe_mm"] for r in rows)),
            "beam_oracle_failure_rate": float(np.average([r["beam_oracle_failure_rate"] for r in rows],
                                                         weights=[r["frames"] for r in rows])),
            "cost_equivalent_both_rate": float(np.average([r["cost_equivalent_both_rate"] for r in rows],
                                                          weights=[r["frames"] for r in rows])),
            **{key: float(np.average([math.nan if r.get(key) is None else r[key] for r in rows],
                                     weights=[r["frames"] for r in rows]))
               for key in ("proposal_oracle_failure_rate", "proposal_catches_rate", "others_miss_rate",
                           "root_relative_failure_rate", "lifter_oracle_failure_rate", "branch_miss_rate")},
            **{f"median_{key}": float(np.median([r.get(key, math.nan) for r in rows]))
               for key in ("accel_mm", "decoded_accel_mm", "naive_accel_mm", "accel_arms_pa_mm")},
            "ms_per_frame": float(np.average([r["tracking_ms_per_frame"] + r["prepare_ms_per_frame"] for r in rows],
                                             weights=[r["frames"] for r in rows])),
            "evaluations_per_frame": float(np.average([r.get("evaluations_per_frame", math.nan) for r in rows],
                                                      weights=[r["frames"] for r in rows])),
            "units": len(rows), **counts}


def table(summaries: dict[str, dict]) -> str:
    """Markdown table of :func:`summarise` results by configuration name."""
    head = ("configuration", "median MPJPE mm", "median root-rel. mm", "median PA-MPJPE mm",
            f"frames > {DEFAULT_FAILURE_MM:g} mm", f"root-rel. > {DEFAULT_FAILURE_MM:g} mm", "worst sequence mm",
            f"turned round (> {TURNED_ROUND_DEG:g}° on > {100 * TURNED_ROUND_SHARE:g} % of frames)",
            f"lost (median root-rel. > {LOST_MM:g} mm)", "beam oracle > 100 mm",
            "proposal oracle > 100 mm", "caught by a proposal alone", "lifter's best of K > 100 mm root-rel.",
            "branch missed (root-rel.)", "failing, costs <= truth's",
            "accel mm/frame² (decoded, naive)", "ms / frame (fps)")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, s in summaries.items():
        lines.append(f"| {name} | {s['median_mpjpe_mm']:.0f} | {s['median_root_relative_mm']:.0f} | "
                     f"{s['median_pa_mpjpe_mm']:.0f} | {100 * s['failure_rate']:.1f} % | "
                     f"{_percent(s['root_relative_failure_rate'])} | {s['worst_mpjpe_mm']:.0f} | "
                     f"{_units(s, 'turned_round')} | {_units(s, 'lost')} | "
                     f"{100 * s['beam_oracle_failure_rate']:.1f} % | {_percent(s['proposal_oracle_failure_rate'])} | "
                     f"{_percent(s['proposal_catches_rate'])} | {_percent(s['lifter_oracle_failure_rate'])} | "
                     f"{_percent(s['branch_miss_rate'])} | {100 * s['cost_equivalent_both_rate']:.1f} % | "
                     f"{_accel(s)} | "
                     f"{s['ms_per_frame']:.1f} "
                     f"({1e3 / s['ms_per_frame']:.0f}) |")
    return "\n".join(lines)


def jitter_table(rows: dict[str, list[dict]]) -> str:
    """Markdown table of each (configuration, sequence, seed)'s acceleration errors about the neck
    and of the PA-aligned arms (mm/frame^2) and median per-frame errors about the neck and in the
    camera (mm): written (smoothed) / decoded (before the smoother) / naive baseline; and how far
    the written poses stray from the decoded ones: the largest mean joint distance over the frames
    (``FrameResult.smoothed_mm``) and the largest distance of any one joint (mm), and the largest
    step of the written chest heading from one frame to the next (degrees; issue 44,
    :func:`experiments.ambiguity.written_against_decoded`); and the unit's :func:`failure_marks`:
    turned round (yes or no, with the share of frames turned round) and lost (a dash where not
    judged)."""
    lines = ["| configuration | sequence | seed | accel about the neck | accel arms (PA) | median about the neck | "
             "median in the camera | written from decoded, max mm (mean joint / worst joint) | heading step, max ° | "
             "turned round (frames) | lost |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    three = lambda r, key: " / ".join(f"{r.get(p + key, math.nan):.1f}" for p in ("", "decoded_", "naive_"))
    for name, rs in rows.items():
        for r in rs:
            lines.append(f"| {name} | {r['sequence']} | {r.get('seed', '')} | {three(r, 'accel_mm')} | "
                         f"{three(r, 'accel_arms_pa_mm')} | {three(r, 'median_frame_root_relative_mm')} | "
                         f"{three(r, 'median_frame_mm')} | {r.get('written_decoded_mean_mm', math.nan):.0f} / "
                         f"{r.get('written_decoded_mm', math.nan):.0f} | "
                         f"{r.get('heading_step_deg', math.nan):.1f} | {_turned(failure_marks(r))} | "
                         f"{_yes_no(failure_marks(r)['lost'])} |")
    return "\n".join(lines)


def _yes_no(mark: bool | None) -> str:
    return "-" if mark is None else ("yes" if mark else "no")


def _turned(marks: dict) -> str:
    """A unit's turned-round mark with its share of frames turned round, or a dash where not judged."""
    if marks["turned_round"] is None:
        return "-"
    return f"{_yes_no(marks['turned_round'])} ({100 * marks['turned_round_rate']:.1f} %)"


def detector_table(rows: dict[str, list[dict]]) -> str:
    """Markdown table of the configurations given MediaPipe's keypoints (:data:`DETECTOR_KEYPOINTS`),
    per sequence and seed: the detector's label swaps (share of frames), and ours beside MediaPipe's
    own 3D (:func:`experiments.ambiguity.beside_detector`): the arms' PA-MPJPE and acceleration
    error, and their ratios (ours over MediaPipe's: below 1 is better)."""
    lines = ["| configuration | sequence | seed | detector: labels swapped | MediaPipe found | arms PA-MPJPE mm, "
             "ours / MediaPipe's | PA ratio | arms accel mm/frame², ours / MediaPipe's | accel ratio |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, rs in rows.items():
        for r in rs:
            if "mediapipe_arms_pa_mpjpe_mm" not in r:
                continue
            ours, theirs = r["arms_pa_mpjpe_mm"], r["mediapipe_arms_pa_mpjpe_mm"]
            lines.append(f"| {name} | {r['sequence']} | {r.get('seed', '')} | {_percent(r['detector_swapped_rate'])} | "
                         f"{_percent(r['mediapipe_found_rate'])} | {ours:.0f} / {theirs:.0f} | {ours / theirs:.2f} | "
                         f"{r['arms_accel']:.1f} / {r['mediapipe_arms_accel']:.1f} | "
                         f"{r['arms_accel'] / r['mediapipe_arms_accel']:.2f} |")
    return "\n".join(lines)


def _units(s: dict, mark: str) -> str:
    """How many units of a summary carry a :func:`failure_marks` mark: "N of M" (M all units),
    "N of M judged" where fewer could be judged, a dash where none could (or a summary from before
    the marks)."""
    judged, units = s.get(f"{mark}_judged", 0), s.get("units", 0)
    if not judged:
        return "-"
    return f"{s[f'{mark}_units']} of {units}" if judged == units else f"{s[f'{mark}_units']} of {judged} judged"


def _unseen_heading(seeds: list[int]) -> str:
    return f"seed{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))}, never used for tuning"


def _accel(s: dict) -> str:
    """The written, decoded and naive acceleration errors of a summary, or a dash where not measured."""
    if not math.isfinite(s["median_accel_mm"]):
        return "-"
    return f"{s['median_accel_mm']:.1f} ({s['median_decoded_accel_mm']:.1f}, {s['median_naive_accel_mm']:.1f})"


def _percent(rate: float) -> str:
    """A rate as a percentage, or a dash where it was not measured (no proposal stage)."""
    return "-" if not math.isfinite(rate) else f"{100 * rate:.1f} %"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.tracking", description=__doc__.split("\n\n")[0])
    p.add_argument("--configs", default="default,paper", help=f"comma-separated names of: {'; '.join(CONFIGS)}")
    p.add_argument("--seeds", default="0,1,2,3,4", help="comma-separated generator seeds")
    p.add_argument("--unseen-seeds", default="",
                   help="comma-separated seeds never used for tuning: tracked too, tabled apart")
    p.add_argument("--sequences", default=",".join(SEQUENCE_NAMES))
    p.add_argument("--out", type=Path, default=RESULTS_DIR / "tracking")
    p.add_argument("--null-offset-px", type=float, default=0.0,
                   help="move every keypoint this far to the right (pixels; e.g. 0.01): a null perturbation "
                        "whose units, compared with experiments.tracking_diff, show how far tracks move from "
                        "nothing (docs/research-log.md, 2026-11-30)")
    p.add_argument("--report", action="store_true",
                   help="draw the figure and write the table into experiments/REPORT.md")
    args = p.parse_args(argv)
    names = [n.strip() for n in args.configs.split(",") if n.strip()]
    unknown = [n for n in names if n not in CONFIGS]
    sequences = [s for s in args.sequences.split(",") if s]
    bad_sequences = [s for s in sequences if s not in SEQUENCE_NAMES]
    try:
        seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
        unseen = [int(s) for s in args.unseen_seeds.split(",") if s.strip()]
    except ValueError:
        seeds = unseen = []
    if not (math.isfinite(args.null_offset_px) and abs(args.null_offset_px) < 1.0):
        print(f"error: --null-offset-px must be finite and under 1 pixel (a null perturbation), "
              f"got {args.null_offset_px}", file=sys.stderr)
        return 2
    if args.null_offset_px and args.report:
        print("error: a null run (--null-offset-px) is not written into the report", file=sys.stderr)
        return 2
    if unknown or bad_sequences or not names or not seeds or not sequences:
        print(f"error: unknown configuration(s) {unknown} or sequence(s) {bad_sequences}, or no seeds; "
              f"configurations: {'; '.join(CONFIGS)}", file=sys.stderr)
        return 2
    if DETECTOR_KEYPOINTS & set(names):
        from mocap.io.mediapipe_keypoints import MISSING_EXTRA, available

        if not available():
            print(f"error: {', '.join(sorted(DETECTOR_KEYPOINTS & set(names)))}: {MISSING_EXTRA}", file=sys.stderr)
            return 2
    from tqdm import tqdm

    from experiments.units import UnpreparableSequence

    units = [(n, s, q) for n in names for s in seeds + unseen for q in sequences]
    measured: dict[tuple[str, int, str], dict] = {}
    left_out: dict[tuple[int, str], str] = {}      # (seed, sequence) -> why it cannot be prepared
    for name, seed, sequence in tqdm(units, desc="ablation", unit="sequence"):
        if (seed, sequence) in left_out:
            continue
        try:
            measured[name, seed, sequence] = run_unit(args.out, name, sequence, seed,
                                                      null_offset_px=args.null_offset_px)
        except UnpreparableSequence as error:
            left_out[seed, sequence] = str(error)
            print(f"left out, cannot be prepared: {sequence} seed {seed}: {error}", file=sys.stderr)
    # a unit one configuration could not prepare is left out of every configuration's summaries
    kept = [(s, q) for s in seeds + unseen for q in sequences if (s, q) not in left_out]
    order = [(s, q) for s, q in kept if s in seeds] + [(s, q) for s, q in kept if s not in seeds]
    rows = {n: [measured[n, s, q] for s, q in order if s in seeds] for n in names}
    unseen_rows = {n: [measured[n, s, q] for s, q in order if s not in seeds] for n in names}
    if not all(rows.values()):
        print("error: no unit of the seeds could be prepared", file=sys.stderr)
        return 1
    summaries = {n: summarise(r) for n, r in rows.items()}
    write_json(args.out / "summary.json", {
        "seeds": seeds, "sequences": sequences, "null_offset_px": args.null_offset_px, "summaries": summaries,
        "per_sequence": {n: {f"{q}-s{s}": measured[n, s, q]["mpjpe_mm"] for s, q in order if s in seeds}
                         for n in names},
        "left_out": [{"sequence": q, "seed": s, "reason": why} for (s, q), why in left_out.items()]})
    heading = f"seeds {', '.join(map(str, seeds))}; {len(sequences)} sequences, full length, 160x120, true calibration"
    if args.null_offset_px:
        heading += f"; keypoints moved {args.null_offset_px:g} px to the right (a null perturbation)"
    if left_out:
        heading += "; left out, cannot be prepared: " + ", ".join(f"{q} s{s}" for s, q in left_out)
    print(heading + "\n")
    print(table(summaries))
    apart = None
    if unseen and all(unseen_rows.values()):
        apart = (unseen, {n: summarise(r) for n, r in unseen_rows.items()})
        print(f"\n{_unseen_heading(unseen)}\n")
        print(table(apart[1]))
    print("\nwritten / decoded / naive (mm/frame² and mm):\n")
    print(jitter_table({n: [{**r, "seed": s} for r, (s, _) in zip(rows[n] + unseen_rows[n], order)]
                        for n in names}))
    if DETECTOR_KEYPOINTS & set(names):
        print("\nbeside MediaPipe's own 3D:\n")
        print(detector_table({n: [{**r, "seed": s} for r, (s, _) in zip(rows[n] + unseen_rows[n], order)]
                              for n in names if n in DETECTOR_KEYPOINTS}))
    if args.report:
        write_report_section(rows, summaries, heading, apart)
    return 0


def write_report_section(rows: dict[str, list[dict]], summaries: dict[str, dict], heading: str,
                         apart: tuple[list[int], dict[str, dict]] | None = None) -> Path:
    """Draw the figure and put the table and figure into ``experiments/REPORT.md``; ``apart``:
    the seeds never used for tuning and their summaries, tabled after the others."""
    from experiments import EXPERIMENTS_DIR
    from experiments.figures import ext_proposal_budget, ext_tracking
    from experiments.report import replace_section

    figures = EXPERIMENTS_DIR / "report"
    ext_tracking.main({n: np.concatenate([r["frame_mpjpe_mm"] for r in rs]) for n, rs in rows.items()}, figures)
    ext_proposal_budget.main(summaries, figures)
    text = "\n".join([
        "## Tracking that recovers: the beam tracker's ablation",
        "",
        f"`python -m experiments.tracking --configs {','.join(rows)}"
        + (f" --unseen-seeds {','.join(map(str, apart[0]))}" if apart else "") + f" --report` ({heading}). "
        "Medians over the sequences; frames over 100 mm pooled over all frames; the beam oracle is the "
        "share of frames on which no kept hypothesis is within 100 mm (what the search leaves); the proposal "
        "oracle the share on which no refined proposal of the proposal stage is within 100 mm, and 'caught by a "
        "proposal alone' the frames on which every other candidate (tracked hypotheses, recovery, re-acquisition, "
        "jumps) is over 100 mm but a refined proposal is not; 'turned round' counts the sequences whose written "
        f"chest heading is over {TURNED_ROUND_DEG:g}° from the truth's (on the circle) on more than "
        f"{100 * TURNED_ROUND_SHARE:g} % of their frames, 'lost' those whose median error about the neck is over "
        f"{LOST_MM:g} mm; the last "
        "columns are the failing frames that both costs rate no worse than the truth, and the tracking "
        "time per frame (image side included) as measured in the run, while other jobs shared the machine's "
        "two cores: for speed see `python -m mocap bench` (`frame_beam`, `frame_500`). `default` is the beam "
        "tracker (K=3, L=8, jumps, prior, four colour classes), `paper` the paper's method on its two-class "
        "model, `single` one hypothesis with recovery and hand re-acquisition, `two-class` the default tracker "
        "on the two-class model.",
        "",
        table(summaries),
        "",
        *([f"Judged apart, {_unseen_heading(apart[0])}:", "", table(apart[1]), ""] if apart else []),
        "![share of frames under each error](report/ext_tracking.png)",
        "",
        "Accuracy against the cost evaluations each configuration spends per frame (all hypotheses, "
        "proposals and refinements):",
        "",
        "![accuracy against evaluations per frame](report/ext_proposal_budget.png)",
        ""])
    return replace_section(EXPERIMENTS_DIR / "REPORT.md", REPORT_SECTION, text)


if __name__ == "__main__":
    sys.exit(main())
