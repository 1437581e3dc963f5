"""``python -m experiments.mediapipe_3d``: MediaPipe's own 3D as evidence, measured (issue 34, item 2).

When MediaPipe gives the 2D keypoints it also gives 3D world landmarks (metres about the hips,
on the image's axes). Here they are placed onto the calibrated body model within the joint limits
(:func:`mocap.io.mediapipe_keypoints.world_joints`, then
:func:`mocap.body.ik.fit_pose_to_joints`, each frame's fit started from the previous frame's) and
given to the tracker in two ways, measured apart and together:

* **proposals**: the placed pose joins the proposal stage (:class:`PlacedSource`), its root placed
  so that its neck is the lifter's most probable hypothesis's (the lifter's root fit to the 2D
  keypoints), then refined like every proposal;
* **a term of the score** (:class:`EvidenceTracker`), ``weight`` times
  ``0.5 * sum_j min(d_j^2 / SIGMA_M^2, CAP)`` over the six arm joints, ``d_j`` the distance of a
  candidate's joint from the placed pose's, both about their shoulders' midpoint (camera axes,
  no rotation: MediaPipe's world axes are the camera's; the check ``axes`` below measures it).

Clips: those :mod:`experiments.peers` already made and ran MediaPipe on (its ``--only synthetic``
and ``--only cmu`` with their ``--out``/``--work``): ``WORK/<clip>`` and
``WORK/<clip>-mediapipe.npz``. Every variant tracks the clip's prepared frames (true calibration
and background, :func:`experiments.units.load_sequence`) with MediaPipe's 2D arm joints as
keypoints and the default settings (and ``--lifter``), in the same process, so the variants
differ only by the evidence. Arm PA-MPJPE (mm) per clip against the truth, with MediaPipe's own
3D, and the placed poses alone. Writes ``OUT/mediapipe_3d.json`` and prints a table.

The term paid and is the library's (:mod:`mocap.track.world`, ``TrackerConfig.world_weight``,
there warm-started from the leading hypothesis; ``experiments.peers`` measures it through
``python -m mocap track``); the proposals did not and stay here (docs/research-log.md has the
numbers). The keypoints given here carry no 3D, so the library's own term stays off and the
variants differ only by this module's.
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from experiments.peers import arm_indices, arm_pa_mpjpe
from mocap.track.proposals import Proposal
from mocap.track.tracker import Tracker
from mocap.track.world import WORLD_CAP, WORLD_SIGMA_M, about_shoulders

#: The term's scale and cap: the library's (:mod:`mocap.track.world`).
SIGMA_M, CAP = WORLD_SIGMA_M, WORLD_CAP
#: Variants: (MediaPipe's placed pose proposed, weight of its score term).
VARIANTS = {"without": (False, 0.0), "proposals": (True, 0.0), "term 0.2": (False, 0.2), "term 0.5": (False, 0.5),
            "term 2": (False, 2.0), "both 0.5": (True, 0.5), "both 2": (True, 2.0)}


def placed_poses(world33: np.ndarray, visibility33: np.ndarray, skeleton) -> list:
    """MediaPipe's world landmarks placed onto the body, frame after frame.

    Parameters
    ----------
    world33 : ndarray, shape (N, 33, 3), metres (NaN where no person was found)
    visibility33 : ndarray, shape (N, 33)
    skeleton : Skeleton

    Returns
    -------
    list of ndarray (23,) or None
        The fitted pose (its root about MediaPipe's hips), None where too few joints were seen.
        Each fit starts from the previous frame's.
    """
    from mocap.body.ik import FIT_MIN_JOINTS, fit_pose_to_joints
    from mocap.io.mediapipe_keypoints import world_joints

    out, previous = [], None
    for points, seen in zip(world33, visibility33):
        if not np.isfinite(points).all():
            out.append(None)
            previous = None
            continue
        joints, present = world_joints(points, seen)
        if present.sum() < FIT_MIN_JOINTS:
            out.append(None)
            previous = None
            continue
        previous = fit_pose_to_joints(joints, present, skeleton, start=previous).pose
        out.append(previous)
    return out


class PlacedSource:
    """Proposes the frame's placed MediaPipe pose (see the module); none without the lifter's
    hypotheses (no keypoints) or without a fit. ``tracker`` tells the frame being tracked."""

    origin: str = "mediapipe3d"

    def __init__(self, placed: list, model) -> None:
        self.placed, self.model, self.frame = placed, model, 0

    def propose(self, prepared, context) -> list:
        q = self.placed[self.frame] if self.frame < len(self.placed) else None
        if q is None or context.lifted is None:
            return []
        pose = np.array(q, dtype=np.float64)
        anchor = context.lifted.poses[0]
        pose[:3] = anchor[:3]
        pose[:3] += self.model.joint_positions(anchor)[1] - self.model.joint_positions(pose)[1]
        return [Proposal(pose, self.origin)]


class EvidenceTracker(Tracker):
    """The tracker with MediaPipe's placed pose as a term of its score (see the module)."""

    def __init__(self, *args, placed: list, weight: float, source: PlacedSource | None, **options) -> None:
        super().__init__(*args, **options)
        self.weight, self.source = weight, source
        if source is not None:
            self.sources = (*self.sources, source)
        self.targets = [None if q is None else about_shoulders(self.model.joint_positions(q)) for q in placed]
        self.frame = 0

    def push(self, frame_index: int, prepared, keypoints=None):
        self.frame = int(frame_index)
        if self.source is not None:
            self.source.frame = self.frame
        return super().push(frame_index, prepared, keypoints)

    def _unary(self, region, edge, keypoint, pose, joints, lifted) -> float:
        unary = super()._unary(region, edge, keypoint, pose, joints, lifted)
        target = self.targets[self.frame] if self.frame < len(self.targets) else None
        if self.weight > 0 and target is not None and keypoint == keypoint:     # frames with keypoints only
            d2 = np.sum((about_shoulders(joints) - target) ** 2, axis=1) / SIGMA_M ** 2
            unary += self.weight * 0.5 * float(np.minimum(d2, CAP).sum())
        return float(unary)


def keypoints_of(uv: np.ndarray) -> list:
    """MediaPipe's arm joints (N, 6, 2) as each frame's :class:`~mocap.io.keypoints.Keypoints`
    (the other joints absent), as :func:`experiments.peers.keypoint_file` writes them."""
    from mocap.io.keypoints import Keypoints

    out = []
    for frame_uv in uv:
        full = np.full((10, 2), np.nan)
        full[arm_indices()] = frame_uv
        out.append(Keypoints(full, np.where(np.isfinite(full).all(axis=1), 1.0, 0.0)))
    return out


def measure_clip(folder: Path, mp: dict, lifter: Path | None, variants: dict) -> dict:
    """Every variant on one clip; arm PA-MPJPE (mm) of each, of MediaPipe's 3D and of its placed poses."""
    from experiments.units import load_sequence
    from mocap.track import TrackerConfig

    loaded = load_sequence(folder)
    prepared = [loaded.prepare(f) for f in loaded.frames]
    n = len(prepared)
    truth = loaded.ground_truth.joints[:n]
    keypoints = keypoints_of(mp["uv"][:n])
    placed = placed_poses(mp["world33"][:n], mp["visibility33"][:n], loaded.model.skeleton)
    placed_joints = np.array([np.full((6, 3), np.nan) if q is None else loaded.model.joint_positions(q)[arm_indices()]
                              for q in placed])
    axes = axes_check(mp, truth)
    row = {"clip": folder.name, "frames": n, "mediapipe_mm": arm_pa_mpjpe(mp["world"][:n], truth[:, arm_indices()]),
           "placed_mm": arm_pa_mpjpe(placed_joints, truth[:, arm_indices()]), "axes": axes}
    config = TrackerConfig() if lifter is None else TrackerConfig(lifter_file=str(lifter))
    for name, (propose, weight) in variants.items():
        source = PlacedSource(placed, loaded.model) if propose else None
        tracker = EvidenceTracker(loaded.model, loaded.calibration.camera, config, loaded.calibration.initial_pose,
                                  placed=placed, weight=weight, source=source)
        results = []
        for i, (frame, kp) in enumerate(zip(prepared, keypoints)):
            results += tracker.push(i, frame, kp)
        results += tracker.finish()
        ours = np.array([r.joints for r in results])[:, arm_indices()]
        row[name] = arm_pa_mpjpe(ours, truth[:, arm_indices()])
        row[f"{name} chosen mediapipe3d"] = float(np.mean([r.origin == "mediapipe3d" for r in results]))
    return row


def axes_check(mp: dict, truth: np.ndarray) -> dict:
    """MediaPipe's world joints against the truth's (camera axes), about their centroids and
    scaled, with no rotation: mean joint error (mm) as given and with an axis flipped. The
    smallest names MediaPipe's axes."""
    from mocap.io.mediapipe_keypoints import world_joints

    flips = {"as given (x right, y down, z away)": (1, 1, 1), "y flipped": (1, -1, 1), "z flipped": (1, 1, -1),
             "x and z flipped": (-1, 1, -1)}
    out = {}
    for label, flip in flips.items():
        errors = []
        for points, seen, t in zip(mp["world33"], mp["visibility33"], truth):
            if not np.isfinite(points).all():
                continue
            joints, present = world_joints(points, seen)
            if present.sum() < 4:
                continue
            a = joints[present] * np.array(flip)
            a = a - a.mean(axis=0)
            b = t[present] - t[present].mean(axis=0)
            errors.append(np.linalg.norm((a * b).sum() / (a * a).sum() * a - b, axis=1).mean())
        out[label] = 1e3 * float(np.mean(errors)) if errors else math.nan
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.mediapipe_3d", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--work", type=Path, required=True, help="experiments.peers' work folder of the clips")
    p.add_argument("--clips", required=True, help="comma-separated clip folders in WORK (e.g. turning,cmu_14_02)")
    p.add_argument("--lifter", type=Path, default=None, help="the tracker's lifter file (default: the shipped one)")
    p.add_argument("--variants", default=",".join(VARIANTS), help=f"comma-separated, of {list(VARIANTS)}")
    p.add_argument("--out", type=Path, required=True, help="folder of mediapipe_3d.json")
    args = p.parse_args(argv)
    variants = {v: VARIANTS[v] for v in args.variants.split(",")}
    rows = []
    for clip in args.clips.split(","):
        stem = clip[len("cmu_"):] if clip.startswith("cmu_") else clip
        with np.load(args.work / f"{stem}-mediapipe.npz") as z:
            mp = {k: z[k] for k in z.files}
        rows.append(measure_clip(args.work / clip, mp, args.lifter, variants))
        r = rows[-1]
        print(f"{clip}: MediaPipe {r['mediapipe_mm']:.0f} mm, placed {r['placed_mm']:.0f} mm; "
              + ", ".join(f"{v} {r[v]:.0f} mm ({r[v] / r['mediapipe_mm']:.2f}x)" for v in variants)
              + f"; axes {json.dumps({k: round(v) for k, v in r['axes'].items()})}", flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "mediapipe_3d.json").write_text(json.dumps({"lifter": None if args.lifter is None else str(args.lifter),
                                                            "rows": rows}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
