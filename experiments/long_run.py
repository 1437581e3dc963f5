"""``python -m experiments.long_run``: a run's memory does not grow with its length.

Tracks a long clip at 160x120 through the whole run (:func:`mocap.run.track`:
image side, tracker, ``poses.csv`` journal and checkpoint after every frame) and samples the
process's resident set size (Linux ``/proc/self/status``) against the number of frames written.
The clip is a short synthetic sequence repeated (a folder of symbolic links), so a 10,000-frame
run costs no 10,000 rendered frames. Prints the RSS at a few frame counts and the change from
``--from`` to the end.

Measured on 2026-11-24 (20 evaluations per frame, 41 frames/s): 251,036 kB at frame 510 and
251,268 kB at frame 9,987, +232 kB, about half of it this script's own list of ~1,000 samples
(sampling at the checkpoint writes instead, without that list: 250,948 kB at both, +0 kB).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import threading
from pathlib import Path


def resident_kb() -> int:
    """This process's resident set size, kB (Linux)."""
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise OSError("no VmRSS in /proc/self/status (Linux only)")


class _Sampler(threading.Thread):
    """Every ``interval`` seconds: (rows in the journal, RSS kB), the journal read incrementally."""

    def __init__(self, journal: Path, interval: float = 0.5) -> None:
        super().__init__(daemon=True)
        self.journal, self.interval = journal, interval
        self.samples: list[tuple[int, int]] = []
        self._offset = self._lines = 0
        self._done = threading.Event()

    def _rows(self) -> int:
        if self.journal.exists():
            with self.journal.open("rb") as fh:
                fh.seek(self._offset)
                data = fh.read()
            self._offset += len(data)
            self._lines += data.count(b"\n")
        return max(0, self._lines - 1)                 # less the header

    def run(self) -> None:
        while not self._done.wait(self.interval):
            self.samples.append((self._rows(), resident_kb()))

    def stop(self) -> None:
        self._done.set()
        self.join()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.long_run", description=__doc__.split("\n\n")[0])
    p.add_argument("--frames", type=int, default=10_000, help="frames of the run (default 10,000)")
    p.add_argument("--from", dest="first", type=int, default=500, help="frame from which RSS must be flat")
    p.add_argument("--iterations", type=int, default=20, help="cost evaluations per frame (default 20)")
    p.add_argument("--work", type=Path, help="working folder (default: a temporary one)")
    args = p.parse_args(argv)
    if args.frames <= args.first or args.first < 1 or args.iterations < 1:
        p.error("need 1 <= --from < --frames and --iterations >= 1")

    import mocap.run
    from mocap.run.files import POSES_CSV
    from mocap.synth import generate_sequence
    from mocap.track import TrackerConfig

    with tempfile.TemporaryDirectory() as tmp:
        work = args.work or Path(tmp)
        seq = generate_sequence("gestures-2", work / "seq", frames=40, seed=3, progress=False)
        frames = sorted((seq / "frames").iterdir())
        loop = work / "loop"
        loop.mkdir(exist_ok=True)
        for i in range(args.frames):
            link = loop / f"{i:06d}{frames[0].suffix}"
            if not link.exists():
                link.symlink_to(frames[i % len(frames)])
        out = work / "run"
        sampler = _Sampler(out / POSES_CSV)
        sampler.start()
        try:
            options = mocap.run.OwnVideoOptions(background=str(seq / "background.png"),
                                                calibration=str(seq / "calibration.json"), overwrite=True,
                                                overlay=False, tracker=TrackerConfig(evaluations=args.iterations),
                                                keypoints="none")
            summary = mocap.run.track(loop, out, options)
        finally:
            sampler.stop()
    during = [(rows, kb) for rows, kb in sampler.samples if rows < args.frames]     # not the final outputs
    start = next(kb for rows, kb in during if rows >= args.first)
    for mark in sorted({args.first, args.frames // 4, args.frames // 2, during[-1][0]}):
        rows, kb = next((r, k) for r, k in during if r >= mark)
        print(f"frame {rows:6d}: RSS {kb:,} kB")
    end = during[-1][1]
    print(f"{summary.frames} frames at {summary.fps:.0f} frames/s; RSS from frame {args.first} to "
          f"{during[-1][0]}: {end - start:+,} kB (peak in between {max(k for r, k in during if r >= args.first):,} kB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
