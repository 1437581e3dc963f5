"""``python -m experiments.fit_proposer``: build the exemplar pose proposer from CMU motion capture.

Reads every trial of ``../shared/data/mocap/train/`` (41 CMU trials of six subjects, ASF/AMC),
retargets it onto the 23-parameter model at 25 frames per second
(:func:`experiments.fit_pose_prior.load_training_poses`) and adds each pose's left/right mirror
image. Every pose becomes one exemplar: the person turned to a random heading over the full
circle, with random body dimensions (:func:`mocap.synth.actor.random_dimensions`; a quarter of
the bodies with bare forearms), at a random depth, height and sideways offset before the
benchmark's camera (160x120, 60 degrees wide), rendered as a class-label image by
:func:`mocap.render.render` and passed through :func:`label_noise` (the image side's errors:
a ragged outline, unclassified pixels, no hair class). Its descriptor
(:func:`mocap.imaging.descriptor.silhouette_descriptor`) is reduced by scikit-learn's PCA.

``--loso`` prints the leave-one-subject-out table that chose the settings: each subject is held
out in turn, the proposer is built from the other five and queried with the held-out
exemplars; a query counts as covered when one of its k nearest exemplars is within 100 mm
(mean joint distance about the neck, :func:`nearest_within`).

Writes ``mocap/track/exemplars.npz`` (:mod:`mocap.track.exemplars`: float16 arrays, the data's
attribution, the checksum) and prints its checksum. Deterministic: fixed seeds, one thread.
The synthetic benchmark's motion and seeds are never used.
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import ndimage

from experiments import EXPERIMENTS_DIR
from experiments.fit_pose_prior import ATTRIBUTION, TRAIN_DIR, load_training_poses, mirror_poses
from mocap.body.kinematics import apply_transforms_into, segment_transforms_into
from mocap.body.model import BodyModel
from mocap.body.pose import JOINT_LIMITS, PARAMETER_INDEX
from mocap.body.skeleton import JOINT_NAMES
from mocap.imaging.descriptor import DESCRIPTOR_GRID, descriptor_size, silhouette_descriptor
from mocap.labels import DEFAULT_CLASS_NAMES, UNKNOWN
from mocap.metrics import root_relative_mpjpe
from mocap.render import Camera, render
from mocap.track.exemplars import EXEMPLAR_FILE, ExemplarSource

SEED = 0
#: Rendered frame size (pixels) and the benchmark camera's field of view.
IMAGE_SIZE = (160, 120)
#: Root depth range (metres) of the exemplars.
DEPTH_RANGE_M = (1.3, 2.6)
#: Chest-base height per metre of depth (camera y): the benchmark's framing 0.33, varied.
HEIGHT_PER_DEPTH = (0.27, 0.39)
#: Sideways root offset per metre of depth.
OFFSET_PER_DEPTH = (-0.15, 0.15)
#: Random bodies the exemplars are spread over.
N_BODIES = 48
#: Share of bodies with bare forearms.
BARE_FOREARMS = 0.25
#: Principal components kept.
N_COMPONENTS = 64
#: Coverage threshold, millimetres.
COVERED_MM = 100.0


@dataclass(frozen=True)
class NoiseModel:
    """The image side's label errors, applied to a clean rendering (:func:`label_noise`).

    Attributes
    ----------
    outline_px : float
        Probability of eroding and, separately, of dilating the outline by one pixel.
    unknown_share : float
        Largest share of foreground pixels turned to "unknown" (drawn uniformly up to it), in
        small clumps.
    no_hair : float
        Probability that the hair is labelled skin (a calibration without a hair class).
    """

    outline_px: float = 0.3
    unknown_share: float = 0.08
    no_hair: float = 0.3


def label_noise(labels: np.ndarray, class_names: tuple[str, ...], rng: np.random.Generator,
                noise: NoiseModel) -> np.ndarray:
    """A clean class-label image with the image side's errors (see :class:`NoiseModel`).

    Parameters
    ----------
    labels : ndarray of uint8, shape (H, W)
    class_names : tuple of str
    rng : numpy.random.Generator
    noise : NoiseModel

    Returns
    -------
    ndarray of uint8, shape (H, W)
    """
    out = labels.copy()
    if "hair" in class_names and "skin" in class_names and rng.random() < noise.no_hair:
        out[out == class_names.index("hair") + 1] = class_names.index("skin") + 1
    foreground = out != 0
    if rng.random() < noise.outline_px:
        out[foreground & ~ndimage.binary_erosion(foreground)] = 0
    if rng.random() < noise.outline_px:                     # grown by the nearest label
        grown = ndimage.binary_dilation(foreground) & ~foreground
        _, (ri, ci) = ndimage.distance_transform_edt(~foreground, return_indices=True)
        out[grown] = out[ri[grown], ci[grown]]
    share = rng.uniform(0.0, noise.unknown_share)
    seeds = (rng.random(out.shape) < share / 4.0) & (out != 0)
    out[ndimage.binary_dilation(seeds, structure=np.ones((2, 2), bool)) & (out != 0)] = UNKNOWN
    return out


def joints_of(poses: np.ndarray, model: BodyModel) -> np.ndarray:
    """Joint positions of many poses (the compiled kinematics without per-pose checks).

    Parameters
    ----------
    poses : ndarray, shape (n, 23)
    model : BodyModel

    Returns
    -------
    ndarray, shape (n, 10, 3), float64, metres
    """
    transforms = np.empty((8, 3, 4))
    out = np.empty((len(poses), len(JOINT_NAMES), 3))
    sk = model.skeleton
    for i, q in enumerate(np.ascontiguousarray(poses, dtype=np.float64)):
        segment_transforms_into(q, sk.offsets, transforms)
        apply_transforms_into(transforms, sk.joint_segment, sk.joint_local, out[i])
    return out


def nearest_within(neighbour_joints: np.ndarray, true_joints: np.ndarray) -> np.ndarray:
    """Root-relative MPJPE (mm, about the neck) of each of k candidates against the truth.

    Parameters
    ----------
    neighbour_joints : ndarray, shape (n, k, 10, 3), metres
    true_joints : ndarray, shape (n, 10, 3), metres

    Returns
    -------
    ndarray, shape (n, k), millimetres
    """
    n, k = neighbour_joints.shape[:2]
    truth = np.repeat(true_joints[:, None], k, axis=1).reshape(n * k, *true_joints.shape[1:])
    return root_relative_mpjpe(neighbour_joints.reshape(n * k, *true_joints.shape[1:]), truth,
                               per_frame=True).reshape(n, k)


def random_views(poses: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Poses turned to a random heading and placed at a random depth, height and offset.

    Parameters
    ----------
    poses : ndarray, shape (n, 23)

    Returns
    -------
    ndarray, shape (n, 23)
        Within the joint limits.
    """
    out = poses.copy()
    n = len(out)
    z = rng.uniform(*DEPTH_RANGE_M, n)
    out[:, PARAMETER_INDEX["root_z"]] = z
    out[:, PARAMETER_INDEX["root_y"]] = z * rng.uniform(*HEIGHT_PER_DEPTH, n)
    out[:, PARAMETER_INDEX["root_x"]] = z * rng.uniform(*OFFSET_PER_DEPTH, n)
    out[:, PARAMETER_INDEX["chest_yaw"]] = rng.uniform(-np.pi, np.pi, n)
    return np.clip(out, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])


def random_bodies(rng: np.random.Generator, n: int) -> list[BodyModel]:
    """``n`` body models of random adult proportions with the four default classes."""
    from mocap.synth.actor import random_dimensions

    bodies = []
    for _ in range(n):
        dims = random_dimensions(rng)
        bare = {"r_forearm": "skin", "l_forearm": "skin"} if rng.random() < BARE_FOREARMS else {}
        bodies.append(BodyModel.build(dims, part_class=bare, class_names=DEFAULT_CLASS_NAMES))
    return bodies


def exemplar_labels(pose: np.ndarray, index: int, bodies: list[BodyModel], seed: int,
                    noise: NoiseModel | None) -> tuple[np.ndarray, tuple[str, ...]]:
    """The label image of exemplar number ``index`` as the build makes it.

    Parameters
    ----------
    pose : ndarray, shape (23,)
        Its placed pose.
    index : int
        Its row: picks the body (``bodies[index % len(bodies)]``) and the noise draw.
    bodies : list of BodyModel
        :func:`random_bodies` of the build.
    seed : int
    noise : NoiseModel or None
        None: the clean rendering.

    Returns
    -------
    labels : ndarray of uint8, shape (120, 160)
    class_names : tuple of str
    """
    body = bodies[index % len(bodies)]
    labels = render(np.asarray(pose, dtype=np.float64), body, Camera.default(*IMAGE_SIZE)).labels
    if noise is not None:
        labels = label_noise(labels, body.class_names, np.random.default_rng([seed, 3, index]), noise)
    return labels, body.class_names


def render_descriptors(poses: np.ndarray, seed: int, noise: NoiseModel | None, grid=DESCRIPTOR_GRID,
                       progress: bool = True) -> np.ndarray:
    """Descriptors of the exemplars' label images (:func:`exemplar_labels`).

    Parameters
    ----------
    poses : ndarray, shape (n, 23)
        Placed poses (:func:`training_set`).
    seed : int
        Fixes the bodies and the noise.
    noise : NoiseModel or None
        None: clean renderings.

    Returns
    -------
    ndarray of float32, shape (n, D)
    """
    from tqdm import tqdm

    bodies = random_bodies(np.random.default_rng([seed, 2]), N_BODIES)
    out = np.empty((len(poses), descriptor_size(grid)), dtype=np.float32)
    for i in tqdm(range(len(poses)), desc="rendering exemplars", unit="pose", disable=not progress, leave=False):
        out[i] = silhouette_descriptor(*exemplar_labels(poses[i], i, bodies, seed, noise), grid)
    return out


def training_set(train_dir: Path, seed: int = SEED, limit: int | None = None):
    """Placed exemplar poses and their subjects (every training pose and its mirror image).

    Returns
    -------
    poses : ndarray, shape (n, 23)
    subjects : ndarray of str, shape (n,)
    """
    poses, subjects = load_training_poses(train_dir)
    poses = np.concatenate([poses, mirror_poses(poses)])
    subjects = np.concatenate([subjects, subjects])
    if limit is not None and limit < len(poses):
        keep = np.sort(np.random.default_rng(seed).choice(len(poses), limit, replace=False))
        poses, subjects = poses[keep], subjects[keep]
    # stored as float16: render exactly what is stored
    placed = random_views(poses, np.random.default_rng([seed, 1])).astype(np.float16)
    low, high = JOINT_LIMITS[:, 0].astype(np.float16), JOINT_LIMITS[:, 1].astype(np.float16)
    placed = np.where(placed > JOINT_LIMITS[:, 1], np.nextafter(high, np.float16(0)), placed)
    placed = np.where(placed < JOINT_LIMITS[:, 0], np.nextafter(low, np.float16(0)), placed)
    return placed.astype(np.float64), subjects


def leave_one_subject_out(poses, subjects, descriptors, queries, ks=(1, 10, 20, 50),
                          n_components: int = N_COMPONENTS) -> dict:
    """Share of held-out queries with one of the k nearest exemplars within :data:`COVERED_MM`.

    Parameters
    ----------
    poses : ndarray, shape (n, 23)
    subjects : ndarray of str, shape (n,)
    descriptors : ndarray, shape (n, D)
        The exemplars' (built from these).
    queries : ndarray, shape (n, D)
        The same poses' descriptors as queried (another noise draw).

    Returns
    -------
    dict
        ``{subject: {k: share}}`` and ``"all"``: the pooled shares.
    """
    from sklearn.decomposition import PCA
    from sklearn.neighbors import NearestNeighbors

    model = BodyModel.build()
    joints = joints_of(poses, model)
    out, pooled = {}, {k: [] for k in ks}
    for s in np.unique(subjects):
        train, held = subjects != s, subjects == s
        pca = PCA(n_components, svd_solver="randomized", random_state=SEED).fit(descriptors[train])
        nn = NearestNeighbors(n_neighbors=max(ks)).fit(pca.transform(descriptors[train]))
        _, idx = nn.kneighbors(pca.transform(queries[held]))
        train_joints = joints[train]
        dist = nearest_within(train_joints[idx], joints[held])
        out[str(s)] = {}
        for k in ks:
            covered = dist[:, :k].min(axis=1) <= COVERED_MM
            out[str(s)][k] = float(covered.mean())
            pooled[k].append(covered)
    out["all"] = {k: float(np.concatenate(v).mean()) for k, v in pooled.items()}
    return out


def build(poses: np.ndarray, descriptors: np.ndarray, n_components: int, provenance: dict) -> ExemplarSource:
    """The exemplar source of ``poses`` (n, 23) and their ``descriptors`` (n, D)."""
    from sklearn.decomposition import PCA

    pca = PCA(n_components, svd_solver="randomized", random_state=SEED).fit(descriptors)
    return ExemplarSource.from_descriptors(poses, descriptors, pca.mean_, pca.components_, ATTRIBUTION, provenance)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.fit_proposer", description=__doc__.split("\n\n")[0])
    p.add_argument("--train", type=Path, default=TRAIN_DIR, help="folder of CMU .asf/.amc trials")
    p.add_argument("--out", type=Path, default=EXPERIMENTS_DIR.parent / "mocap" / "track" / EXEMPLAR_FILE)
    p.add_argument("--limit", type=int, default=None, help="at most this many exemplars (a random subset)")
    p.add_argument("--loso", action="store_true", help="print the leave-one-subject-out table instead of building")
    args = p.parse_args(argv)
    if args.limit is not None and args.limit < N_COMPONENTS:
        print(f"error: --limit must be at least {N_COMPONENTS}, got {args.limit}", file=sys.stderr)
        return 2
    if not args.train.is_dir():
        print(f"error: no training folder {args.train} (the CMU trials of ../shared/data/mocap/train)",
              file=sys.stderr)
        return 2
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    noise = NoiseModel()
    poses, subjects = training_set(args.train, SEED, args.limit)
    descriptors = render_descriptors(poses, SEED, noise)
    if args.loso:
        queries = render_descriptors(poses, SEED + 1, noise)
        table = leave_one_subject_out(poses, subjects, descriptors, queries)
        ks = list(table["all"])
        print("subject  " + "  ".join(f"k={k:<4d}" for k in ks))
        for s, row in table.items():
            print(f"{s:7s}  " + "  ".join(f"{100 * row[k]:5.1f}%" for k in ks))
        return 0
    source = build(poses, descriptors, N_COMPONENTS, {
        "subjects": sorted({str(s) for s in np.unique(subjects)}), "exemplars": int(len(poses)),
        "mirrored": True, "seed": SEED, "grid": list(DESCRIPTOR_GRID), "components": N_COMPONENTS,
        "noise": vars(noise)})
    checksum = source.save(args.out)
    print(f"wrote {args.out}: {len(poses)} exemplars, sha256 {checksum}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
