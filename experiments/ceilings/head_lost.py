"""Share of the truth's rendered head (skin/hair pixels above the neck) labelled background, per
benchmark unit, against the MediaPipe units' turned-round share and error about the neck."""
import json, glob, numpy as np
from pathlib import Path
from experiments.ambiguity import benchmark_sequence
from mocap.render import render_labels
from mocap.body.skeleton import JOINT_INDEX
from mocap.labels import BACKGROUND
root = Path("/work/main/experiments/results/tracking")
rows = []
for f in sorted(glob.glob("/tmp/trk/main/units/*-80d8655a61-mediapipe.json")):
    u = json.load(open(f)); r = u["result"]
    loaded, prepared = benchmark_sequence(r["sequence"], root, u["seed"])
    cam = loaded.calibration.camera; names = loaded.calibration.class_names
    head_classes = [names.index(c) + 1 for c in ("skin", "hair") if c in names]
    lost = []
    for i in range(0, len(prepared), 10):
        q = loaded.ground_truth.poses[i]
        ren = render_labels(q, loaded.model, cam)
        neck_v = cam.project(loaded.ground_truth.joints[i, JOINT_INDEX["neck"]][None])[0, 1]
        rows_v = np.arange(ren.shape[0])[:, None] < neck_v
        head = np.isin(ren, head_classes) & rows_v
        if head.sum() >= 5:
            lost.append(float((prepared[i].labels[head] == BACKGROUND).mean()))
    rows.append((r["sequence"], u["seed"], float(np.mean(lost)) if lost else np.nan, r["turned_round_rate"], r["median_frame_root_relative_mm"]))
    print(rows[-1], flush=True)
json.dump(rows, open("/tmp/head_lost.json", "w"))
a = np.array([x[2:] for x in rows], float)
for lo, hi in ((0, 0.2), (0.2, 0.5), (0.5, 1.01)):
    m = (a[:, 0] >= lo) & (a[:, 0] < hi)
    print(f"head lost {lo}-{hi}: {m.sum()} units, turned-round share mean {a[m,1].mean():.3f}, units over 20 %: {(a[m,1] > 0.2).sum()}, median about the neck {np.median(a[m,2]):.0f} mm")
