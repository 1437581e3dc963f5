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
# # Calibration: by hand (the paper's Fig. 2b) and automatically
#
# The paper calibrates by adjusting the 20 joint angles and the size of every body part until
# the projected model overlaps the actor in the first frame. The sliders below do exactly that
# (run the notebook in Jupyter to move them); **Save** writes `calibration.json`. Beyond the
# paper, the model has a lower body (trousers or skirt under the torso: its size slider) and a
# hair region on the head above a hairline (its slider, in half head lengths above the head's
# centre), so that the colour classes hair and lower body can be learnt inside them. The
# automatic first-frame fit (`python -m mocap calibrate`) is shown at the end for comparison.

# %% tags=["parameters"]
import os

OUT = os.environ.get("MOCAP_NOTEBOOK_OUT", "calibration-notebook.json")

# %%
import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import display

from mocap.body import ANGLE_NAMES, JOINT_LIMITS, PARAMETER_INDEX, BodyDimensions
from mocap.body.dimensions import SIZED_PART_NAMES
from mocap.calibrate import Calibration, auto_calibrate
from mocap.imaging.visual import draw_model
from mocap.io.sequence import find_sequence
from mocap.io.video import iter_frames, read_image
from mocap.render import render
from mocap.synth.datasets import default_sequence

root = default_sequence(frames=5)
seq = find_sequence(root)
frame = next(iter_frames(seq.frames, 0, 1))
background = read_image(seq.background)
start = Calibration()          # default adult, neutral pose
camera = start.camera.scaled(frame.shape[1], frame.shape[0])

# %% [markdown]
# ## By hand: sliders for the angles (degrees), the position (metres) and part sizes (scale)

# %%
angle_sliders = {
    name: widgets.FloatSlider(value=float(np.degrees(start.initial_pose[PARAMETER_INDEX[name]])),
                              min=float(np.degrees(JOINT_LIMITS[PARAMETER_INDEX[name], 0])),
                              max=float(np.degrees(JOINT_LIMITS[PARAMETER_INDEX[name], 1])),
                              step=1.0, description=name, continuous_update=False)
    for name in ANGLE_NAMES}
position_sliders = {
    name: widgets.FloatSlider(value=float(start.initial_pose[PARAMETER_INDEX[name]]), min=lo, max=hi, step=0.01,
                              description=name, continuous_update=False)
    for name, lo, hi in (("root_x", -1.0, 1.0), ("root_y", -1.0, 1.0), ("root_z", 0.8, 4.0))}
size_sliders = {part: widgets.FloatSlider(value=1.0, min=0.6, max=1.5, step=0.01, description=part,
                                          continuous_update=False) for part in SIZED_PART_NAMES}
hairline_slider = widgets.FloatSlider(value=start.dims.hairline, min=-0.2, max=0.95, step=0.05, description="hairline",
                                      continuous_update=False)


def current_calibration() -> Calibration:
    """The calibration the sliders describe."""
    pose = start.initial_pose.copy()
    for name, s in position_sliders.items():
        pose[PARAMETER_INDEX[name]] = s.value
    for name, s in angle_sliders.items():
        pose[PARAMETER_INDEX[name]] = np.radians(s.value)
    dims = BodyDimensions().with_hairline(hairline_slider.value)
    for part, s in size_sliders.items():
        dims = dims.scaled(s.value, parts=(part,))
    return Calibration(dims, pose, camera)


def draw(**_values) -> None:
    """Project the model over the first frame (the paper's Fig. 2b)."""
    cal = current_calibration()
    model = cal.body_model(12)
    r = render(cal.initial_pose, model, camera)
    plt.figure(figsize=(5, 4))
    plt.imshow(draw_model(frame, r.labels, r.edges, model.n_classes, class_names=model.class_names))
    plt.axis("off")
    plt.show()


all_sliders = {**position_sliders, **angle_sliders, **size_sliders, "hairline": hairline_slider}
save = widgets.Button(description="Save")
save.on_click(lambda _b: current_calibration().to_json(OUT))
ui = widgets.Tab(children=[widgets.VBox(list(position_sliders.values()) + list(angle_sliders.values())),
                           widgets.VBox(list(size_sliders.values()) + [hairline_slider])])
ui.set_title(0, "pose")
ui.set_title(1, "part sizes")
display(widgets.VBox([ui, save]), widgets.interactive_output(draw, all_sliders))
draw()

# %% [markdown]
# ## Automatically
# `auto_calibrate` fits the position, arm pose and relative proportions to the silhouette,
# learns the colours inside the fitted model (hair and lower body only when the frame supports
# them) and refines on the colour classes, the hairline included. The overall scale stays that
# of an average adult: from one view a bigger actor farther away looks the same.

# %%
auto = auto_calibrate(frame, background, camera)
auto_model = auto.body_model(12)
r = render(auto.initial_pose, auto_model, camera)
plt.figure(figsize=(5, 4))
plt.imshow(draw_model(frame, r.labels, r.edges, auto_model.n_classes, class_names=auto_model.class_names))
plt.axis("off")
plt.title(f"automatic: actor at {auto.initial_pose[2]:.2f} m, classes {', '.join(auto.class_names)}, "
          f"hairline {auto.dims.hairline}")
auto.to_json(OUT)
print(f"saved {OUT}")
