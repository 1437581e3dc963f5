"""``python -m experiments.ambiguity``: how much of the 3D error is the monocular depth flip?

Tracks each synthetic sequence (full length, 160x120, true calibration) with a tracker
configuration and measures, against ground truth:

* ``mpjpe_mm`` and ``failure_rate`` (frames over 100 mm), as ``python -m mocap track`` does;
* ``reprojection_px``: the same joints' error in the image, which the costs can see;
* ``flip_oracle_mpjpe_mm`` and ``flip_oracle_failure_rate``: the error left when, per frame and
  per arm, an oracle that knows the truth picks the best of the four depth reflections of the
  tracked arm (upper arm and forearm each mirrored or not about the plane through their proximal
  joint that faces the camera). The four project to nearly the same silhouette and edges, so
  this is the error that choosing the right depth branch could remove, and what is left is not
  a branch error. The oracle is applied after tracking (the tracker is not fed its choice), so
  it is a bound on the flip's share, not a tracker.

* ``beam_oracle_mpjpe_mm`` and ``beam_oracle_failure_rate``: the error of the hypothesis nearest
  the truth among those the tracker keeps on each frame (right after the frame, before decoding):
  what a perfect choice among the beam could reach, so the part of the error that the search,
  not the score or the decoder, leaves;

* ``root_relative_failure_rate``: the share of frames over 100 mm about the neck; with the lifter
  (frames with keypoints) ``lifter_oracle_failure_rate``: the share of frames on which none of
  the lifter's hypotheses (unrefined) is within 100 mm about the neck, and ``branch_miss_rate``:
  the share on which the tracker's pose is over 100 mm about the neck while one of them is
  within (a choice missed; None without the lifter);

* ``cost_equivalent_failure_rate``: the share of frames that fail (over 100 mm) although the
  tracked pose's F (eq. 1) is no higher than the true pose's, on the same label image with the
  same model; ``cost_equivalent_both_rate`` asks the same of F and of the mean edge distance
  (eq. 2) together. On these frames the costs rate a pose more than 100 mm wrong at least as
  well as the truth, so a better search of the same costs cannot be relied on to mend them:
  what fails there is what the costs see, not how they are minimised.

With ``--two-way`` each sequence is tracked twice, forwards and then backwards from the forward
track's last pose, and each frame keeps the pose of the two with the lower F
(:func:`lower_region_cost`): an offline use of recorded video that is not in the paper. The two
tracks lose the arms on different frames, and on most failing frames F rates the truth better
than the tracked pose (see ``cost_equivalent_failure_rate``), so F can often tell which track
holds.

With ``--from-truth LAGS`` it measures instead how good one frame's registration is when it
starts close to the answer: every frame is registered (the same two-step registration, budget
and costs) from the *true* pose ``lag`` frames earlier, and the result is compared with that
frame's truth. Nothing carries over between frames, so this is the error of the costs and the
optimiser on a pose displaced by ``lag`` frames of motion, without the tracker's accumulated
losses; the gap between it and ``mpjpe_mm`` is what tracking loses on the way.

Results go to ``--out`` (default ``experiments/results/ambiguity``): the generated sequences
(reused, as by :mod:`experiments.sweep`) and one JSON file per sequence and configuration
(written atomically). A second run reuses a result only when it was measured with the same code
(:func:`code_key`: the ``mocap`` package and this experiment's modules, byte for byte); a result
from other code is measured again, with a line on stderr, and overwritten. A Markdown table is
printed.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from experiments import RESULTS_DIR
from experiments.config import sequence_list
from experiments.units import (EXTENSIONS, PREPARED_FILE, PREPARED_FILE_PAPER, DataSpec, load_prepared, load_sequence,
                               prepare_data, prepared_file)
from mocap.body import JOINT_NAMES, PARAMETER_INDEX
from mocap.body.pose import HEADING
from mocap.body.skeleton import JOINT_INDEX
from mocap.io.files import read_json, write_json
from mocap.metrics import (DEFAULT_FAILURE_MM, acceleration_error, failure_rate, mpjpe, pa_mpjpe, reprojection_error,
                           root_relative_mpjpe)
from mocap.synth import SEQUENCE_NAMES, SEQUENCES
from mocap.track import Tracker, TrackerConfig, register, track_prepared

#: Image size of the benchmark (pixels).
SIZE = (160, 120)
#: Joints of one arm, proximal to distal; the upper arm turns about the shoulder, the forearm
#: (with the hand) about the elbow.
ARM_JOINTS = {side: tuple(JOINT_NAMES.index(f"{side}_{j}") for j in ("shoulder", "elbow", "wrist", "hand"))
              for side in "rl"}


def reflect_in_depth(points: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """Mirror points about the plane through ``pivot`` whose normal is the camera ray to it.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres, camera coordinates
    pivot : ndarray, shape (3,), metres

    Returns
    -------
    ndarray, shape (n, 3)
        Points the same distance from the plane on its other side: under a pinhole camera they
        project close to the originals (exactly for a very distant camera).
    """
    normal = pivot / np.linalg.norm(pivot)
    return points - 2.0 * ((points - pivot) @ normal)[:, None] * normal[None, :]


def flip_oracle(joints: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Tracked joints with each arm replaced by its depth reflection nearest to the truth.

    Parameters
    ----------
    joints, truth : ndarray, shape (frames, joints, 3), metres

    Returns
    -------
    ndarray, shape (frames, joints, 3)
        Per frame and arm, the best (summed joint distance to ``truth``) of: the arm as tracked,
        the forearm mirrored about the elbow, the whole arm mirrored about the shoulder, and both.
    """
    out = joints.copy()
    for f in range(joints.shape[0]):
        for idx in ARM_JOINTS.values():
            arm, true_arm = joints[f, idx], truth[f, idx]
            best, best_err = arm, np.inf
            for mirror_upper in (False, True):
                a = arm.copy()
                if mirror_upper:
                    a[1:] = reflect_in_depth(a[1:], a[0])
                for mirror_fore in (False, True):
                    b = a.copy()
                    if mirror_fore:
                        b[2:] = reflect_in_depth(b[2:], b[1])
                    err = np.linalg.norm(b - true_arm, axis=1).sum()
                    if err < best_err:
                        best, best_err = b, err
            out[f, idx] = best
    return out


def cost_equivalent_rates(error_mm: np.ndarray, tracked: np.ndarray, truth: np.ndarray,
                          threshold_mm: float = DEFAULT_FAILURE_MM) -> tuple[float, float]:
    """Shares of frames that fail although the costs rate them no worse than the truth.

    Parameters
    ----------
    error_mm : ndarray, shape (frames,), millimetres
        Per-frame MPJPE of the tracked poses.
    tracked, truth : ndarray, shape (frames, 2)
        Region cost F (eq. 1) and mean edge distance (eq. 2, pixels) of the tracked and of the
        true pose on each frame. NaN (an empty frame) never counts as equivalent.
    threshold_mm : float
        Failure threshold.

    Returns
    -------
    (float, float)
        Share of all frames with ``error_mm > threshold_mm`` and F(tracked) <= F(truth); and
        with, in addition, the edge distance no higher than the truth's.
    """
    error_mm, tracked, truth = (np.asarray(a, dtype=np.float64) for a in (error_mm, tracked, truth))
    if tracked.shape != truth.shape or tracked.shape != (len(error_mm), 2) or len(error_mm) == 0:
        raise ValueError(f"need (frames,) errors and (frames, 2) costs, got {error_mm.shape}, {tracked.shape}, "
                         f"{truth.shape}")
    failing = error_mm > threshold_mm
    region_le = tracked[:, 0] <= truth[:, 0]
    both_le = region_le & (tracked[:, 1] <= truth[:, 1])
    return float((failing & region_le).mean()), float((failing & both_le).mean())


def choice_rates(relative_error_mm: np.ndarray, lifter_best_mm: np.ndarray,
                 threshold_mm: float = DEFAULT_FAILURE_MM) -> tuple[float, float, float]:
    """Shares of frames: the tracked pose over ``threshold_mm`` about the neck; no lifter hypothesis
    within it (the lifter's oracle); the first while not the second (a choice missed).

    Parameters
    ----------
    relative_error_mm : ndarray, shape (N,)
        The tracked pose's MPJPE about the neck per frame (millimetres).
    lifter_best_mm : ndarray, shape (N,)
        The best lifter hypothesis's MPJPE about the neck per frame (``inf`` where none).
    """
    relative_error_mm, lifter_best_mm = np.asarray(relative_error_mm), np.asarray(lifter_best_mm)
    if relative_error_mm.shape != lifter_best_mm.shape or relative_error_mm.ndim != 1 or len(relative_error_mm) == 0:
        raise ValueError(f"need two equal non-empty per-frame arrays, got {relative_error_mm.shape} and "
                         f"{lifter_best_mm.shape}")
    failing, covered = relative_error_mm > threshold_mm, lifter_best_mm <= threshold_mm
    return float(failing.mean()), float((~covered).mean()), float((failing & covered).mean())


def benchmark_sequence(sequence: str, root: Path, seed: int, without: tuple[str, ...] = ()):
    """The generated, prepared benchmark sequence (loaded sequence, prepared frames)."""
    spec = DataSpec(sequence, None, SEQUENCES[sequence].frames, seed, *SIZE)
    folder = prepare_data(spec, str(root), without)
    return load_sequence(folder, without=without), load_prepared(folder, without)


def lower_region_cost(forward: list, backward: list) -> list:
    """Frame by frame, the result of lower region residual F of two tracks of the same frames.

    Parameters
    ----------
    forward, backward : list of FrameResult
        The same frames in the same order. A NaN residual (an empty frame) loses to a number;
        ties keep ``forward``.

    Returns
    -------
    list of FrameResult
    """
    if len(forward) != len(backward):
        raise ValueError(f"the two tracks must cover the same frames, got {len(forward)} and {len(backward)}")
    return [b if b.region_residual < a.region_residual or (np.isnan(a.region_residual)
                                                           and not np.isnan(b.region_residual)) else a
            for a, b in zip(forward, backward)]


def measure(sequence: str, config: TrackerConfig, root: Path, seed: int = 0, two_way: bool = False,
            without: tuple[str, ...] = (), oracle_sigma_px: float | None = None,
            swap_share: float | None = None, detector: bool = False, null_offset_px: float = 0.0) -> dict:
    """Track one benchmark sequence with ``config`` and measure its errors (see the module);
    ``without``: model extensions left out (:func:`experiments.units.load_sequence`; both: the
    paper's two-class model); ``oracle_sigma_px``: give the tracker the oracle keypoints of
    :func:`experiments.keypoints.oracle_keypoints` with that noise (seeded by ``seed``);
    ``swap_share``: their left and right swapped on runs of frames covering that share
    (:func:`experiments.keypoints.swap_runs`), as a detector that does not see the face does;
    ``detector``: give it MediaPipe's keypoints on the rendered frames instead
    (:func:`experiments.keypoints.detector_keypoints`, kept in the sequence's folder);
    ``null_offset_px``: the keypoints moved that far to the right
    (:func:`experiments.keypoints.offset_keypoints`; 0: as they are).
    The result has ``labels_right_rate`` (the share of frames whose written arms are nearer the
    truth's than the truth's with left and right swapped, about the neck), ``arms_centred_mm``
    (the arms' eight joints' mean error about their own centre, no rotation: a body turned around
    shows there), ``labels_swapped_rate`` (frames the tracker read the keypoints swapped on) and
    ``detector_swapped_rate`` (frames the keypoints were swapped on), and
    ``frame_heading_error_deg`` (each frame's written chest heading less the truth's, degrees on
    the circle: :func:`heading_error_deg`)."""
    from experiments.keypoints import (DETECTOR_FILE, detector_keypoints, offset_keypoints, oracle_keypoints,
                                       swap_labels, swap_runs)

    if detector and oracle_sigma_px is not None:
        raise ValueError("give the tracker the oracle's keypoints or the detector's, not both")

    loaded, prepared = benchmark_sequence(sequence, root, seed, without)
    camera = loaded.calibration.camera
    tracker = Tracker(loaded.model, camera, config, loaded.calibration.initial_pose)
    calls = None
    if tracker.smoother is not None:        # every window the smoother is given, to replay it with other settings
        tracker.smoother = calls = SmootherCalls(tracker.smoother)
    truth_joints = loaded.ground_truth.joints
    keypoints = ([None] * len(prepared) if oracle_sigma_px is None
                 else oracle_keypoints(truth_joints[: len(prepared)], camera, oracle_sigma_px, seed))
    if detector:
        keypoints = detector_keypoints(loaded.frames[: len(prepared)], loaded.folder / DETECTOR_FILE)
    detector_swapped = np.zeros(len(prepared), bool)
    if swap_share is not None and oracle_sigma_px is not None:
        detector_swapped = swap_runs(len(prepared), swap_share, seed)
        keypoints = swap_labels(keypoints, detector_swapped)
    if detector:        # the frames MediaPipe's arms fit the truth's projection better swapped
        from experiments.peers import ARM_JOINTS, label_swapped

        arms = [JOINT_INDEX[name] for name in ARM_JOINTS]
        detected = np.array([np.where(k.present[arms, None], k.uv[arms], np.nan) for k in keypoints])
        truth_uv = camera.project(truth_joints[: len(prepared), arms].reshape(-1, 3)).reshape(len(prepared), len(arms), 2)
        detector_swapped = label_swapped(detected, truth_uv)
    if null_offset_px:
        keypoints = offset_keypoints(keypoints, null_offset_px)
    results, beam_best, proposal_best, other_best, lifter_best, seconds = [], [], [], [], [], 0.0
    proposal_origins = {source.origin for source in tracker.sources}
    error = lambda q, i: mpjpe(loaded.model.joint_positions(q)[None], truth_joints[i:i + 1])
    for i, frame in enumerate(prepared):      # track_prepared's loop, timed and with the beam looked at
        started = time.perf_counter()
        results += tracker.push(i, frame, keypoints[i])
        seconds += time.perf_counter() - started
        beam_best.append(min(error(q, i) for q in tracker.hypotheses))
        candidates = tracker.candidates if not frame.is_empty else []
        proposal_best.append(min([error(q, i) for o, q in candidates if o in proposal_origins], default=math.inf))
        other_best.append(min([error(q, i) for o, q in candidates if o not in proposal_origins], default=math.inf))
        lifted = tracker.lifted if not frame.is_empty else None
        lifter_best.append(math.inf if lifted is None else float(np.min(root_relative_mpjpe(
            lifted.joints, np.repeat(truth_joints[i:i + 1], len(lifted), axis=0), per_frame=True))))
    started = time.perf_counter()
    results += tracker.finish()
    seconds += time.perf_counter() - started
    if two_way:
        backward = track_prepared(prepared[::-1], Tracker(loaded.model, camera, config, results[-1].pose))
        n = len(prepared)
        results = lower_region_cost(results, [replace(r, frame=n - 1 - r.frame) for r in backward[::-1]])
    if calls is not None:
        keypoints_tag = ("-mediapipe" if detector else "") + ("" if oracle_sigma_px is None
                                                               else f"-oracle{oracle_sigma_px:g}px")
        keypoints_tag += f"-null{null_offset_px:g}px" if null_offset_px else ""
        calls.save(root / "smoother_calls" / f"{sequence}-s{seed}-{config_key(config)}{keypoints_tag}.npz")
    joints = np.array([r.joints for r in results])
    truth = loaded.ground_truth.joints[: len(joints)]
    decoded = np.array([loaded.model.joint_positions(r.decoded_pose) for r in results])
    oracle = flip_oracle(joints, truth)
    proposed = bool(np.isfinite(proposal_best).any())      # a source that never proposed (no keypoints) is no stage
    lifted_any = bool(np.isfinite(lifter_best).any())
    relative_failing, lifter_missing, branch_missed = choice_rates(root_relative_mpjpe(joints, truth, per_frame=True),
                                                                   np.array(lifter_best))
    tracked_costs = np.array([(r.region_residual, r.edge_residual) for r in results])
    truth_costs = np.array([(region(q), edge(q)) for (region, edge), q in
                            zip(map(tracker.costs, prepared), loaded.ground_truth.poses[: len(joints)])])
    equivalent, equivalent_both = cost_equivalent_rates(mpjpe(joints, truth, per_frame=True), tracked_costs,
                                                        truth_costs)
    return {"sequence": sequence, "frames": len(joints), "classes": ",".join(loaded.model.class_names),
            "mpjpe_mm": mpjpe(joints, truth), "failure_rate": failure_rate(joints, truth),
            "root_relative_mpjpe_mm": root_relative_mpjpe(joints, truth), "pa_mpjpe_mm": pa_mpjpe(joints, truth),
            "root_relative_failure_rate": relative_failing,
            "lifter_oracle_failure_rate": lifter_missing if lifted_any else None,
            "branch_miss_rate": branch_missed if lifted_any else None,
            "frame_mpjpe_mm": mpjpe(joints, truth, per_frame=True).tolist(),
            "frame_root_relative_mm": root_relative_mpjpe(joints, truth, per_frame=True).tolist(),
            "beam_oracle_mpjpe_mm": float(np.mean(beam_best)),
            "beam_oracle_failure_rate": float(np.mean(np.array(beam_best) > DEFAULT_FAILURE_MM)),
            # the proposal stage: its best refined proposal per frame, and the frames on which every
            # other candidate (tracked hypotheses, recovery, re-acquisition, jumps) misses but it does not
            # (None without a proposal stage)
            "proposal_oracle_failure_rate": float(np.mean(np.array(proposal_best) > DEFAULT_FAILURE_MM))
            if proposed else None,
            "proposal_catches_rate": float(np.mean((np.array(other_best) > DEFAULT_FAILURE_MM)
                                                   & (np.array(proposal_best) <= DEFAULT_FAILURE_MM)))
            if proposed else None,
            "others_miss_rate": float(np.mean(np.array(other_best) > DEFAULT_FAILURE_MM)),
            "tracking_ms_per_frame": 1e3 * seconds / len(joints),
            "evaluations_per_frame": float(np.mean([r.evaluations for r in results])),
            "prepare_ms_per_frame": float(np.mean([r.timings_ms.get("prepare", 0.0) for r in results])),
            "reprojection_px": reprojection_error(joints, truth, camera),
            "flip_oracle_mpjpe_mm": mpjpe(oracle, truth), "flip_oracle_failure_rate": failure_rate(oracle, truth),
            "flip_oracle_reprojection_px": reprojection_error(oracle, truth, camera),
            "cost_equivalent_failure_rate": equivalent, "cost_equivalent_both_rate": equivalent_both,
            **jitter(joints, decoded, truth), **arm_labels(joints, truth),
            **written_against_decoded(np.array([r.pose for r in results]), joints, decoded),
            "frame_heading_error_deg": heading_error_deg(np.array([r.pose for r in results]),
                                                         loaded.ground_truth.poses[: len(joints)]).tolist(),
            "labels_swapped_rate": float(np.mean([getattr(r, "labels_swapped", False) for r in results])),
            "detector_swapped_rate": float(np.mean(detector_swapped)),
            **(beside_detector(joints, keypoints, truth) if detector else {}),
            "decoded_poses": np.array([r.decoded_pose for r in results]).tolist()}


def beside_detector(joints: np.ndarray, keypoints: list, truth: np.ndarray) -> dict:
    """Ours and MediaPipe's own 3D side by side (the detector's world joints in ``keypoints``, see
    :func:`experiments.keypoints.detector_keypoints`): the arms' PA-MPJPE (mm) and acceleration
    error (mm/frame², each frame aligned) of both, over the frames MediaPipe found the arms, as
    :mod:`experiments.peers` measures them; ``joints`` and ``truth`` (N, 10, 3) metres."""
    from experiments.peers import arm_figures, arm_indices

    arms = arm_indices()
    n = len(joints)
    world = np.array([np.full((len(arms), 3), np.nan) if k.world is None else k.world[arms] for k in keypoints[:n]])
    found = np.isfinite(world).all(axis=(1, 2))
    ours = arm_figures(np.where(found[:, None, None], joints[:, arms], np.nan), truth[:, arms])
    theirs = arm_figures(world, truth[:, arms])
    return {"arms_pa_mpjpe_mm": ours["pa_mpjpe_mm"], "arms_accel": ours["accel"],
            "mediapipe_arms_pa_mpjpe_mm": theirs["pa_mpjpe_mm"], "mediapipe_arms_accel": theirs["accel"],
            "mediapipe_found_rate": float(found.mean())}


#: The arms' joints, right side then left (rows of :data:`mocap.body.skeleton.JOINT_NAMES`).
SIDED_ARM_JOINTS = tuple(JOINT_INDEX[f"{side}_{j}"] for side in "rl" for j in ("shoulder", "elbow", "wrist", "hand"))


def arm_labels(joints: np.ndarray, truth: np.ndarray) -> dict:
    """Whether the tracked arms carry the right labels, and the arms' error about their centre.

    Parameters
    ----------
    joints, truth : ndarray, shape (frames, 10, 3), metres

    Returns
    -------
    dict
        ``labels_right_rate``: the share of frames whose arms' joints (about the neck) are nearer
        the truth's than the truth's with left and right swapped (ties count as right);
        ``arms_centred_mm``: the eight arm joints' mean distance to the truth's, each set about
        its own centroid (no rotation), millimetres, mean over frames.
    """
    joints, truth = np.asarray(joints, dtype=np.float64), np.asarray(truth, dtype=np.float64)
    neck = JOINT_INDEX["neck"]
    arms = list(SIDED_ARM_JOINTS)
    mirrored = arms[4:] + arms[:4]
    a = joints[:, arms] - joints[:, neck:neck + 1]
    right = np.linalg.norm(a - (truth[:, arms] - truth[:, neck:neck + 1]), axis=2).mean(axis=1)
    wrong = np.linalg.norm(a - (truth[:, mirrored] - truth[:, neck:neck + 1]), axis=2).mean(axis=1)
    centred = lambda x: x - x.mean(axis=1, keepdims=True)
    arms_mm = 1e3 * np.linalg.norm(centred(joints[:, arms]) - centred(truth[:, arms]), axis=2).mean()
    return {"labels_right_rate": float(np.mean(right <= wrong)), "arms_centred_mm": float(arms_mm)}


class SmootherCalls:
    """A :class:`mocap.track.smooth.Smoother` that keeps every window it is given (the decoded
    path's tentative poses, joints, weights and empty frames, and how many frames were written): replayed
    through a smoother of other settings, they give exactly the poses it would have written
    (the decoding does not depend on the smoother)."""

    def __init__(self, smoother) -> None:
        self.smoother, self.calls = smoother, []

    def weights(self, confidence):
        return self.smoother.weights(confidence)

    def smooth(self, poses, joints, weights, count: int = 1, empty=None):
        empty = np.zeros(len(poses), dtype=bool) if empty is None else np.array(empty, dtype=bool)
        self.calls.append((np.array(poses), np.array(joints), np.array(weights), count, empty))
        return self.smoother.smooth(poses, joints, weights, count, empty=empty)

    def save(self, path: Path) -> None:
        """All windows, concatenated, with each one's length and count (``np.savez``)."""
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(path, poses=np.concatenate([c[0] for c in self.calls]),
                 joints=np.concatenate([c[1] for c in self.calls]),
                 weights=np.concatenate([c[2] for c in self.calls]),
                 empty=np.concatenate([c[4] for c in self.calls]),
                 lengths=np.array([len(c[0]) for c in self.calls]), counts=np.array([c[3] for c in self.calls]))


#: Arm joints of the acceleration error after Procrustes alignment (the peers' arms).
JITTER_ARM_JOINTS = ("r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist")
#: Half-width (frames) of the naive baseline's centred mean (issue 39).
NAIVE_HALF_WIDTH = 4


def jitter(joints: np.ndarray, decoded: np.ndarray, truth: np.ndarray) -> dict:
    """Acceleration errors (:func:`mocap.metrics.acceleration_error`, mm/frame^2) and median
    per-frame errors (mm) of the written joints, of the decoded ones (before the smoother) and of
    the naive baseline: a centred mean over +-:data:`NAIVE_HALF_WIDTH` frames of the decoded joints
    (ends: the nearest frame repeated). All arrays (N, 10, 3), metres."""
    from scipy.ndimage import uniform_filter1d

    naive = uniform_filter1d(decoded, size=2 * NAIVE_HALF_WIDTH + 1, axis=0, mode="nearest")
    arms = [JOINT_NAMES.index(j) for j in JITTER_ARM_JOINTS]
    row = {}
    for name, x in (("", joints), ("decoded_", decoded), ("naive_", naive)):
        if len(x) >= 3:
            row[f"{name}accel_mm"] = acceleration_error(x, truth)
            row[f"{name}accel_arms_pa_mm"] = acceleration_error(x[:, arms], truth[:, arms], align="procrustes")
        row[f"{name}median_frame_mm"] = float(np.median(mpjpe(x, truth, per_frame=True)))
        row[f"{name}median_frame_root_relative_mm"] = float(np.median(root_relative_mpjpe(x, truth, per_frame=True)))
    return row


def written_against_decoded(written_poses: np.ndarray, joints: np.ndarray, decoded: np.ndarray) -> dict:
    """How far the written trajectory strays from the decoded one (issue 44: a heading brought
    360 degrees away made the smoother sweep the body through a turn).

    ``written_decoded_mm``: the largest distance of any joint of a written pose from the same
    joint of its frame's decoded pose, over all frames (mm); ``written_decoded_mean_mm``: the
    largest over frames of the mean joint distance (``FrameResult.smoothed_mm``; mm);
    ``heading_step_deg``: the largest change of the written chest heading (``chest_yaw``, as
    written: unwrapped) from one frame to the next (degrees). Arrays: written poses (N, 23),
    metres and radians; written and decoded joints (N, 10, 3), metres.
    """
    distance = np.linalg.norm(np.asarray(joints) - np.asarray(decoded), axis=2)        # (N, 10), metres
    yaw = np.asarray(written_poses)[:, PARAMETER_INDEX[HEADING]]
    return {"written_decoded_mm": 1e3 * float(distance.max(initial=0.0)),
            "written_decoded_mean_mm": 1e3 * float(distance.mean(axis=1).max(initial=0.0)),
            "heading_step_deg": math.degrees(float(np.abs(np.diff(yaw)).max(initial=0.0)))}


def heading_error_deg(written_poses: np.ndarray, true_poses: np.ndarray) -> np.ndarray:
    """Per frame, the written chest heading (:data:`mocap.body.pose.HEADING`) less the truth's, on
    the circle: wrapped to (-180, 180] degrees, so that headings a whole turn apart (the tracker
    keeps its heading unwrapped) differ by 0 and a body turned round by 180.

    Parameters
    ----------
    written_poses, true_poses : ndarray, shape (N, 23), metres and radians
        Pose vectors (:data:`mocap.body.PARAMETER_NAMES` order).

    Returns
    -------
    ndarray, shape (N,), degrees
    """
    i = PARAMETER_INDEX[HEADING]
    difference = np.degrees(np.asarray(written_poses, dtype=float)[:, i] - np.asarray(true_poses, dtype=float)[:, i])
    return 180.0 - np.mod(180.0 - difference, 360.0)


def register_from_truth(prepared, model, camera, true_poses: np.ndarray, config: TrackerConfig, lag: int,
                        every: int = 1, details: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Register frames one by one, each from the true pose ``lag`` frames earlier.

    Parameters
    ----------
    prepared : sequence of PreparedFrame
    model : BodyModel
        Rebuilt at ``config.mesh_resolution`` when that is not 0, as the tracker does.
    camera : Camera
    true_poses : ndarray, shape (frames, 23), metres and radians
    config : TrackerConfig
    lag : int
        Frames between the start pose and the registered frame (>= 0; frame ``f < lag`` starts
        from frame 0's truth).
    every : int
        Register every ``every``-th frame only (>= 1).
    details : dict, optional
        Filled with per registered frame: ``seconds`` (the registration's CPU time: the process's,
        so that other work on a shared machine does not count; the registration is single-threaded),
        ``edge_residual`` (eq. 2 at the result, pixels), ``region_residual`` (eq. 1) and
        ``failed`` (the paper's residual thresholds, :meth:`~mocap.track.Registration.failed`).

    Returns
    -------
    frames : ndarray of int, shape (k,)
    poses : ndarray, shape (k, 23)
        The registered poses.
    """
    if lag < 0 or every < 1:
        raise ValueError(f"lag must be >= 0 and every >= 1, got {lag} and {every}")
    tracker = Tracker(model, camera, config, true_poses[0])     # only for its model and costs
    frames = np.arange(0, min(len(prepared), len(true_poses)), every)
    poses = np.empty((len(frames), true_poses.shape[1]))
    rows = []
    if len(frames):      # once untimed: the kernels compile (or load from the cache) on first use
        register(*tracker.costs(prepared[frames[0]]), true_poses[0], config)
    for k, f in enumerate(frames):
        region, edge = tracker.costs(prepared[f])
        started = time.process_time()         # CPU time: a shared machine's waits are not counted
        result = register(region, edge, true_poses[max(f - lag, 0)], config)
        rows.append((time.process_time() - started, result.edge_residual, result.region_residual,
                     result.failed(config)))
        poses[k] = result.pose
    if details is not None:
        for name, column in zip(("seconds", "edge_residual", "region_residual", "failed"), zip(*rows)):
            details[name] = list(column)
    return frames, poses


def measure_from_truth(sequence: str, config: TrackerConfig, root: Path, seed: int = 0,
                       lags: tuple[int, ...] = (1, 3), without: tuple[str, ...] = ()) -> dict:
    """Registration error of one benchmark sequence from true start poses (see the module)."""
    loaded, prepared = benchmark_sequence(sequence, root, seed, without)
    truth_poses, truth_joints = loaded.ground_truth.poses, loaded.ground_truth.joints
    row = {"sequence": sequence, "frames": len(prepared)}
    for lag in lags:
        details: dict = {}
        frames, poses = register_from_truth(prepared, loaded.model, loaded.calibration.camera, truth_poses,
                                            config, lag, details=details)
        joints = np.array([loaded.model.joint_positions(q) for q in poses])
        start = truth_joints[np.maximum(frames - lag, 0)]
        row[f"lag{lag}_start_mpjpe_mm"] = mpjpe(start, truth_joints[frames])
        row[f"lag{lag}_mpjpe_mm"] = mpjpe(joints, truth_joints[frames])
        row[f"lag{lag}_failure_rate"] = failure_rate(joints, truth_joints[frames])
        row[f"lag{lag}_frame_mpjpe_mm"] = mpjpe(joints, truth_joints[frames], per_frame=True).tolist()
        row[f"lag{lag}_frame_start_mpjpe_mm"] = mpjpe(start, truth_joints[frames], per_frame=True).tolist()
        row[f"lag{lag}_ms_per_frame"] = 1e3 * float(np.mean(details["seconds"]))
        row[f"lag{lag}_edge_residual_px"] = float(np.mean(details["edge_residual"]))
        row[f"lag{lag}_region_residual"] = float(np.mean(details["region_residual"]))
        row[f"lag{lag}_residual_failures"] = int(np.sum(details["failed"]))
    return row


def summary(rows: list[dict], lags: tuple[int, ...] | None) -> dict:
    """One machine-readable object over every sequence and seed of a run (``--json``).

    With lags (``--from-truth``), for the first lag: ``median_mm`` and ``mean_mm``, the median and
    mean MPJPE over all registered frames; ``start_median_mm``, the same of the start poses;
    ``ms_per_frame``, the registration's mean CPU time per frame (one thread); ``edge_residual_px``, the
    mean edge distance (eq. 2) at the results; ``region_residual``, the mean F (eq. 1);
    ``residual_failures``, frames over the paper's residual thresholds; ``failure_rate``, frames
    over 100 mm. Tracking rows give ``median_mm`` over the frames, the frame-weighted
    ``failure_rate`` and ``ms_per_frame`` (tracking alone). Both also give ``frames`` and
    ``per_sequence`` (each row's sequence, seed and MPJPE).
    """
    if lags:
        lag = lags[0]
        errors = np.concatenate([r[f"lag{lag}_frame_mpjpe_mm"] for r in rows])
        starts = np.concatenate([r[f"lag{lag}_frame_start_mpjpe_mm"] for r in rows])
        frames = np.array([len(r[f"lag{lag}_frame_mpjpe_mm"]) for r in rows], dtype=np.float64)
        weighted = lambda key: float(np.dot(frames, [r[key] for r in rows]) / frames.sum())
        return {"lag": lag, "frames": int(frames.sum()), "median_mm": float(np.median(errors)),
                "mean_mm": float(np.mean(errors)), "start_median_mm": float(np.median(starts)),
                "failure_rate": float(np.mean(errors > DEFAULT_FAILURE_MM)),
                "ms_per_frame": weighted(f"lag{lag}_ms_per_frame"),
                "edge_residual_px": weighted(f"lag{lag}_edge_residual_px"),
                "region_residual": weighted(f"lag{lag}_region_residual"),
                "residual_failures": int(sum(r[f"lag{lag}_residual_failures"] for r in rows)),
                "per_sequence": [{"sequence": r["sequence"], "seed": r["seed"], "mpjpe_mm": r[f"lag{lag}_mpjpe_mm"]}
                                 for r in rows]}
    errors = np.concatenate([r["frame_mpjpe_mm"] for r in rows])
    frames = np.array([r["frames"] for r in rows], dtype=np.float64)
    return {"frames": int(frames.sum()), "median_mm": float(np.median(errors)), "mean_mm": float(np.mean(errors)),
            "failure_rate": float(np.mean(errors > DEFAULT_FAILURE_MM)),
            "ms_per_frame": float(np.dot(frames, [r["tracking_ms_per_frame"] for r in rows]) / frames.sum()),
            "per_sequence": [{"sequence": r["sequence"], "seed": r["seed"], "mpjpe_mm": r["mpjpe_mm"]} for r in rows]}


def config_key(config: TrackerConfig) -> str:
    """Short stable name of a tracker configuration (for result file names)."""
    text = json.dumps(config.to_dict(), sort_keys=True)
    return hashlib.sha1(text.encode()).hexdigest()[:10]


#: The experiment's own modules whose code shapes a result, beside the whole ``mocap`` package.
CODE_MODULES: tuple[str, ...] = ("ambiguity.py", "units.py", "keypoints.py")


def code_key(package: Path | None = None, modules: tuple[Path, ...] | None = None) -> str:
    """Short stable name of the code a result is measured with (part of the cache's key).

    SHA-256 over every file git would track in ``package`` (its ``.py`` sources and its fitted
    models, ``.json`` and ``.npz``; caches such as ``__pycache__`` and Numba's ``.nbi``/``.nbc``
    are left out) and over ``modules``, each with its path relative to its folder.

    Parameters
    ----------
    package : Path, optional
        The package folder (default: the imported ``mocap``).
    modules : tuple of Path, optional
        Further source files (default: :data:`CODE_MODULES` beside this module).

    Returns
    -------
    str
        12 hex digits.
    """
    import mocap

    package = Path(mocap.__file__).resolve().parent if package is None else Path(package)
    here = Path(__file__).resolve().parent
    modules = tuple(here / m for m in CODE_MODULES) if modules is None else tuple(modules)
    files = sorted(f for f in package.rglob("*") if f.is_file() and f.suffix in (".py", ".json", ".npz")
                   and "__pycache__" not in f.relative_to(package).parts)
    digest = hashlib.sha256()
    for name, f in [(f.relative_to(package).as_posix(), f) for f in files] + [(m.name, m) for m in modules]:
        data = f.read_bytes()
        digest.update(f"{name}\0{len(data)}\0".encode())
        digest.update(data)
    return digest.hexdigest()[:12]


def cached_result(path: Path, code: str, lags: tuple[int, ...] | None) -> dict | None:
    """The result stored at ``path`` if it can be reused, else None.

    Reused only when it was measured with the code ``code`` (:func:`code_key`) and holds the
    fields this kind of run reports (tracking, or ``--from-truth`` with ``lags``). A file from
    other code is reported on stderr (it is measured again and overwritten).
    """
    if not path.is_file():
        return None
    stored = read_json(path)
    if stored.get("code") != code:
        print(f"{path.name}: measured with other code ({stored.get('code', 'before code keys')}, now {code}); "
              f"measuring again", file=sys.stderr)
        return None
    cached = stored["result"]
    if ("cost_equivalent_failure_rate" in cached if lags is None else f"lag{lags[0]}_frame_mpjpe_mm" in cached):
        return cached
    return None


def table(rows: list[dict]) -> str:
    """Markdown table of :func:`measure` results, with the medians over the sequences."""
    cols = ("mpjpe_mm", "failure_rate", "reprojection_px", "flip_oracle_mpjpe_mm", "flip_oracle_failure_rate",
            "cost_equivalent_failure_rate", "cost_equivalent_both_rate")
    head = ("sequence", "MPJPE mm", f"frames > {DEFAULT_FAILURE_MM:g} mm", "reproj. px", "flip oracle MPJPE mm",
            f"flip oracle > {DEFAULT_FAILURE_MM:g} mm", "failing, F <= truth's", "failing, F and edge <= truth's")
    fmt = lambda c, v: f"{100 * v:.0f} %" if "rate" in c else (f"{v:.1f}" if "px" in c else f"{v:.0f}")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        lines.append("| " + " | ".join([r["sequence"]] + [fmt(c, r[c]) for c in cols]) + " |")
    lines.append("| **median** | " + " | ".join(fmt(c, float(np.median([r[c] for r in rows]))) for c in cols) + " |")
    return "\n".join(lines)


def table_from_truth(rows: list[dict], lags: tuple[int, ...]) -> str:
    """Markdown table of :func:`measure_from_truth` results, with the medians."""
    cols = [c for lag in lags for c in (f"lag{lag}_start_mpjpe_mm", f"lag{lag}_mpjpe_mm", f"lag{lag}_failure_rate")]
    head = ["sequence"] + [h for lag in lags for h in (f"start {lag} frame(s) back, mm", "registered, mm",
                                                           f"> {DEFAULT_FAILURE_MM:g} mm")]
    fmt = lambda c, v: f"{100 * v:.0f} %" if "rate" in c else f"{v:.0f}"
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        lines.append("| " + " | ".join([r["sequence"]] + [fmt(c, r[c]) for c in cols]) + " |")
    lines.append("| **median** | " + " | ".join(fmt(c, float(np.median([r[c] for r in rows]))) for c in cols) + " |")
    return "\n".join(lines)


def pooled_table(rows: list[dict]) -> str:
    """Markdown table of :func:`measure` results over several seeds (rows carry ``seed``): per
    sequence the median over seeds of the MPJPE and the frame-weighted (pooled) rates, then all
    sequences pooled."""
    cols = ("failure_rate", "cost_equivalent_failure_rate", "cost_equivalent_both_rate")
    head = ("sequence", "seeds", "frames", "MPJPE mm (median over seeds)", f"frames > {DEFAULT_FAILURE_MM:g} mm",
            "failing, F <= truth's", "failing, F and edge <= truth's")
    pct = lambda v: f"{100 * v:.1f} %"

    def pooled(group):
        frames = np.array([r["frames"] for r in group], dtype=np.float64)
        return [pct(float(np.dot(frames, [r[c] for r in group]) / frames.sum())) for c in cols]

    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    names = list(dict.fromkeys(r["sequence"] for r in rows))
    for name in names:
        group = [r for r in rows if r["sequence"] == name]
        lines.append("| " + " | ".join([name, ",".join(str(r["seed"]) for r in group), str(sum(r["frames"] for r in group)),
                                         f"{np.median([r['mpjpe_mm'] for r in group]):.0f}"] + pooled(group)) + " |")
    lines.append("| **all** | " + " | ".join([",".join(sorted({str(r["seed"]) for r in rows})),
                                              str(sum(r["frames"] for r in rows)),
                                              f"{np.median([r['mpjpe_mm'] for r in rows]):.0f}"] + pooled(rows)) + " |")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m experiments.ambiguity", description=__doc__.split("\n\n")[0])
    p.add_argument("--sequences", default=",".join(SEQUENCE_NAMES),
                   help="comma-separated benchmark sequences (default: all six)")
    p.add_argument("--evaluations", type=int, default=None, help="cost evaluations per frame (default: the config's)")
    p.add_argument("--config", type=Path, default=None, help="TrackerConfig JSON (default: the tracker's defaults)")
    p.add_argument("--out", type=Path, default=RESULTS_DIR / "ambiguity", help="results folder")
    p.add_argument("--seed", default="0",
                   help="sequence generator seed, or comma-separated seeds (e.g. 0,1,2,3,4: adds a table pooled "
                        "over the seeds)")
    p.add_argument("--from-truth", default=None, metavar="LAGS",
                   help="comma-separated frame lags, e.g. 1,3: register each frame from the true pose that many "
                        "frames earlier instead of tracking")
    p.add_argument("--paper-model", action="store_true",
                   help="the paper's model: skin and clothes only, no hair region, no lower body (default: the "
                        "calibration's classes, those the first frame supports); as --without hair,lower_body")
    p.add_argument("--without", default="", metavar="PARTS",
                   help=f"comma-separated model extensions to leave out: {', '.join(EXTENSIONS)}")
    p.add_argument("--two-way", action="store_true",
                   help="track forwards and backwards and keep, per frame, the pose of lower F (offline)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (median_mm, ms_per_frame, ... over every sequence and seed) "
                        "instead of the tables")
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        names = sequence_list(args.sequences)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    config = TrackerConfig.from_json(args.config) if args.config is not None else TrackerConfig()
    if args.evaluations is not None:
        config = TrackerConfig.from_dict({**config.to_dict(), "evaluations": args.evaluations})
    lags = None
    if args.from_truth is not None:
        try:
            lags = tuple(sorted({int(v) for v in args.from_truth.split(",") if v.strip()}))
        except ValueError:
            lags = ()
        if not lags or min(lags) < 0:
            print(f"error: --from-truth takes non-negative integer lags such as 1,3, got {args.from_truth!r}",
                  file=sys.stderr)
            return 2
        if args.two_way:
            print("error: --two-way tracks; it cannot be combined with --from-truth", file=sys.stderr)
            return 2
    without = tuple(v.strip() for v in args.without.split(",") if v.strip())
    without = EXTENSIONS if args.paper_model else without
    if set(without) - set(EXTENSIONS):
        print(f"error: --without takes {', '.join(EXTENSIONS)}, got {args.without!r}", file=sys.stderr)
        return 2
    try:
        seeds = tuple(int(v) for v in args.seed.split(",") if v.strip())
    except ValueError:
        seeds = ()
    if not seeds:
        print(f"error: --seed takes an integer or comma-separated integers, got {args.seed!r}", file=sys.stderr)
        return 2
    key = config_key(config)
    code = code_key()
    suffix = ("-two-way" if args.two_way else "") if lags is None else "-truth" + "_".join(map(str, lags))
    suffix += {PREPARED_FILE_PAPER: "-paper", PREPARED_FILE: ""}.get(
        prepared_file(without), "-without-" + "-".join(e for e in EXTENSIONS if e in without))
    every = []
    for seed in seeds:
        rows = []
        for name in names:
            path = args.out / "units" / f"{name}-s{seed}-{key}{suffix}.json"
            cached = cached_result(path, code, lags)
            if cached is not None:
                rows.append(cached)
                continue
            print(f"{'tracking' if lags is None else 'registering'} {name} (seed {seed}) ...", file=sys.stderr,
                  flush=True)
            row = (measure(name, config, args.out, seed, args.two_way, without) if lags is None
                   else measure_from_truth(name, config, args.out, seed, lags, without))
            write_json(path, {"config": config.to_dict(), "code": code, "result": row})
            rows.append(row)
        every += [{**r, "seed": seed} for r in rows]
        if args.json:
            continue
        print(f"configuration {key} ({config.evaluations} evaluations per frame"
              f"{', tracked both ways' if args.two_way else ''}{', without ' + ', '.join(without) if without else ''}), "
              f"seed {seed}\n")
        print(table(rows) if lags is None else table_from_truth(rows, lags))
        print()
    if args.json:
        print(json.dumps({"configuration": key, "seeds": list(seeds), "sequences": list(names), **summary(every, lags)}))
        return 0
    if len(seeds) > 1 and lags is None:
        print(f"pooled over seeds {', '.join(map(str, seeds))}\n")
        print(pooled_table(every))
    return 0


if __name__ == "__main__":
    sys.exit(main())
