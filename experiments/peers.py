"""``python -m experiments.peers``: this tracker and MediaPipe Pose side by side.

MediaPipe is what a user with their own video would otherwise pick. It is the optional extra
``keypoints`` (``pip install -e .[keypoints]``: ``mediapipe==0.10.14``, the last release whose
wheel bundles the BlazePose models, so it runs offline; it works with the project's numpy 2.4,
and the test extra includes it)::

    python -m experiments.peers --out experiments/peers

Three comparisons, on the same frames:

* **synthetic** (ground truth): PA-MPJPE of shoulders, elbows and wrists (millimetres, every
  frame aligned by the best similarity transform, so MediaPipe's hip-centred world landmarks
  and our camera-frame joints compare) on the benchmark clips rendered at ``--size`` (default
  160x120), MediaPipe (video mode) fed the frames as they are; our tracker with the clip's true
  calibration and background.
* **real** (no ground truth; MediaPipe as reference): ``python -m mocap track CLIP --keypoints
  none`` (the silhouette alone; the command's default ``auto`` is the keypoint run below where
  MediaPipe is installed) on the clips of ``../shared/data/video/``, and the share of our projected
  shoulders, elbows and wrists (``poses.csv``'s ``_u``/``_v``) within half of MediaPipe's
  shoulder width of its 2D landmarks (:func:`mocap.metrics.pck_2d`).
* **cmu** (issue 34, item 5; issue 49, item 6; ground truth): the toolkit's generator
  (:func:`mocap.synth.generate_sequence` with ``motion=``) driven by trials of training subjects
  of ``../shared/data/mocap/train``, each subject held out in turn (``--subjects``, default
  :data:`CMU_TRIALS`'s), rendered at each of ``--cmu-sizes`` (default 160x120, 320x240 and
  640x480) with the face and with hair all round the head (``--faces both``, the default; ``face``
  or ``no-face`` for one: :attr:`mocap.synth.actor.Appearance.face`), and the tracker given a
  lifter trained without that subject (the tracker's ``lifter_file``): ``LIFTERS/lifter_no<S>.npz``
  (``--lifters``, default ``OUT/work``, which git ignores), used when present, else trained first,
  about 6 minutes of one core each, as ``python -m experiments.fit_lifter --trials-from
  experiments/fit_lifter.json --exclude-subject S --out LIFTERS/lifter_no<S>.npz`` (never shipped).

  The subjects and trials (:data:`CMU_TRIALS`, 150 frames each, 25 fps, from each trial's start):
  subject 14 (boxing, jumping jacks and side twists, jumping jacks again, directing traffic: arms
  across the body, above the head and turning) and subject 02 (punching, washing: a second body
  and a second mover, arms in front of the chest). Two subjects with arm-heavy trials of the
  shipped lifter's training set (``experiments/fit_lifter.json``, so each held-out lifter really
  lacks them), and a clip count whose whole measurement (6 trials x 3 sizes x 2 heads = 36 runs)
  took 19 minutes of one core once the two lifters were trained (each about 5 minutes).

With keypoints (issues 23 and 44), ours runs as a user runs it, ``python -m mocap track CLIP
--keypoints mediapipe``: the run's own detector (image mode) on the same frames MediaPipe alone
sees, at the same size (MediaPipe crops and resamples the person itself: enlarging the frames
first brought nothing, ``experiments.detector_size``). On the real clips it is measured by the
share of frames whose six arm joints are all within a quarter of MediaPipe's shoulder width of
its 2D landmarks (and the failed frames where MediaPipe found the person). On the synthetic and
CMU-driven clips, against the truth (:func:`scored_clip`):

- the detector (the run's ``keypoints.csv``): the share of frames it labels the person's left
  arm right and back (``detector_swapped``) and its arm joints' 2D error against the truth's
  projection (px, each frame under its better labelling);
- ours and MediaPipe's own 3D: arm PA-MPJPE; the arms' error about their centre with no
  rotation (:func:`mocap.metrics.centred_mpjpe`: PA-MPJPE hides a body turned around); the
  acceleration error of the aligned arms (mm/frame², over runs of found frames); the share of
  frames whose arms carry the right labels; and the ratios ours / MediaPipe's of PA-MPJPE and
  of the acceleration error (issue 44's targets: at most 1 and 0.5).

Speed: our ``ms_total`` per frame (image side and registration, as ``run.json``) and
MediaPipe's ``process`` time per frame, both wall-clock on this machine as loaded.
Writes ``results.json``, ``peers.md`` (the table) and overlay stills ``still_<clip>.png``.
"""
from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mocap.io.mediapipe_keypoints import MEDIAPIPE_LANDMARKS
from mocap.metrics import acceleration_error, centred_mpjpe, pa_mpjpe, pck_2d
from mocap.run.files import POSES_CSV, RUN_JSON

#: Joints compared (ours), in order (right, then left: the order :func:`label_swapped` pairs them in).
ARM_JOINTS = ("r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist")
#: Each of :data:`ARM_JOINTS` with its other side's.
OTHER_SIDE = (3, 4, 5, 0, 1, 2)
#: MediaPipe Pose landmark index of each of :data:`ARM_JOINTS` (its left/right are the person's).
MEDIAPIPE_INDEX = {j: MEDIAPIPE_LANDMARKS[j][0] for j in ARM_JOINTS}
#: Synthetic clips compared (the issue's four) and their length.
SYNTHETIC = ("turning", "arms-crossing", "not-facing", "gestures-2")
SYNTHETIC_FRAMES = 60
#: Real clips (in the shared data's video folder).
REAL = ("intel_asl_no.mkv", "intel_asl_sister.mkv", "intel_asl_book.mkv")
#: CMU-driven clips (``--only cmu``): each held-out subject's trials (``train/cmu_<trial>.amc``), each
#: rendered with one of the synthetic sequences' actor and scene (:data:`CMU_SCENES`, in this order
#: within a subject, cycled), and their length in frames (25 fps). Subject 14's four keep the scenes
#: they had when it was the only subject (``experiments.detector_size`` and ``branch_audit`` read them).
CMU_TRIALS = {"14": ("14_02", "14_06", "14_20", "14_24"), "02": ("02_05", "02_10")}
CMU_SCENES = ("gestures-2", "turning", "arms-crossing", "not-facing")
CMU_FRAMES = 150
#: Sizes (width, height, pixels) the CMU-driven clips are rendered at by default (issue 49 item 6).
CMU_SIZES = ((160, 120), (320, 240), (640, 480))
#: ``--faces``: the heads the CMU-driven clips are drawn with (True: the face; False: hair all round).
FACES = {"both": (True, False), "face": (True,), "no-face": (False,)}
#: Issue 49's targets for ours with MediaPipe's keypoints against MediaPipe's own 3D on the CMU-driven
#: clips, with the face and without, every clip and size: the arms' PA-MPJPE ratio at most
#: ``pa_ratio_max`` on every clip and ``pa_ratio_median_max`` on the median clip, the acceleration
#: error ratio at most ``accel_ratio_max``, and our arms labelled right on at least
#: ``labels_right_min`` of the frames.
CMU_TARGETS = {"pa_ratio_max": 1.0, "pa_ratio_median_max": 0.85, "accel_ratio_max": 0.5, "labels_right_min": 0.95}
#: Default size (width, height, pixels) the synthetic and CMU-driven clips are rendered at.
SIZE = (160, 120)


def arm_indices() -> np.ndarray:
    """Indices of :data:`ARM_JOINTS` in :data:`mocap.body.skeleton.JOINT_NAMES`."""
    from mocap.body.skeleton import JOINT_NAMES
    return np.array([JOINT_NAMES.index(j) for j in ARM_JOINTS])


def arm_pa_mpjpe(pred: np.ndarray, true: np.ndarray) -> float:
    """PA-MPJPE (mm) over the six arm joints, frames where ``pred`` is NaN left out.

    Parameters
    ----------
    pred, true : ndarray, shape (N, 6, 3), metres
        Joints in :data:`ARM_JOINTS` order.
    """
    keep = np.isfinite(pred).all(axis=(1, 2))
    if not keep.any():
        return float("nan")
    return pa_mpjpe(pred[keep], true[keep])


def label_swapped(detected: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per frame, whether the detected arms fit the truth better with left and right exchanged.

    Parameters
    ----------
    detected, truth : ndarray, shape (N, 6, D), pixels (D = 2) or metres (D = 3)
        :data:`ARM_JOINTS` order; NaN rows of ``detected`` where nothing was found.

    Returns
    -------
    ndarray of bool, shape (N,)
        False where nothing was found.
    """
    as_given = np.linalg.norm(detected - truth, axis=2).sum(axis=1)
    exchanged = np.linalg.norm(detected[:, OTHER_SIDE] - truth, axis=2).sum(axis=1)
    return np.nan_to_num(exchanged, nan=np.inf) < np.nan_to_num(as_given, nan=np.inf)


def shoulder_width(uv: np.ndarray) -> np.ndarray:
    """Per-frame distance between the two shoulders of ``uv`` (N, 6, 2) in ARM_JOINTS order."""
    return np.linalg.norm(uv[:, 0] - uv[:, 3], axis=1)


def run_mediapipe(frames, upscale: int = 1) -> dict:
    """MediaPipe Pose (video mode, model complexity 1) on frames.

    Returns ``uv`` (N, 6, 2) pixels of the given frames, ``world`` (N, 6, 3) metres, both
    NaN where no person was found, ``ms`` (N,) per frame, and every landmark's world position
    ``world33`` (N, 33, 3) metres and ``visibility33`` (N, 33) (NaN where not found).
    """
    import mediapipe as mp
    from skimage.transform import rescale

    uv, world, ms, world33, seen33 = [], [], [], [], []
    order = [MEDIAPIPE_INDEX[j] for j in ARM_JOINTS]
    with mp.solutions.pose.Pose(static_image_mode=False, model_complexity=1) as pose:
        for frame in frames:
            h, w = frame.shape[:2]
            image = frame if upscale == 1 else \
                (rescale(frame, upscale, order=1, channel_axis=-1) * 255).round().astype(np.uint8)
            t0 = time.perf_counter()
            result = pose.process(np.ascontiguousarray(image))
            ms.append(1e3 * (time.perf_counter() - t0))
            if result.pose_landmarks is None:
                uv.append(np.full((6, 2), np.nan))
                world.append(np.full((6, 3), np.nan))
                world33.append(np.full((33, 3), np.nan))
                seen33.append(np.full(33, np.nan))
                continue
            lm, wl = result.pose_landmarks.landmark, result.pose_world_landmarks.landmark
            uv.append([(lm[i].x * w, lm[i].y * h) for i in order])
            world.append([(wl[i].x, wl[i].y, wl[i].z) for i in order])
            world33.append([(p.x, p.y, p.z) for p in wl])
            seen33.append([p.visibility for p in wl])
    return {"uv": np.asarray(uv, float), "world": np.asarray(world, float), "ms": np.asarray(ms),
            "world33": np.asarray(world33, float).reshape(-1, 33, 3),
            "visibility33": np.asarray(seen33, float).reshape(-1, 33)}


def _track(video: Path, out: Path, *, overlay: bool, keypoints: str = "none",
           lifter: Path | None = None) -> "PoseTable":  # noqa: F821
    """``python -m mocap track VIDEO --keypoints none`` with no other option (``--no-overlay``
    unless ``overlay``; ``--keypoints`` when given), through the library entry point the CLI calls;
    ``lifter``: the tracker's lifter file (None: the shipped lifter); default settings otherwise."""
    from mocap.io.pose_table import PoseTable
    from mocap.track.config import TrackerConfig
    import mocap.run

    tracker = TrackerConfig(lifter_file=None if lifter is None else str(lifter))
    mocap.run.track(video, out, mocap.run.OwnVideoOptions(overlay=overlay, overwrite=True, keypoints=keypoints,
                                                          tracker=tracker))
    return PoseTable.read(out / POSES_CSV)


def ours_uv(table) -> np.ndarray:
    """Our projected arm joints (N, 6, 2) from a ``poses.csv`` table (input pixels)."""
    return np.stack([np.stack([table.extra[f"{j}_u"], table.extra[f"{j}_v"]], axis=1) for j in ARM_JOINTS], axis=1)


def within_quarter(ours: np.ndarray, ref: np.ndarray) -> dict:
    """PCK at a quarter of MediaPipe's shoulder width, and the share of frames (of those where
    MediaPipe found the person) whose six arm joints are all that close."""
    width = shoulder_width(ref)
    found = np.isfinite(ref).all(axis=(1, 2))
    close = np.linalg.norm(ours - ref, axis=2) < 0.25 * width[:, None]
    return {"pck_quarter": pck_2d(ours, ref, width, 0.25),
            "frames_all_within_quarter": float(close[found].all(axis=1).mean()) if found.any() else float("nan")}


def _runs_of_found(found: np.ndarray) -> list[slice]:
    """The maximal runs of consecutive True frames of ``found`` (N,) at least 3 long."""
    runs, start = [], None
    for i, f in enumerate(list(found) + [False]):
        if f and start is None:
            start = i
        elif not f and start is not None:
            if i - start >= 3:
                runs.append(slice(start, i))
            start = None
    return runs


def arm_accel(pred: np.ndarray, true: np.ndarray) -> float:
    """Acceleration error (mm/frame²) of the six arm joints, each frame aligned as
    :func:`mocap.metrics.pa_mpjpe` aligns it, over the runs of at least three consecutive frames
    where ``pred`` (N, 6, 3) is found (finite), weighted by their inner frames; NaN without."""
    found = np.isfinite(pred).all(axis=(1, 2))
    values = [acceleration_error(pred[r], true[r], align="procrustes", per_frame=True) for r in _runs_of_found(found)]
    return float(np.concatenate(values).mean()) if values else float("nan")


def arm_figures(pred: np.ndarray, true: np.ndarray) -> dict:
    """Arm PA-MPJPE, the error about the arms' centre with no rotation (a body turned around
    shows there: :func:`mocap.metrics.centred_mpjpe`), the acceleration error and the share of
    frames whose arms carry the right labels (nearer the truth about their centre than with left
    and right exchanged), over the frames where ``pred`` (N, 6, 3) is found; ``true`` (N, 6, 3)."""
    found = np.isfinite(pred).all(axis=(1, 2))
    if not found.any():
        return {"pa_mpjpe_mm": float("nan"), "centred_mm": float("nan"), "accel": float("nan"),
                "labels_right": float("nan")}
    p, t = pred[found], true[found]
    centre = lambda x: x - x.mean(axis=1, keepdims=True)
    return {"pa_mpjpe_mm": pa_mpjpe(p, t), "centred_mm": centred_mpjpe(p, t), "accel": arm_accel(pred, true),
            "labels_right": float(1.0 - label_swapped(centre(p), centre(t)).mean())}


def detector_figures(run: Path, truth_uv: np.ndarray) -> dict:
    """The tracker's detector (``run``'s ``keypoints.csv``: its own labels, input pixels) against
    the truth's projection ``truth_uv`` (N, 6, 2): the share of frames it found the arms, the
    share of those it labelled left and right swapped, and its median arm joint error (px, each
    frame under its better labelling)."""
    from mocap.io.keypoints import read_keypoints
    from mocap.run.files import KEYPOINTS_CSV

    stored = read_keypoints(run / KEYPOINTS_CSV)
    uv = np.full(truth_uv.shape, np.nan)
    for i in range(len(truth_uv)):
        if i in stored:
            k = stored[i]
            present = k.present[arm_indices()]
            uv[i][present] = k.uv[arm_indices()][present]
    found = np.isfinite(uv).all(axis=(1, 2))
    swapped = label_swapped(uv, truth_uv)
    better = np.where(swapped[:, None, None], uv[:, OTHER_SIDE], uv)
    errors = np.linalg.norm(better - truth_uv, axis=2)[found]
    return {"detector_found": float(found.mean()),
            "detector_swapped": float(swapped[found].mean()) if found.any() else float("nan"),
            "detector_error_px": float(np.median(errors)) if errors.size else float("nan")}


def scored_clip(seq: Path, run: Path, table, mp: dict, frames: int) -> dict:
    """Ours with MediaPipe's keypoints (``run``, ``table`` its ``poses.csv``) and MediaPipe's own
    3D (``mp``: :func:`run_mediapipe`) on the clip ``seq``, against its ground truth."""
    from mocap.calibrate import Calibration
    from mocap.io.pose_table import PoseTable

    truth = PoseTable.read(seq / "ground_truth.csv").joints[:frames, arm_indices()]
    camera = Calibration.from_json(seq / "calibration.json").camera
    truth_uv = camera.project(truth.reshape(-1, 3)).reshape(truth.shape[0], len(ARM_JOINTS), 2)
    ours = {f"ours_keypoints_{k}": v for k, v in arm_figures(table.joints[:frames, arm_indices()], truth).items()}
    theirs = {f"mediapipe_{k}": v for k, v in arm_figures(mp["world"][:frames], truth).items()}
    return {**ours, **theirs, **detector_figures(run, truth_uv),
            "pa_ratio": ours["ours_keypoints_pa_mpjpe_mm"] / theirs["mediapipe_pa_mpjpe_mm"],
            "accel_ratio": ours["ours_keypoints_accel"] / theirs["mediapipe_accel"],
            "mediapipe_found": float(np.isfinite(mp["world"][:frames]).all(axis=(1, 2)).mean()),
            "ours_keypoints_ms": float(np.median(table.extra["ms_total"][1:])),
            "mediapipe_ms": float(np.median(mp["ms"][1:]))}


def synthetic_row(name: str, work: Path, seed: int, size: tuple[int, int] = SIZE) -> dict:
    """One synthetic clip at ``size``: ours without keypoints, ours with ``--keypoints mediapipe``
    (the run's own detector on the frames as they are) and MediaPipe alone (video mode, the same
    frames: it crops and resamples the person itself, so enlarging them first brings nothing,
    ``experiments.detector_size``)."""
    from mocap.io.pose_table import PoseTable
    from mocap.io.video import iter_frames
    from mocap.synth import generate_sequence

    tag = "" if size == SIZE else f"-{size[0]}x{size[1]}"
    seq = generate_sequence(name, work / f"{name}{tag}", frames=SYNTHETIC_FRAMES, seed=seed, size=size, progress=False)
    table = _track(seq, work / f"{name}{tag}-run", overlay=False)
    truth = PoseTable.read(seq / "ground_truth.csv").joints[:, arm_indices()]
    mp = run_mediapipe(list(iter_frames(seq / "frames")))
    np.savez(work / f"{name}{tag}-mediapipe.npz", **mp)          # for later analyses
    keyed = _track(seq, work / f"{name}{tag}-keypoints-run", overlay=False, keypoints="mediapipe")
    n = min(len(table), len(keyed), len(truth))
    return {"clip": name, "size": f"{size[0]}x{size[1]}", "frames": n,
            "ours_pa_mpjpe_mm": arm_pa_mpjpe(table.joints[:n, arm_indices()], truth[:n]),
            **scored_clip(seq, work / f"{name}{tag}-keypoints-run", keyed, mp, n),
            "ours_ms": float(np.median(table.extra["ms_total"][1:]))}


@dataclass(frozen=True)
class CmuClip:
    """One CMU-driven clip of ``--only cmu``.

    Attributes
    ----------
    subject : str
        The CMU subject held out of the clip's lifter (e.g. ``"14"``).
    trial : str
        The subject's trial (``train/cmu_<trial>.amc``), e.g. ``"14_02"``.
    scene : str
        The synthetic sequence whose actor, scene, light and camera draw it (:data:`CMU_SCENES`).
    size : (int, int)
        Width and height, pixels.
    face : bool
        The head drawn with its face; False: hair all round (no face seen from any side).
    """
    subject: str
    trial: str
    scene: str
    size: tuple[int, int]
    face: bool

    @property
    def tag(self) -> str:
        """The suffix of its files in the work folder: ``-WxH`` unless 160x120, ``-noface`` without
        the face (empty for 160x120 with the face, the names from before either option)."""
        return ("" if self.size == SIZE else f"-{self.size[0]}x{self.size[1]}") + ("" if self.face else "-noface")


def cmu_clips(subjects: list[str], trials: list[str] | None, sizes, faces) -> list[CmuClip]:
    """The clips of ``--only cmu``: each subject's trials (``trials``: those of it, else its
    :data:`CMU_TRIALS`), each at every size of ``sizes`` ((width, height) pixels) and with every head
    of ``faces`` (bools), in that order. A trial's scene is :data:`CMU_SCENES` cycled over the
    subject's trials in their order (``trials`` when given).

    Raises
    ------
    ValueError
        On a trial of none of ``subjects``, a subject left with no trial, or a subject without
        default trials when ``trials`` is None.
    """
    if trials is not None:
        strays = [t for t in trials if t.split("_")[0] not in subjects]
        if strays:
            raise ValueError(f"trials {', '.join(strays)} are not of the held-out subjects {', '.join(subjects)}")
    out = []
    for subject in subjects:
        if trials is not None:
            own = [t for t in trials if t.split("_")[0] == subject]
        elif subject in CMU_TRIALS:
            own = list(CMU_TRIALS[subject])
        else:
            raise ValueError(f"no default trials for subject {subject} (those of {', '.join(CMU_TRIALS)}): give --trials")
        if not own:
            raise ValueError(f"no trial of subject {subject} among --trials")
        out += [CmuClip(subject, trial, CMU_SCENES[k % len(CMU_SCENES)], tuple(size), bool(face))
                for k, trial in enumerate(own) for size in sizes for face in faces]
    return out


def lifter_path(folder: Path, subject: str) -> Path:
    """The file of the lifter trained without ``subject`` in ``folder``: ``lifter_no<subject>.npz``."""
    return folder / f"lifter_no{subject}.npz"


def held_out_lifter(subject: str, folder: Path, train: Path) -> Path:
    """The lifter trained without ``subject`` (:func:`lifter_path`): the file when present, else
    trained first on the shipped lifter's trials less the subject's (``python -m
    experiments.fit_lifter --trials-from experiments/fit_lifter.json --exclude-subject S --out
    FILE --train TRAIN``, about 6 minutes of one core) and written there.

    Raises
    ------
    RuntimeError
        When the training fails.
    """
    path = lifter_path(folder, subject)
    if path.exists():
        return path
    from experiments import fit_lifter

    folder.mkdir(parents=True, exist_ok=True)
    print(f"training {path.name} (the shipped lifter's trials without subject {subject}, about 6 minutes)", flush=True)
    code = fit_lifter.main(["--trials-from", str(fit_lifter.RECORD), "--exclude-subject", subject,
                            "--train", str(train), "--out", str(path)])
    if code != 0 or not path.exists():
        raise RuntimeError(f"training the lifter without subject {subject} failed (exit {code})")
    return path


def cmu_row(clip: CmuClip, work: Path, *, train: Path, seed: int, frames: int, lifter: Path | None) -> dict:
    """One CMU-driven clip: ``clip.trial``'s motion (``train/cmu_<trial>.amc``) rendered at
    ``clip.size`` in ``clip.scene``'s setting, with the face or hair all round (``clip.face``),
    tracked with ``--keypoints mediapipe`` (the run's detector) and the lifter file ``lifter``,
    beside MediaPipe's own 3D on the same frames. MediaPipe's landmarks are kept in
    ``work/<trial><tag>-mediapipe.npz`` (with ``world33``/``visibility33``; :attr:`CmuClip.tag`).
    ``wall_s``: the clip's seconds, rendering, MediaPipe and tracking, on this machine as loaded."""
    from mocap.io.video import iter_frames
    from mocap.synth import generate_sequence

    started = time.perf_counter()
    name = f"cmu_{clip.trial}"
    seq = generate_sequence(clip.scene, work / f"{name}{clip.tag}", frames=frames, seed=seed, size=clip.size,
                            motion=train / f"{name}.amc", progress=False, face=clip.face)
    mp = run_mediapipe(list(iter_frames(seq / "frames")))
    np.savez(work / f"{clip.trial}{clip.tag}-mediapipe.npz", **mp)
    run = work / f"{name}{clip.tag}-keypoints-run"
    keyed = _track(seq, run, overlay=False, keypoints="mediapipe", lifter=lifter)
    n = min(len(keyed), len(mp["world"]))
    return {"clip": clip.trial, "subject": clip.subject, "scene": clip.scene, "size": f"{clip.size[0]}x{clip.size[1]}",
            "face": clip.face, "frames": n, "lifter": None if lifter is None else lifter.name,
            "wall_s": round(time.perf_counter() - started, 1), **scored_clip(seq, run, keyed, mp, n)}


def target_summary(rows: list[dict]) -> list[dict]:
    """Issue 49's targets (:data:`CMU_TARGETS`) over CMU rows, per head (face, no face) and for both:
    ``group``, ``clips``, the PA ratio's highest (``pa_ratio_max``) and median (``pa_ratio_median``)
    over the rows, the acceleration ratio's highest, the lowest share of frames labelled right,
    and whether each target is met (``*_met``); NaN figures count as missed."""
    out = []
    groups = [("face", [r for r in rows if r.get("face", True)]), ("no face", [r for r in rows if not r.get("face", True)]),
              ("all", rows)]
    for group, members in groups:
        if not members:
            continue
        pa = np.array([r["pa_ratio"] for r in members], float)
        accel = np.array([r["accel_ratio"] for r in members], float)
        labels = np.array([r["ours_keypoints_labels_right"] for r in members], float)
        worst = lambda x, f: float(f(x)) if np.isfinite(x).all() else float("nan")
        summary = {"group": group, "clips": len(members), "pa_ratio_max": worst(pa, np.max),
                   "pa_ratio_median": worst(pa, np.median), "accel_ratio_max": worst(accel, np.max),
                   "labels_right_min": worst(labels, np.min)}
        summary["pa_ratio_max_met"] = bool(summary["pa_ratio_max"] <= CMU_TARGETS["pa_ratio_max"])
        summary["pa_ratio_median_met"] = bool(summary["pa_ratio_median"] <= CMU_TARGETS["pa_ratio_median_max"])
        summary["accel_ratio_max_met"] = bool(summary["accel_ratio_max"] <= CMU_TARGETS["accel_ratio_max"])
        summary["labels_right_min_met"] = bool(summary["labels_right_min"] >= CMU_TARGETS["labels_right_min"])
        out.append(summary)
    return out


def real_row(video: Path, work: Path, out: Path) -> dict:
    from mocap.io.video import iter_frames

    table = _track(video, work / f"{video.stem}-run", overlay=True)
    frames = list(iter_frames(video))
    cache = work / f"{video.stem}-mediapipe.npz"       # MediaPipe's landmarks do not change between our runs
    if cache.exists():
        with np.load(cache) as stored:
            mp = {k: stored[k] for k in ("uv", "world", "ms")}
    else:
        mp = run_mediapipe(frames)
        np.savez(cache, **mp)
    ours = ours_uv(table)
    n = min(len(ours), len(mp["uv"]))
    ours, ref = ours[:n], mp["uv"][:n]
    width = shoulder_width(ref)
    per_joint = {j: pck_2d(ours[:, [k]], ref[:, [k]], width) for k, j in enumerate(ARM_JOINTS)}
    run = json.loads((work / f"{video.stem}-run" / RUN_JSON).read_text())
    _still(frames[n // 2], ours[n // 2], ref[n // 2], out / f"still_{video.stem}.png")
    keyed = _track(video, work / f"{video.stem}-keypoints-run", overlay=False, keypoints="mediapipe")
    keyed_run = json.loads((work / f"{video.stem}-keypoints-run" / RUN_JSON).read_text())
    found = np.isfinite(ref).all(axis=(1, 2))
    quarter = {f"ours_{k}": v for k, v in within_quarter(ours, ref).items()}
    quarter |= {f"ours_keypoints_{k}": v for k, v in within_quarter(ours_uv(keyed)[:n], ref).items()}
    return {"clip": video.name, "frames": n, "pck": pck_2d(ours, ref, width), "pck_per_joint": per_joint, **quarter,
            "ours_keypoints_failed_where_found": float(keyed.extra["failed"][:n][found].mean()),
            "ours_keypoints_ms": float(np.median(keyed.extra["ms_total"][1:])),
            "ours_keypoints_detector_ms": keyed_run.get("keypoints_ms_per_frame", float("nan")),
            "mediapipe_found": float(np.isfinite(ref).all(axis=(1, 2)).mean()),
            "background": _background_chosen(run["settings"]["own_video"]["background"]),
            "ours_ms": float(np.median(table.extra["ms_total"][1:])), "ours_fps_run": run["fps"],
            "mediapipe_ms": float(np.median(mp["ms"][1:]))}


def _background_chosen(account: dict) -> str:
    """``run.json`` ``settings.own_video.background`` in a few words: its mode, and for ``auto``
    whether the estimate was used (else the foreground is colour-only)."""
    if account["mode"] != "auto":
        return account["mode"]
    return "auto: estimated" if account["used"] else "auto: colour only"


def _still(frame: np.ndarray, ours: np.ndarray, ref: np.ndarray, path: Path) -> None:
    """Both skeletons' arms over one frame (small PNG): ours orange, MediaPipe's cyan."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(3.2, 2.4), dpi=100)
    ax.imshow(frame)
    for uv, colour, label in ((ref, "tab:cyan", "MediaPipe"), (ours, "tab:orange", "ours")):
        for chain in ((0, 1, 2), (3, 4, 5), (0, 3)):
            ax.plot(uv[list(chain), 0], uv[list(chain), 1], "-o", color=colour, lw=1.5, ms=2.5,
                    label=label if chain == (0, 1, 2) else None)
    ax.legend(loc="upper right", fontsize=6, framealpha=0.6)
    ax.set_axis_off()
    fig.subplots_adjust(0, 0, 1, 1)
    fig.savefig(path)
    plt.close(fig)


#: The columns of the tables of ours with MediaPipe's keypoints against MediaPipe's own 3D (keys, headings).
KEYED_COLUMNS = (("detector_swapped", "detector: labels swapped"), ("detector_error_px", "detector: arms 2D error px"),
                 ("ours_keypoints_pa_mpjpe_mm", "ours PA-MPJPE arms mm"), ("mediapipe_pa_mpjpe_mm", "MediaPipe's 3D"),
                 ("pa_ratio", "PA ratio"), ("ours_keypoints_centred_mm", "ours arms about their centre mm"),
                 ("mediapipe_centred_mm", "MediaPipe's"), ("ours_keypoints_accel", "ours Accel mm/frame²"),
                 ("mediapipe_accel", "MediaPipe's"), ("accel_ratio", "Accel ratio"),
                 ("ours_keypoints_labels_right", "ours arms labelled right"))


def _keyed_table(rows: list[dict], first: str) -> list[str]:
    """The keyed comparison of ``rows`` (synthetic or CMU), a row a clip."""
    def cell(key, value):
        if isinstance(value, float) and math.isnan(value):
            return "–"
        if key in ("detector_swapped", "ours_keypoints_labels_right"):
            return f"{100 * value:.0f} %"
        if key.endswith("ratio"):
            return f"**{value:.2f}**"
        return f"{value:.1f}" if key.endswith("_px") else f"{value:.0f}"

    heads = any("face" in r for r in rows)             # CMU rows say which head they were drawn with
    lines = ["| " + first + " | size | " + ("head | " if heads else "") + " | ".join(h for _, h in KEYED_COLUMNS)
             + " |", "|---|---|" + ("---|" if heads else "") + "---|" * len(KEYED_COLUMNS)]
    for r in rows:
        head = ("face | " if r.get("face", True) else "no face | ") if heads else ""
        lines.append(f"| {r['clip']} | {r.get('size', '160x120')} | {head}"
                     + " | ".join(cell(k, r.get(k, float("nan"))) for k, _ in KEYED_COLUMNS) + " |")
    return lines


def _target_table(rows: list[dict]) -> list[str]:
    """Issue 49's targets over the CMU rows (:func:`target_summary`), a line per head."""
    t = CMU_TARGETS
    mark = lambda met: "met" if met else "**missed**"
    lines = [f"| CMU-driven clips, issue 49's targets | clips x sizes | PA ratio, highest (target ≤ {t['pa_ratio_max']:g}) "
             f"| PA ratio, median clip (≤ {t['pa_ratio_median_max']:g}) | Accel ratio, highest (≤ {t['accel_ratio_max']:g}) "
             f"| arms labelled right, lowest (≥ {100 * t['labels_right_min']:.0f} %) |", "|---|---|---|---|---|---|"]
    for g in target_summary(rows):
        lines.append(f"| {g['group']} | {g['clips']} | {g['pa_ratio_max']:.2f} {mark(g['pa_ratio_max_met'])} | "
                     f"{g['pa_ratio_median']:.2f} {mark(g['pa_ratio_median_met'])} | "
                     f"{g['accel_ratio_max']:.2f} {mark(g['accel_ratio_max_met'])} | "
                     f"{100 * g['labels_right_min']:.0f} % {mark(g['labels_right_min_met'])} |")
    return lines


def markdown(results: dict) -> str:
    lines = ["| synthetic clip (60 frames) | size | ours PA-MPJPE arms (mm) | MediaPipe PA-MPJPE arms (mm) "
             "| MediaPipe found | ours ms/frame | MediaPipe ms/frame |", "|---|---|---|---|---|---|---|"]
    for r in results["synthetic"]:
        lines.append(f"| {r['clip']} | {r.get('size', '160x120')} | {r['ours_pa_mpjpe_mm']:.0f} | "
                     f"{r['mediapipe_pa_mpjpe_mm']:.0f} | {100 * r['mediapipe_found']:.0f} % | {r['ours_ms']:.1f} | "
                     f"{r['mediapipe_ms']:.1f} |")
    lines += ["", "| real clip (640x480) | frames | background chosen | PCK@0.5 shoulder width vs MediaPipe | "
              "per joint (r/l shoulder, elbow, wrist) | ours ms/frame | MediaPipe ms/frame |",
              "|---|---|---|---|---|---|---|"]
    for r in results["real"]:
        pj = r["pck_per_joint"]
        joints = " / ".join(f"{100 * pj[a]:.0f}-{100 * pj[b]:.0f}" for a, b in
                            (("r_shoulder", "l_shoulder"), ("r_elbow", "l_elbow"), ("r_wrist", "l_wrist")))
        lines.append(f"| {r['clip']} | {r['frames']} | {r['background']} | **{100 * r['pck']:.1f} %** | {joints} | "
                     f"{r['ours_ms']:.1f} | {r['mediapipe_ms']:.1f} |")
    keyed_synthetic = [r for r in results["synthetic"] if "ours_keypoints_pa_mpjpe_mm" in r]
    keyed_real = [r for r in results["real"] if "ours_keypoints_frames_all_within_quarter" in r]
    if keyed_synthetic:
        lines += ["", *_keyed_table(keyed_synthetic, "synthetic clip, `--keypoints mediapipe`")]
    if results.get("cmu"):
        lines += ["", *_keyed_table(results["cmu"], "CMU-driven clip (subject held out of the lifter), "
                                                    "`--keypoints mediapipe`"), "", *_target_table(results["cmu"])]
    if keyed_real:
        lines += ["", "| real clip | frames with all six arm joints within 1/4 shoulder width of MediaPipe: ours | "
                  "ours with `--keypoints mediapipe` | failed frames where MediaPipe found the person | "
                  "ours with keypoints ms/frame | its MediaPipe ms/frame |", "|---|---|---|---|---|---|"]
        lines += [f"| {r['clip']} | {100 * r['ours_frames_all_within_quarter']:.0f} % | "
                  f"**{100 * r['ours_keypoints_frames_all_within_quarter']:.0f} %** | "
                  f"{100 * r['ours_keypoints_failed_where_found']:.0f} % | {r['ours_keypoints_ms']:.1f} | "
                  f"{r['ours_keypoints_detector_ms']:.1f} |" for r in keyed_real]
    return "\n".join(lines) + "\n"


def report_section(folder: Path, rel: str = "peers") -> list[str]:
    """The REPORT.md section from ``folder/results.json`` and its stills (links relative to
    the report: ``rel``); empty when the comparison has not been run."""
    stored = folder / "results.json"
    if not stored.exists():
        return []
    results = json.loads(stored.read_text())
    real = results.get("real", [])
    L = ["## MediaPipe side by side (`python -m experiments.peers`)", "",
         "What a user with their own video would otherwise pick: MediaPipe Pose 0.10.14 (BlazePose, model "
         "complexity 1, video mode), on the same frames. Synthetic: PA-MPJPE of shoulders, elbows and wrists "
         "against the ground truth, our tracker with the clip's true calibration and background, MediaPipe's "
         "world landmarks from the same frames (MediaPipe resamples the person itself). Real: `python -m mocap track CLIP` with no other option "
         "(no background plate, automatic calibration, working resolution chosen by the tracker); the share of "
         "our projected shoulders, elbows and wrists (`poses.csv` `_u`/`_v`) within half of MediaPipe's "
         "shoulder width of its 2D landmarks, MediaPipe taken as the reference. One view cannot tell size from "
         "distance, so the 3D comparison is after Procrustes alignment. Times are wall-clock milliseconds per "
         "frame on the development machine while other jobs shared its two cores (load average 4-10; "
         "MediaPipe's landmarks and times on the real clips are cached from its first run, "
         "`OUT/work/<clip>-mediapipe.npz`): they compare the two tools under a similar load, not either's "
         "speed on an idle core (`python -m mocap bench --groups video` for ours); ours include hand "
         "re-acquisition, which on these clips runs a second registration on most frames (about 1,000 cost "
         "evaluations a frame).", "",
         markdown(results).rstrip("\n"), ""]
    if real:
        L.append(" ".join(f"![{r['clip']}]({rel}/still_{Path(r['clip']).stem}.png)" for r in real))
        L += ["", "Middle frame of each clip: our arms orange, MediaPipe's cyan.", ""]
    return L


def _parse_size(text: str) -> tuple[int, int] | None:
    """``"WxH"`` as (width, height) pixels, each at least 16; None when it is not that."""
    try:
        size = tuple(int(v) for v in text.strip().lower().split("x"))
    except ValueError:
        return None
    return size if len(size) == 2 and min(size) >= 16 else None


def main(argv: list[str] | None = None) -> int:
    from experiments import EXPERIMENTS_DIR

    p = argparse.ArgumentParser(prog="python -m experiments.peers", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", type=Path, default=EXPERIMENTS_DIR.parent.parent / "shared" / "data",
                   help="the shared data folder (its video/ clips)")
    p.add_argument("--out", type=Path, default=EXPERIMENTS_DIR / "peers", help="results folder")
    p.add_argument("--work", type=Path, default=None, help="scratch folder for clips and runs (default OUT/work)")
    p.add_argument("--seed", type=int, default=0, help="the synthetic and CMU-driven clips' seed")
    p.add_argument("--only", choices=("synthetic", "real", "cmu"), default=None,
                   help="run one part; the other parts' stored results in OUT are kept (cmu runs only when named)")
    p.add_argument("--train", type=Path, default=None, help="CMU trials folder (default DATA/mocap/train)")
    p.add_argument("--subjects", default=",".join(CMU_TRIALS),
                   help="cmu: comma-separated CMU subjects, each held out of its clips' lifter in turn "
                        f"(default {','.join(CMU_TRIALS)}; their trials: --trials, else the defaults)")
    p.add_argument("--trials", default=None,
                   help="cmu: comma-separated trials of those subjects (default: each subject's own, CMU_TRIALS)")
    p.add_argument("--cmu-frames", type=int, default=CMU_FRAMES, help="cmu: frames per clip (25 fps)")
    p.add_argument("--cmu-sizes", default=",".join(f"{w}x{h}" for w, h in CMU_SIZES),
                   help="cmu: comma-separated sizes WxH in pixels the clips are rendered at, for MediaPipe alone "
                        "and the tracker alike (default: %(default)s)")
    p.add_argument("--faces", choices=tuple(FACES), default="both",
                   help="cmu: draw the head with its face, with hair all round (no face seen from any side), "
                        "or each clip both ways (default)")
    p.add_argument("--lifters", type=Path, default=None,
                   help="cmu: folder of the lifters trained without each subject, lifter_no<S>.npz, used when "
                        "present and trained there (about 6 minutes of one core each) when not (default OUT/work)")
    p.add_argument("--size", default=None,
                   help=f"synthetic: the clips' size WxH in pixels (default {SIZE[0]}x{SIZE[1]}; cmu: --cmu-sizes)")
    args = p.parse_args(argv)
    size = SIZE if args.size is None else _parse_size(args.size)
    if size is None:
        p.error(f"--size takes WxH in pixels (at least 16 each), got {args.size!r}")
    if args.only == "cmu" and args.size is not None:
        p.error("--size is the synthetic clips'; the CMU-driven clips take --cmu-sizes")
    if args.cmu_frames < 1:
        p.error(f"--cmu-frames must be positive, got {args.cmu_frames}")
    sizes = [_parse_size(v) for v in args.cmu_sizes.split(",")]
    if not sizes or None in sizes:
        p.error(f"--cmu-sizes takes comma-separated WxH in pixels (at least 16 each), got {args.cmu_sizes!r}")
    subjects = [v.strip() for v in args.subjects.split(",") if v.strip()]
    if not subjects or len(set(subjects)) != len(subjects):
        p.error(f"--subjects takes distinct comma-separated CMU subjects, got {args.subjects!r}")
    try:
        clips = cmu_clips(subjects, None if args.trials is None else [t.strip() for t in args.trials.split(",")],
                          sizes, FACES[args.faces])
    except ValueError as error:
        p.error(str(error))
    from mocap.io.mediapipe_keypoints import available

    if not available():
        print("error: mediapipe is not installed: pip install -e .[keypoints]")
        return 2
    work = args.work or args.out / "work"
    work.mkdir(parents=True, exist_ok=True)
    args.out.mkdir(parents=True, exist_ok=True)
    stored = args.out / "results.json"
    results = json.loads(stored.read_text()) if stored.exists() and args.only else {"synthetic": [], "real": []}
    if args.only == "cmu":
        train = args.train or args.data / "mocap" / "train"
        missing = sorted({f"cmu_{c.trial}.amc" for c in clips if not (train / f"cmu_{c.trial}.amc").exists()})
        if missing:
            p.error(f"no {', '.join(missing)} in {train}")
        lifters = {s: held_out_lifter(s, args.lifters or work, train) for s in subjects}
        results["cmu"] = [cmu_row(c, work, train=train, seed=args.seed, frames=args.cmu_frames, lifter=lifters[c.subject])
                          for c in clips]
    if args.only in (None, "synthetic"):
        results["synthetic"] = [synthetic_row(name, work, args.seed, size) for name in SYNTHETIC]
    if args.only in (None, "real"):
        results["real"] = [real_row(args.data / "video" / clip, work, args.out) for clip in REAL]
    (args.out / "results.json").write_text(json.dumps(results, indent=2))
    table = markdown(results)
    (args.out / "peers.md").write_text(table)
    print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
