"""``python -m experiments.fit_pose_prior``: fit the tracker's pose prior on CMU motion capture.

Reads every trial of ``../shared/data/mocap/train/`` (200 CMU trials of nine subjects, ASF/AMC;
``--trials-from RECORD`` reads only the trials a prior file's ``training.trials`` lists, which is
how the shipped prior, fitted on the 41 trials of six subjects the folder held until 2026-11-27,
is reproduced), retargets it onto the 23-parameter model at 25 frames per second
(:func:`mocap.synth.retarget.retarget`), adds each pose's left/right mirror image (people use
either arm), and fits a Gaussian mixture over :data:`mocap.body.prior.PRIOR_PARAMETERS` with
scikit-learn (full covariances, k-means start, fixed seed). The number of components is chosen
on held-out subjects: each candidate is fitted on all subjects but one and scored on that one,
in turn; the best mean held-out log-likelihood wins and is refitted on all of them.

Writes ``mocap/body/pose_prior.json`` (a few tens of kB) with the attribution the data's README
asks for, the list of trials it was fitted on (``training.trials``, file names) and prints its
checksum. The checksum covers the mixture's parameters only, not the training record. The synthetic benchmark's motion is not used (no inverse
crime).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from experiments import EXPERIMENTS_DIR
from mocap.body.pose import PARAMETER_INDEX
from mocap.body.prior import PRIOR_FILE, PRIOR_INDEX, PosePrior
from mocap.io.files import write_json

#: Default training folder: ``../shared/data/mocap/train`` beside the repository.
TRAIN_DIR = EXPERIMENTS_DIR.parent.parent / "shared" / "data" / "mocap" / "train"
#: Attribution the CMU data's README asks for.
ATTRIBUTION = ('Fitted on trials of the CMU Graphics Lab Motion Capture Database: "The data used in this '
               'project was obtained from mocap.cs.cmu.edu. The database was created with funding from '
               'NSF EIA-0196217."')
#: Mixture sizes tried.
COMPONENTS = (4, 8, 16, 24)
#: Added to the covariances' diagonals (radians squared): about 1.8 degrees of spread at least.
REG_COVAR = 1e-3
SEED = 0


def positive_integers(text: str) -> tuple[int, ...]:
    """``"4,8,16"`` -> ``(4, 8, 16)``; an empty tuple unless the text is comma-separated positive integers."""
    try:
        values = tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        return ()
    return values if values and min(values) >= 1 else ()


def mirror_poses(poses: np.ndarray) -> np.ndarray:
    """Left/right mirror images of poses (the actor's right arm becomes the left, and so on).

    Parameters
    ----------
    poses : ndarray, shape (n, 23)

    Returns
    -------
    ndarray, shape (n, 23)
        Arm angles swapped between the sides (their signs are defined per side, so they carry
        over unchanged); chest yaw and roll, head tilt and turn negated; ``root_x`` negated.
    """
    out = poses.copy()
    for name in PARAMETER_INDEX:
        if name.startswith("r_"):
            left = "l_" + name[2:]
            out[:, PARAMETER_INDEX[name]] = poses[:, PARAMETER_INDEX[left]]
            out[:, PARAMETER_INDEX[left]] = poses[:, PARAMETER_INDEX[name]]
    for name in ("root_x", "chest_yaw", "chest_roll", "head_tilt", "head_turn"):
        out[:, PARAMETER_INDEX[name]] = -poses[:, PARAMETER_INDEX[name]]
    return out


def trial_files(train_dir: Path, trials=None) -> list[Path]:
    """The ``.amc`` trials of ``train_dir``, sorted by name: every one, or those named in ``trials``.

    Parameters
    ----------
    train_dir : Path
    trials : sequence of str, optional
        File names (``cmu_02_05.amc``); each must be in ``train_dir``.

    Raises
    ------
    FileNotFoundError
        When the folder has no trial, or a named trial is not there.
    """
    if trials is None:
        files = sorted(train_dir.glob("*.amc"))
        if not files:
            raise FileNotFoundError(f"no .amc trials in {train_dir}")
        return files
    missing = [t for t in trials if not (train_dir / t).is_file()]
    if missing or not trials:
        raise FileNotFoundError(f"trials not in {train_dir}: {missing[:5]}" if missing else "no trials named")
    return sorted(train_dir / t for t in trials)


def record_trials(record: Path) -> list[str]:
    """The trial file names a fitted model's record lists (``training.trials`` of a prior file, or
    ``trials`` at the top level of a lifter's record). ValueError when it lists none."""
    import json

    data = json.loads(Path(record).read_text())
    trials = data.get("training", {}).get("trials") if isinstance(data.get("training"), dict) else None
    trials = trials if trials is not None else data.get("trials")
    if not trials or not all(isinstance(t, str) and t.endswith(".amc") for t in trials):
        raise ValueError(f"{record} lists no training trials (.amc file names)")
    return list(trials)


def load_training_poses(train_dir: Path, trials=None) -> tuple[np.ndarray, np.ndarray]:
    """Retargeted poses of every trial (or of the named ones, :func:`trial_files`) and the subject
    of each pose.

    Returns
    -------
    poses : ndarray, shape (n, 23)
    subjects : ndarray of str, shape (n,)
    """
    from tqdm import tqdm

    from mocap.synth.retarget import load_clip, retarget

    files = trial_files(train_dir, trials)
    poses, subjects = [], []
    for path in tqdm(files, desc="retargeting", unit="trial"):
        q = retarget(load_clip(path))
        poses.append(q)
        subjects += [path.stem.split("_")[1]] * len(q)
    return np.concatenate(poses), np.array(subjects)


def fit(x: np.ndarray, n_components: int):
    """scikit-learn GaussianMixture fitted on ``x`` (n, d)."""
    from sklearn.mixture import GaussianMixture

    return GaussianMixture(n_components, covariance_type="full", reg_covar=REG_COVAR, n_init=1,
                           max_iter=500, random_state=SEED).fit(x)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.fit_pose_prior", description=__doc__.split("\n\n")[0])
    p.add_argument("--train", type=Path, default=TRAIN_DIR, help="folder of CMU .asf/.amc trials")
    p.add_argument("--out", type=Path, default=EXPERIMENTS_DIR.parent / "mocap" / "body" / PRIOR_FILE)
    p.add_argument("--components", default=",".join(map(str, COMPONENTS)),
                   help="comma-separated mixture sizes to choose from on held-out subjects (one size: "
                        "fitted without the choice)")
    p.add_argument("--trials-from", type=Path, default=None, metavar="RECORD",
                   help="fit only on the trials this prior file (or lifter record) lists, e.g. the shipped "
                        "mocap/body/pose_prior.json to reproduce it (default: every trial of --train)")
    args = p.parse_args(argv)
    sizes = positive_integers(args.components)
    if not sizes:
        print(f"error: --components takes positive integers, got {args.components!r}", file=sys.stderr)
        return 2
    if not args.train.is_dir():
        print(f"error: no training folder {args.train} (the CMU trials of ../shared/data/mocap/train)",
              file=sys.stderr)
        return 2
    try:
        trials = record_trials(args.trials_from) if args.trials_from is not None else None
        files = trial_files(args.train, trials)
    except (OSError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)            # one core: BLAS threads only fight each other on these sizes
    poses, subjects = load_training_poses(args.train, [f.name for f in files])
    poses = np.concatenate([poses, mirror_poses(poses)])
    subjects = np.concatenate([subjects, subjects])
    x = poses[:, PRIOR_INDEX]
    scores = {}
    for k in (sizes if len(sizes) > 1 else ()):
        held = [fit(x[subjects != s], k).score(x[subjects == s]) for s in np.unique(subjects)]
        scores[k] = float(np.mean(held))
        print(f"{k:3d} components: mean held-out log-likelihood {scores[k]:.2f} per pose", file=sys.stderr)
    best = max(scores, key=scores.get) if scores else sizes[0]
    gmm = fit(x, best)
    prior = PosePrior(gmm.weights_, gmm.means_, gmm.precisions_cholesky_, ATTRIBUTION)
    write_json(args.out, prior.to_dict(
        training={"subjects": sorted({str(s) for s in np.unique(subjects)}), "poses": int(len(x)),
                  "fps": 25.0, "mirrored": True, "held_out_log_likelihood": scores, "components": best,
                  "reg_covar": REG_COVAR, "seed": SEED,
                  "trials": [f.name for f in files]}))
    print(f"wrote {args.out}: {best} components, sha256 {prior.checksum}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
