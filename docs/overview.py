"""Make ``docs/overview.png``, the README's picture (the paper's Fig. 1 on our default sequence):
captured frame, segmented colour classes, edges in the foreground with the distance map, and
one frame of ``overlay.mp4`` — the registered model drawn over the frame, with the fitted
skeleton seen from the side and from above (the frame enlarged 4x to 640x480, the size of
the benchmark's clip). Run ``python docs/overview.py``."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from mocap.calibrate import Calibration, colour_model_from_pose
from mocap.imaging import prepare_frame
from mocap.imaging.visual import ModelDrawer, colour_distance, colour_labels
from mocap.io.sequence import find_sequence
from mocap.io.video import iter_frames, read_image
from mocap.synth.datasets import default_sequence
from mocap.track import Tracker, TrackerConfig, track_prepared

#: Frames shown (indices into the default sequence); the overlay is the last one's.
SHOWN = (10, 45)
#: Enlargement of the overlay's frame (160x120 to 640x480).
OVERLAY_FACTOR = 4


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
    fig = plt.figure(figsize=(10, 3.5), constrained_layout=True)
    grid = fig.add_gridspec(len(SHOWN), 5)
    for row, k in enumerate(SHOWN):
        p = prepared[k]
        edges = colour_distance(p.distance, float(p.distance.max()))
        edges[p.edges] = 255
        for column, image in enumerate([frames[k], colour_labels(p.labels, 2), edges]):
            _show(fig.add_subplot(grid[row, column]), image,
                  ["captured frame", "skin / clothes classes", "edges and distance map"][column] if row == 0 else None)
    k, (h, w) = SHOWN[-1], frames[SHOWN[-1]].shape[:2]
    big = np.repeat(np.repeat(frames[k], OVERLAY_FACTOR, 0), OVERLAY_FACTOR, 1)
    drawer = ModelDrawer(model, cal.camera.enlarged(OVERLAY_FACTOR, OVERLAY_FACTOR * w, OVERLAY_FACTOR * h))
    _show(fig.add_subplot(grid[:, 3:]), drawer.draw(big, results[k].pose),
          "registered model; side and top views (overlay.mp4)")
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")


def _show(ax, image: np.ndarray, title: str | None) -> None:
    ax.imshow(image)
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=9)


if __name__ == "__main__":
    main()
