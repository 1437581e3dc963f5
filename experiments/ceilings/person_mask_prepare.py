"""Ceiling measurement (not the library): the benchmark's prepared frames with the foreground
widened by MediaPipe Pose's person mask (image mode, enable_segmentation, > 0.5) where it finds
the person; classes, edges and distance map recomputed as prepare_frame does. Writes copies of
the chosen units' data folders under /tmp/trk/seg/data."""
import sys, io, json, glob, shutil, numpy as np
from pathlib import Path
import mediapipe as mp
from experiments.units import load_sequence, load_prepared, PREPARED_FILE
from mocap.imaging.config import ImagingConfig
from mocap.imaging._validate import check_rgb
from mocap.imaging.background import clean_mask_unchecked
from mocap.imaging.edges import detect_edges_unchecked, distance_map_unchecked
units = [tuple(u.split(":")) for u in sys.argv[1].split(",")]
src_root, dst_root = Path("/work/main/experiments/results/tracking/data"), Path("/tmp/trk/seg/data")
cfg = ImagingConfig()
stats = {}
with mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1, enable_segmentation=True) as pose:
    for seq, seed in units:
        src = Path(glob.glob(str(src_root / f"{seq}-s{seed}-*"))[0]); dst = dst_root / src.name
        if (dst / PREPARED_FILE).is_file():
            continue
        shutil.copytree(src, dst, ignore=shutil.ignore_patterns("prepared*.npz"), dirs_exist_ok=True)
        prepared = load_prepared(src)
        loaded = load_sequence(dst, len(prepared))
        out = {k: [] for k in ("labels", "foreground", "edges", "distance", "is_empty")}
        found = added = 0
        for i, p in enumerate(prepared):
            frame, scale = check_rgb(loaded.frames[i], "frame")
            res = pose.process(np.ascontiguousarray(loaded.frames[i]))
            fg = p.foreground.copy()
            if res.segmentation_mask is not None:
                found += 1
                wide = clean_mask_unchecked(fg | (res.segmentation_mask > 0.5), cfg)
                added += int((wide & ~fg).sum()); fg = wide
            labels = loaded.colour_model._classify(frame, scale, fg, cfg.colour_threshold)
            edges = detect_edges_unchecked(frame, scale, fg, cfg.edge_method, cfg.edge_sigma, cfg.edge_low_threshold,
                                           cfg.edge_high_threshold, cfg.edge_dilation, cfg.silhouette_edges)
            distance = distance_map_unchecked(edges, cfg.distance_method, cfg.max_distance)
            for k, v in (("labels", labels), ("foreground", fg), ("edges", edges), ("distance", distance),
                         ("is_empty", not fg.any())):
                out[k].append(v)
        keys = tuple(prepared[0].timings)
        buf = io.BytesIO()
        np.savez_compressed(buf, **{k: np.stack(v) if k != "is_empty" else np.array(v) for k, v in out.items()},
                            timing_keys=np.array(keys),
                            timings=np.array([[p.timings[k] for k in keys] for p in prepared], dtype=np.float64))
        (dst / PREPARED_FILE).write_bytes(buf.getvalue())
        print(seq, seed, f"MediaPipe found {found}/{len(prepared)} frames, {added / max(found, 1):.0f} px a frame added", flush=True)
