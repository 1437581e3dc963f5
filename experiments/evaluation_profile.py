"""Where one cost evaluation's time goes inside the compiled simplex loop (issue 41).

``python -m experiments.evaluation_profile [--sizes 160x120 640x480] [--frames 4] [--repeats 5]``

On frames of the synthetic ``gestures-1`` sequence at each size, the paper's registration
(region step then edge step, 250 + 250 evaluations from the previous frame's true pose) is run
once through the Python simplex loop to record every trial pose; then compiled loops run over
those poses, each adding one stage of an evaluation:

- ``transforms``: the segment transforms of the pose;
- ``project``: + the vertices transformed and projected;
- ``setup``: + every triangle's set-up in the rasterizer (culling, box, edge functions, depth
  plane; no pixel touched: the rasterizer's stage switch ``fill=False``);
- ``render_clear``: + the spans filled (the label and depth writes), then the box cleared;
- ``region`` / ``edge``: the render, then the region count or the edge sum (each clearing the
  box as it goes), as :func:`mocap.cost.region_cost_kernel` / :func:`mocap.cost.edge_cost_kernel`;
- ``loop_region`` / ``loop_edge``: the real compiled simplex loop (:func:`mocap.optimize.minimize_cost`)
  from the same start, per evaluation.

Differences between consecutive rows are the stages' costs. Times are CPU time of this thread
(a loaded machine preempts, it does not bill), the fastest of ``repeats`` interleaved passes
(each pass: every recorded pose once; the fastest is the one least disturbed by other
processes), then the median over frames, µs per evaluation, one core.
Also printed: triangles drawn, pixels written (with overdraw) and the model's box per pose.
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time

import numba
import numpy as np


def _stage_loops():
    from mocap.body.kinematics import segment_transforms_into
    from mocap.cost import edge_cost_kernel, region_cost_kernel
    from mocap.render.rasterize import clear_drawn, project_vertices, rasterize_triangles

    @numba.njit(nogil=True)
    def loop(stage, poses, region_args, edge_args):
        scene, buffers = region_args.scene, region_args.buffers
        total = 0.0
        for i in range(poses.shape[0]):
            pose = poses[i]
            if stage == 0:
                segment_transforms_into(pose, scene.offsets, buffers.transforms)
                total += buffers.transforms[0, 0, 3]
                continue
            if stage >= 1 and stage <= 3:
                segment_transforms_into(pose, scene.offsets, buffers.transforms)
                project_vertices(buffers.transforms, scene.vertices, scene.vertex_segment, scene.camera,
                                 buffers.vertex_x, buffers.vertex_y, buffers.vertex_inverse_depth)
                if stage == 2:
                    rasterize_triangles(buffers.vertex_x, buffers.vertex_y, buffers.vertex_inverse_depth,
                                        scene.triangles, scene.triangle_part, scene.width, scene.height, True,
                                        buffers.part_ids, buffers.inverse_depth, buffers.triangle_ids,
                                        buffers.coverage, buffers.box, False)      # set-up only: no fill
                elif stage == 3:
                    rasterize_triangles(buffers.vertex_x, buffers.vertex_y, buffers.vertex_inverse_depth,
                                        scene.triangles, scene.triangle_part, scene.width, scene.height, True,
                                        buffers.part_ids, buffers.inverse_depth, buffers.triangle_ids,
                                        buffers.coverage, buffers.box)
                    clear_drawn(buffers.part_ids, buffers.inverse_depth, scene.width, buffers.box)
                total += buffers.vertex_x[0]
            elif stage == 4:
                total += region_cost_kernel(pose, region_args)
            else:
                total += edge_cost_kernel(pose, edge_args)
        return total

    return loop


STAGES = ("transforms", "project", "setup", "render_clear", "region", "edge")


def _record(size, frames, seed=0):
    """(costs per frame, recorded trial poses per frame, region/edge start simplices)."""
    from mocap.bench import BenchSequence
    from mocap.body.pose import JOINT_LIMITS
    from mocap.cost import EdgeCost, RegionCost
    from mocap.imaging import prepare_frame
    from mocap.optimize import initial_simplex, minimize
    from mocap.track import TrackerConfig

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        bench = BenchSequence.make(tmp, size, frames + 1, seed=seed)
        model, camera, images, truth = bench.model, bench.camera, bench.images, bench.poses
        background, colour = bench.background, bench.colour
        config = TrackerConfig.paper(evaluations=500)
        lower, upper = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
        for k in range(1, frames + 1):
            prepared = prepare_frame(images[k], background, colour)
            region, edge = RegionCost(prepared.labels, model, camera), EdgeCost(prepared.distance, model, camera)
            poses = []

            def recording(cost):
                def f(x):
                    poses.append(x.copy())
                    return cost.evaluate_unchecked(x)
                return f

            start = initial_simplex(truth[k - 1], config.steps(), lower, upper)
            r = minimize(recording(region), start, lower, upper, budget=250, ftol=config.ftol)
            n_region = len(poses)
            minimize(recording(edge), r.simplex, lower, upper, budget=250, ftol=config.ftol)
            out.append((region, edge, np.array(poses), n_region, start, r.simplex))
    return model, camera, out


def profile(size, frames, repeats):
    from mocap.optimize import minimize_cost
    from mocap.body.pose import JOINT_LIMITS
    from mocap.render.rasterize import render

    loop = _stage_loops()
    model, camera, recorded = _record(size, frames)
    lower, upper = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    times = {s: [] for s in STAGES + ("loop_region", "loop_edge")}
    per_pose = {"evaluations": 0, "triangles_drawn": [], "pixels_covered": [], "pixels_written": [], "box_pixels": []}
    for region, edge, poses, n_region, start, region_simplex in recorded:
        ep = poses[n_region:]
        ra, ea = region.kernel_args(), edge.kernel_args()
        runs = [(name, lambda s=s: (loop(s, poses, ra, ea), len(poses))[1]) for s, name in enumerate(STAGES)]
        runs += [(name, lambda cost=cost, simplex=simplex, n=n: minimize_cost(cost, simplex, lower, upper, budget=n,
                                                                            ftol=1e-3).evaluations)
                 for name, cost, simplex, n in (("loop_region", region, start, n_region),
                                                ("loop_edge", edge, region_simplex, len(ep)))]
        best = {name: np.inf for name, _ in runs}
        for name, run in runs:
            run()                                                    # warm-up / compile
        for _ in range(repeats):                                     # interleaved: load hits every stage alike
            for name, run in runs:
                t0 = time.thread_time_ns()
                n = run()
                best[name] = min(best[name], (time.thread_time_ns() - t0) / 1000.0 / n)
        for name in best:
            times[name].append(best[name])
        per_pose["evaluations"] += len(poses)
        for q in poses[::10]:
            r = render(q, model, camera, triangle_ids=True)
            parts = r.parts > 0
            ys, xs = np.nonzero(parts)
            per_pose["pixels_covered"].append(int(parts.sum()))
            per_pose["box_pixels"].append(int((np.ptp(xs) + 1) * (np.ptp(ys) + 1)) if len(xs) else 0)
            per_pose["triangles_drawn"].append(int(len(np.unique(r.triangle_ids[parts]))))
    out = {"size": f"{size[0]}x{size[1]}", "triangles": int(model.mesh.n_triangles),
           "us_per_evaluation": {k: float(np.median(v)) for k, v in times.items()},
           "evaluations": per_pose["evaluations"]}
    for k in ("pixels_covered", "box_pixels", "triangles_drawn"):
        out[k] = float(np.median(per_pose[k]))
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", nargs="+", default=["160x120", "640x480"])
    p.add_argument("--frames", type=int, default=4)
    p.add_argument("--repeats", type=int, default=5)
    args = p.parse_args(argv)
    from mocap.bench import pin_to_one_core
    pin_to_one_core()
    for s in args.sizes:
        w, h = (int(v) for v in s.split("x"))
        r = profile((w, h), args.frames, args.repeats)
        us = r["us_per_evaluation"]
        print(json.dumps(r))
        prev = 0.0
        for name in STAGES[:4]:
            print(f"  {name:<14}{us[name]:8.2f} µs  (+{us[name] - prev:.2f})")
            prev = us[name]
        for name in ("region", "edge"):
            print(f"  {name:<14}{us[name]:8.2f} µs  (+{us[name] - us['render_clear']:.2f} over render_clear)")
        for name in ("loop_region", "loop_edge"):
            print(f"  {name:<14}{us[name]:8.2f} µs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
