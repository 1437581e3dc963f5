# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # mocap walkthrough
#
# From a video frame to a tracked 3D pose, one stage at a time, on the bundled default
# sequence (a synthetic actor with exact ground truth; `data/default`, or regenerated when the
# package is not run from its source tree).
#
# 1. the frame and what the image side makes of it: colour classes, edges, distance map;
# 2. the body model projected in its calibrated pose: coloured silhouette and occluding edges;
# 3. one registration, step by step: region step (non-overlapping ratio, eq. 1), then edge step
#    (mean edge distance, eq. 2) starting from the region step's final simplex;
# 4. tracking a few seconds of video, with residuals and errors against ground truth.

# %% tags=["parameters"]
import os

N_FRAMES = int(os.environ.get("MOCAP_NOTEBOOK_FRAMES", "60"))   # frames tracked in section 4
EVALUATIONS = 500                                               # cost evaluations per frame

# %%
import matplotlib.pyplot as plt
import numpy as np

from mocap.body import PARAMETER_INDEX, clamp_to_limits
from mocap.calibrate import Calibration, colour_model_from_pose
from mocap.cost import EdgeCost, RegionCost
from mocap.imaging import prepare_frame
from mocap.imaging.visual import colour_distance, colour_labels, draw_model
from mocap.io.pose_table import PoseTable
from mocap.io.sequence import find_sequence
from mocap.io.video import iter_frames, read_image
from mocap.metrics import mpjpe
from mocap.render import render
from mocap.synth.datasets import default_sequence
from mocap.track import TrackerConfig, register

root = default_sequence(frames=N_FRAMES)
seq = find_sequence(root)
calibration = Calibration.from_json(seq.calibration)
camera = calibration.camera
model = calibration.body_model(8)
frames = list(iter_frames(seq.frames, 0, N_FRAMES))
background = read_image(seq.background)
truth = PoseTable.read(seq.ground_truth)
print(f"{root}: {len(frames)} frames of {camera.width}x{camera.height}; mesh of {model.mesh.n_triangles} triangles")

# %% [markdown]
# ## 1. The image side
# The colour classes are learnt inside the calibrated model's projection on the first frame;
# `prepare_frame` then subtracts the background, classifies the foreground (skin, clothes,
# hair, lower body, unknown), finds edges in the foreground and the distance of every pixel to the nearest edge.

# %%
colour_model = colour_model_from_pose(frames[0], background, model, camera, calibration.initial_pose)
model = model.with_class_names(colour_model.names)    # hair, lower body: only if the frame supports them
prepared = prepare_frame(frames[0], background, colour_model)
fig, axes = plt.subplots(1, 4, figsize=(13, 2.8))
for ax, image, title in zip(axes, [frames[0], colour_labels(prepared.labels, colour_model.m, colour_model.names), prepared.edges,
                                   colour_distance(prepared.distance, float(prepared.distance.max()))],
                            ["frame", "colour classes", "edges", "distance to edges"]):
    ax.imshow(image, cmap="gray")
    ax.set_title(title)
    ax.axis("off")
print(colour_model, {k: f"{1e3 * v:.2f} ms" for k, v in prepared.timings.items()})

# %% [markdown]
# ## 2. The model in its calibrated pose
# The rasterizer draws the coloured silhouette and the occluding edges: the outline plus the
# contours where one part passes in front of another (not the creases where parts meet).

# %%
r = render(calibration.initial_pose, model, camera)
fig, axes = plt.subplots(1, 3, figsize=(10, 2.8))
axes[0].imshow(colour_labels(r.labels, model.n_classes, model.class_names))
axes[0].set_title("model labels")
axes[1].imshow(r.edges, cmap="gray")
axes[1].set_title("occluding edges")
axes[2].imshow(draw_model(frames[0], r.labels, r.edges, model.n_classes, class_names=model.class_names))
axes[2].set_title("model over frame")
for ax in axes:
    ax.axis("off")

# %% [markdown]
# ## 3. One registration, step by step
# Start from a wrong pose (the right arm off by 25 degrees, the body shifted by 4 cm), run the
# region step with 250 evaluations, then the edge step with 250 more from the region step's
# final simplex.

# %%
k = min(20, len(frames) - 1)
prepared_k = prepare_frame(frames[k], background, colour_model)
region_cost = RegionCost(prepared_k.labels, model, camera)
edge_cost = EdgeCost(prepared_k.distance, model, camera)
start = truth.poses[k].copy()
start[PARAMETER_INDEX["r_shoulder_abd"]] += np.radians(25)
start[PARAMETER_INDEX["r_elbow_flex"]] += np.radians(-20)
start[0] += 0.04
start = clamp_to_limits(start)
reg = register(region_cost, edge_cost, start, TrackerConfig(evaluations=EVALUATIONS, split="1:1"))
stages = [("start", start), ("after region step", reg.region.x), ("after edge step", reg.pose)]
fig, axes = plt.subplots(1, 3, figsize=(10, 2.8))
for ax, (name, pose) in zip(axes, stages):
    rr = render(pose, model, camera)
    err = 1e3 * np.linalg.norm(model.joint_positions(pose) - truth.joints[k], axis=1).mean()
    ax.imshow(draw_model(frames[k], rr.labels, rr.edges, model.n_classes, class_names=model.class_names))
    ax.set_title(f"{name}\nF={region_cost(pose):.3f}  D={edge_cost(pose):.2f}px  {err:.0f}mm", fontsize=9)
    ax.axis("off")
print(f"region: {reg.region.evaluations} evaluations, {reg.region.iterations} iterations; "
      f"edge: {reg.edge.evaluations} evaluations, {reg.edge.iterations} iterations")

# %% [markdown]
# ## 4. Tracking
# The whole run, as `python -m mocap track` does it (`mocap.run.track`: set-up, reader thread,
# tracker, `poses.csv` and the other files; docs/design.md section 4). Each frame starts from
# the previous pose; the auto policy splits the budget 50/50 from 200 evaluations on.

# %%
import tempfile

import mocap.run

run_dir = tempfile.mkdtemp(prefix="mocap-walkthrough-")      # a temporary folder: nothing left in the repository
options = mocap.run.OwnVideoOptions(max_frames=N_FRAMES, overlay=False, overwrite=True,
                                    tracker=TrackerConfig(evaluations=EVALUATIONS))
summary = mocap.run.track(root, run_dir, options, progress=False)
table = PoseTable.read(f"{run_dir}/poses.csv")
per_frame_mm = mpjpe(table.joints, truth.joints[: len(table)], per_frame=True)
ms = table.extra["ms_total"][1:]
fig, axes = plt.subplots(3, 1, figsize=(9, 6), sharex=True)
axes[0].plot(table.extra["region_residual"], color="0.2")
axes[0].set_ylabel("F")
axes[1].plot(table.extra["edge_residual"], color="0.2")
axes[1].set_ylabel("edge dist. (px)")
axes[2].plot(per_frame_mm, color="tab:blue")
axes[2].set_ylabel("MPJPE (mm)")
axes[2].set_xlabel("frame")
print(f"MPJPE {per_frame_mm.mean():.1f} mm over {len(table)} frames at {1e3 / ms.mean():.0f} frames/s")
