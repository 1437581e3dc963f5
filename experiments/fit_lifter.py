"""``python -m experiments.fit_lifter``: train the 2D->3D lifter (:mod:`mocap.track.lifter`) with PyTorch.

Needs the optional extra ``fit`` (``torch==2.13.0``, the CPU build). Reads every trial of
``../shared/data/mocap/train/`` (200 CMU trials of nine subjects; ``--trials-from RECORD`` only the
trials a record lists), retargeted at 25 frames per second by
:func:`experiments.fit_pose_prior.load_training_poses`, and adds each pose's mirror image.
Every training step draws a fresh batch of projections of those poses, all in PyTorch:

* augmentation: half the poses take their left arm from another pose (the arms move
  independently), every angle jittered by :data:`ANGLE_JITTER` within the limits, a quarter of
  the elbows straightened (:data:`STRAIGHT_ELBOW`);
* a random body (:func:`mocap.synth.actor.random_dimensions`, :data:`N_BODIES` of them) and a
  random heading over the full circle (added to the chest's yaw);
* a random camera: horizontal field of view :data:`FOV_DEG` (webcam to phone), the person's
  neck anywhere in the middle 60 % of the image, at a depth where the frame is
  :data:`FRAME_WIDTH_AT_DEPTH` metres wide there;
* keypoint noise: half the batch the oracle's (isotropic Gaussian, a random share up to
  :data:`ORACLE_NOISE_MAX` of the keypoints' scale), half MediaPipe Pose's as measured on the
  toolkit's own synthetic frames (:mod:`experiments.lifter_keypoint_noise`: a mean offset per
  joint plus Gaussian noise per joint, in units of the keypoints' scale, gross misses at their
  measured rate, misses at theirs; no neck);
* random drop-outs (each joint missing with a random probability up to :data:`DROP_MAX`, at
  least :data:`~mocap.track.lifter.MIN_VISIBLE` + 1 left), the mask an input.

The network (:class:`LifterNet`) predicts K = :data:`HYPOTHESES` angle sets (inside the joint
limits by construction) and a confidence logit each; the loss is the mean joint distance about
the neck after the forward kinematics of the sample's own body (:func:`torch_joints`, the twin of
:mod:`mocap.body.kinematics`), winner takes all (plus :data:`RELAX` times the mean over the
hypotheses, so none is left untrained), plus the cross-entropy of the confidences against the
winner. Adam, cosine learning rate.

Deterministic for a seed: ``torch.manual_seed``, deterministic algorithms, :data:`THREADS`
threads. The synthetic benchmark's procedural motion and seeds are never used. Writes
``mocap/track/lifter.npz`` (or ``--out``) and prints its checksum; the shipped file's record
(:data:`RECORD`) lists the trials it was trained on. ``--quick`` trains a tiny network on two
trials in seconds (for tests).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from experiments import EXPERIMENTS_DIR
from experiments.fit_pose_prior import (ATTRIBUTION, TRAIN_DIR, load_training_poses, mirror_poses, record_trials,
                                         trial_files)
from mocap.body.kinematics import Skeleton
from mocap.body.pose import JOINT_LIMITS, PARAMETER_INDEX
from mocap.body.skeleton import JOINT_INDEX, JOINT_NAMES
from mocap.track.lifter import (BOUNDED_ANGLES, LIFTER_FILE, MIN_VISIBLE, N_FEATURES, OUTPUTS_PER_HYPOTHESIS,
                                Lifter)

SEED = 0
#: Hypotheses per frame.
HYPOTHESES = 10
#: Hidden layer widths of the full and the --quick model.
HIDDEN = (512, 512, 512)
QUICK_HIDDEN = (32, 32)
#: Training steps and batch size (full, --quick).
STEPS, QUICK_STEPS = 8000, 30
BATCH, QUICK_BATCH = 256, 64
LEARNING_RATE = 1e-3
#: Weight of the mean over hypotheses in the winner-takes-all loss.
RELAX = 0.05
#: Weight of the confidence head's cross-entropy (against metres of joint error).
CONFIDENCE_WEIGHT = 0.02
#: Random bodies.
N_BODIES = 256
#: Horizontal field of view range, degrees (webcam to phone).
FOV_DEG = (45.0, 80.0)
#: Width of the frame at the person's depth, metres (how much of the scene the frame shows).
FRAME_WIDTH_AT_DEPTH = (1.5, 4.4)
#: Share of samples with the detector's (MediaPipe's) measured keypoint errors; the others the oracle's.
DETECTOR_SHARE = 0.5
#: Largest oracle noise, as a share of the keypoints' RMS spread about their centre.
ORACLE_NOISE_MAX = 0.12
#: Largest per-joint drop-out probability.
DROP_MAX = 0.3
#: Share of samples whose left arm comes from another pose, and the jitter (radians, standard
#: deviation) added to every angle, within the limits.
ARM_MIX = 0.5
ANGLE_JITTER = 0.1
#: Share of arms straightened (elbow flexion drawn from 0 to STRAIGHT_ELBOW_MAX radians): in the
#: retargeted CMU trials 95 % of elbows are bent by more than 22 degrees.
STRAIGHT_ELBOW = 0.25
STRAIGHT_ELBOW_MAX = np.deg2rad(25.0)
_ELBOWS = (PARAMETER_INDEX["r_elbow_flex"], PARAMETER_INDEX["l_elbow_flex"])
_LEFT_ARM = [PARAMETER_INDEX[n] for n in PARAMETER_INDEX if n.startswith("l_")]
#: Spread (per coordinate, units of the keypoints' scale) of a detector's gross misses.
GROSS_SIGMA = 0.6
#: CPU threads (deterministic for a fixed count). One: on a shared, busy machine two intra-op threads
#: spun against each other and the other processes (a step took 10 to 30 times longer than with one).
THREADS = 1
#: The measured MediaPipe keypoint model (written by experiments.lifter_keypoint_noise).
NOISE_FILE = EXPERIMENTS_DIR / "lifter_keypoint_noise.json"
#: Trials of --quick (file names; the first two of the folder when it held 41 trials).
QUICK_TRIALS = ("cmu_02_05.amc", "cmu_02_06.amc")
#: The shipped file, and the record of the training that wrote it (checksum, wall time, machine load).
SHIPPED = EXPERIMENTS_DIR.parent / "mocap" / "track" / LIFTER_FILE
RECORD = EXPERIMENTS_DIR / "fit_lifter.json"


@dataclass(frozen=True)
class KeypointNoise:
    """A detector's keypoints against the model's projected joints, in units of the keypoints'
    scale (RMS distance of the visible joints from their mean).

    Attributes
    ----------
    offset : ndarray, shape (10, 2)
        Mean displacement of each joint (image axes u right, v down); zero for the neck.
    sigma : ndarray, shape (10,)
        Standard deviation per coordinate about that offset.
    missing : ndarray, shape (10,)
        Share of frames on which the detector misses each joint (the neck: 1, it has none).
    gross : ndarray, shape (10,)
        Share of gross misses of each joint (further than 1 scale unit), drawn in training as an
        extra displacement of :data:`GROSS_SIGMA` per coordinate.
    """

    offset: np.ndarray
    sigma: np.ndarray
    missing: np.ndarray
    gross: np.ndarray

    @classmethod
    def read(cls, path: Path = NOISE_FILE) -> "KeypointNoise":
        data = json.loads(Path(path).read_text())
        joints = data["joints"]
        return cls(np.array([joints[j]["offset"] for j in JOINT_NAMES]),
                   np.array([joints[j]["sigma"] for j in JOINT_NAMES]),
                   np.array([joints[j]["missing"] for j in JOINT_NAMES]),
                   np.array([joints[j].get("gross", 0.0) for j in JOINT_NAMES]))


def _torch():
    try:
        import torch
    except ImportError:
        raise SystemExit("error: training the lifter needs PyTorch, the optional extra 'fit': "
                         "pip install -e '.[fit]'") from None
    return torch


def make_net(hidden: tuple[int, ...], hypotheses: int = HYPOTHESES):
    """The network: Linear+ReLU hidden layers, then a linear output of K * 22 values."""
    torch = _torch()
    layers, n_in = [], N_FEATURES
    for width in hidden:
        layers += [torch.nn.Linear(n_in, width), torch.nn.ReLU()]
        n_in = width
    layers.append(torch.nn.Linear(n_in, hypotheses * OUTPUTS_PER_HYPOTHESIS))
    return torch.nn.Sequential(*layers)


def export_weights(net) -> tuple:
    """The network's weights as :class:`~mocap.track.lifter.Lifter` takes them (W as (in, out))."""
    out = []
    for layer in net:
        if hasattr(layer, "weight"):
            out += [layer.weight.detach().numpy().T.astype(np.float32).copy(),
                    layer.bias.detach().numpy().astype(np.float32).copy()]
    return tuple(out)


def load_weights(net, weights) -> None:
    """Set ``net``'s weights from a :class:`~mocap.track.lifter.Lifter`'s (the inverse of :func:`export_weights`)."""
    torch = _torch()
    linear = [layer for layer in net if hasattr(layer, "weight")]
    with torch.no_grad():
        for layer, (w, b) in zip(linear, zip(weights[0::2], weights[1::2])):
            layer.weight.copy_(torch.from_numpy(np.ascontiguousarray(np.asarray(w, np.float32).T)))
            layer.bias.copy_(torch.from_numpy(np.asarray(b, np.float32)))


# -- the model's kinematics in PyTorch -------------------------------------------------------------
def _rot(axis: str, a):
    torch = _torch()
    c, s = torch.cos(a), torch.sin(a)
    o, z = torch.ones_like(a), torch.zeros_like(a)
    rows = {"x": (o, z, z, z, c, -s, z, s, c), "y": (c, z, s, z, o, z, -s, z, c),
            "z": (c, -s, z, s, c, z, z, z, o)}[axis]
    return torch.stack(rows, dim=-1).reshape(*a.shape, 3, 3)


def torch_joints(poses, offsets, joint_segment: np.ndarray, joint_local):
    """Joints of a batch of poses (the twin of :func:`mocap.body.kinematics.joint_positions`).

    Parameters
    ----------
    poses : torch.Tensor, shape (n, 23)
    offsets : torch.Tensor, shape (n, 8, 3)
        Each pose's body's segment offsets.
    joint_segment : ndarray of int, shape (10,)
        The same for every body.
    joint_local : torch.Tensor, shape (n, 10, 3)

    Returns
    -------
    torch.Tensor, shape (n, 10, 3), metres, camera coordinates
    """
    torch = _torch()
    q = poses
    rs, ts = [None] * 8, [None] * 8
    rs[0] = _rot("y", q[:, 3]) @ _rot("x", q[:, 4]) @ _rot("z", q[:, 5])
    ts[0] = q[:, 0:3]

    def place(k, parent, r):
        rs[k] = r
        ts[k] = (rs[parent] @ offsets[:, k, :, None])[..., 0] + ts[parent]

    place(1, 0, rs[0] @ _rot("x", q[:, 6]) @ _rot("z", q[:, 7]) @ _rot("y", q[:, 8]))
    for side, (base, seg, m) in enumerate(((9, 2, 1.0), (16, 5, -1.0))):
        place(seg, 0, rs[0] @ _rot("x", -q[:, base]) @ _rot("z", m * q[:, base + 1]) @ _rot("y", m * q[:, base + 2]))
        place(seg + 1, seg, rs[seg] @ _rot("x", -q[:, base + 3]) @ _rot("y", m * q[:, base + 4]))
        place(seg + 2, seg + 1, rs[seg + 1] @ _rot("x", -q[:, base + 5]) @ _rot("z", m * q[:, base + 6]))
    index = torch.as_tensor(np.array(joint_segment, dtype=np.int64))
    r = torch.stack(rs, dim=1)[:, index]                     # (n, 10, 3, 3)
    t = torch.stack(ts, dim=1)[:, index]
    return (r @ joint_local[..., None])[..., 0] + t


def torch_features(xy, mask):
    """The twin of :func:`mocap.track.lifter.lifter_features` for a batch in image-plane units.

    Parameters
    ----------
    xy : torch.Tensor, shape (n, 10, 2)
        ``((u - cx) / fx, (v - cy) / fy)`` of every joint.
    mask : torch.Tensor of bool, shape (n, 10)

    Returns
    -------
    torch.Tensor, shape (n, 32)
    """
    torch = _torch()
    m = mask.to(xy.dtype)[..., None]
    count = m.sum(dim=1)
    centre = (xy * m).sum(dim=1) / count
    d = (xy - centre[:, None]) * m
    scale = torch.sqrt((d ** 2).sum(dim=(1, 2)) / count[:, 0])
    rel = d / scale[:, None, None]
    return torch.cat([rel.reshape(len(xy), -1), mask.to(xy.dtype), centre], dim=1)


def decode_poses(out, hypotheses: int):
    """Network outputs (n, K * 22) -> logits (n, K) and poses (n, K, 23) with the root at zero
    (the twin of :meth:`mocap.track.lifter.Lifter.decode`)."""
    torch = _torch()
    o = out.reshape(len(out), hypotheses, OUTPUTS_PER_HYPOTHESIS)
    lo = torch.tensor(JOINT_LIMITS[[PARAMETER_INDEX[n] for n in BOUNDED_ANGLES], 0], dtype=out.dtype)
    hi = torch.tensor(JOINT_LIMITS[[PARAMETER_INDEX[n] for n in BOUNDED_ANGLES], 1], dtype=out.dtype)
    poses = torch.zeros(len(out), hypotheses, 23, dtype=out.dtype)
    poses[..., PARAMETER_INDEX["chest_yaw"]] = torch.atan2(o[..., 2], o[..., 1])
    poses[..., [PARAMETER_INDEX[n] for n in BOUNDED_ANGLES]] = lo + (hi - lo) * torch.sigmoid(o[..., 3:])
    return o[..., 0], poses


# -- the training data ------------------------------------------------------------------------------
@dataclass
class Bodies:
    """Kinematic constants of the random bodies (PyTorch tensors)."""

    offsets: object          # (B, 8, 3)
    joint_local: object      # (B, 10, 3)
    joint_segment: np.ndarray


def make_bodies(seed: int, n: int) -> Bodies:
    from mocap.synth.actor import random_dimensions

    torch = _torch()
    rng = np.random.default_rng([seed, 1])
    skeletons = [Skeleton.from_dimensions(random_dimensions(rng)) for _ in range(n)]
    segment = skeletons[0].joint_segment
    if any((s.joint_segment != segment).any() for s in skeletons):
        raise RuntimeError("bodies differ in which segment carries a joint")
    return Bodies(torch.tensor(np.stack([s.offsets for s in skeletons]), dtype=torch.float32),
                  torch.tensor(np.stack([s.joint_local for s in skeletons]), dtype=torch.float32), segment)


def _limits_tensor():
    torch = _torch()
    return torch.tensor(np.clip(JOINT_LIMITS, -50.0, 50.0), dtype=torch.float32)


def draw_batch(poses, bodies: Bodies, noise: KeypointNoise, n: int, generator):
    """One batch of projections (see the module docstring).

    Returns
    -------
    features : torch.Tensor, shape (n, 32)
    body : torch.Tensor of int64, shape (n,)
    truth : torch.Tensor, shape (n, 10, 3), metres about the neck
    """
    torch = _torch()
    g = generator
    limits = _limits_tensor()

    def uniform(lo, hi, size=(n,)):
        return lo + (hi - lo) * torch.rand(size, generator=g)

    q = poses[torch.randint(len(poses), (n,), generator=g)].clone()
    # augmentation: the left arm of another pose (arms move independently), angles jittered
    other = poses[torch.randint(len(poses), (n,), generator=g)]
    mix = (torch.rand(n, generator=g) < ARM_MIX)[:, None]
    q[:, _LEFT_ARM] = torch.where(mix, other[:, _LEFT_ARM], q[:, _LEFT_ARM])
    q[:, 3:] = q[:, 3:] + ANGLE_JITTER * torch.randn((n, q.shape[1] - 3), generator=g)
    for elbow in _ELBOWS:                          # CMU's elbows are rarely straight: some arms straightened
        straight = torch.rand(n, generator=g) < STRAIGHT_ELBOW
        q[:, elbow] = torch.where(straight, STRAIGHT_ELBOW_MAX * torch.rand(n, generator=g), q[:, elbow])
    q = torch.minimum(torch.maximum(q, limits[:, 0]), limits[:, 1])
    body = torch.randint(len(bodies.offsets), (n,), generator=g)
    q[:, 0:3] = 0.0
    q[:, PARAMETER_INDEX["chest_yaw"]] = uniform(-np.pi, np.pi)
    joints = torch_joints(q, bodies.offsets[body], bodies.joint_segment, bodies.joint_local[body])
    neck = joints[:, JOINT_INDEX["neck"]]
    truth = joints - neck[:, None]
    half = torch.tan(0.5 * torch.deg2rad(uniform(*FOV_DEG)))
    depth = uniform(*FRAME_WIDTH_AT_DEPTH) / (2.0 * half)
    aspect = torch.tensor([0.75, 0.5625, 4.0 / 3.0])[torch.randint(3, (n,), generator=g)]
    target = torch.stack([uniform(-0.6, 0.6) * half, uniform(-0.6, 0.6) * half * aspect], dim=1)
    cam = truth + torch.cat([target * depth[:, None], depth[:, None]], dim=1)[:, None]
    xy = cam[..., :2] / torch.clamp(cam[..., 2:], min=0.05)
    # noise in units of the clean keypoints' scale
    centre = xy.mean(dim=1, keepdim=True)
    scale = torch.sqrt(((xy - centre) ** 2).sum(dim=2).mean(dim=1))[:, None, None]
    detector = torch.rand(n, generator=g) < DETECTOR_SHARE
    sigma_oracle = uniform(0.0, ORACLE_NOISE_MAX)[:, None, None]
    offset = torch.tensor(noise.offset, dtype=torch.float32)[None]
    sigma_det = torch.tensor(noise.sigma, dtype=torch.float32)[None, :, None]
    eps = torch.randn(xy.shape, generator=g)
    gross = (torch.rand((n, len(JOINT_NAMES)), generator=g) < torch.tensor(noise.gross, dtype=torch.float32))[..., None]
    eps_gross = GROSS_SIGMA * torch.randn(xy.shape, generator=g)
    shift = torch.where(detector[:, None, None], offset + sigma_det * eps + gross * eps_gross, sigma_oracle * eps)
    xy = xy + scale * shift
    drop = torch.rand((n, len(JOINT_NAMES)), generator=g) < uniform(0.0, DROP_MAX)[:, None]
    missing_det = torch.rand((n, len(JOINT_NAMES)), generator=g) < torch.tensor(noise.missing, dtype=torch.float32)
    drop = drop | (detector[:, None] & missing_det)
    visible = ~drop
    too_few = visible.sum(dim=1) < MIN_VISIBLE + 1
    visible[too_few] = True
    return torch_features(xy, visible), body, truth


def wta_loss(out, body, truth, bodies: Bodies, hypotheses: int):
    """Winner-takes-all joint loss plus the confidences' cross-entropy; returns (loss, mean best error m)."""
    torch = _torch()
    logits, poses = decode_poses(out, hypotheses)
    n = len(out)
    flat = poses.reshape(n * hypotheses, -1)
    b = body.repeat_interleave(hypotheses)
    joints = torch_joints(flat, bodies.offsets[b], bodies.joint_segment, bodies.joint_local[b])
    joints = (joints - joints[:, JOINT_INDEX["neck"]][:, None]).reshape(n, hypotheses, len(JOINT_NAMES), 3)
    err = torch.linalg.norm(joints - truth[:, None], dim=-1).mean(dim=-1)     # (n, K) metres
    best, winner = err.min(dim=1)
    confidence = torch.nn.functional.cross_entropy(logits, winner)
    return (1.0 - RELAX) * best.mean() + RELAX * err.mean() + CONFIDENCE_WEIGHT * confidence, best.mean().detach()


def training_poses(train_dir: Path, trials=None, exclude_subject: str | None = None):
    """Retargeted training poses and their mirror images (float32, (n, 23)) and their subjects.

    ``trials``: file names to read (default every trial of ``train_dir``,
    :func:`experiments.fit_pose_prior.trial_files`); ``exclude_subject`` drops that subject's poses.
    """
    poses, subjects = load_training_poses(train_dir, trials)
    if exclude_subject is not None:
        keep = subjects != exclude_subject
        poses, subjects = poses[keep], subjects[keep]
    return np.concatenate([poses, mirror_poses(poses)]).astype(np.float32), np.concatenate([subjects, subjects])


def train(poses: np.ndarray, *, seed: int = SEED, hidden=HIDDEN, steps: int = STEPS, batch: int = BATCH,
          noise: KeypointNoise | None = None, progress: bool = True, log=None, on_step=None, every: int = 0):
    """Train a lifter network on ``poses`` (n, 23); returns the PyTorch module (eval mode).

    ``on_step(step, net)``, when given with ``every`` > 0, is called after every ``every``-th step
    (``step`` counted from 1); it must leave ``net`` and the random state alone (the network has no
    dropout or normalisation, so evaluating it does not change training).
    """
    torch = _torch()
    from tqdm import tqdm

    torch.manual_seed(seed)
    torch.use_deterministic_algorithms(True)
    torch.set_num_threads(THREADS)
    noise = noise if noise is not None else KeypointNoise.read()
    bodies = make_bodies(seed, N_BODIES if steps > QUICK_STEPS else 16)
    g = torch.Generator().manual_seed(seed)
    pool = torch.from_numpy(np.ascontiguousarray(poses, dtype=np.float32))
    net = make_net(hidden)
    opt = torch.optim.Adam(net.parameters(), lr=LEARNING_RATE)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, steps, eta_min=LEARNING_RATE * 0.01)
    bar = tqdm(range(steps), desc="training the lifter", unit="step", disable=not progress, mininterval=5)
    running = None
    for step in bar:
        features, body, truth = draw_batch(pool, bodies, noise, batch, g)
        loss, best = wta_loss(net(features), body, truth, bodies, HYPOTHESES)
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
        running = float(best) if running is None else 0.98 * running + 0.02 * float(best)
        if on_step is not None and every > 0 and (step + 1) % every == 0:
            with torch.no_grad():
                on_step(step + 1, net)
        if step % 100 == 0:
            bar.set_postfix(best_of_k_mm=f"{1e3 * running:.0f}")
            if log is not None:
                print(f"step {step} best-of-K {1e3 * running:.1f} mm", file=log, flush=True)
    return net.eval()


def command_line(prog: str, argv) -> str:
    """The command as a record keeps it: absolute paths (this machine's) left out with the option
    that takes them, so that the rest is what reproduces the file from the repository root with
    the default folders."""
    args = list(argv)
    kept = []
    for i, a in enumerate(args):
        if a.startswith("/") or (a.startswith("--") and i + 1 < len(args) and args[i + 1].startswith("/")):
            continue
        kept.append(a)
    return " ".join([prog, *kept])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.fit_lifter", description=__doc__.split("\n\n")[0])
    p.add_argument("--train", type=Path, default=TRAIN_DIR, help="folder of CMU .asf/.amc trials")
    p.add_argument("--out", type=Path, default=SHIPPED,
                   help=f"lifter file (default: the shipped one; then {RECORD.name} records its checksum)")
    p.add_argument("--seed", type=int, default=SEED)
    p.add_argument("--quick", action="store_true", help="a tiny network on two trials in seconds (tests)")
    p.add_argument("--steps", type=int, default=None, help=f"training steps (default {STEPS}, --quick {QUICK_STEPS})")
    p.add_argument("--hidden", default=None,
                   help=f"hidden layer widths, comma-separated (default {','.join(map(str, HIDDEN))})")
    p.add_argument("--exclude-subject", default=None, help="leave this CMU subject out (e.g. 14)")
    p.add_argument("--trials-from", type=Path, default=None, metavar="RECORD",
                   help="train only on the trials this record lists (experiments/fit_lifter.json's 'trials', or a "
                        "pose prior file's training.trials; default: every trial of --train)")
    args = p.parse_args(argv)
    if not args.train.is_dir():
        print(f"error: no training folder {args.train} (the CMU trials of ../shared/data/mocap/train)", file=sys.stderr)
        return 2
    if args.steps is not None and args.steps < 1:
        print(f"error: --steps must be positive, got {args.steps}", file=sys.stderr)
        return 2
    from experiments.fit_pose_prior import positive_integers

    hidden = positive_integers(args.hidden) if args.hidden else (QUICK_HIDDEN if args.quick else HIDDEN)
    if not hidden:
        print(f"error: --hidden takes comma-separated positive integers, got {args.hidden!r}", file=sys.stderr)
        return 2
    try:
        trials = record_trials(args.trials_from) if args.trials_from is not None else (
            list(QUICK_TRIALS) if args.quick else None)
        files = trial_files(args.train, trials)
    except (OSError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    torch = _torch()
    started = time.perf_counter()
    import os

    load_at_start = [round(v, 2) for v in os.getloadavg()]
    poses, subjects = training_poses(args.train, [f.name for f in files], args.exclude_subject)
    steps = args.steps or (QUICK_STEPS if args.quick else STEPS)
    batch = QUICK_BATCH if args.quick else BATCH
    noise = KeypointNoise.read()
    net = train(poses, seed=args.seed, hidden=hidden, steps=steps, batch=batch, noise=noise,
                progress=not args.quick)
    wall = time.perf_counter() - started
    provenance = {"command": command_line("python -m experiments.fit_lifter",
                                          argv if argv is not None else sys.argv[1:]),
                  "seed": args.seed, "subjects": sorted({str(s) for s in subjects}), "poses": int(len(poses)),
                  "mirrored": True, "fps": 25.0, "hidden": list(hidden), "hypotheses": HYPOTHESES, "steps": steps,
                  "batch": batch, "torch": torch.__version__, "load_average_at_start": load_at_start, "threads": THREADS, "wall_s": round(wall, 1),
                  "keypoint_noise": {"file": NOISE_FILE.name, "offset": noise.offset.round(4).tolist(),
                                     "sigma": noise.sigma.round(4).tolist(), "missing": noise.missing.round(4).tolist(),
                                     "gross": noise.gross.round(4).tolist(), "gross_sigma": GROSS_SIGMA},
                  "fov_deg": list(FOV_DEG), "oracle_noise_max": ORACLE_NOISE_MAX, "drop_max": DROP_MAX,
                  "trials": [f.name for f in files if args.exclude_subject is None
                             or f.stem.split("_")[1] != args.exclude_subject]}
    lifter = Lifter(export_weights(net), attribution=ATTRIBUTION, provenance=provenance)
    checksum = lifter.save(args.out)
    if args.out.resolve() == SHIPPED.resolve():
        import os

        from mocap.io.files import write_json

        write_json(RECORD, {"sha256": checksum, "file": f"mocap/track/{LIFTER_FILE}",
                            "load_average_1_5_15": [round(v, 2) for v in os.getloadavg()],
                            "cpu_count": os.cpu_count(), **provenance})
    print(f"wrote {args.out}: sha256 {checksum} ({wall:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
