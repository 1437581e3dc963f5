"""``python -m experiments.branch_audit``: can the cues tell a pose from its depth mirrors?

The evidence audit of issue 39 (item 1), before the tracker's branch comparison is designed.
On every frame of a benchmark sequence it takes the **true pose** and its **depth
alternatives**: each arm bone's depth flipped about its parent joint (the upper arm about the
shoulder, the forearm about the elbow, or both: the child joint moved to the other crossing of
its camera ray with the sphere of the bone's length about the parent), which keeps the joints'
projections and the bone lengths, placed onto the body within the joint limits: the tracker's own
:func:`mocap.track.branches.depth_alternatives`. A mirror that the limits do not let the arm reach
(the tracker's pruning thresholds, :func:`mirror_alternatives`) is **pruned**: counted, not compared.

Every candidate (the truth and each alternative) is scored by each cue twice: **unrefined**
(the exact mirror as built, no registration) and **refined** (the tracker's two-step
registration, :func:`mocap.track.register` with the tracker's config and the frame's keypoint
distance, started where the candidate stands, with the same number of evaluations for every
candidate). The cues (:data:`CUES`, lower is better for each):

* ``region``: F, the non-overlapping ratio (eq. 1); ``edge``: the mean edge distance (eq. 2, px);
* ``keypoint``: the keypoint distance D_k (px) to the frame's keypoints (true 2D + noise, as the
  experiments' oracle keypoints: :func:`experiments.keypoints.oracle_keypoints`);
* ``lifter``: the lifter term (:meth:`mocap.track.proposals.LifterSource.energy`, nats, capped);
* ``prior``: the pose prior's energy (nats);
* ``world``: the number of arm bones whose depth branch (the child's depth along its camera ray
  relative to the parent, :func:`depth_order_disagreements`) disagrees with the keypoints' own 3D
  (MediaPipe's world landmarks); NaN without them (the oracle keypoints have none);
* and two weighted sums: ``region_edge`` (``REGION_WEIGHT * F + edge_weight * edge``, the
  tracker's weights) and ``score`` (the tracker's whole unary score with keypoints: plus
  ``keypoint_weight``, ``prior_weight`` and ``lifter_weight`` times theirs).

A pair (truth, alternative) is compared only when the alternative is **distinct**: some joint at
least :data:`DISTINCT_M` from the truth's. A cue **separates** the pair when it rates the truth
lower than the alternative by more than rounding (:func:`truth_better`); after refinement a pair
whose refined alternative came back within :data:`DISTINCT_M` of the truth's joints (every joint)
also counts as separated (nothing wrong can be chosen), and is counted as ``collapsed``. A frame
is at the **ambiguity floor** when one of its distinct alternatives is separated by none of the
single cues: nothing the cues see could choose the truth there.

Results go to ``--out`` (default ``experiments/results/branch_audit``): the generated sequences
(as :mod:`experiments.ambiguity`), and one ``.npz`` per sequence, seed and budget under
``units/`` (written atomically, each when its sequence is done; a crash loses at most the
sequence in progress). A unit is reused only when it was measured with the same code
(:func:`measuring_code_key`) and settings. ``report`` prints the
tables (and ``--json`` a summary) and draws the figure (:mod:`experiments.figures.ext_branch_audit`).
"""
from __future__ import annotations

import argparse
import io
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from experiments import RESULTS_DIR
from experiments.config import sequence_list
from mocap.body.jumps import ARM_JUMPS, SIDES
from mocap.body.pose import clamp_to_limits
from mocap.body.skeleton import JOINT_INDEX, JOINT_NAMES
from mocap.synth import SEQUENCE_NAMES, SEQUENCES
from mocap.track import TrackerConfig

#: Candidate slots of a frame: the truth, then each arm's alternatives.
SLOTS: tuple[str, ...] = ("truth",) + tuple(f"{side}_{name}" for side in SIDES for name in ARM_JUMPS)
#: Single cues, lower is better for each (see the module).
CUES: tuple[str, ...] = ("region", "edge", "keypoint", "lifter", "prior", "world")
#: The weighted sums of cues (see the module).
COMBINED: tuple[str, ...] = ("region_edge", "score")
#: Every column of a candidate's cue vector.
COLUMNS: tuple[str, ...] = CUES + COMBINED
#: An alternative is compared only when some joint is at least this far from the truth's (metres).
DISTINCT_M = 0.05
#: Relative difference under which two cue values count as a tie (rounding).
TIE_RELATIVE = 1e-6
#: Oracle keypoint noise, pixels (as the experiments' oracle keypoints).
ORACLE_SIGMA_PX = 2.0
#: Arm bones as (parent, child) joint names, for the depth-order cue.
ARM_BONES: tuple[tuple[str, str], ...] = tuple((f"{s}_{a}", f"{s}_{b}") for s in SIDES
                                               for a, b in (("shoulder", "elbow"), ("elbow", "wrist")))
#: Seeds the logistic combination is fitted on; it is checked on the others.
FIT_SEEDS: tuple[int, ...] = (0, 1, 2)


@dataclass(frozen=True)
class Alternative:
    """One depth alternative of a pose.

    Attributes
    ----------
    name : str
        Its slot (:data:`SLOTS`), e.g. ``"r_forearm"``.
    pose : ndarray, shape (23,), float64
        Inside the joint limits (metres, radians).
    pruned : bool
        Whether the limits keep the arm off the exact mirror (see :func:`mirror_alternatives`).
    """

    name: str
    pose: np.ndarray
    pruned: bool


#: Each flip of :func:`mocap.track.branches.depth_alternatives` by its slot name.
FLIP_NAMES = {("upper_arm",): "upper_arm", ("forearm",): "forearm", ("upper_arm", "forearm"): "both"}


def mirror_alternatives(pose, model, camera) -> list[Alternative]:
    """The depth alternatives of ``pose`` as the tracker builds them
    (:func:`mocap.track.branches.depth_alternatives`), the pruned ones kept and marked.

    Built without pruning, then marked pruned by the tracker's own thresholds: the placed arm more
    than :data:`~mocap.track.branches.MAX_MISS_M` off the exact mirror (the joint limits do not let
    it take the other branch) or a joint's projection moved more than
    :data:`~mocap.track.branches.MAX_SHIFT_PX`. A mirror whose arm moves less than
    :data:`~mocap.track.branches.MIN_CHANGE_M` is left out, as the tracker does.

    Parameters
    ----------
    pose : array_like, shape (23,)
    model : BodyModel
    camera : Camera

    Returns
    -------
    list of Alternative
        In :data:`SLOTS` order.
    """
    from mocap.track.branches import MAX_MISS_M, MAX_SHIFT_PX, depth_alternatives

    return [Alternative(f"{a.side}_{FLIP_NAMES[a.flipped]}", a.pose, a.miss_m > MAX_MISS_M or a.shift_px > MAX_SHIFT_PX)
            for a in depth_alternatives(pose, model, camera, max_shift_px=1e9, max_miss_m=1e9)]


def depth_order_disagreements(joints, world) -> float:
    """Arm bones whose depth branch disagrees with a detector's 3D.

    A bone's branch is the sign of its child's depth along the child's own camera ray relative to
    the parent, ``(child - parent) . ray``: what a depth mirror flips (the joints' z difference
    does not flip for a bone seen off the optical axis: an arm hanging below a camera at chest
    height keeps the hand nearer in z on both branches). The detector's 3D is read along the same
    ray (its origin is free, its axes the camera's).

    Parameters
    ----------
    joints : array_like, shape (10, 3), metres
        A candidate's joints (camera coordinates).
    world : array_like, shape (10, 3), metres, or None
        The detector's 3D of each joint (camera axes, any origin; NaN where absent).

    Returns
    -------
    float
        How many of :data:`ARM_BONES` have opposite signs (bones with an absent joint left out);
        NaN without ``world``.
    """
    if world is None:
        return math.nan
    j, w = np.asarray(joints, dtype=np.float64), np.asarray(world, dtype=np.float64)
    count = 0
    for parent, child in ARM_BONES:
        a, b = JOINT_INDEX[parent], JOINT_INDEX[child]
        ray = j[b] / np.linalg.norm(j[b])
        dw = float((w[b] - w[a]) @ ray)
        if np.isfinite(dw) and dw != 0.0 and float((j[b] - j[a]) @ ray) * dw < 0.0:
            count += 1
    return float(count)


def cue_vector(tracker, costs, keypoint_cost, lifted, world, pose, region=None, edge=None, keypoint=None) -> np.ndarray:
    """The cues of one pose (:data:`COLUMNS` order); residuals already known may be passed."""
    cfg = tracker.config
    region_cost, edge_cost = costs
    joints = tracker.model.joint_positions(pose)
    r = region_cost(pose) if region is None else region
    e = edge_cost(pose) if edge is None else edge
    k = (keypoint_cost(pose) if keypoint is None else keypoint) if keypoint_cost is not None else math.nan
    lifter = tracker.lifting.energy(lifted, joints) if lifted is not None else math.nan
    prior = tracker.prior.energy(pose) if tracker.prior is not None else math.nan
    order = depth_order_disagreements(joints, world)
    from mocap.track.config import REGION_WEIGHT
    region_edge = REGION_WEIGHT * r + cfg.edge_weight * e
    score = region_edge + sum(w * v for w, v in ((cfg.keypoint_weight, k), (cfg.prior_weight, prior),
                                                  (cfg.lifter_weight, lifter)) if not math.isnan(v))
    return np.array([r, e, k, lifter, prior, order, region_edge, score])


def audit_frames(model, camera, config: TrackerConfig, truth_poses, prepared, keypoints, evaluations: int,
                 alternatives=mirror_alternatives, progress: bool = False, description: str = "auditing",
                 stride: int = 1) -> dict:
    """The audit's raw measurements on a run of frames.

    Parameters
    ----------
    model : BodyModel
    camera : Camera
    config : TrackerConfig
        The tracker's settings (registration, weights, lifter, prior).
    truth_poses : ndarray, shape (N, 23)
    prepared : sequence of PreparedFrame, length N
    keypoints : sequence of Keypoints or None, length N
    evaluations : int
        Every candidate's refinement budget.
    alternatives : callable
        ``alternatives(pose, model, camera) -> list[Alternative]`` (default :func:`mirror_alternatives`).
    stride : int
        Audit every ``stride``-th frame only (the others stay empty: ``exists`` False); the
        unit's ``stride`` records it.

    Returns
    -------
    dict of str to ndarray
        ``exists`` (N, S) bool, ``pruned`` (N, S) bool, ``start_joints`` and ``refined_joints``
        (N, S, 10, 3) metres, ``unrefined`` and ``refined`` (N, S, len(COLUMNS)) cue values,
        ``refined_evaluations`` (N, S) int, ``truth_joints`` (N, 10, 3); S = len(:data:`SLOTS`),
        NaN where a candidate does not exist. The **leader** stage: ``leader_exists``,
        ``leader_pruned``, ``leader_joints`` and ``leader`` (cues), slot 0 the refined truth (the
        converged leader) and the others its own exact mirrors, unrefined: what the tracker would
        compare when it builds the alternatives from its converged leader.
    """
    from tqdm import tqdm

    from mocap.track import Tracker, register

    n, s, c = len(prepared), len(SLOTS), len(COLUMNS)
    if len(truth_poses) != n or len(keypoints) != n:
        raise ValueError(f"need as many true poses and keypoints as frames, got {len(truth_poses)}, "
                         f"{len(keypoints)} and {n}")
    tracker = Tracker(model, camera, config, truth_poses[0])
    out = {"exists": np.zeros((n, s), bool), "pruned": np.zeros((n, s), bool),
           "start_joints": np.full((n, s, len(JOINT_NAMES), 3), np.nan),
           "refined_joints": np.full((n, s, len(JOINT_NAMES), 3), np.nan),
           "unrefined": np.full((n, s, c), np.nan), "refined": np.full((n, s, c), np.nan),
           "refined_evaluations": np.zeros((n, s), np.int64),
           "truth_joints": np.array([model.joint_positions(q) for q in truth_poses]),
           "leader_exists": np.zeros((n, s), bool), "leader_pruned": np.zeros((n, s), bool),
           "leader_joints": np.full((n, s, len(JOINT_NAMES), 3), np.nan), "leader": np.full((n, s, c), np.nan),
           "stride": np.array(int(stride))}
    for i in tqdm(range(0, n, stride), desc=description, unit="frame", disable=not progress):
        if prepared[i].is_empty:
            continue
        costs = tracker.costs(prepared[i])
        kp = keypoints[i]
        keypoint_cost = tracker.keypoint_cost(kp)
        lifted = tracker.lifting.lift(kp, camera, model) if tracker.lifting is not None else None
        world = None if kp is None else kp.world
        truth = clamp_to_limits(np.asarray(truth_poses[i], dtype=np.float64))
        candidates = [("truth", truth, False)] + [(a.name, a.pose, a.pruned) for a in alternatives(truth, model, camera)]
        for name, pose, pruned in candidates:
            k = SLOTS.index(name)
            out["exists"][i, k], out["pruned"][i, k] = True, pruned
            out["start_joints"][i, k] = model.joint_positions(pose)
            if pruned:
                continue
            out["unrefined"][i, k] = cue_vector(tracker, costs, keypoint_cost, lifted, world, pose)
            reg = register(*costs, pose, config, evaluations=evaluations, keypoint_cost=keypoint_cost)
            out["refined_joints"][i, k] = model.joint_positions(reg.pose)
            out["refined_evaluations"][i, k] = reg.evaluations
            out["refined"][i, k] = cue_vector(tracker, costs, keypoint_cost, lifted, world, reg.pose,
                                              reg.region_residual, reg.edge_residual,
                                              reg.keypoint_residual if keypoint_cost is not None else None)
            if k == 0:                          # the converged leader and its own exact mirrors
                out["leader_exists"][i, 0] = True
                out["leader_joints"][i, 0] = out["refined_joints"][i, 0]
                out["leader"][i, 0] = out["refined"][i, 0]
                for a in alternatives(reg.pose, model, camera):
                    j = SLOTS.index(a.name)
                    out["leader_exists"][i, j], out["leader_pruned"][i, j] = True, a.pruned
                    out["leader_joints"][i, j] = model.joint_positions(a.pose)
                    if not a.pruned:
                        out["leader"][i, j] = cue_vector(tracker, costs, keypoint_cost, lifted, world, a.pose)
    return out


#: Materials the audit runs on: the six benchmark sequences at full length with the oracle's true
#: 2D (or MediaPipe's); ``peers``: :mod:`experiments.peers`' synthetic clips and ``cmu``: its
#: CMU-driven clips (the held-out subject's trials in the scenes), both with MediaPipe's 2D and 3D.
MATERIALS: tuple[str, ...] = ("benchmark", "peers", "cmu")
#: Keypoint sources: the truth's projection plus noise, or MediaPipe Pose on the frames enlarged 4x.
KEYPOINT_SOURCES: tuple[str, ...] = ("oracle", "mediapipe")


def material_clips(material: str, sequences: tuple[str, ...], train: Path | None = None) -> list[tuple[str, str | None, int]]:
    """The clips of a material as (name, motion file or None, frames)."""
    from experiments import peers

    if material == "benchmark":
        return [(s, None, SEQUENCES[s].frames) for s in sequences]
    if material == "peers":
        return [(s, None, peers.SYNTHETIC_FRAMES) for s in peers.SYNTHETIC]
    if material == "cmu":
        if train is None:
            raise ValueError("the cmu material needs the CMU trials folder (--train)")
        trials = peers.CMU_TRIALS["14"]
        return [(scene, str(train / f"cmu_{trial}.amc"), peers.CMU_FRAMES)
                for trial, scene in zip(trials, peers.CMU_SCENES)]
    raise ValueError(f"material must be one of {MATERIALS}, got {material!r}")


def mediapipe_keypoints(frames, cache: Path) -> list:
    """MediaPipe Pose's arm joints (2D) and its 3D joints on ``frames``, as :mod:`experiments.peers`
    gives them to the tracker (frames enlarged 4x; a Keypoints per frame, None where nobody was
    found), its landmarks cached in ``cache`` (``.npz``)."""
    from experiments.peers import arm_indices, run_mediapipe
    from mocap.io.keypoints import Keypoints
    from mocap.io.mediapipe_keypoints import world_joints

    if cache.is_file():
        with np.load(cache) as z:
            mp = {k: z[k] for k in z.files}
    else:
        mp = run_mediapipe(frames, upscale=4)
        cache.parent.mkdir(parents=True, exist_ok=True)
        np.savez(cache, **mp)
    out = []
    for i in range(len(frames)):
        if not np.isfinite(mp["uv"][i]).all():
            out.append(None)
            continue
        full = np.full((len(JOINT_NAMES), 2), np.nan)
        full[arm_indices()] = mp["uv"][i]
        world = (world_joints(mp["world33"][i], mp["visibility33"][i])[0] if np.isfinite(mp["world33"][i]).all()
                 else None)
        out.append(Keypoints(full, np.where(np.isfinite(full).all(axis=1), 1.0, 0.0), world))
    return out


def audit_sequence(sequence: str, seed: int, root: Path, config: TrackerConfig, evaluations: int,
                   sigma_px: float = ORACLE_SIGMA_PX, frames: int | None = None, progress: bool = False,
                   motion: str | None = None, keypoint_source: str = "oracle", stride: int = 1) -> dict:
    """:func:`audit_frames` on a benchmark sequence (``motion``: driven by that clip; generated
    under ``root`` if not there) with the oracle keypoints of its truth (``sigma_px``, seeded by
    ``seed``) or MediaPipe's (:func:`mediapipe_keypoints`)."""
    from experiments.keypoints import oracle_keypoints
    from experiments.units import DataSpec, load_prepared, load_sequence, prepare_data

    length = SEQUENCES[sequence].frames if frames is None else frames
    spec = DataSpec(sequence, motion, length, seed, 160, 120)
    folder = prepare_data(spec, str(root))
    loaded, prepared = load_sequence(folder, length), load_prepared(folder)
    n = min(length, len(prepared), len(loaded.ground_truth.poses))
    camera = loaded.calibration.camera
    truth = np.asarray(loaded.ground_truth.poses[:n], dtype=np.float64)
    if keypoint_source == "oracle":
        keypoints = oracle_keypoints(loaded.ground_truth.joints[:n], camera, sigma_px, seed)
    elif keypoint_source == "mediapipe":
        keypoints = mediapipe_keypoints(loaded.frames[:n], Path(folder) / f"mediapipe-{n}.npz")
    else:
        raise ValueError(f"keypoint_source must be one of {KEYPOINT_SOURCES}, got {keypoint_source!r}")
    return audit_frames(loaded.model, camera, config, truth, prepared[:n], keypoints, evaluations,
                        progress=progress, description=f"{spec.name} s{seed}", stride=stride)


# -- analysis ----------------------------------------------------------------------------------
def truth_better(truth, other) -> np.ndarray:
    """Whether the truth's cue value is lower than another's by more than rounding.

    Parameters
    ----------
    truth, other : array_like, same shape
        Cue values (NaN: not measured, never better).

    Returns
    -------
    ndarray of bool
        ``truth < other`` with a margin of :data:`TIE_RELATIVE` of the larger magnitude (at least 1).
    """
    a, b = np.asarray(truth, dtype=np.float64), np.asarray(other, dtype=np.float64)
    margin = TIE_RELATIVE * np.maximum(1.0, np.maximum(np.abs(a), np.abs(b)))
    with np.errstate(invalid="ignore"):
        return (b - a) > margin


def max_joint_distance(a, b) -> np.ndarray:
    """Largest joint distance between joint sets (..., 10, 3) -> (...), metres."""
    return np.linalg.norm(np.asarray(a) - np.asarray(b), axis=-1).max(axis=-1)


def pairs(unit: dict) -> dict:
    """The compared pairs of a unit: each distinct, unpruned alternative against the truth.

    Returns
    -------
    dict of str to ndarray
        ``frame`` (P,) and ``slot`` (P,) indices; ``unrefined`` and ``refined`` (P, len(COLUMNS))
        bool: the cue separates the pair (refined: or the alternative collapsed); ``collapsed``
        (P,) bool; ``diff_unrefined`` and ``diff_refined`` (P, len(COLUMNS)): the alternative's
        cue minus the truth's.
    """
    exists, pruned = unit["exists"], unit["pruned"]
    start_distance = max_joint_distance(unit["start_joints"], unit["truth_joints"][:, None])
    compared = exists & ~pruned & (start_distance >= DISTINCT_M)
    compared[:, 0] = False
    frame, slot = np.nonzero(compared)
    u, r = unit["unrefined"], unit["refined"]
    collapsed = max_joint_distance(unit["refined_joints"][frame, slot], unit["truth_joints"][frame]) < DISTINCT_M
    sep_u = truth_better(u[frame, 0], u[frame, slot])
    sep_r = truth_better(r[frame, 0], r[frame, slot]) | collapsed[:, None]
    out = {"frame": frame, "slot": slot, "unrefined": sep_u, "refined": sep_r, "collapsed": collapsed,
           "diff_unrefined": u[frame, slot] - u[frame, 0], "diff_refined": r[frame, slot] - r[frame, 0]}
    if "leader" in unit:
        distance = max_joint_distance(unit["leader_joints"], unit["leader_joints"][:, :1])
        lead = unit["leader_exists"] & ~unit["leader_pruned"] & (distance >= DISTINCT_M)
        lead[:, 0] = False
        lf, ls = np.nonzero(lead)
        v = unit["leader"]
        out.update(leader_frame=lf, leader_slot=ls, leader=truth_better(v[lf, 0], v[lf, ls]),
                   diff_leader=v[lf, ls] - v[lf, 0])
    return out


def stage_pairs(p: dict, stage: str) -> dict:
    """The pairs of one stage (``unrefined``, ``refined`` or ``leader``) as ``frame``, ``slot``,
    ``separated`` (P, len(COLUMNS)) and ``diff`` (P, len(COLUMNS))."""
    if stage == "leader":
        return {"frame": p["leader_frame"], "slot": p["leader_slot"], "separated": p["leader"], "diff": p["diff_leader"]}
    return {"frame": p["frame"], "slot": p["slot"], "separated": p[stage], "diff": p[f"diff_{stage}"]}


#: The comparisons reported: the truth against its exact mirrors, both unrefined; both refined
#: with the same budget; the refined truth (a converged leader) against its own exact mirrors.
STAGES: tuple[str, ...] = ("unrefined", "refined", "leader")
STAGE_TEXT = {"unrefined": "the truth against its exact mirrors, no registration",
              "refined": "the truth and its mirrors each registered with the same budget from where they stand",
              "leader": "the refined truth (a converged leader) against its own exact mirrors, unrefined"}


def frame_rates(n: int, sp: dict, separated: np.ndarray | None = None) -> dict:
    """Per-frame shares over the frames (of ``n``) with a compared pair of one stage (:func:`stage_pairs`).

    ``<cue>``: the share of those frames on which the cue separates every pair (it alone would
    choose the truth); ``floor``: the share on which some pair is separated by no single cue.
    ``separated`` (P,) adds ``logistic``: one decision per pair (the logistic combination)."""
    has_pair = np.zeros(n, bool)
    has_pair[sp["frame"]] = True
    frames = int(has_pair.sum())
    out = {"frames": frames}
    if frames == 0:
        return out
    cols = sp["separated"]
    single = [COLUMNS.index(c) for c in CUES]
    bad = np.zeros(n, bool)
    np.logical_or.at(bad, sp["frame"], ~cols[:, single].any(axis=1))
    out["floor"] = float(bad[has_pair].mean())
    for name, sep in [(c, cols[:, COLUMNS.index(c)]) for c in COLUMNS] + (
            [("logistic", separated)] if separated is not None else []):
        missed = np.zeros(n, bool)
        np.logical_or.at(missed, sp["frame"], ~sep)
        out[name] = float((~missed[has_pair]).mean())
    return out


#: Frames of evidence summed for a decision over the tracker's default lag (``lag`` + 1).
WINDOW = 9


def window_rates(n: int, sp: dict, window: int = WINDOW, stride: int = 1) -> np.ndarray:
    """Evidence accumulated over windows: per cue, whether the cue's differences (alternative minus
    truth) summed over ``window`` consecutive frames favour the truth.

    Each alternative slot is a branch followed through time; a window counts for a slot when the
    slot is compared on at least half its audited frames (every ``stride``-th), and the sum runs
    over those frames.

    Parameters
    ----------
    n : int
        Frames of the unit.
    sp : dict
        :func:`stage_pairs` of the unit.

    Returns
    -------
    ndarray of bool, shape (W, len(COLUMNS))
        One row per counted (window, slot); a cue without values is False.
    """
    rows = []
    for slot in np.unique(sp["slot"]):
        sel = sp["slot"] == slot
        diff = np.full((n, len(COLUMNS)), np.nan)
        diff[sp["frame"][sel]] = sp["diff"][sel]
        present = np.isfinite(diff[:, 0])
        audited = max(1, -(-window // stride))
        for start in range(0, max(n - window + 1, 0), stride):
            if present[start:start + window].sum() * 2 < audited:
                continue
            total = np.nansum(diff[start:start + window], axis=0)
            margin = TIE_RELATIVE * np.maximum(1.0, np.nansum(np.abs(diff[start:start + window]), axis=0))
            rows.append(total > margin)
    return np.array(rows, dtype=bool).reshape(-1, len(COLUMNS))


#: The cues the logistic combination weighs.
LOGISTIC_CUES: tuple[str, ...] = ("region", "edge", "keypoint", "lifter", "prior")


def logistic_fit(diffs: np.ndarray, columns: tuple[str, ...] = LOGISTIC_CUES):
    """A logistic decision on the cue differences (alternative minus truth), no intercept, each
    difference scaled by its standard deviation; each pair enters both ways round.

    Returns
    -------
    (callable, dict)
        ``decide(diffs) -> (P,) bool`` (the truth chosen) for (P, len(COLUMNS)) differences, and
        the weights per cue (per unit of the cue).
    """
    from sklearn.linear_model import LogisticRegression

    idx = [COLUMNS.index(c) for c in columns]
    x = np.nan_to_num(diffs[:, idx])
    scale = x.std(axis=0)
    scale[scale == 0] = 1.0
    x = x / scale
    model = LogisticRegression(fit_intercept=False, C=1.0, max_iter=1000)
    model.fit(np.vstack([x, -x]), np.r_[np.ones(len(x)), np.zeros(len(x))])
    weights = model.coef_[0] / scale

    def decide(d: np.ndarray) -> np.ndarray:
        return np.nan_to_num(d[:, idx]) @ weights > 0.0

    return decide, dict(zip(columns, weights.tolist()))


def _shares(sep: np.ndarray, measured: np.ndarray) -> dict:
    return {c: float(sep[:, i].mean()) if len(sep) and measured[i] else math.nan for i, c in enumerate(COLUMNS)}


def summarise(units: dict[tuple[str, int], dict]) -> dict:
    """Every reported number of a set of units keyed by (sequence, seed) (see the module).

    Per stage (:data:`STAGES`), per sequence and pooled: :func:`frame_rates` (frame-weighted),
    ``pairs`` and ``pair_truth_better`` (per cue, the share of pairs it separates),
    ``windows``, ``window_truth_better`` and ``window_floor`` (:func:`window_rates`); refined:
    ``collapsed``. ``per_alternative``: ``pair_truth_better`` per alternative slot. With units of
    :data:`FIT_SEEDS` and of other seeds, a logistic combination per stage fitted on the first
    (``logistic_<stage>_weights``) and its ``logistic`` frame rate on the others.
    """
    per_pair = {k: pairs(u) for k, u in units.items()}
    stages = [st for st in STAGES if all(st != "leader" or "leader" in p for p in per_pair.values())]
    sp = {(k, st): stage_pairs(per_pair[k], st) for k in units for st in stages}
    n_of = {k: u["exists"].shape[0] for k, u in units.items()}
    stride_of = {k: int(u.get("stride", 1)) for k, u in units.items()}
    out = {"settings": {"distinct_m": DISTINCT_M, "tie_relative": TIE_RELATIVE,
                        "window": WINDOW},
           "stages": stages, "per_sequence": {}, "pooled": {}, "per_alternative": {}}
    out["frames"] = sum(int(u["exists"][:, 0].sum()) for u in units.values())
    out["frames_with_pruned_mirror"] = sum(int(u["pruned"][:, 1:].any(axis=1).sum()) for u in units.values())
    out["pruned_share_of_alternatives"] = sum(int(u["pruned"][:, 1:].sum()) for u in units.values()) / max(
        1, sum(int(u["exists"][:, 1:].sum()) for u in units.values()))
    fit_keys = [k for k in units if k[1] in FIT_SEEDS]
    test_keys = [k for k in units if k[1] not in FIT_SEEDS]
    decide = {}
    if fit_keys and test_keys:
        for st in stages:
            decide[st], out[f"logistic_{st}_weights"] = logistic_fit(np.vstack([sp[k, st]["diff"] for k in fit_keys]))

    def group_rates(keys):
        rates = {}
        for st in stages:
            acc, frames = {}, 0
            for k in keys:
                extra = None
                if st in decide and k in test_keys:
                    extra = decide[st](sp[k, st]["diff"])
                    if st == "refined":
                        extra = extra | per_pair[k]["collapsed"]
                r = frame_rates(n_of[k], sp[k, st], extra)
                for name, v in r.items():
                    if name != "frames":            # frame-weighted (logistic: over the checked seeds only)
                        acc.setdefault(name, [0.0, 0])
                        acc[name][0] += v * r["frames"]
                        acc[name][1] += r["frames"]
                frames += r["frames"]
            rate = {"frames": frames, **{n: (a / w if w else math.nan) for n, (a, w) in acc.items()}}
            sep = np.vstack([sp[k, st]["separated"] for k in keys])
            measured = np.isfinite(np.vstack([sp[k, st]["diff"] for k in keys])).any(axis=0)
            for i, c in enumerate(COLUMNS):
                if not measured[i]:             # a cue without values (world on true 2D)
                    rate[c] = math.nan
            rate["pairs"], rate["pair_truth_better"] = int(len(sep)), _shares(sep, measured)
            w = np.vstack([window_rates(n_of[k], sp[k, st], stride=stride_of[k]) for k in keys])
            single = [COLUMNS.index(c) for c in CUES]
            rate["windows"], rate["window_truth_better"] = int(len(w)), _shares(w, measured)
            rate["window_floor"] = float((~w[:, single].any(axis=1)).mean()) if len(w) else math.nan
            if st == "refined":
                collapsed = np.concatenate([per_pair[k]["collapsed"] for k in keys])
                rate["collapsed"] = float(collapsed.mean()) if len(collapsed) else math.nan
            rates[st] = rate
        return rates

    for name in dict.fromkeys(k[0] for k in units):
        out["per_sequence"][name] = group_rates([k for k in units if k[0] == name])
    out["pooled"] = group_rates(list(units))
    for slot in SLOTS[1:]:
        sel = {}
        for st in stages:
            chosen = [(sp[k, st], sp[k, st]["slot"] == SLOTS.index(slot)) for k in units]
            sep = np.vstack([a["separated"][m] for a, m in chosen])
            measured = np.isfinite(np.vstack([a["diff"][m] for a, m in chosen])).any(axis=0)
            sel[st] = {"pairs": int(len(sep)), **_shares(sep, measured)}
        out["per_alternative"][slot] = sel
    return out


def tables(summary: dict) -> str:
    """Markdown tables of :func:`summarise`."""
    pct = lambda v: "–" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{100 * v:.1f}"
    lines = [f"{summary['frames']} frames; {summary['frames_with_pruned_mirror']} with a pruned mirror "
             f"({pct(summary['pruned_share_of_alternatives'])} % of alternatives pruned)", ""]
    for stage in summary["stages"]:
        head = ["sequence", "frames", "pairs"] + [f"{c} %" for c in COLUMNS] + ["logistic %", "floor %"]
        lines += [f"### {stage}: {STAGE_TEXT[stage]}", "",
                  f"**{stage}**: share of frames on which the cue rates the truth better than every distinct "
                  "alternative; floor: frames with an alternative no single cue separates", "",
                  "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for name, rates in list(summary["per_sequence"].items()) + [("**pooled**", summary["pooled"])]:
            r = rates[stage]
            lines.append("| " + " | ".join([name, str(r["frames"]), str(r["pairs"])]
                                           + [pct(r.get(c)) for c in COLUMNS]
                                           + [pct(r.get("logistic")), pct(r.get("floor"))]) + " |")
        lines.append("")
        head = ["alternative", "pairs"] + [f"{c} %" for c in COLUMNS]
        lines += [f"**{stage}**, per pair: share on which the cue rates the truth better", "",
                  "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for slot, sel in summary["per_alternative"].items():
            lines.append("| " + " | ".join([slot, str(sel[stage]["pairs"])] + [pct(sel[stage][c]) for c in COLUMNS]) + " |")
        p = summary["pooled"][stage]
        lines.append("| **all** | " + " | ".join([str(p["pairs"])] + [pct(p["pair_truth_better"][c]) for c in COLUMNS])
                     + " |")
        lines.append("")
        head = ["sequence", "windows"] + [f"{c} %" for c in COLUMNS] + ["floor %"]
        lines += [f"**{stage}**, evidence summed over {WINDOW} frames per alternative branch: share of windows "
                  "on which the sum favours the truth", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for name, rates in list(summary["per_sequence"].items()) + [("**pooled**", summary["pooled"])]:
            r = rates[stage]
            lines.append("| " + " | ".join([name, str(r["windows"])] + [pct(r["window_truth_better"][c]) for c in COLUMNS]
                                           + [pct(r["window_floor"])]) + " |")
        lines.append("")
    if "collapsed" in summary["pooled"]["refined"]:
        lines.append(f"refined alternatives back within {DISTINCT_M * 1e3:.0f} mm of the truth (collapsed): "
                     f"{pct(summary['pooled']['refined']['collapsed'])} %")
    for stage in summary["stages"]:
        if f"logistic_{stage}_weights" in summary:
            w = summary[f"logistic_{stage}_weights"]
            lines.append(f"logistic ({stage}, fitted on seeds {','.join(map(str, FIT_SEEDS))}, checked on the others): "
                         + ", ".join(f"{k} {v:.3g}" for k, v in w.items()))
    return "\n".join(lines)


# -- units on disk ------------------------------------------------------------------------------
def unit_path(out: Path, name: str, seed: int, evaluations: int, frames: int | None, keypoints: str = "oracle",
              stride: int = 1) -> Path:
    """Where a unit is stored: ``out/units/<clip>-s<seed>-e<evaluations>[-<keypoints>][-f<frames>][-x<stride>].npz``."""
    source = "" if keypoints == "oracle" else f"-{keypoints}"
    every = "" if stride == 1 else f"-x{stride}"
    return out / "units" / f"{name}-s{seed}-e{evaluations}{source}{'' if frames is None else f'-f{frames}'}{every}.npz"


def save_unit(path: Path, unit: dict, meta: dict) -> None:
    """Write a unit atomically (the arrays and a JSON ``meta``)."""
    from mocap.io.files import write_bytes_atomic

    buf = io.BytesIO()
    np.savez_compressed(buf, meta=np.array(json.dumps(meta)), **unit)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_bytes_atomic(path, buf.getvalue())


def load_unit(path: Path, meta: dict | None = None) -> dict | None:
    """A unit stored at ``path`` when its meta equals ``meta`` (None: any); else None."""
    if not path.is_file():
        return None
    with np.load(path, allow_pickle=False) as z:
        stored = json.loads(str(z["meta"]))
        if meta is not None and stored != meta:
            print(f"{path.name}: measured with other code or settings; measuring again", file=sys.stderr)
            return None
        return {k: z[k] for k in z.files if k != "meta"}


def measuring_code_key() -> str:
    """Short stable name of the code a unit is measured with: the ``mocap`` package and the
    experiment modules it reads (:func:`experiments.ambiguity.code_key`), and the source of this
    module's measuring functions and constants (the analysis may change without measuring again)."""
    import hashlib
    import inspect

    from experiments.ambiguity import code_key

    here = Path(__file__).resolve().parent
    digest = hashlib.sha256(code_key(modules=(here / "ambiguity.py", here / "units.py", here / "keypoints.py")).encode())
    for f in (mirror_alternatives, depth_order_disagreements, cue_vector, audit_frames):
        digest.update(inspect.getsource(f).encode())
    digest.update(repr((SLOTS, COLUMNS, ORACLE_SIGMA_PX, ARM_BONES)).encode())
    return digest.hexdigest()[:12]


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m experiments.branch_audit", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    for name, text in (("measure", "measure the units not stored yet, then report"),
                       ("report", "report the stored units only")):
        s = sub.add_parser(name, help=text)
        s.add_argument("--material", choices=MATERIALS, default="benchmark",
                       help="benchmark: the six sequences at full length; peers / cmu: experiments.peers' "
                            "synthetic / CMU-driven clips (with --keypoints mediapipe)")
        s.add_argument("--keypoints", choices=KEYPOINT_SOURCES, default="oracle",
                       help=f"oracle: true 2D + {ORACLE_SIGMA_PX:g} px; mediapipe: MediaPipe's 2D arm joints and 3D")
        s.add_argument("--train", type=Path, default=None,
                       help="cmu: the CMU trials folder (default ../shared/data/mocap/train beside the checkout)")
        s.add_argument("--sequences", default=",".join(SEQUENCE_NAMES), help="comma-separated benchmark sequences")
        s.add_argument("--seeds", default="0", help="comma-separated seeds (default 0)")
        s.add_argument("--evaluations", type=int, default=200,
                       help="every candidate's refinement budget (default 200)")
        s.add_argument("--frames", type=int, default=None, help="first frames only (default: full length)")
        s.add_argument("--stride", type=int, default=1, help="audit every N-th frame only (default 1: every frame)")
        s.add_argument("--config", type=Path, default=None, help="TrackerConfig JSON (default: the tracker's)")
        s.add_argument("--out", type=Path, default=RESULTS_DIR / "branch_audit", help="results folder")
        s.add_argument("--json", action="store_true", help="print the summary as JSON instead of the tables")
        s.add_argument("--no-figure", action="store_true", help="do not draw the figure")
        s.add_argument("--no-progress", action="store_true")
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        names = sequence_list(args.sequences)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        seeds = tuple(int(v) for v in args.seeds.split(",") if v.strip())
    except ValueError:
        seeds = ()
    if not seeds or args.evaluations < 1 or args.stride < 1 or (args.frames is not None and args.frames < 1):
        print("error: --seeds takes comma-separated integers, --evaluations, --stride and --frames positive integers",
              file=sys.stderr)
        return 2
    config = TrackerConfig.from_json(args.config) if args.config is not None else TrackerConfig()
    meta = {"code": measuring_code_key(), "config": config.to_dict(), "evaluations": args.evaluations,
            "keypoints": args.keypoints, "sigma_px": ORACLE_SIGMA_PX if args.keypoints == "oracle" else None}
    train = args.train if args.train is not None else Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap" / "train"
    try:
        clips = material_clips(args.material, names, train)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    units = {}
    for seed in seeds:
        for name, motion, length in clips:
            label = name if motion is None else f"{name}+{Path(motion).stem}"
            frames = args.frames if args.frames is not None else (None if args.material == "benchmark" else length)
            path = unit_path(args.out, label, seed, args.evaluations, frames, args.keypoints, args.stride)
            unit = load_unit(path, meta if args.command == "measure" else None)
            if unit is None and args.command == "measure":
                unit = audit_sequence(name, seed, args.out, config, args.evaluations, frames=frames,
                                      progress=not args.no_progress, motion=motion, keypoint_source=args.keypoints,
                                      stride=args.stride)
                save_unit(path, unit, meta)
            if unit is not None:
                units[(label, seed)] = unit
    if not units:
        print("error: no stored units; run measure first", file=sys.stderr)
        return 2
    summary = summarise(units)
    summary["units"] = [f"{k[0]} s{k[1]}" for k in units]
    summary["evaluations"] = args.evaluations
    if not args.no_figure:
        from experiments.figures import ext_branch_audit

        ext_branch_audit.main(summary, args.out / "figures")
    print(json.dumps(summary, indent=1) if args.json else tables(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
