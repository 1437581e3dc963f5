"""Make ``docs/overview.png``, the README's picture (the paper's Fig. 1 on our default sequence):
captured frame, segmented colour classes, edges in the foreground with the distance map, and
the registered model drawn over the frame. Run ``python docs/overview.py``."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from mocap.calibrate import Calibration, colour_model_from_pose
from mocap.imaging import prepare_frame
from mocap.imaging.visual import colour_distance, colour_labels, draw_model
from mocap.io.sequence import find_sequence
from mocap.io.video import iter_frames, read_image
from mocap.render import render
from mocap.synth.datasets import default_sequence
from mocap.track import Tracker, TrackerConfig, track_prepared

#: Frames shown (indices into the default sequence).
SHOWN = (10, 45)


def main(out: Path = Path(__file__).with_name("overview.png")) -> None:
    root = default_sequence(frames=max(SHOWN) + 1)
    seq = find_sequence(root)
    cal = Calibration.from_json(seq.calibration)
    model = cal.body_model(8)
    frames = list(iter_frames(seq.frames, 0, max(SHOWN) + 1))
    background = read_image(seq.background)
    colour = colour_model_from_pose(frames[0], background, model, cal.camera, cal.initial_pose)
    prepared = [prepare_frame(f, background, colour) for f in frames]
    results = track_prepared(prepared, Tracker(model, cal.camera, TrackerConfig(), cal.initial_pose))
    fig, axes = plt.subplots(len(SHOWN), 4, figsize=(10, 2.1 * len(SHOWN)), constrained_layout=True)
    for row, k in zip(axes, SHOWN):
        p = prepared[k]
        edges = colour_distance(p.distance, float(p.distance.max()))
        edges[p.edges] = 255
        r = render(results[k].pose, model, cal.camera)
        for ax, image in zip(row, [frames[k], colour_labels(p.labels, 2), edges,
                                   draw_model(frames[k], r.labels, r.edges)]):
            ax.imshow(image)
            ax.set_xticks([])
            ax.set_yticks([])
    for ax, title in zip(axes[0], ["captured frame", "skin / clothes classes", "edges and distance map",
                                   "registered model"]):
        ax.set_title(title, fontsize=10)
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
