"""``python -m experiments.hand_size``: does the hand's size by perspective tell a pose from its depth mirrors?

Issue 46, item 1's first cue (hand size) and item 2's answer for it. A depth mirror
(:func:`mocap.track.branches.depth_alternatives`, geometry :func:`mocap.body.jumps.flipped_arm_joints`)
keeps every joint's projection, so the keypoints cannot tell it from the truth; perspective can:
a hand nearer the camera looks larger, and a hand whose forearm points elsewhere is turned
otherwise. MediaPipe gives three hand landmarks (wrist, index and pinky knuckles) in **input**
pixels (:data:`mocap.io.mediapipe_keypoints.MEDIAPIPE_LANDMARKS`; the model's hand joint is their
mean).

**The hand's points on the model** (:func:`hand_points`): on each hand segment, the wrist (the
segment's origin) and two knuckles at :data:`KNUCKLE_ALONG` of the hand's length along its long
axis and half the hand's width either side (local x; the index on the thumb's side, the body's
outside in the zero pose): the mean of the three is the model's hand joint (half the hand's
length), as MediaPipe's three landmarks make it. Their projection carries the hand's depth (the
palm's width and the wrist-to-knuckles length scale as ``f / z``) and its orientation (both
foreshorten with the hand's direction), which the mirror changes with the forearm.

**The cue** (:func:`hand_cue`), lower is better, per candidate, against the detector's three
points in input pixels:

* ``points``: the mean distance (px) of the candidate's projected hand points from the detector's;
* ``span``: the absolute differences (px) of the two spans, knuckle to knuckle (the palm's width)
  and wrist to the knuckles' midpoint (the hand's length), summed: the size alone, blind to where
  the hand is in the image (which the keypoint distance already sees).

**The oracle** (:func:`measure_sequence`): the true poses of a benchmark sequence (``mocap.synth``:
the motion and the actor only, nothing rendered), the truth's hand points projected at the
input size :data:`INPUT_SIZE` (the working camera enlarged, :meth:`mocap.render.camera.Camera.enlarged`)
plus Gaussian noise per coordinate and landmark, independent (a pessimistic model: a detector's
errors on three points of one hand are partly shared, and a shared shift does not change the
spans). Levels :data:`NOISE_PX`, 0 the upper bound, and :data:`MEDIAPIPE_SIGMA_PX` MediaPipe's.
Two stages of :mod:`experiments.branch_audit` (:data:`STAGES`): **unrefined**, each frame's truth
against its exact mirrors, and **leader**, the truth registered by the tracker's two-step
registration (its config, the oracle's 2D, :data:`LEADER_EVALUATIONS`: a converged leader)
against its own exact mirrors; the detector sees the truth's hand at both. The mirrors are built
as the tracker builds them (:func:`experiments.branch_audit.mirror_alternatives`, the tracker's
pruning thresholds at the working size), a pair counted only when the mirror is distinct (some
joint at least :data:`experiments.branch_audit.DISTINCT_M` away) and unpruned; the cue prefers
the truth when :func:`experiments.branch_audit.truth_better` (the audit's convention). Beside it,
on the same pairs, the pose prior's energy and the tracker's whole unary score
(:func:`experiments.branch_audit.cue_vector`, the frames rendered at the working size), and
``score + w * cue`` (and ``prior + w * cue``) with ``w`` chosen on seeds :data:`FIT_SEEDS` and
judged on the seed never used, :data:`UNSEEN_SEED`; per pair and summed over the lag's window
(:func:`window_shares`).

Results go to ``--out`` (default ``experiments/results/hand_size``): one ``.npz`` of pairs per
stage, sequence and seed under ``units/<stage>/`` (reused when measured by the same code,
:func:`measuring_key`), the rendered sequences under ``data/``, ``summary.json``, ``hand_size.md``
and a figure per stage (:mod:`experiments.figures.ext_hand_size`: ``figures/ext_hand_size_<stage>.png``).

Measured on 2026-11-28 (docs/research-log.md): at MediaPipe's noise the cue adds 3.4 points to the
score's share at the leader stage on the unseen seed, under the issue's 5: not in the score.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from experiments import RESULTS_DIR
from experiments.branch_audit import DISTINCT_M, TIE_RELATIVE, WINDOW, max_joint_distance, mirror_alternatives, truth_better
from mocap.body.skeleton import JOINT_INDEX, SEGMENT_NAMES
from mocap.synth import SEQUENCE_NAMES

#: The detector's input size (pixels): the tracker works at 160x120, MediaPipe sees 640x480.
INPUT_SIZE: tuple[int, int] = (640, 480)
#: The tracker's working size (pixels): the mirrors are pruned in its pixels.
WORKING_SIZE: tuple[int, int] = (160, 120)
#: The hand's three points, in :func:`hand_points` order (MediaPipe's wrist, index and pinky).
HAND_POINTS: tuple[str, ...] = ("wrist", "index", "pinky")
#: Where the knuckles lie along the hand, as a fraction of its length from the wrist: with the
#: wrist at 0 their mean with the wrist is the hand joint at one half.
KNUCKLE_ALONG = 0.75
#: Where the knuckles lie across the hand, as a fraction of half its width either side.
KNUCKLE_ACROSS = 1.0
#: The cue's variants (see the module).
CUE_KINDS: tuple[str, ...] = ("points", "span")
#: MediaPipe's 2D error per coordinate at the input size (pixels): its arm joints lie 1.3-1.4 %
#: of the image width from the truth in the median (docs/research-log.md, 2026-11-28, issue 44
#: item 2, ``experiments.detector_size``), 1.35 % of 640 px = 8.6 px; a 2D Gaussian's median
#: radius is ``sigma * sqrt(2 ln 2)``, so sigma = 8.6 / 1.177 = 7.3 px per coordinate.
MEDIAPIPE_SIGMA_PX = 0.0135 * INPUT_SIZE[0] / math.sqrt(2.0 * math.log(2.0))
#: MediaPipe's wrist error per coordinate as ``experiments/lifter_keypoint_noise.json`` measured it
#: (video mode on CMU-driven renders enlarged 4x; 1.4826 MAD, the two wrists' mean, 0.105 of the
#: ten true joints' RMS spread, which is about 150 px at 640x480 on the benchmark): 16 px, a
#: second, harder level.
MEDIAPIPE_JSON_SIGMA_PX = 16.0
#: The wrists' sigma in ``experiments/lifter_keypoint_noise.json`` (units of the joints' RMS spread).
JSON_WRIST_SIGMA = 0.5 * (0.1139 + 0.0964)
#: Noise levels per coordinate (pixels at the input size).
NOISE_PX: tuple[float, ...] = (0.0, 1.0, 2.0, 4.0, round(MEDIAPIPE_SIGMA_PX, 1), MEDIAPIPE_JSON_SIGMA_PX)
#: Seeds the combination's weight is chosen on, and the seed never used before that judges it.
FIT_SEEDS: tuple[int, ...] = (0, 1, 2, 3, 4)
UNSEEN_SEED = 83
#: Flip kinds (the slot's suffix in :data:`experiments.branch_audit.SLOTS`).
FLIP_KINDS: tuple[str, ...] = ("upper_arm", "forearm", "both")
#: Bin edges (metres) of the hand joint's depth change between truth and mirror.
DEPTH_BINS_M: tuple[float, ...] = (0.0, 0.05, 0.10, 0.20, 0.30, 0.50, 2.0)
#: The audit's stages measured (:data:`experiments.branch_audit.STAGES`): the truth against its exact
#: mirrors, and the registered truth (a converged leader) against its own.
STAGES: tuple[str, ...] = ("unrefined", "leader")
#: The leader's registration budget (the audit's: 200 evaluations).
LEADER_EVALUATIONS = 200
#: Weights tried for ``prior + w * cue`` (nats per pixel).
COMBINE_WEIGHTS: tuple[float, ...] = (0.0, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0)


def hand_local_points(model, side: str) -> np.ndarray:
    """The hand's three points in the hand segment's frame (:data:`HAND_POINTS` order).

    Parameters
    ----------
    model : BodyModel
    side : {"r", "l"}

    Returns
    -------
    ndarray, shape (3, 3), float64, metres
        The wrist (origin), the index knuckle and the pinky knuckle; the long axis is local +y,
        the width local x. The index lies on the body's outside in the zero pose (the right hand
        at local -x, as the right shoulder's offset).
    """
    if side not in ("r", "l"):
        raise ValueError(f"side must be 'r' or 'l', got {side!r}")
    size = model.dims[f"{side}_hand"]
    out_sign = -1.0 if side == "r" else 1.0
    along, across = KNUCKLE_ALONG * size.length, KNUCKLE_ACROSS * 0.5 * size.width
    return np.array([[0.0, 0.0, 0.0], [out_sign * across, along, 0.0], [-out_sign * across, along, 0.0]])


def hand_points(pose, model, side: str) -> np.ndarray:
    """The hand's three points of a pose in camera coordinates.

    Parameters
    ----------
    pose : array_like, shape (23,)
        Metres and radians.
    model : BodyModel
    side : {"r", "l"}

    Returns
    -------
    ndarray, shape (3, 3), float64, metres
        :data:`HAND_POINTS` order; their mean is the model's ``<side>_hand`` joint.
    """
    t = model.segment_transforms(pose)[SEGMENT_NAMES.index(f"{side}_hand")]
    return hand_local_points(model, side) @ t[:, :3].T + t[:, 3]


def spans(points_px) -> np.ndarray:
    """The hand's two spans in an image.

    Parameters
    ----------
    points_px : array_like, shape (..., 3, 2), pixels
        Wrist, index, pinky (:data:`HAND_POINTS` order).

    Returns
    -------
    ndarray, shape (..., 2), float64, pixels
        The palm's width (index to pinky) and the hand's length (wrist to the knuckles' midpoint).
    """
    p = np.asarray(points_px, dtype=np.float64)
    width = np.linalg.norm(p[..., 1, :] - p[..., 2, :], axis=-1)
    length = np.linalg.norm(0.5 * (p[..., 1, :] + p[..., 2, :]) - p[..., 0, :], axis=-1)
    return np.stack([width, length], axis=-1)


def hand_cue(observed_px, predicted_px, kind: str = "points") -> np.ndarray:
    """The hand cue of candidates against the detector's hand points, lower is better.

    Parameters
    ----------
    observed_px : array_like, shape (..., 3, 2), pixels
        The detector's wrist, index and pinky (input pixels).
    predicted_px : array_like, shape (..., 3, 2), pixels
        A candidate's projected hand points (:func:`hand_points` through the input camera);
        broadcast against ``observed_px``.
    kind : {"points", "span"}
        ``points``: the mean distance of the three points; ``span``: the summed absolute
        differences of the two spans (:func:`spans`).

    Returns
    -------
    ndarray, shape (...), float64, pixels
    """
    o, p = np.asarray(observed_px, dtype=np.float64), np.asarray(predicted_px, dtype=np.float64)
    if kind == "points":
        return np.linalg.norm(o - p, axis=-1).mean(axis=-1)
    if kind == "span":
        return np.abs(spans(o) - spans(p)).sum(axis=-1)
    raise ValueError(f"kind must be one of {CUE_KINDS}, got {kind!r}")


def predicted_hand_px(pose, model, camera, side: str) -> np.ndarray:
    """A candidate's hand points projected by ``camera`` (the input's), shape (3, 2), pixels."""
    return camera.project(hand_points(pose, model, side))


def sequence_truth(name: str, seed: int):
    """A benchmark sequence's true poses, its actor's model and the working camera, without rendering.

    Returns
    -------
    (ndarray (N, 23), BodyModel, Camera)
        Metres and radians; the camera at :data:`WORKING_SIZE`.
    """
    from mocap.body.model import BodyModel
    from mocap.synth import sequence_poses, setup_sequence

    setup = setup_sequence(name, seed=seed, size=WORKING_SIZE)
    poses, _ = sequence_poses(setup)
    return np.asarray(poses, dtype=np.float64), BodyModel.build(setup.actor.dims), setup.camera


def measure_sequence(name: str, seed: int, stride: int = 1, noise_px=NOISE_PX, score_root: Path | None = None,
                     prior=None, stage: str = "unrefined", evaluations: int = LEADER_EVALUATIONS) -> dict:
    """The hand cue on every ``stride``-th frame of a sequence: the truth (or the leader) against its exact mirrors.

    The detector's points are the truth's hand points at the input size plus noise (one draw per
    frame, hand and level, seeded by ``seed`` and the sequence), the same for the truth and its
    mirrors. With ``score_root`` the sequence is rendered at the working size there
    (:func:`experiments.units.prepare_data`, as :func:`experiments.branch_audit.audit_sequence`)
    and the tracker's whole unary score of both candidates is measured too
    (:func:`experiments.branch_audit.cue_vector`, oracle keypoints, the tracker's config): the
    audit's ``unrefined`` stage; without it only the motion is generated. ``stage="leader"`` (with
    ``score_root``): the audit's leader stage, the reference is the truth registered by
    :func:`mocap.track.register` (the tracker's config, the frame's keypoints, ``evaluations``: a
    converged leader), compared with its own exact mirrors; the detector still sees the truth's
    hand. The ``truth_*`` values below are then the leader's.

    Returns
    -------
    dict of str to ndarray, one row per compared pair (P)
        ``frame``, ``slot`` (index in :data:`experiments.branch_audit.SLOTS`), ``kind`` (index in
        :data:`FLIP_KINDS`), ``side`` (0 right, 1 left); ``hand_dz`` (m, the mirror's hand joint
        depth minus the truth's); ``move_px`` (the mean move of the three hand points, noise-free,
        px) and ``span_change_px`` (P, 2: the mirror's spans minus the truth's); per level
        (``noise_px``, (L,)) and kind, ``truth_<kind>`` and ``alt_<kind>`` (P, L) cue values;
        ``truth_prior`` and ``alt_prior`` (P,) nats; ``truth_score`` and ``alt_score`` (P,) the
        tracker's score (NaN without ``score_root``); ``body_rms_px`` (the frames' RMS spread of
        the ten true joints at the input size, px) and ``frames`` (audited frames).
    """
    from experiments.branch_audit import COLUMNS, ORACLE_SIGMA_PX, SLOTS, cue_vector
    from mocap.body.pose import clamp_to_limits
    from mocap.body.prior import default_prior

    if stage not in STAGES:
        raise ValueError(f"stage must be one of {STAGES}, got {stage!r}")
    if stage == "leader" and score_root is None:
        raise ValueError("the leader stage registers the truth on the rendered frames: it needs score_root")
    tracker = costs_of = None
    if score_root is None:
        poses, model, working = sequence_truth(name, seed)
        prior = default_prior() if prior is None else prior
    else:
        from experiments.keypoints import oracle_keypoints
        from experiments.units import DataSpec, load_prepared, load_sequence, prepare_data
        from mocap.synth import SEQUENCES
        from mocap.track import Tracker, TrackerConfig

        length = SEQUENCES[name].frames
        folder = prepare_data(DataSpec(name, None, length, seed, *WORKING_SIZE), str(score_root))
        loaded, prepared = load_sequence(folder, length), load_prepared(folder)
        n = min(length, len(prepared), len(loaded.ground_truth.poses))
        poses, model, working = np.asarray(loaded.ground_truth.poses[:n], np.float64), loaded.model, loaded.calibration.camera
        keypoints = oracle_keypoints(loaded.ground_truth.joints[:n], working, ORACLE_SIGMA_PX, seed)
        tracker = Tracker(model, working, TrackerConfig(), poses[0])
        prior = tracker.prior if prior is None else prior

        def costs_of(i):
            """The frame's score of a pose, and its registration from a pose."""
            from mocap.track import register

            kp = keypoints[i]
            lifted = tracker.lifting.lift(kp, working, model) if tracker.lifting is not None else None
            costs, keypoint_cost = tracker.costs(prepared[i]), tracker.keypoint_cost(kp)
            return (lambda q: cue_vector(tracker, costs, keypoint_cost, lifted, None, q)[COLUMNS.index("score")],
                    lambda q: register(*costs, q, tracker.config, evaluations=evaluations,
                                       keypoint_cost=keypoint_cost).pose)
    camera = working.enlarged(INPUT_SIZE[0] // WORKING_SIZE[0], *INPUT_SIZE)
    levels = np.asarray(noise_px, dtype=np.float64)
    rng = np.random.default_rng([seed, SEQUENCE_NAMES.index(name) if name in SEQUENCE_NAMES else 99])
    rows = {k: [] for k in ("frame", "slot", "kind", "side", "hand_dz", "move_px", "span_change_px",
                            "truth_prior", "alt_prior", "truth_score", "alt_score")}
    values = {f"{who}_{kind}": [] for who in ("truth", "alt") for kind in CUE_KINDS}
    body_rms, audited = [], 0
    for i in range(0, len(poses), stride):
        real = clamp_to_limits(poses[i])
        uv = camera.project(model.joint_positions(real))
        body_rms.append(float(np.sqrt(((uv - uv.mean(axis=0)) ** 2).sum(axis=1).mean())))
        audited += 1
        seen_px = {s: predicted_hand_px(real, model, camera, s) for s in ("r", "l")}
        noise = rng.normal(0.0, 1.0, (2, 3, 2))                     # one draw per hand, scaled per level
        observed = {s: seen_px[s][None] + levels[:, None, None] * noise[k][None] for k, s in enumerate(("r", "l"))}
        score = None
        truth = real
        if stage == "leader":
            score, refine = costs_of(i)
            truth = refine(real)
            truth_score = score(truth)
        joints = model.joint_positions(truth)
        true_px = {s: predicted_hand_px(truth, model, camera, s) for s in ("r", "l")}
        truth_prior = prior.energy(truth)
        for alt in mirror_alternatives(truth, model, working):
            alt_joints = model.joint_positions(alt.pose)
            if alt.pruned or max_joint_distance(alt_joints, joints) < DISTINCT_M:
                continue
            if costs_of is not None and score is None:
                score = costs_of(i)[0]
                truth_score = score(truth)
            side, kind = alt.name.split("_", 1)
            pred = predicted_hand_px(alt.pose, model, camera, side)
            h = JOINT_INDEX[f"{side}_hand"]
            rows["frame"].append(i)
            rows["slot"].append(SLOTS.index(alt.name))
            rows["kind"].append(FLIP_KINDS.index(kind))
            rows["side"].append(0 if side == "r" else 1)
            rows["hand_dz"].append(alt_joints[h, 2] - joints[h, 2])
            rows["move_px"].append(hand_cue(true_px[side], pred, "points"))
            rows["span_change_px"].append(spans(pred) - spans(true_px[side]))
            rows["truth_prior"].append(truth_prior)
            rows["alt_prior"].append(prior.energy(alt.pose))
            rows["truth_score"].append(truth_score if score is not None else math.nan)
            rows["alt_score"].append(score(alt.pose) if score is not None else math.nan)
            for cue in CUE_KINDS:
                values[f"truth_{cue}"].append(hand_cue(observed[side], true_px[side][None], cue))
                values[f"alt_{cue}"].append(hand_cue(observed[side], pred[None], cue))
    out = {k: np.asarray(v, dtype=np.int64 if k in ("frame", "slot", "kind", "side") else np.float64)
           for k, v in rows.items()}
    out["span_change_px"] = out["span_change_px"].reshape(-1, 2)
    for k, v in values.items():
        out[k] = np.asarray(v, dtype=np.float64).reshape(-1, len(levels))
    out.update(noise_px=levels, body_rms_px=np.asarray(body_rms), frames=np.asarray(audited))
    return out


def unit_path(out: Path, name: str, seed: int, stride: int, stage: str = "unrefined") -> Path:
    """Where a sequence's pairs are stored: ``out/units/<stage>/<sequence>-s<seed>-x<stride>.npz``."""
    return out / "units" / stage / f"{name}-s{seed}-x{stride}.npz"


def measuring_key() -> str:
    """Short stable name of the measuring code and settings (a unit is reused only when equal)."""
    import hashlib
    import inspect

    digest = hashlib.sha256()
    for f in (hand_local_points, hand_points, spans, hand_cue, predicted_hand_px, sequence_truth, measure_sequence):
        digest.update(inspect.getsource(f).encode())
    digest.update(repr((INPUT_SIZE, WORKING_SIZE, KNUCKLE_ALONG, KNUCKLE_ACROSS, NOISE_PX, DISTINCT_M,
                        LEADER_EVALUATIONS)).encode())
    return digest.hexdigest()[:12]


def load_or_measure(out: Path, name: str, seed: int, stride: int, measure: bool, score_root: Path | None,
                    stage: str = "unrefined") -> dict | None:
    """A stored unit measured by the same code (:func:`measuring_key`), else measured now (``measure``) and
    stored atomically; None when absent and not measured."""
    from mocap.io.files import write_bytes_atomic

    path = unit_path(out, name, seed, stride, stage)
    key = measuring_key()
    if path.is_file():
        with np.load(path, allow_pickle=False) as z:
            if str(z["key"]) == key or not measure:
                return {k: z[k] for k in z.files if k != "key"}
    if not measure:
        return None
    unit = measure_sequence(name, seed, stride, score_root=score_root, stage=stage)
    import io
    buf = io.BytesIO()
    np.savez_compressed(buf, key=np.array(key), **unit)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bytes_atomic(path, buf.getvalue())
    return unit


def cost_per_candidate_us(repeats: int = 2000) -> float:
    """Median time (µs, wall clock) of the cue for one candidate: its hand points from the pose
    (:func:`hand_points`: the segment transforms), their projection and :func:`hand_cue`."""
    from mocap.body.model import BodyModel
    from mocap.body.pose import N_PARAMETERS, PARAMETER_INDEX
    from mocap.render.camera import Camera

    model = BodyModel.build()
    camera = Camera.default(*INPUT_SIZE)
    pose = np.zeros(N_PARAMETERS)
    pose[PARAMETER_INDEX["root_z"]] = 2.3
    observed = predicted_hand_px(pose, model, camera, "r")
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        hand_cue(observed, predicted_hand_px(pose, model, camera, "r"), "points")
        times.append(time.perf_counter() - t)
    return 1e6 * float(np.median(times))


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m experiments.hand_size", description=__doc__.split("\n\n")[0])
    p.add_argument("command", choices=("measure", "report"), nargs="?", default="measure",
                   help="measure the units not stored yet, then report (default); report: the stored units only")
    p.add_argument("--sequences", default=",".join(SEQUENCE_NAMES), help="comma-separated benchmark sequences")
    p.add_argument("--seeds", default=",".join(map(str, FIT_SEEDS + (UNSEEN_SEED,))),
                   help="comma-separated seeds (default 0-4 and the unseen 83)")
    p.add_argument("--stride", type=int, default=2, help="every N-th frame (default 2)")
    p.add_argument("--no-score", action="store_true",
                   help="do not render the sequences nor measure the tracker's score (the hand cue and the prior "
                        "only, the unrefined stage only)")
    p.add_argument("--stages", default=",".join(STAGES), help=f"comma-separated stages of {STAGES} (default both)")
    p.add_argument("--out", type=Path, default=RESULTS_DIR / "hand_size", help="results folder")
    p.add_argument("--no-figure", action="store_true")
    return p


def main(argv=None) -> int:
    from experiments.config import sequence_list

    args = build_parser().parse_args(argv)
    try:
        names = sequence_list(args.sequences)
        seeds = tuple(int(v) for v in args.seeds.split(",") if v.strip())
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    stages = tuple(v.strip() for v in args.stages.split(",") if v.strip())
    if args.no_score:
        stages = tuple(st for st in stages if st == "unrefined")
    if not seeds or args.stride < 1 or not stages or any(st not in STAGES for st in stages):
        print(f"error: --seeds takes comma-separated integers, --stride a positive integer, --stages some of {STAGES} "
              "(the leader stage needs the score: not with --no-score)", file=sys.stderr)
        return 2
    summary = {"stages": {}, "command": "python -m experiments.hand_size " + " ".join(
        argv if argv is not None else sys.argv[1:])}
    for stage in stages:
        units = {}
        for seed in seeds:
            for name in names:
                t = time.perf_counter()
                unit = load_or_measure(args.out, name, seed, args.stride, args.command == "measure",
                                       None if args.no_score else args.out / "data", stage)
                if unit is not None:
                    units[(name, seed)] = unit
                    print(f"{stage} {name} s{seed}: {len(unit['frame'])} compared ({time.perf_counter() - t:.1f} s)",
                          file=sys.stderr, flush=True)
        if units:
            summary["stages"][stage] = {"stage": stage, **summarise(units)}
    if not summary["stages"]:
        print("error: no stored units; run measure first", file=sys.stderr)
        return 2
    summary["cost_us_per_candidate"] = cost_per_candidate_us()
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "summary.json").write_text(json.dumps(summary, indent=1))
    text = "\n\n".join(f"## stage: {stage}\n\n" + tables(st) for stage, st in summary["stages"].items())
    text = f"cost: {summary['cost_us_per_candidate']:.1f} µs per candidate\n\n" + text
    (args.out / "hand_size.md").write_text(text + "\n")
    if not args.no_figure:
        from experiments.figures import ext_hand_size

        for stage, st in summary["stages"].items():
            ext_hand_size.main(st, args.out / "figures", f"ext_hand_size_{stage}")
    print(text)
    return 0


# -- analysis ----------------------------------------------------------------------------------
def _share(truth, alt) -> float:
    """Share of pairs on which ``truth`` is better (:func:`experiments.branch_audit.truth_better`); NaN when empty
    or unmeasured."""
    t, a = np.asarray(truth, dtype=np.float64), np.asarray(alt, dtype=np.float64)
    if t.size == 0 or not np.isfinite(t).any():
        return math.nan
    return float(truth_better(t, a).mean())


def pooled(units: dict, keys) -> dict:
    """The pairs of several units concatenated (the per-pair arrays only)."""
    keys = list(keys)
    if not keys:
        return {}
    names = [k for k, v in units[keys[0]].items() if np.ndim(v) >= 1 and k not in ("noise_px", "body_rms_px")]
    return {k: np.concatenate([units[u][k] for u in keys]) for k in names}


def shares(p: dict, levels) -> dict:
    """Per cue the share of pairs with the truth better: ``points`` and ``span`` per noise level
    (lists, :data:`NOISE_PX` order), ``prior`` and ``score``; and ``pairs``."""
    if not p or len(p["frame"]) == 0:
        return {"pairs": 0}
    out = {"pairs": int(len(p["frame"]))}
    for cue in CUE_KINDS:
        out[cue] = [_share(p[f"truth_{cue}"][:, k], p[f"alt_{cue}"][:, k]) for k in range(len(levels))]
    out["prior"] = _share(p["truth_prior"], p["alt_prior"])
    out["score"] = _share(p["truth_score"], p["alt_score"])
    return out


def combined_share(p: dict, base: str, cue: str, level: int, weight: float) -> float:
    """Share of pairs on which ``base + weight * cue`` (the cue at noise level index ``level``) rates the truth better."""
    t = p[f"truth_{base}"] + weight * p[f"truth_{cue}"][:, level]
    a = p[f"alt_{base}"] + weight * p[f"alt_{cue}"][:, level]
    return _share(t, a)


def pair_diffs(p: dict, levels, weights: dict | None = None) -> tuple[list[str], np.ndarray]:
    """Per pair the differences (alternative minus truth) of each column: ``score``, ``prior``,
    ``points@<level>`` and ``span@<level>``, and with ``weights`` ({level: w}) ``score+points@<level>``."""
    names, cols = ["score", "prior"], [p["alt_score"] - p["truth_score"], p["alt_prior"] - p["truth_prior"]]
    for cue in CUE_KINDS:
        for k, level in enumerate(levels):
            names.append(f"{cue}@{level:g}")
            cols.append(p[f"alt_{cue}"][:, k] - p[f"truth_{cue}"][:, k])
    for k, level in enumerate(levels):
        if weights is not None and level in weights:
            names.append(f"score+points@{level:g}")
            cols.append(cols[0] + weights[level] * (p["alt_points"][:, k] - p["truth_points"][:, k]))
    return names, np.stack(cols, axis=1)


def window_shares(units: dict, keys, levels, weights: dict | None = None, window: int = WINDOW) -> dict:
    """Evidence summed over the lag (as :func:`experiments.branch_audit.window_rates`): per unit and
    mirror slot (a branch followed through time), windows of ``window`` frames starting at every
    audited frame, kept when the slot is compared on at least half the window's audited frames; per
    column of :func:`pair_diffs` the share of windows whose summed difference favours the truth."""
    rows, names = [], None
    for key in keys:
        u = units[key]
        if len(u["frame"]) == 0:
            continue
        stride = int(np.min(np.diff(np.unique(u["frame"])))) if len(np.unique(u["frame"])) > 1 else 1
        names, diff = pair_diffs(u, levels, weights)
        n = int(u["frame"].max()) + 1
        audited = max(1, -(-window // stride))
        for slot in np.unique(u["slot"]):
            sel = u["slot"] == slot
            d = np.full((n, diff.shape[1]), np.nan)
            d[u["frame"][sel]] = diff[sel]
            present = np.isfinite(d[:, 1])
            for start in range(0, max(n - window + 1, 0), stride):
                if present[start:start + window].sum() * 2 < audited:
                    continue
                block = d[start:start + window]
                total = np.nansum(block, axis=0)
                margin = TIE_RELATIVE * np.maximum(1.0, np.nansum(np.abs(block), axis=0))
                rows.append(total > margin)
    if not rows:
        return {"windows": 0}
    r = np.array(rows)
    return {"windows": int(len(r)), **{c: float(r[:, i].mean()) for i, c in enumerate(names)}}


def summarise(units: dict) -> dict:
    """Every reported number of units keyed by (sequence, seed) (see the module).

    ``groups``: ``fit`` (seeds :data:`FIT_SEEDS`) and ``unseen`` (:data:`UNSEEN_SEED`), each with
    ``pooled``, ``per_sequence``, ``per_kind`` (:data:`FLIP_KINDS`) and ``per_depth`` (bins of
    :data:`DEPTH_BINS_M` of the hand's |depth change|) shares (:func:`shares`); ``signal``: the
    mirror's noise-free change of the hand points (median mean move, px; median |span change|, px)
    and of the hand's depth (m), per kind; ``combined``: per base (``score``, ``prior``), cue and
    level, the weight chosen on the fit seeds (the best share there, the smallest weight on a
    tie) and its shares on both groups, beside the base alone.
    """
    levels = list(next(iter(units.values()))["noise_px"].tolist())
    out = {"settings": {"noise_px": levels, "mediapipe_sigma_px": MEDIAPIPE_SIGMA_PX,
                        "mediapipe_json_sigma_px": MEDIAPIPE_JSON_SIGMA_PX, "distinct_m": DISTINCT_M,
                        "input_size": list(INPUT_SIZE), "knuckle_along": KNUCKLE_ALONG,
                        "knuckle_across": KNUCKLE_ACROSS, "fit_seeds": list(FIT_SEEDS), "unseen_seed": UNSEEN_SEED,
                        "depth_bins_m": list(DEPTH_BINS_M), "flip_kinds": list(FLIP_KINDS)},
           "units": [f"{k[0]} s{k[1]}" for k in units], "groups": {}}
    rms = np.concatenate([u["body_rms_px"] for u in units.values()])
    out["body_rms_px_median"] = float(np.median(rms))
    out["json_wrist_sigma_px"] = JSON_WRIST_SIGMA * float(np.median(rms))
    out["frames"] = int(sum(int(u["frames"]) for u in units.values()))
    groups = {"fit": [k for k in units if k[1] in FIT_SEEDS], "unseen": [k for k in units if k[1] == UNSEEN_SEED]}
    merged = {}
    for g, keys in groups.items():
        if not keys:
            continue
        p = merged[g] = pooled(units, keys)
        dz = np.abs(p["hand_dz"])
        edges = np.asarray(DEPTH_BINS_M)
        out["groups"][g] = {
            "units": len(keys), "frames": int(sum(int(units[k]["frames"]) for k in keys)),
            "pooled": shares(p, levels),
            "per_sequence": {n: shares(pooled(units, [k for k in keys if k[0] == n]), levels)
                             for n in dict.fromkeys(k[0] for k in keys)},
            "per_kind": {kind: shares({k: v[p["kind"] == i] for k, v in p.items()}, levels)
                         for i, kind in enumerate(FLIP_KINDS)},
            "per_depth": [dict(low_m=float(lo), high_m=float(hi),
                               **shares({k: v[(dz >= lo) & (dz < hi)] for k, v in p.items()}, levels))
                          for lo, hi in zip(edges[:-1], edges[1:])],
            "signal": {kind: {"move_px": float(np.median(p["move_px"][sel])) if sel.any() else math.nan,
                              "span_change_px": np.median(np.abs(p["span_change_px"][sel]), axis=0).tolist()
                              if sel.any() else [math.nan, math.nan],
                              "hand_dz_m": float(np.median(dz[sel])) if sel.any() else math.nan}
                       for kind, sel in [(k, p["kind"] == i) for i, k in enumerate(FLIP_KINDS)] + [("all", p["kind"] >= 0)]},
        }
    out["combined"] = []
    if "fit" in merged:
        for base in ("score", "prior"):
            if not np.isfinite(merged["fit"][f"truth_{base}"]).any():
                continue
            for cue in CUE_KINDS:
                for li, level in enumerate(levels):
                    fit = [combined_share(merged["fit"], base, cue, li, w) for w in COMBINE_WEIGHTS]
                    best = int(np.argmax(fit))
                    w = COMBINE_WEIGHTS[best]
                    row = {"base": base, "cue": cue, "noise_px": level, "weight": w, "fit_base": fit[0],
                           "fit": fit[best], "fit_curve": fit}
                    if "unseen" in merged:
                        row["unseen_base"] = combined_share(merged["unseen"], base, cue, li, 0.0)
                        row["unseen"] = combined_share(merged["unseen"], base, cue, li, w)
                        row["unseen_curve"] = [combined_share(merged["unseen"], base, cue, li, x) for x in COMBINE_WEIGHTS]
                    out["combined"].append(row)
    out["combine_weights"] = list(COMBINE_WEIGHTS)
    chosen = {r["noise_px"]: r["weight"] for r in out["combined"] if r["base"] == "score" and r["cue"] == "points"}
    out["window"] = WINDOW
    for g, keys in groups.items():
        if keys:
            out["groups"][g]["windows"] = window_shares(units, keys, levels, chosen or None)
    return out


def tables(summary: dict) -> str:
    """Markdown tables of :func:`summarise`."""
    pct = lambda v: "–" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{100 * v:.1f}"
    levels = summary["settings"]["noise_px"]
    head = ["group", "pairs"] + [f"points σ={s:g}" for s in levels] + [f"span σ={s:g}" for s in levels] + ["prior", "score"]
    lines = [f"{summary['frames']} frames audited; noise σ per coordinate at {summary['settings']['input_size'][0]}x"
             f"{summary['settings']['input_size'][1]} px (MediaPipe: {summary['settings']['mediapipe_sigma_px']:.1f} px "
             f"image mode, {summary['settings']['mediapipe_json_sigma_px']:g} px the lifter's noise file; the joints' RMS "
             f"spread {summary['body_rms_px_median']:.0f} px, the file's wrist σ = {summary['json_wrist_sigma_px']:.1f} px)",
             ""]

    def row(name, r):
        if not r.get("pairs"):
            return "| " + " | ".join([name, "0"] + ["–"] * (len(head) - 2)) + " |"
        return "| " + " | ".join([name, str(r["pairs"])] + [pct(v) for v in r["points"]] + [pct(v) for v in r["span"]]
                                 + [pct(r["prior"]), pct(r["score"])]) + " |"

    for g, data in summary["groups"].items():
        seeds = ",".join(map(str, summary["settings"]["fit_seeds"])) if g == "fit" else str(summary["settings"]["unseen_seed"])
        lines += [f"### seeds {seeds}: share of pairs (truth, distinct exact mirror) with the truth better, %", "",
                  "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        lines += [row(n, r) for n, r in data["per_sequence"].items()] + [row("**pooled**", data["pooled"])]
        lines += [row(f"flip: {k}", r) for k, r in data["per_kind"].items()]
        lines += [row(f"hand |dz| {100 * r['low_m']:.0f}-{100 * r['high_m']:.0f} cm", r) for r in data["per_depth"]]
        lines += ["", "signal (noise-free, medians): " + "; ".join(
            f"{k}: hand points move {s['move_px']:.1f} px, palm width {s['span_change_px'][0]:.1f} px, "
            f"length {s['span_change_px'][1]:.1f} px, hand depth {100 * s['hand_dz_m']:.0f} cm"
            for k, s in data["signal"].items()), ""]
    windows = {g: d["windows"] for g, d in summary["groups"].items() if d.get("windows", {}).get("windows")}
    if windows:
        columns = [c for c in next(iter(windows.values())) if c != "windows"]
        lines += [f"### evidence summed over {summary['window']} frames per mirror branch: share of windows with the "
                  "truth better (%); score+points: the per-pair weight below", "",
                  "| column | " + " | ".join(f"{g} ({w['windows']} windows)" for g, w in windows.items()) + " |",
                  "|---|" + "---|" * len(windows)]
        lines += [f"| {c} | " + " | ".join(pct(w.get(c, math.nan)) for w in windows.values()) + " |" for c in columns]
        lines.append("")
    if summary["combined"]:
        lines += ["### base + w * hand cue: w chosen on the fit seeds, judged on the unseen seed (%)", "",
                  "| base | cue | σ px | w | fit: base | fit: combined | unseen: base | unseen: combined | gain |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for r in summary["combined"]:
            gain = r.get("unseen", math.nan) - r.get("unseen_base", math.nan)
            lines.append(f"| {r['base']} | {r['cue']} | {r['noise_px']:g} | {r['weight']:g} | {pct(r['fit_base'])} | "
                         f"{pct(r['fit'])} | {pct(r.get('unseen_base'))} | {pct(r.get('unseen'))} | "
                         f"{'–' if math.isnan(gain) else f'{100 * gain:+.1f}'} |")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
