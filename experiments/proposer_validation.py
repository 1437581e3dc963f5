"""``python -m experiments.proposer_validation``: the exemplar proposer against the real image side.

The exemplars of :mod:`experiments.fit_proposer` are rendered as class labels with a label-noise
model, not through the synthetic camera (64 ms a frame). This checks that model, and the
proposer's settings, on labels the image side really makes: one trial of each CMU training
subject (:data:`VALIDATION_TRIALS`, 150 frames at 25 fps) drives a synthetic actor through the
synthetic sensor and :func:`mocap.imaging.prepare_frame` (:func:`experiments.units.prepare_data`;
generator seeds 1000-1005, none of the benchmark's), and is queried against the exemplars of the
other five subjects only. Printed:

* per subject, the share of frames with one of the k nearest exemplars (k = 1 / 10 / 20 / 50,
  no turns; the shipped PCA size) within 100 mm (joints about the neck), queried with the
  image side's labels, with the noise model's labels of the same poses on the calibrated model,
  and with clean renders;
* pooled, the share with one of M proposals (M/2 exemplars and their turns) within 100 mm on
  the image side's labels, for each PCA size of ``--components``;
* with ``--channel-weights``, the same for descriptors whose channels
  (:data:`mocap.imaging.descriptor.DESCRIPTOR_CHANNELS`: foreground, skin, hair) are weighted
  before the PCA (the shipped PCA size; weight 0 leaves a channel out).

The sequences are kept under ``--out`` (default ``experiments/results/proposer_validation``).
About 4 minutes of CPU plus the sequences' generation (about 1 minute each) the first time.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from experiments import RESULTS_DIR
from experiments.fit_pose_prior import TRAIN_DIR, positive_integers
from experiments.fit_proposer import (COVERED_MM, IMAGE_SIZE, N_COMPONENTS, SEED, NoiseModel, joints_of, label_noise,
                                      nearest_within, render_descriptors, training_set)
from mocap.body.jumps import turned_mirror
from mocap.body.model import BodyModel
from mocap.imaging.descriptor import DESCRIPTOR_CHANNELS, silhouette_descriptor
from mocap.render import Camera, render
from mocap.synth import SEQUENCE_NAMES

#: One trial per training subject (subject, trial).
VALIDATION_TRIALS: tuple[tuple[str, str], ...] = (
    ("02", "02_05"), ("05", "05_02"), ("127", "127_02"), ("14", "14_02"), ("17", "17_10"), ("49", "49_09"))
#: Generator seed of the first trial's sequence (then +1 per trial); the benchmark never uses them.
FIRST_SEED = 1000
FRAMES = 150
NEIGHBOURS = (1, 10, 20, 50)
PROPOSALS = (10, 20, 40)


def validation_clip(index: int, train_dir: Path, root: Path):
    """The prepared sequence of :data:`VALIDATION_TRIALS` ``[index]``: (loaded sequence, prepared frames)."""
    from experiments.units import DataSpec, load_prepared, load_sequence, prepare_data

    _, trial = VALIDATION_TRIALS[index]
    spec = DataSpec(SEQUENCE_NAMES[index % len(SEQUENCE_NAMES)], str(train_dir / f"cmu_{trial}.amc"), FRAMES,
                    FIRST_SEED + index, *IMAGE_SIZE)
    folder = prepare_data(spec, str(root))
    return load_sequence(folder), load_prepared(folder)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.proposer_validation",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("--train", type=Path, default=TRAIN_DIR, help="folder of CMU .asf/.amc trials")
    p.add_argument("--out", type=Path, default=RESULTS_DIR / "proposer_validation")
    p.add_argument("--components", default="16,32,64,128", help="comma-separated PCA sizes compared")
    p.add_argument("--channel-weights", default="",
                   help="semicolon-separated weights of the descriptor's channels, e.g. '1,0,0;1,0.5,0'")
    args = p.parse_args(argv)
    try:
        weightings = [tuple(float(v) for v in w.split(",")) for w in args.channel_weights.split(";") if w.strip()]
    except ValueError:
        weightings = None
    if weightings is None or any(len(w) != len(DESCRIPTOR_CHANNELS) or min(w) < 0 for w in weightings):
        print(f"error: --channel-weights takes {len(DESCRIPTOR_CHANNELS)} non-negative numbers per weighting, "
              f"got {args.channel_weights!r}", file=sys.stderr)
        return 2
    sizes = positive_integers(args.components)
    if not sizes:
        print(f"error: --components takes positive integers, got {args.components!r}", file=sys.stderr)
        return 2
    if not args.train.is_dir():
        print(f"error: no training folder {args.train}", file=sys.stderr)
        return 2
    sizes = tuple(sorted(set(sizes) | {N_COMPONENTS}))
    from sklearn.decomposition import PCA
    from sklearn.neighbors import NearestNeighbors
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    noise = NoiseModel()
    poses, subjects = training_set(args.train, SEED)
    descriptors = render_descriptors(poses, SEED, noise)
    standard = BodyModel.build()
    joints = joints_of(poses, standard)
    turned = joints_of(np.array([turned_mirror(q) for q in poses]), standard)
    camera = Camera.default(*IMAGE_SIZE)
    rng = np.random.default_rng([SEED, 4])
    per_subject, pooled = [], {(n, m): [] for n in sizes for m in PROPOSALS}
    weighted = {(w, m): [] for w in weightings for m in PROPOSALS}
    cells = descriptors.shape[1] // len(DESCRIPTOR_CHANNELS)
    for index, (subject, trial) in enumerate(VALIDATION_TRIALS):
        loaded, prepared = validation_clip(index, args.train, args.out)
        model = loaded.model
        truth = loaded.ground_truth.poses[: len(prepared)]
        truth_joints = joints_of(truth, standard)
        queries = {
            "image side": np.array([silhouette_descriptor(f.labels, model.class_names) for f in prepared]),
            "noise model": np.array([silhouette_descriptor(label_noise(render(q, model, camera).labels, model.class_names,
                                                                       rng, noise), model.class_names) for q in truth]),
            "clean render": np.array([silhouette_descriptor(render(q, model, camera).labels, model.class_names)
                                      for q in truth])}
        train = np.flatnonzero(subjects != subject)
        row = {"subject": subject, "trial": trial}
        for n in sizes:
            pca = PCA(n, svd_solver="randomized", random_state=SEED).fit(descriptors[train])
            index_nn = NearestNeighbors().fit(pca.transform(descriptors[train]))
            for name, q in queries.items():
                if name != "image side" and n != N_COMPONENTS:     # the three sources: the shipped size only
                    continue
                _, rows = index_nn.kneighbors(pca.transform(q), max(max(NEIGHBOURS), max(PROPOSALS) // 2))
                rows = train[rows]
                if n == N_COMPONENTS:
                    dist = nearest_within(joints[rows[:, :max(NEIGHBOURS)]], truth_joints)
                    row[name] = [float((dist[:, :k].min(axis=1) <= COVERED_MM).mean()) for k in NEIGHBOURS]
                if name == "image side":
                    for m in PROPOSALS:
                        both = np.concatenate([joints[rows[:, :m // 2]], turned[rows[:, :m // 2]]], axis=1)
                        pooled[(n, m)].append(nearest_within(both, truth_joints).min(axis=1) <= COVERED_MM)
        for w in weightings:
            scale = np.repeat(np.array(w, dtype=np.float32), cells)
            pca = PCA(N_COMPONENTS, svd_solver="randomized", random_state=SEED).fit(descriptors[train] * scale)
            index_nn = NearestNeighbors().fit(pca.transform(descriptors[train] * scale))
            _, rows = index_nn.kneighbors(pca.transform(queries["image side"] * scale), max(PROPOSALS) // 2)
            rows = train[rows]
            for m in PROPOSALS:
                both = np.concatenate([joints[rows[:, :m // 2]], turned[rows[:, :m // 2]]], axis=1)
                weighted[(w, m)].append(nearest_within(both, truth_joints).min(axis=1) <= COVERED_MM)
        per_subject.append(row)
    ks = " / ".join(map(str, NEIGHBOURS))
    print(f"| held out (trial) | image side's labels, k = {ks} | noise model | clean render |")
    print("|---|---|---|---|")
    for row in per_subject:
        print(f"| {row['subject']} ({row['trial']}) | " + " | ".join(
            " / ".join(f"{100 * v:.0f}" for v in row[name]) + " %" for name in ("image side", "noise model", "clean render"))
              + " |")
    print()
    print("| PCA size | " + " | ".join(f"M = {m}" for m in PROPOSALS) + " |")
    print("|---" * (1 + len(PROPOSALS)) + "|")
    for n in sizes:
        print(f"| {n} | " + " | ".join(f"{100 * np.concatenate(pooled[(n, m)]).mean():.1f} %" for m in PROPOSALS) + " |")
    if weightings:
        names = "/".join(name for name, _ in DESCRIPTOR_CHANNELS)
        print()
        print(f"| weights ({names}), PCA {N_COMPONENTS} | " + " | ".join(f"M = {m}" for m in PROPOSALS) + " |")
        print("|---" * (1 + len(PROPOSALS)) + "|")
        for w in weightings:
            print(f"| {', '.join(f'{v:g}' for v in w)} | "
                  + " | ".join(f"{100 * np.concatenate(weighted[(w, m)]).mean():.1f} %" for m in PROPOSALS) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
