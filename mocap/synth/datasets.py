"""The benchmark set: the six named sequences, and the small default sequence bundled in ``data/``.

``python -m mocap.synth.datasets [--out DIR] [--seed S] [--size WxH] [--frames N] [--only NAME ...]``
regenerates every named sequence into ``DIR/<name>`` (default ``data/cache``, which git
ignores); ``--default`` rewrites the bundled default sequence instead (``data/default``, the
settings of :data:`DEFAULT_SEQUENCE`). ``data/make_benchmark.py`` runs the former from anywhere.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path
from types import MappingProxyType

from tqdm import tqdm

import mocap
from mocap.synth.sequence import SEQUENCE_NAMES, generate_sequence, parse_size

__all__ = ["DEFAULT_SEQUENCE", "bundled_default_sequence", "data_folder", "default_sequence", "main",
           "make_benchmark", "make_default_sequence"]

#: Settings of the sequence bundled in ``data/default`` (used by ``python -m mocap demo`` and the
#: tests): 80 frames (3.2 s) of gestures-1 at 160 x 120, the camera's JPEG frames (a PNG copy
#: would be four times larger).
DEFAULT_SEQUENCE = MappingProxyType({"name": "gestures-1", "frames": 80, "seed": 0, "size": (160, 120),
                                     "frame_format": "jpg"})


def data_folder() -> Path:
    """The repository's ``data`` folder (beside the ``mocap`` package of a source checkout)."""
    return Path(mocap.__file__).resolve().parent.parent / "data"


def bundled_default_sequence() -> Path:
    """The bundled default sequence folder.

    Raises
    ------
    FileNotFoundError
        If this installation has no ``data/default`` (e.g. installed from a wheel); regenerate it
        with ``python -m mocap.synth.datasets --default --out DIR``.
    """
    folder = data_folder() / "default"
    if not (folder / "meta.json").is_file():
        raise FileNotFoundError(f"no bundled default sequence at {folder}; write one with "
                                "'python -m mocap.synth.datasets --default --out DIR'")
    return folder


def make_default_sequence(out: str | Path, *, frames: int | None = None, progress: bool = True) -> Path:
    """Write the default sequence (:data:`DEFAULT_SEQUENCE`; only its first ``frames`` frames
    when given) to ``out``."""
    s = DEFAULT_SEQUENCE
    return generate_sequence(s["name"], out, frames=s["frames"] if frames is None else frames, seed=s["seed"],
                             size=s["size"], frame_format=s["frame_format"], progress=progress)


def default_sequence(out: str | Path | None = None, *, frames: int | None = None, progress: bool = True) -> Path:
    """The bundled default sequence folder; where this installation has none (e.g. a wheel), the
    same sequence generated into ``out`` (default: a new temporary folder), or found there from an
    earlier call.

    Parameters
    ----------
    out : str or Path, optional
        Where to generate it when it is not bundled.
    frames : int, optional
        Generate only the first ``frames`` frames (the bundled folder has all 80).
    progress : bool
        Progress bar while generating.
    """
    try:
        return bundled_default_sequence()
    except FileNotFoundError:
        pass
    out = Path(tempfile.mkdtemp(prefix="mocap-default-")) if out is None else Path(out)
    if (out / "meta.json").is_file():
        return out
    return make_default_sequence(out, frames=frames, progress=progress)


def make_benchmark(out: str | Path, *, seed: int = 0, size=(160, 120), frames: int | None = None,
                   names: tuple[str, ...] = SEQUENCE_NAMES, frame_format: str = "png",
                   progress: bool = True) -> list[Path]:
    """Write the named sequences to ``out/<name>``.

    Parameters
    ----------
    out : str or Path
    seed : int
    size : (int, int)
        Width and height, pixels.
    frames : int, optional
        Frames per sequence (default: each sequence's own).
    names : tuple of str
        Which sequences (default all six).
    frame_format : {"png", "jpg"}
    progress : bool

    Returns
    -------
    list of Path
        The sequence folders.
    """
    unknown = [n for n in names if n not in SEQUENCE_NAMES]
    if unknown:
        raise ValueError(f"unknown sequence(s) {', '.join(unknown)}; choose from {', '.join(SEQUENCE_NAMES)}")
    out = Path(out)
    return [generate_sequence(name, out / name, frames=frames, seed=seed, size=size, frame_format=frame_format,
                              progress=progress)
            for name in tqdm(names, desc="benchmark", unit="sequence", disable=not progress)]


def main(argv: list[str] | None = None, *, default_out: Path | None = None) -> int:
    """Command line; see the module docstring. Returns the exit status."""
    parser = argparse.ArgumentParser(prog="python -m mocap.synth.datasets",
                                     description="Regenerate the synthetic benchmark sequences.")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="output folder (default data/cache, or data/default with --default)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--size", metavar="WxH", default="160x120")
    parser.add_argument("--frames", metavar="N", type=int, default=None)
    parser.add_argument("--only", metavar="NAME", nargs="+", default=list(SEQUENCE_NAMES),
                        help=f"sequences to write (default all: {', '.join(SEQUENCE_NAMES)})")
    parser.add_argument("--format", dest="frame_format", choices=("png", "jpg"), default="png")
    parser.add_argument("--default", action="store_true",
                        help="write the bundled default sequence (fixed settings) instead")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    try:
        if args.default:
            out = Path(args.out) if args.out else data_folder() / "default"
            folders = [make_default_sequence(out)]
        else:
            out = Path(args.out) if args.out else (default_out or Path("data") / "cache")
            folders = make_benchmark(out, seed=args.seed, size=parse_size(args.size), frames=args.frames,
                                     names=tuple(args.only), frame_format=args.frame_format)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    for f in folders:
        print(f)
    print(f"{len(folders)} sequence(s) in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
