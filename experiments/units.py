"""Units of work of a sweep and the functions that run them (on any worker).

A **data unit** (:class:`DataSpec`) writes one sequence folder with
:func:`mocap.synth.generate_sequence` and its prepared frames (label images, edge distance
maps) once, into ``<results>/data/<key>/``: image processing does not depend on the budgets.

A **run unit** (:class:`RunSpec`) tracks one sequence with one tracker setting (region and
edge budgets, edge-step start, convergence test) and returns per-frame residuals, timings,
poses, joints and ground-truth errors; the sweep writes them to one file. A *timing* run unit
prepares its frames afresh so that Table 1 times the whole frame, and runs alone.

The **Table 2 unit** (:func:`measure_table2`) times image processing and each cost at the
paper's resolutions on frames of the benchmark's own actor.

Every function here takes plain, picklable arguments and only reads/writes below the results
folder, so it runs the same in a local process pool and on Dask workers (which must see the
results folder: a local cluster, or a shared file system).
"""
from __future__ import annotations

import io
import json
import math
import os
import platform
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from mocap.io.files import write_bytes_atomic
from mocap.track import EDGE_STARTS

#: Folder names below the results folder.
DATA_DIR, UNITS_DIR = "data", "units"
#: Name of the prepared-frames file inside a sequence folder (the calibration's colour classes).
PREPARED_FILE = "prepared.npz"
#: The same, with the paper's two colour classes (``without`` hair and lower body).
PREPARED_FILE_PAPER = "prepared-paper.npz"
#: Model extensions an experiment can leave out (:func:`load_sequence`).
EXTENSIONS: tuple[str, ...] = ("hair", "lower_body")


class UnpreparableSequence(ValueError):
    """A generated sequence whose frames cannot be prepared: the colour classes cannot be learnt
    from its first frame (:func:`mocap.calibrate.colour_model_from_pose` refuses it, e.g. a face
    against a background of its own colour). The generated folder is kept; its prepared frames
    are not written."""


def prepared_file(without: tuple[str, ...] = ()) -> str:
    """Name of the prepared-frames file for a model without the extensions ``without``."""
    left_out = [e for e in EXTENSIONS if e in without]
    if len(left_out) == len(EXTENSIONS):
        return PREPARED_FILE_PAPER
    return "prepared-without-" + "-".join(left_out) + ".npz" if left_out else PREPARED_FILE
#: Per-frame arrays of a run unit's result, besides ``meta``.
FRAME_ARRAYS: tuple[str, ...] = (
    "frame", "region_residual", "edge_residual", "edge_residual_after_region", "empty", "evaluations",
    "region_iterations", "edge_iterations", "ms_prepare", "ms_region", "ms_edge", "ms_total", "poses", "joints",
    "mpjpe_mm", "pa_mpjpe_mm", "angle_error_deg", "reprojection_px")
RUN_KINDS = ("run", "timing")


@dataclass(frozen=True)
class DataSpec:
    """One benchmark sequence to generate and prepare.

    Attributes
    ----------
    actor : str
        Named synthetic sequence (its actor, clothes and scene; its motion unless ``motion``).
    motion : str or None
        Motion-capture clip (BVH, or AMC with its ASF beside it) driving the actor.
    frames : int
        Frames (for a clip: at most this many; shorter clips are used whole).
    seed : int
    width, height : int
        Pixels.
    """

    actor: str
    motion: str | None
    frames: int
    seed: int
    width: int
    height: int

    @property
    def name(self) -> str:
        """Sequence name in figures: the actor, plus ``+clip`` when a clip drives it."""
        return self.actor if self.motion is None else f"{self.actor}+{clip_name(self.motion)}"

    @property
    def key(self) -> str:
        """Folder name of the sequence below ``data/`` (unique per setting)."""
        frames = f"{self.frames}f" if self.motion is None else f"max{self.frames}f"
        return f"{self.name}-s{self.seed}-{frames}-{self.width}x{self.height}"


def clip_name(path: str | Path) -> str:
    """Name of a motion clip: its file stem (``cmu_12_01_walk``)."""
    return Path(path).stem


@dataclass(frozen=True)
class RunSpec:
    """One tracker run on one sequence.

    Attributes
    ----------
    data : DataSpec
    region, edge : int
        Evaluations per frame of the region and the edge step.
    edge_start : {"region_simplex", "fresh"}
        Edge step starts from the region step's final simplex, or from a large fresh one.
    ftol : float
        Convergence test of both steps.
    kind : {"run", "timing"}
        ``timing`` prepares frames afresh inside the unit (Table 1) and runs alone.
    gradient : bool
        The gradient step on (:attr:`mocap.track.TrackerConfig.gradient_step`): it takes
        :func:`mocap.track.config.gradient_budget` of the edge step's ``edge`` evaluations, so the
        total stays ``region + edge``. Set to False where that share is 0 (the run would be the
        simplex-only one), so such a unit is not run twice.
    """

    data: DataSpec
    region: int
    edge: int
    edge_start: str = "region_simplex"
    ftol: float = 1e-3
    kind: str = "run"
    gradient: bool = False

    def __post_init__(self) -> None:
        for name in ("region", "edge"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise ValueError(f"{name} budget must be a non-negative integer, got {v!r}")
        if self.edge_start not in EDGE_STARTS:
            raise ValueError(f"edge_start must be one of {EDGE_STARTS}, got {self.edge_start!r}")
        if self.kind not in RUN_KINDS:
            raise ValueError(f"kind must be one of {RUN_KINDS}, got {self.kind!r}")
        if self.region == 0 or self.edge == 0:       # the start matters only when both steps run
            object.__setattr__(self, "edge_start", "region_simplex")
        if not isinstance(self.gradient, bool):
            raise ValueError(f"gradient must be a bool, got {self.gradient!r}")
        if self.gradient:
            from mocap.track.config import gradient_budget

            if gradient_budget(self.edge) == 0:      # the step would not run: the simplex-only unit
                object.__setattr__(self, "gradient", False)

    @property
    def key(self) -> str:
        """File stem of the result below ``units/<data key>/``."""
        start = "" if self.edge_start == "region_simplex" else "_fresh"
        timing = "_timing" if self.kind == "timing" else ""
        gradient = "_gradient" if self.gradient else ""
        return f"r{self.region:04d}_e{self.edge:04d}{start}_ftol{self.ftol:g}{gradient}{timing}"

    def path(self, root: str | Path) -> Path:
        """Where the result file of this unit lives."""
        return Path(root) / UNITS_DIR / self.data.key / f"{self.key}.npz"

    def tracker_config(self):
        """The :class:`mocap.track.TrackerConfig` of this run: the paper's method
        (:meth:`mocap.track.TrackerConfig.paper`: one hypothesis, no recovery, the paper had
        none) with this unit's budgets, edge start, ``ftol`` and gradient step."""
        from mocap.track import TrackerConfig

        total = self.region + self.edge
        split = f"{self.region}:{self.edge}" if total else "1:0"
        return TrackerConfig.paper(evaluations=total, split=split, edge_start=self.edge_start, ftol=self.ftol,
                                  gradient_step=self.gradient)


# ----------------------------------------------------------------------------- data units
def data_folder(spec: DataSpec, root: str | Path) -> Path:
    """The sequence folder of ``spec`` below the results folder ``root``."""
    return Path(root) / DATA_DIR / spec.key


def prepare_data(spec: DataSpec, root: str, without: tuple[str, ...] = ()) -> str:
    """Generate the sequence of ``spec`` (if not there yet) and its prepared frames.

    Parameters
    ----------
    spec : DataSpec
    root : str
        Results folder.
    without : tuple of str
        Prepare the label images for the model without these extensions (see
        :func:`load_sequence`), in :func:`prepared_file`.

    Returns
    -------
    str
        The sequence folder.

    Raises
    ------
    UnpreparableSequence
        When the first frame does not give the colour classes (the folder is kept, unprepared).
    """
    from mocap.synth import generate_sequence

    folder = data_folder(spec, root)
    if not (folder / "meta.json").is_file():          # meta.json is written last by the generator
        # a clip is generated whole (its length is only known once retargeted) and used up to spec.frames
        generate_sequence(spec.actor, folder, frames=spec.frames if spec.motion is None else None, seed=spec.seed,
                          size=(spec.width, spec.height), motion=spec.motion, progress=False)
        for old in folder.glob("prepared*.npz"):
            old.unlink()
    name = prepared_file(without)
    if not (folder / name).is_file():
        try:
            sequence = load_sequence(folder, spec.frames, without=without)
        except ValueError as error:
            raise UnpreparableSequence(f"{folder.name}: {error}") from error
        prepared = [sequence.prepare(f) for f in sequence.frames]
        keys = tuple(prepared[0].timings)
        buf = io.BytesIO()
        np.savez_compressed(
            buf, labels=np.stack([p.labels for p in prepared]), foreground=np.stack([p.foreground for p in prepared]),
            edges=np.stack([p.edges for p in prepared]), distance=np.stack([p.distance for p in prepared]),
            is_empty=np.array([p.is_empty for p in prepared]), timing_keys=np.array(keys),
            timings=np.array([[p.timings[k] for k in keys] for p in prepared], dtype=np.float64))
        write_bytes_atomic(folder / name, buf.getvalue())
    return str(folder)


@dataclass
class LoadedSequence:
    """A sequence folder in memory, with what the tracker needs."""

    folder: Path
    calibration: object
    model: object
    frames: list
    background: np.ndarray | None
    colour_model: object
    ground_truth: object
    meta: dict

    def prepare(self, frame):
        """:func:`mocap.imaging.prepare_frame` with this sequence's background and colours."""
        from mocap.imaging import prepare_frame

        return prepare_frame(frame, self.background, self.colour_model)


def load_sequence(folder: str | Path, frames: int | None = None, without: tuple[str, ...] = ()) -> LoadedSequence:
    """Read a synthetic sequence folder and build its model and colour model.

    The colour classes are learnt from the first frame inside the calibrated (true) pose, as
    ``python -m mocap track`` does by default, and the model keeps the classes the colour model
    kept (a hair or lower-body class the frame does not support is merged).

    Parameters
    ----------
    folder : str or Path
    frames : int, optional
        Read only the first ``frames`` frames (all when None or when the sequence is shorter).
    without : tuple of str
        Leave model extensions (:data:`EXTENSIONS`) out of the calibration: ``"hair"`` (no hair
        region, no hair class), ``"lower_body"`` (no lower-body part, no such class); both
        give the paper's model (skin and clothes only).
    """
    from mocap.body import resolution_for_image
    from mocap.calibrate import Calibration, colour_model_from_pose
    from mocap.io.pose_table import PoseTable
    from mocap.io.sequence import find_sequence
    from mocap.io.video import iter_frames, read_image
    from mocap.body import BodyDimensions

    paths = find_sequence(folder)
    if paths.calibration is None or paths.ground_truth is None:
        raise ValueError(f"{folder} is not a synthetic sequence folder (calibration.json and ground_truth.csv needed)")
    calibration = Calibration.from_json(paths.calibration)
    unknown = set(without) - set(EXTENSIONS)
    if unknown:
        raise ValueError(f"unknown model extension(s) {sorted(unknown)}; known: {', '.join(EXTENSIONS)}")
    if without:
        dims = calibration.dims
        if "hair" in without:
            dims = dims.with_hairline(None)
        if "lower_body" in without:
            dims = BodyDimensions({n: v for n, v in dims.parts.items() if n != "lower_body"}, dims.hairline)
        classes = tuple(c for c in calibration.class_names if c not in without)
        calibration = Calibration(dims, calibration.initial_pose, calibration.camera, classes, calibration.part_class)
    camera = calibration.camera
    model = calibration.body_model(resolution_for_image(camera.width, camera.height))
    frames = list(iter_frames(paths.frames, 0, frames))
    background = read_image(paths.background) if paths.background is not None else None
    colour = colour_model_from_pose(frames[0], background, model, camera, calibration.initial_pose)
    model = model.with_class_names(colour.names)
    meta = json.loads(paths.meta.read_text()) if paths.meta is not None else {}
    return LoadedSequence(Path(folder), calibration, model, frames, background, colour,
                          PoseTable.read(paths.ground_truth), meta)


def load_prepared(folder: str | Path, without: tuple[str, ...] = ()) -> list:
    """The prepared frames stored by :func:`prepare_data`, as :class:`mocap.imaging.PreparedFrame`."""
    from mocap.imaging import PreparedFrame

    with np.load(Path(folder) / prepared_file(without), allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    keys = [str(k) for k in arrays["timing_keys"]]
    return [PreparedFrame(labels=np.ascontiguousarray(arrays["labels"][i]),
                          foreground=np.ascontiguousarray(arrays["foreground"][i]),
                          edges=np.ascontiguousarray(arrays["edges"][i]),
                          distance=np.ascontiguousarray(arrays["distance"][i]),
                          is_empty=bool(arrays["is_empty"][i]),
                          timings=dict(zip(keys, map(float, arrays["timings"][i]))))
            for i in range(arrays["labels"].shape[0])]


# ----------------------------------------------------------------------------- run units
def run_unit(spec: RunSpec, root: str) -> dict:
    """Track the sequence of ``spec.data`` with the settings of ``spec``.

    Parameters
    ----------
    spec : RunSpec
    root : str
        Results folder (its ``data/`` must hold the prepared sequence).

    Returns
    -------
    dict
        The per-frame arrays of :data:`FRAME_ARRAYS` (residuals: F in [0, 1], edge distance in
        pixels; times in ms; poses in metres/radians; joints in metres; errors in mm, degrees,
        pixels) and ``meta``, a JSON string (spec, tracker settings, summary, wall time).
    """
    from mocap import metrics
    from mocap.track import Tracker, track_prepared

    started = time.perf_counter()
    folder = data_folder(spec.data, root)
    seq = load_sequence(folder, spec.data.frames)
    if spec.kind == "timing":
        prepared = [seq.prepare(f) for f in seq.frames]
    else:
        prepared = load_prepared(folder)
    config = spec.tracker_config()
    tracker = Tracker(seq.model, seq.calibration.camera, config, seq.calibration.initial_pose)
    results = track_prepared(prepared, tracker)
    n = len(results)
    truth = seq.ground_truth
    joints = np.stack([r.joints for r in results])
    poses = np.stack([r.pose for r in results])
    out = {
        "frame": np.array([r.frame for r in results], dtype=np.int64),
        "region_residual": np.array([r.region_residual for r in results]),
        "edge_residual": np.array([r.edge_residual for r in results]),
        "edge_residual_after_region": np.array([r.edge_residual_after_region for r in results]),
        "empty": np.array([r.empty for r in results]),
        "evaluations": np.array([r.evaluations for r in results], dtype=np.int64),
        "region_iterations": np.array([r.region_iterations for r in results], dtype=np.int64),
        "edge_iterations": np.array([r.edge_iterations for r in results], dtype=np.int64),
        "poses": poses, "joints": joints,
    }
    for name in ("prepare", "region", "edge", "total"):
        out[f"ms_{name}"] = np.array([r.timings_ms.get(name, math.nan) for r in results])
    true_joints, true_poses = truth.joints[:n], truth.poses[:n]
    out["mpjpe_mm"] = metrics.mpjpe(joints, true_joints, per_frame=True)
    out["pa_mpjpe_mm"] = metrics.pa_mpjpe(joints, true_joints, per_frame=True)
    out["angle_error_deg"] = metrics.joint_angle_error(poses, true_poses, per_frame=True)
    try:
        out["reprojection_px"] = metrics.reprojection_error(joints, true_joints, seq.calibration.camera,
                                                            per_frame=True)
    except ValueError:                                    # a joint behind the camera: not projectable
        out["reprojection_px"] = np.full(n, math.nan)
    summary = {k: float(np.nanmean(out[k])) for k in ("region_residual", "edge_residual", "mpjpe_mm",
                                                       "pa_mpjpe_mm", "angle_error_deg", "ms_total")}
    meta = {"spec": asdict(spec), "sequence": spec.data.name, "frames": n, "tracker": config.to_dict(),
            "summary": summary, "wall_s": time.perf_counter() - started, "host": platform.node(),
            "pid": os.getpid(), "motion": seq.meta.get("motion")}
    out["meta"] = json.dumps(meta)
    return out


def save_unit(path: str | Path, result: dict) -> None:
    """Write one run unit's result atomically (one ``.npz``; ``meta`` as a JSON string)."""
    missing = set(FRAME_ARRAYS) - set(result)
    if missing or "meta" not in result:
        raise ValueError(f"unit result lacks {', '.join(sorted(missing | ({'meta'} - set(result))))}")
    buf = io.BytesIO()
    np.savez(buf, **{k: np.asarray(v) for k, v in result.items()})
    write_bytes_atomic(path, buf.getvalue())


def load_unit(path: str | Path) -> dict:
    """Read a run unit's result: the per-frame arrays and ``meta`` (a dict)."""
    with np.load(path, allow_pickle=False) as z:
        out = {k: z[k] for k in z.files}
    out["meta"] = json.loads(str(out["meta"]))
    return out


# ----------------------------------------------------------------------------- Table 2
def measure_table2(sizes: tuple[tuple[int, int], ...], sequence: str, frames: int, seed: int, min_runs: int,
                   min_seconds: float, root: str) -> dict:
    """Time image processing and each cost evaluation at several resolutions (Table 2).

    At each size, ``frames`` frames of ``sequence`` are generated through the same actor and
    camera model (scaled), the colour model is learnt from the true first pose, and
    :func:`mocap.bench.time_calls` times :func:`mocap.imaging.prepare_frame` (whole, and its
    parts from its own timings) and one evaluation of each cost (render + F, render + mean edge
    distance) at poses scattered around the true ones, as the optimiser tries them.

    Returns
    -------
    dict
        ``{"rows": [{"width", "height", "triangles", "prepare_ms_mean", "prepare_ms_median",
        "prepare_parts_ms": {...}, "cost_region_ms_mean", "cost_region_ms_median",
        "cost_edge_ms_mean", "cost_edge_ms_median", "runs"}...], "cpu", "versions"}``
    """
    from mocap.bench import environment, time_calls
    from mocap.body import JOINT_LIMITS, clamp_to_limits
    from mocap.cost import EdgeCost, RegionCost

    rows = []
    rng = np.random.default_rng(seed)
    for width, height in sizes:
        spec = DataSpec(sequence, None, frames, seed, width, height)
        folder = Path(prepare_data(spec, root))
        seq = load_sequence(folder, frames)
        camera = seq.calibration.camera
        parts: dict[str, list[float]] = {}

        def prepare(i: int) -> None:
            p = seq.prepare(seq.frames[i % len(seq.frames)])
            for k, v in p.timings.items():
                parts.setdefault(k, []).append(1e3 * v)

        t_prepare = time_calls(prepare, min_runs=min_runs, min_seconds=min_seconds) / 1e3
        prepared = load_prepared(folder)
        poses = []
        for i in range(64):
            q = seq.ground_truth.poses[i % len(prepared)].copy()
            q[:3] += rng.normal(0.0, 0.02, 3)
            q[3:] += rng.normal(0.0, 0.1, q.size - 3)
            poses.append(clamp_to_limits(q, JOINT_LIMITS))
        region = [RegionCost(p.labels, seq.model, camera) for p in prepared]
        edge = [EdgeCost(p.distance, seq.model, camera) for p in prepared]
        t_region = time_calls(lambda i: region[i % len(region)](poses[i % len(poses)]), min_runs=min_runs,
                              min_seconds=min_seconds) / 1e3
        t_edge = time_calls(lambda i: edge[i % len(edge)](poses[i % len(poses)]), min_runs=min_runs,
                            min_seconds=min_seconds) / 1e3
        rows.append({"width": width, "height": height, "triangles": int(seq.model.mesh.n_triangles),
                     "prepare_ms_mean": float(t_prepare.mean()), "prepare_ms_median": float(np.median(t_prepare)),
                     "prepare_ms_std": float(t_prepare.std()),
                     "prepare_parts_ms": {k: float(np.mean(v)) for k, v in parts.items()},
                     "cost_region_ms_mean": float(t_region.mean()), "cost_region_ms_median": float(np.median(t_region)),
                     "cost_edge_ms_mean": float(t_edge.mean()), "cost_edge_ms_median": float(np.median(t_edge)),
                     "runs": int(min(t_prepare.size, t_region.size, t_edge.size))})
    versions, cpu = environment()
    return {"rows": rows, "cpu": cpu, "versions": versions, "sequence": sequence, "frames": frames,
            "bench": bench_imaging(min_runs, min_seconds)}


def bench_imaging(min_runs: int, min_seconds: float) -> dict | None:
    """``mocap bench``'s own image-processing rows (its synthetic scene, the Table 2 sizes), or None.

    A cross-check of :func:`measure_table2`'s image-processing column. ``mocap bench`` pins the
    process to one CPU; the CPU set is restored afterwards.
    """
    from mocap.bench import run_benchmark

    affinity = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else None
    try:
        result = run_benchmark(quick=min_runs < 30, with_llvmpipe=False, stages=("imaging",), progress=False)
    except ValueError:                      # an older mocap without the imaging group
        return None
    finally:
        if affinity is not None:
            os.sched_setaffinity(0, affinity)
    return result
