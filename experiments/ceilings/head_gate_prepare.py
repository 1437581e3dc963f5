"""Gated ceiling (not the library): widen our foreground by MediaPipe's person mask only inside
the head's box from MediaPipe's own landmarks (head point, shoulders; confidence >= 0.5).
Box: half-width 0.35 s, from 0.6 s above the head point to 0.3 s below, s = shoulder distance (px).
A: always in the box.  B: only where our foreground covers < 50 % of the mask's pixels in the box.
The mask is read back from /tmp/trk/seg (clean(fg | MediaPipe mask > 0.5))."""
import sys, io, glob, shutil, numpy as np, csv
from pathlib import Path
from experiments.units import load_sequence, load_prepared, PREPARED_FILE
from mocap.imaging.config import ImagingConfig
from mocap.imaging._validate import check_rgb
from mocap.imaging.background import clean_mask_unchecked
from mocap.imaging.edges import detect_edges_unchecked, distance_map_unchecked
variant = sys.argv[1]
units = [tuple(u.split(":")) for u in sys.argv[2].split(",")]
main_root, seg_root = Path("/work/main/experiments/results/tracking/data"), Path("/tmp/trk/seg/data")
dst_root = Path(f"/tmp/trk/gate{variant}/data")
cfg = ImagingConfig()
def boxes(path, n, shape):
    pts = {}
    for r in csv.DictReader(open(path)):
        if r["joint"] in ("head", "r_shoulder", "l_shoulder") and float(r["confidence"]) >= 0.5 and r["u"] not in ("", "nan"):
            pts.setdefault(int(r["frame"]), {})[r["joint"]] = (float(r["u"]), float(r["v"]))
    out = []
    vv, uu = np.mgrid[:shape[0], :shape[1]]
    for i in range(n):
        p = pts.get(i, {})
        if len(p) < 3:
            out.append(None); continue
        s = np.hypot(*np.subtract(p["r_shoulder"], p["l_shoulder"]))
        hu, hv = p["head"]
        out.append((np.abs(uu - hu) <= 0.35 * s) & (vv >= hv - 0.6 * s) & (vv <= hv + 0.3 * s))
    return out
for seq, seed in units:
    src = Path(glob.glob(str(main_root / f"{seq}-s{seed}-*"))[0]); seg = seg_root / src.name; dst = dst_root / src.name
    if (dst / PREPARED_FILE).is_file():
        continue
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("prepared*.npz"), dirs_exist_ok=True)
    prepared, seg_prepared = load_prepared(src), load_prepared(seg)
    loaded = load_sequence(dst, len(prepared))
    bx = boxes(src / "keypoints-mediapipe.csv", len(prepared), prepared[0].foreground.shape)
    out = {k: [] for k in ("labels", "foreground", "edges", "distance", "is_empty")}
    changed = added = 0
    for i, (p, q) in enumerate(zip(prepared, seg_prepared)):
        fg = p.foreground
        box = bx[i]
        use = False
        if box is not None:
            mask = q.foreground & box
            if mask.any():
                use = variant == "A" or (fg & mask).sum() < 0.5 * mask.sum()
        if use and (mask & ~fg).any():
            frame, scale = check_rgb(loaded.frames[i], "frame")
            new = clean_mask_unchecked(fg | mask, cfg)
            changed += 1; added += int((new & ~fg).sum())
            labels = loaded.colour_model._classify(frame, scale, new, cfg.colour_threshold)
            edges = detect_edges_unchecked(frame, scale, new, cfg.edge_method, cfg.edge_sigma, cfg.edge_low_threshold,
                                           cfg.edge_high_threshold, cfg.edge_dilation, cfg.silhouette_edges)
            distance = distance_map_unchecked(edges, cfg.distance_method, cfg.max_distance)
            vals = (labels, new, edges, distance, not new.any())
        else:
            vals = (p.labels, p.foreground, p.edges, p.distance, p.is_empty)
        for k, v in zip(out, vals):
            out[k].append(v)
    keys = tuple(prepared[0].timings)
    buf = io.BytesIO()
    np.savez_compressed(buf, **{k: np.stack(v) if k != "is_empty" else np.array(v) for k, v in out.items()},
                        timing_keys=np.array(keys),
                        timings=np.array([[p.timings[k] for k in keys] for p in prepared], dtype=np.float64))
    (dst / PREPARED_FILE).write_bytes(buf.getvalue())
    print(variant, seq, seed, f"changed {changed}/{len(prepared)} frames, {added / max(changed, 1):.0f} px a changed frame", flush=True)
