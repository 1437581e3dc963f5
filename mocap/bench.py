"""``python -m mocap bench``: medians of every stage at every resolution (docs/design.md section 6).

Stages (JSON ``stage`` names): ``render`` (pose + rasterize the label image, through the public
``LabelRenderer`` call), ``cost_region`` (render + non-overlapping ratio), ``cost_edge`` (render +
mean edge distance) — the costs as an optimiser calls them (``evaluate_unchecked``: no pose
validation, ~1.7 µs) — of the default model (four colour classes: hair region and lower body),
and the same three of the paper's model (two classes, no hair region, no lower body) as
``render_paper``, ``cost_region_paper``, ``cost_edge_paper``, measured in the same run,
``gradient_region`` and ``gradient_edge`` (one value and gradient of eq. 1 and of eq. 2,
:meth:`mocap.cost.RegionCost.gradient`, :meth:`mocap.cost.EdgeCost.gradient`, of the default
model: one render each, the occluding-contour samples and, for eq. 1, the seams),
``llvmpipe_render`` (the same mesh through OpenGL on Mesa llvmpipe + read-back, when the
``bench`` extra is installed), ``prepare_frame`` and its parts ``prepare_background``,
``prepare_colour``, ``prepare_edges``, ``prepare_distance``, ``frame_100`` / ``frame_500`` (a
whole frame of the paper's method, image side included, at that many cost evaluations),
``evaluation_in_loop`` (one cost evaluation inside the compiled simplex loop, from
``frame_500``'s region and edge steps: what the tracker pays, against the Python calls of the
``cost_*`` rows), ``frame_beam`` (a whole frame of the default tracker), ``frame_beam_keypoints`` (the same given
the true joints projected as 2D keypoints: the keypoint cue, the learned lifter's proposals
and its score), ``lifter`` (one frame's 2D keypoints lifted to the K hypotheses of
:mod:`mocap.track.lifter`, group ``lifter``), and
``video_640x480`` (group ``video``): the whole own-video path of ``python -m mocap track`` on a
640x480 clip — decode, reduction to the 160x120 working resolution, image side, registration
at the default budget and every output (journal, BVH, residual plot, overlay video) — as wall
time of the run divided by its frames (``runs`` is the frame count; p10/p90 are those of the
per-frame image side and registration alone); ``video_640x480_cpu`` is the same run's CPU time
(this process and its ffmpeg children) per frame, the figure that holds on a busy machine.

Everything runs on one core (the process is pinned to one CPU where the OS allows, llvmpipe
gets one thread), after a warm-up call that also triggers Numba compilation — except
``video_640x480``, which runs on the CPUs the process had before pinning, as ``track`` runs: its
frame reader thread and ffmpeg processes work beside the tracker, and the row measures what the
tracker's critical path costs end to end (``video_640x480_cpu`` still counts all of their CPU).
"""
from __future__ import annotations

import gc
import json
import os
import platform
import sys
import time
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np

if TYPE_CHECKING:
    from mocap.body.model import BodyModel
    from mocap.imaging import ColourModel
    from mocap.render import Camera

#: Resolutions of the render and cost stages.
RENDER_SIZES: tuple[tuple[int, int], ...] = ((160, 120), (320, 240), (640, 480))
#: Resolutions of the image-processing stages (the paper's Table 2).
TABLE2_SIZES: tuple[tuple[int, int], ...] = ((160, 120), (256, 256), (320, 240), (480, 480), (512, 512), (640, 480))


#: The clock of every row but the ``video_640x480`` ones and those of :data:`PROCESS_CLOCK_STAGES`:
#: CPU time of the timing thread (``time.thread_time_ns``). The rows run on one pinned core, so
#: on a quiet machine this is their wall time; on a loaded one the time other processes take is
#: not billed to them (they still slow it through shared caches). ``"clock"`` of the JSON result.
CLOCK = "thread_cpu"
#: The clocks :func:`time_calls` reads, by name (``BenchRow.clock``): CPU time of the calling
#: thread, or of the whole process (every thread of it: what one pinned core spent on the call).
CLOCKS: dict[str, Callable[[], int]] = {"thread_cpu": time.thread_time_ns, "process_cpu": time.process_time_ns}
#: Stages whose work runs in threads other than the caller's (Mesa llvmpipe rasterizes in a
#: thread of its own even with ``LP_NUM_THREADS=1``): timed in process CPU time on the pinned
#: core, since the calling thread's CPU time would leave their work out (issue 50).
PROCESS_CLOCK_STAGES = ("llvmpipe_render",)


@dataclass(frozen=True)
class BenchRow:
    """One timed stage. Times in microseconds."""

    stage: str
    width: int
    height: int
    triangles: int
    median_us: float
    p10_us: float
    p90_us: float
    runs: int
    clock: str = CLOCK          # what timed it: a name of CLOCKS, or "wall"


def clock_of(stage: str) -> str:
    """The clock a stage's row is timed with (a name of :data:`CLOCKS`)."""
    return "process_cpu" if stage in PROCESS_CLOCK_STAGES else CLOCK


def time_calls(call: Callable[[int], object], *, min_runs: int, min_seconds: float,
               clock: str = CLOCK) -> np.ndarray:
    """Time ``call(i)`` for i = 0, 1, ... until both ``min_runs`` and ``min_seconds`` (of wall
    time) are reached; each call in CPU time of this thread (``clock`` ``"thread_cpu"``,
    :data:`CLOCK`) or of the whole process (``"process_cpu"``: other threads' work counted too).

    Returns
    -------
    ndarray, shape (runs,), float64, microseconds
    """
    if clock not in CLOCKS:
        raise ValueError(f"clock must be one of {tuple(CLOCKS)}, got {clock!r}")
    now = CLOCKS[clock]
    call(0)                                   # warm-up (and JIT compilation)
    times = []
    start = time.perf_counter()
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        i = 0
        while i < min_runs or time.perf_counter() - start < min_seconds:
            t0 = now()
            call(i)
            times.append(now() - t0)
            i += 1
    finally:
        if gc_was_enabled:
            gc.enable()
    return np.asarray(times, dtype=np.float64) / 1000.0


def _row(stage: str, size: tuple[int, int], triangles: int, times_us: np.ndarray) -> BenchRow:
    """A row of times taken by :func:`time_calls` with the stage's clock (:func:`clock_of`)."""
    p10, med, p90 = np.percentile(times_us, [10, 50, 90])
    return BenchRow(stage, size[0], size[1], int(triangles), float(med), float(p10), float(p90), int(times_us.size),
                    clock_of(stage))


def _poses(n: int, seed: int = 0) -> list[np.ndarray]:
    """Poses around the neutral one, as an optimiser would try them."""
    from mocap.body import JOINT_LIMITS, clamp_to_limits, neutral_pose
    rng = np.random.default_rng(seed)
    base = neutral_pose()
    out = []
    for _ in range(n):
        q = base.copy()
        q[:3] += rng.normal(0.0, 0.02, 3)
        q[3:] += rng.normal(0.0, 0.15, 20)
        out.append(clamp_to_limits(q, JOINT_LIMITS))
    return out


def render_rows(sizes: Sequence[tuple[int, int]], *, min_runs: int, min_seconds: float,
                with_llvmpipe: bool) -> tuple[list[BenchRow], list[str]]:
    """Rows of the stages ``render``, ``cost_region``, ``cost_edge`` and ``llvmpipe_render``."""
    from scipy import ndimage

    from mocap.body import BodyModel, neutral_pose, resolution_for_image
    from mocap.cost import EdgeCost, LabelRenderer, RegionCost
    from mocap.render import Camera, render

    rows: list[BenchRow] = []
    notes: list[str] = []
    poses = _poses(256)
    pick = lambda i: poses[i % len(poses)]
    for size in sizes:
        camera = Camera.default(*size)
        full = BodyModel.build(resolution=resolution_for_image(*size))
        paper = BodyModel.build(full.dims.without_extensions(), resolution=resolution_for_image(*size))
        for suffix, model in (("", full), ("_paper", paper)):
            tri = model.mesh.n_triangles
            target = render(neutral_pose(), model, camera)
            distance = ndimage.distance_transform_edt(~target.edges).astype(np.float32)
            labels = LabelRenderer(model, camera)
            region = RegionCost(target.labels, model, camera)
            edge = EdgeCost(distance, model, camera)
            rows.append(_row("render" + suffix, size, tri, time_calls(lambda i: labels(pick(i)), min_runs=min_runs,
                                                                       min_seconds=min_seconds)))
            rows.append(_row("cost_region" + suffix, size, tri, time_calls(lambda i: region.evaluate_unchecked(pick(i)),
                                                                            min_runs=min_runs, min_seconds=min_seconds)))
            rows.append(_row("cost_edge" + suffix, size, tri, time_calls(lambda i: edge.evaluate_unchecked(pick(i)),
                                                                          min_runs=min_runs, min_seconds=min_seconds)))
            if suffix == "":
                gradient = np.zeros(len(neutral_pose()))
                edge.gradient_args()                     # built once per frame, not per call
                region.gradient_args()
                rows.append(_row("gradient_region", size, tri, time_calls(
                    lambda i: region.gradient_unchecked(pick(i), gradient), min_runs=min_runs,
                    min_seconds=min_seconds)))
                rows.append(_row("gradient_edge", size, tri, time_calls(
                    lambda i: edge.gradient_unchecked(pick(i), gradient), min_runs=min_runs, min_seconds=min_seconds)))
        model = full
        tri = model.mesh.n_triangles
        if with_llvmpipe:
            try:
                from mocap.render.gl_reference import GLRenderer
                gl = GLRenderer(model, camera, threads=1)
            except RuntimeError as exc:
                notes.append(f"llvmpipe rows skipped: {exc}")
                with_llvmpipe = False
                continue
            try:
                rows.append(_row("llvmpipe_render", size, tri, time_calls(
                    lambda i: gl.render_labels(pick(i)), min_runs=min_runs, min_seconds=min_seconds,
                    clock=clock_of("llvmpipe_render"))))
                if len(notes) == 0 or not notes[0].startswith("llvmpipe renderer"):
                    notes.insert(0, f"llvmpipe renderer: {gl.renderer_name}, LP_NUM_THREADS=1")
            finally:
                gl.release()
    return rows, notes


def imaging_rows(sizes: Sequence[tuple[int, int]], *, min_runs: int, min_seconds: float) -> list[BenchRow]:
    """Rows ``prepare_frame`` (whole image side, timed outside) and its parts ``prepare_background``,
    ``prepare_colour``, ``prepare_edges``, ``prepare_distance`` (timed inside the same calls), on the
    synthetic scene of :mod:`mocap.imaging.testing` (varying seeds: noise and arm positions)."""
    from mocap.imaging import ColourModel, prepare_frame
    from mocap.imaging.testing import synthetic_scene_with_labels

    rows: list[BenchRow] = []
    for size in sizes:
        scenes = [synthetic_scene_with_labels(size[0], size[1], seed) for seed in range(8)]
        colour = ColourModel.from_boxes(scenes[0].frame, {"skin": scenes[0].face_box,
                                                          "clothes": scenes[0].clothes_box})
        parts: dict[str, list[float]] = {}

        def call(i):
            s = scenes[i % len(scenes)]
            out = prepare_frame(s.frame, s.background, colour)
            if i > 0:
                for k, v in out.timings.items():
                    parts.setdefault(k, []).append(1e6 * v)

        rows.append(_row("prepare_frame", size, 0, time_calls(call, min_runs=min_runs, min_seconds=min_seconds)))
        for key in ("background", "colour", "edges", "distance"):
            rows.append(_row(f"prepare_{key}", size, 0, np.asarray(parts[key])))
    return rows


@dataclass(frozen=True, eq=False)
class BenchSequence:
    """The bench's synthetic sequence, loaded as the tracker sees it (:meth:`make`).

    Attributes
    ----------
    model : BodyModel
        The true calibration's actor at the mesh resolution of the image size, with the colour
        classes of ``colour``.
    camera : Camera
        The sequence's camera (pixels of ``size``).
    images : list of ndarray, each (H, W, 3) uint8
        The frames.
    background : ndarray, (H, W, 3) uint8
    colour : ColourModel
        Learnt on the first frame from the true initial pose.
    initial_pose : ndarray, shape (23,), float64
        The calibration's pose (metres, radians).
    poses : ndarray, shape (frames, 23), float64
        The true poses.
    joints : ndarray, shape (frames, 10, 3), float64
        The true joints (camera coordinates, metres).
    """

    model: BodyModel
    camera: Camera
    images: list[np.ndarray]
    background: np.ndarray
    colour: ColourModel
    initial_pose: np.ndarray
    poses: np.ndarray
    joints: np.ndarray

    @classmethod
    def make(cls, folder, size: tuple[int, int], frames: int, *, name: str = "gestures-1",
             seed: int = 0) -> "BenchSequence":
        """Generate sequence ``name`` (``frames`` frames of ``size`` = (width, height) pixels,
        ``seed``) into ``folder`` and load it."""
        from mocap.body.mesh import resolution_for_image
        from mocap.calibrate import Calibration, colour_model_from_pose
        from mocap.io.pose_table import PoseTable
        from mocap.io.sequence import find_sequence
        from mocap.io.video import iter_frames, read_image
        from mocap.synth import generate_sequence

        seq = find_sequence(generate_sequence(name, folder, frames=frames, seed=seed, size=size, progress=False))
        calibration = Calibration.from_json(seq.calibration)
        model = calibration.body_model(resolution_for_image(*size))
        camera = calibration.camera
        images = list(iter_frames(seq.frames))
        background = read_image(seq.background)
        colour = colour_model_from_pose(images[0], background, model, camera, calibration.initial_pose)
        truth = PoseTable.read(seq.ground_truth)
        return cls(model=model.with_class_names(colour.names), camera=camera, images=images, background=background,
                   colour=colour, initial_pose=calibration.initial_pose, poses=truth.poses, joints=truth.joints)


def frame_rows(size: tuple[int, int], budgets: Sequence[int], *, frames: int, min_runs: int) -> list[BenchRow]:
    """Rows of one whole frame (image side + registration) on a synthetic sequence, median over
    its frames: ``frame_<N>`` the paper's method (one hypothesis, two-step registration with N cost
    evaluations, auto split; :meth:`~mocap.track.TrackerConfig.paper`) for each N of ``budgets``,
    and ``frame_beam`` the default tracker (beam, proposals and decoding; its evaluations vary
    from frame to frame), ``frame_beam_keypoints`` the same given the ground truth's joints
    projected as 2D keypoints (the keypoint cue with the default configuration's sources).

    With 500 among ``budgets``, also ``evaluation_in_loop`` (:func:`_evaluations_in_loop`)."""
    import tempfile

    from mocap.imaging import prepare_frame
    from mocap.io.keypoints import Keypoints
    from mocap.track import Tracker, TrackerConfig
    from mocap.track.lifter import Lifter

    rows: list[BenchRow] = []
    with tempfile.TemporaryDirectory() as tmp:
        bench = BenchSequence.make(tmp, size, frames)
        model, camera, images = bench.model, bench.camera, bench.images
        configs = {f"frame_{b}": TrackerConfig.paper(evaluations=b) for b in budgets}
        configs["frame_beam"] = configs["frame_beam_keypoints"] = TrackerConfig()
        keypoints = [Keypoints(camera.project(j), np.ones(len(j))) for j in bench.joints]
        lifter = Lifter.load()          # once: a tracker would load it at its first frame with keypoints
        for name, config in configs.items():
            times = []
            given = keypoints if name == "frame_beam_keypoints" else [None] * len(images)
            while len(times) < min_runs:
                tracker = Tracker(model, camera, config, bench.initial_pose, lifter=lifter)
                if not times:           # every kernel loaded (compiled) first, as a run does
                    tracker.warm_up(keypoints=given[0] is not None)
                for i, frame in enumerate(images):
                    t0 = time.thread_time_ns()
                    tracker.push(i, prepare_frame(frame, bench.background, bench.colour), given[i])
                    times.append((time.thread_time_ns() - t0) / 1000.0)
            rows.append(_row(name, size, model.mesh.n_triangles, np.asarray(times[1:])))
            if name == "frame_500":
                rows.append(_row("evaluation_in_loop", size, model.mesh.n_triangles,
                                 _evaluations_in_loop(bench, min_runs)))
    return rows


def _evaluations_in_loop(bench: BenchSequence, min_runs: int) -> np.ndarray:
    """What one cost evaluation costs inside the compiled simplex loop, µs: on each frame but the
    first, the paper's registration at 500 evaluations (:func:`mocap.optimize.minimize_cost`: the
    region step from the previous frame's true pose, then the edge step from its simplex, 250
    evaluations each) timed per call and divided by the call's evaluations; one value per call,
    over the frames until ``min_runs`` values. Timed in CPU time of the calling thread: the loop
    is compiled code on one thread, so on a quiet core this is its wall time, and on a loaded
    machine the time other processes take is not billed to it."""
    from mocap.body.pose import JOINT_LIMITS
    from mocap.cost import EdgeCost, RegionCost
    from mocap.imaging import prepare_frame
    from mocap.optimize import initial_simplex, minimize_cost
    from mocap.track import TrackerConfig

    config = TrackerConfig.paper(evaluations=500)
    lower, upper = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    model, camera = bench.model, bench.camera
    costs = []
    for k in range(1, len(bench.images)):
        prepared = prepare_frame(bench.images[k], bench.background, bench.colour)
        costs.append((RegionCost(prepared.labels, model, camera), EdgeCost(prepared.distance, model, camera),
                      initial_simplex(bench.poses[k - 1], config.steps(), lower, upper)))
    minimize_cost(costs[0][0], costs[0][2], lower, upper, budget=2)            # warm-up
    out = []
    while len(out) < min_runs:
        for region, edge, start in costs:
            t0 = time.thread_time_ns()
            r = minimize_cost(region, start, lower, upper, budget=250, ftol=config.ftol)
            t1 = time.thread_time_ns()
            e = minimize_cost(edge, r.simplex, lower, upper, budget=250, ftol=config.ftol)
            t2 = time.thread_time_ns()
            out += [(t1 - t0) / 1000.0 / max(r.evaluations, 1), (t2 - t1) / 1000.0 / max(e.evaluations, 1)]
    return np.asarray(out)


def lifter_rows(size: tuple[int, int], *, min_runs: int, min_seconds: float) -> list[BenchRow]:
    """Row ``lifter``: one frame's :meth:`mocap.track.lifter.Lifter.lift` with the shipped weights (the
    features, the network, the forward kinematics and the root of its K hypotheses), on the projected
    joints of varied poses before the default camera at ``size``, every joint visible."""
    from mocap.body.model import BodyModel
    from mocap.render import Camera
    from mocap.track.lifter import Lifter

    lifter, model, camera = Lifter.load(), BodyModel.build(), Camera.default(*size)
    uv = [camera.project(model.joint_positions(q)) for q in _poses(64)]
    visible = np.ones(len(uv[0]), dtype=bool)

    def call(i):
        lifter.lift(uv[i % len(uv)], visible, camera, model)

    return [_row("lifter", size, 0, time_calls(call, min_runs=min_runs, min_seconds=min_seconds))]


def video_rows(*, frames: int, cpus: set[int] | None = None) -> list[BenchRow]:
    """Row ``video_640x480``: :func:`mocap.run.track` (what ``python -m mocap track``
    calls) end to end on a 640x480 MP4 (the synthetic
    ``gestures-1`` clip rendered at 160x120 and enlarged 4x, so that the working resolution
    sees the benchmark's own frames), with its true calibration and background.

    ``cpus``: the CPUs the run may use (as ``track`` runs: the tracker on one, the frame reader
    thread and ffmpeg on another when there is one); by default the calling thread's."""
    import resource
    import tempfile
    from pathlib import Path

    import dataclasses

    import imageio.v3 as iio

    from mocap.calibrate import Calibration
    from mocap.io.frames import VideoSource
    from mocap.io.pose_table import PoseTable
    from mocap.io.video import VideoWriter, iter_frames, read_image
    import mocap.run
    from mocap.run import OwnVideoOptions
    from mocap.run.files import POSES_CSV
    from mocap.synth import generate_sequence

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        seq = generate_sequence("gestures-1", tmp / "seq", frames=frames, seed=0, progress=False)
        video = tmp / "clip.mp4"
        with VideoWriter(video, 25) as writer:
            for frame in iter_frames(seq / "frames"):
                writer.write(np.repeat(np.repeat(frame, 4, 0), 4, 1))
        background = tmp / "background.png"
        iio.imwrite(background, np.repeat(np.repeat(read_image(seq / "background.png"), 4, 0), 4, 1))
        source = VideoSource(video)
        calibration = Calibration.from_json(seq / "calibration.json")     # at the working size, 160x120
        options = OwnVideoOptions(background=str(background), calibration=str(seq / "calibration.json"),
                                  overwrite=True, keypoints="none")
        run = lambda out, n: mocap.run.track(video, out, dataclasses.replace(options, max_frames=n), progress=False)
        run(tmp / "warm-up", 2)                     # compile and load every kernel first
        pinned = os.sched_getaffinity(0) if cpus is not None else None
        if cpus is not None:
            os.sched_setaffinity(0, cpus)
        try:
            children = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0, c0 = time.perf_counter(), time.process_time()
            run(tmp / "run", None)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        finally:
            if pinned is not None:
                os.sched_setaffinity(0, pinned)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)      # ffmpeg: decoding and the overlay's encoding
        cpu += (after.ru_utime - children.ru_utime) + (after.ru_stime - children.ru_stime)
        per_frame = PoseTable.read(tmp / "run" / POSES_CSV).extra["ms_total"] * 1e3
        n = source.count
        p10, p90 = np.percentile(per_frame, [10, 90])
        from mocap.body.mesh import resolution_for_image
        triangles = calibration.body_model(resolution_for_image(*calibration.camera.shape[::-1])).mesh.n_triangles
        return [BenchRow("video_640x480", source.width, source.height, int(triangles), 1e6 * wall / n,
                         float(p10), float(p90), int(n), "wall"),
                BenchRow("video_640x480_cpu", source.width, source.height, int(triangles), 1e6 * cpu / n,
                         float(p10), float(p90), int(n), "process_cpu")]


def environment() -> tuple[dict, str]:
    """Versions of the libraries that matter and the CPU model."""
    import numba
    import scipy
    import skimage

    import mocap
    versions = {"python": platform.python_version(), "mocap": mocap.__version__, "numpy": np.__version__,
                "numba": numba.__version__, "scipy": scipy.__version__, "scikit-image": skimage.__version__}
    try:
        import moderngl
        versions["moderngl"] = moderngl.__version__
    except ImportError:
        pass
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return versions, cpu


def pin_to_one_core() -> bool:
    """Pin this process to one CPU (Linux); returns whether it could."""
    if not hasattr(os, "sched_setaffinity"):
        return False
    try:
        cpus = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cpus[-1]})
        return True
    except OSError:
        return False


def format_table(rows: Sequence[BenchRow], notes: Sequence[str]) -> str:
    """Rows as an aligned text table, plus our-vs-llvmpipe ratios."""
    lines = [f"{'stage':<20}{'size':>10}{'triangles':>11}{'median µs':>12}{'p10 µs':>10}{'p90 µs':>10}{'runs':>7}"]
    for r in rows:
        lines.append(f"{r.stage:<20}{f'{r.width}x{r.height}':>10}{r.triangles:>11}{r.median_us:>12.1f}"
                     f"{r.p10_us:>10.1f}{r.p90_us:>10.1f}{r.runs:>7}")
    by = {(r.stage, r.width, r.height): r for r in rows}
    for (stage, w, h), r in by.items():
        if stage == "llvmpipe_render" and ("render", w, h) in by:
            ours = by[("render", w, h)].median_us
            lines.append(f"llvmpipe / ours (render + label image) at {w}x{h}: {r.median_us / ours:.1f}x")
    lines += [f"note: {n}" for n in notes]
    return "\n".join(lines)


#: Groups of stages, in the order a full run measures them.
GROUPS: tuple[str, ...] = ("render", "imaging", "frame", "lifter", "video")


def run_benchmark(*, quick: bool = False, with_llvmpipe: bool = True, stages: Sequence[str] = GROUPS,
                  progress: bool = True) -> dict:
    """Run the benchmark and return the JSON-ready result of docs/design.md section 6."""
    from tqdm import tqdm

    min_runs, min_seconds = (20, 0.02) if quick else (300, 1.0)
    rows: list[BenchRow] = []
    notes: list[str] = []
    cpus = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else None
    pinned = pin_to_one_core()
    if not pinned:
        notes.append("could not pin to one core")
    elif len(cpus) > 1:
        notes.append(f"video_640x480 runs on {len(cpus)} CPUs as track does (reader thread and ffmpeg beside "
                     "the tracker); every other row on one")
    groups = {"render": lambda: render_rows(RENDER_SIZES, min_runs=min_runs, min_seconds=min_seconds,
                                            with_llvmpipe=with_llvmpipe),
              "imaging": lambda: (imaging_rows(TABLE2_SIZES, min_runs=min_runs // 3, min_seconds=min_seconds), []),
              "frame": lambda: (frame_rows((160, 120), (100, 500), frames=12 if quick else 50,
                                           min_runs=12 if quick else 100), []),
              "lifter": lambda: (lifter_rows((160, 120), min_runs=min_runs, min_seconds=min_seconds), []),
              "video": lambda: (video_rows(frames=12 if quick else 100, cpus=cpus if pinned else None), [])}
    for name in tqdm(stages, desc="bench", unit="group", disable=not progress, file=sys.stderr):
        if name not in groups:
            raise ValueError(f"unknown benchmark group {name!r}; known: {', '.join(groups)}")
        r, n = groups[name]()
        rows += r
        notes += n
    versions, cpu = environment()
    return {"rows": [asdict(r) for r in rows], "versions": versions, "cpu": cpu, "notes": notes, "clock": CLOCK}


def print_result(result: dict, as_json: bool) -> None:
    if as_json:
        print(json.dumps(result, indent=2))
    else:
        print(format_table([BenchRow(**r) for r in result["rows"]], result.get("notes", [])))
