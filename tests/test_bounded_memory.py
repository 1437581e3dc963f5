"""A long run holds a constant amount of tracker state: memory does not grow with the run's length."""
from __future__ import annotations

import gc
import tracemalloc

import numpy as np
from scipy import ndimage

from mocap.body import PARAMETER_INDEX as P, BodyModel, neutral_pose
from mocap.imaging import PreparedFrame
from mocap.render import Camera, render
from mocap.track import Tracker, TrackerConfig

MODEL = BodyModel.build(resolution=4)
CAMERA = Camera.default(80, 60)
#: Frames of the long run, and the frame after which memory must stay flat (1,000 and 200 until
#: the suite had to fit 6 minutes: the leak below shows as well over 450 frames).
N_FRAMES, WARM_UP = 600, 150
#: Allowed change of traced Python memory over the last frames, bytes (the unbounded history of
#: accepted poses grew by about 300 bytes a frame: 135 kB here; the beam tracker's window and its
#: per-frame objects moved it by 5 kB alone and 34 kB inside the whole suite, where other tests'
#: leftover threads allocate meanwhile: tracemalloc counts every thread).
FLAT_BYTES = 80_000


def frames(n: int) -> list[PreparedFrame]:
    """``n`` clean frames of a waving right arm."""
    out = []
    for k in range(n):
        pose = neutral_pose()
        pose[P["r_shoulder_abd"]] = np.radians(30.0 + 40.0 * k / n)
        r = render(pose, MODEL, CAMERA)
        distance = np.minimum(ndimage.distance_transform_edt(~r.edges), 20.0).astype(np.float32)
        out.append(PreparedFrame(r.labels, r.labels != 0, r.edges, distance, False, {}))
    return out


def state_bytes(tracker: Tracker) -> int:
    return sum(v.nbytes for v in tracker.state().values())


def test_long_run_keeps_a_constant_state_and_flat_memory():
    config = TrackerConfig(evaluations=4, hypothesis_evaluations=2, jump_evaluations=2, recovery=False,
                           hand_reacquisition=False)
    tracker = Tracker(MODEL, CAMERA, config, neutral_pose())
    clip = frames(6)
    states = {}
    tracemalloc.start()
    try:
        for i in range(N_FRAMES):
            if i == WARM_UP:
                gc.collect()                  # count what is reachable, not garbage awaiting collection
                states[i], (memory_start, _) = state_bytes(tracker), tracemalloc.get_traced_memory()
            for result in tracker.push(i, clip[i % len(clip)]):
                assert result.frame <= i
        gc.collect()
        states[N_FRAMES], (memory_end, _) = state_bytes(tracker), tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # the beam and the decoder's window of ``lag`` frames, whatever the length (the numbers in them
    # are stored as text, so their size moves a little with the digits)
    assert tracker.pending == config.lag
    assert abs(states[N_FRAMES] - states[WARM_UP]) < 0.1 * states[WARM_UP]
    assert abs(memory_end - memory_start) < FLAT_BYTES, (memory_start, memory_end)


#: Peak memory (resident set, MB) ``track`` may reach on the large clip below: the program with
#: its libraries (about 300 MB) and a fixed number of working-size frames. Holding the clip's
#: frames at input size, as the set-up did before (up to 1,500 of them for the background
#: estimate), would take more than this for the frames alone.
TRACK_PEAK_MB = 450


def test_track_peak_memory_does_not_grow_with_the_clip(tmp_path):
    """``python -m mocap track`` with a calibration on a 640x480, 520-frame clip (a synthetic actor
    enlarged 4x, looped): peak RSS measured by the OS (``getrusage`` of a wrapper's children)."""
    import subprocess
    import sys

    import imageio_ffmpeg

    from mocap.synth import generate_sequence

    seq = generate_sequence("gestures-1", tmp_path / "seq", frames=12, seed=0, progress=False)
    clip, frames, size = tmp_path / "clip.mp4", 520, (640, 480)
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-y", "-stream_loop", "-1", "-framerate", "25",
                    "-i", str(seq / "frames" / "%06d.png"), "-frames:v", str(frames), "-vf",
                    f"scale={size[0]}:{size[1]}:flags=neighbor", "-c:v", "libx264", "-preset", "ultrafast",
                    "-pix_fmt", "yuv420p", str(clip)], check=True)
    assert frames * size[0] * size[1] * 3 > TRACK_PEAK_MB * 2 ** 20      # the clip's frames alone would not fit
    wrapper = ("import resource, subprocess, sys; "
               "code = subprocess.run([sys.executable, '-m', 'mocap', 'track', *sys.argv[1:]]).returncode; "
               "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss); sys.exit(code)")
    # the calibration given (no face search, at the working size 160x120); the background found
    # from the clip, as with no option at all: frames sampled over the whole clip
    done = subprocess.run([sys.executable, "-c", wrapper, str(clip), "--calibration", str(seq / "calibration.json"),
                           "--out", str(tmp_path / "run"), "--max-frames", "2", "--iterations", "20", "--no-overlay",
                           "--keypoints", "none"],          # the tracker's memory, not MediaPipe's
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    peak_mb = int(done.stdout.split()[-1]) / 1024                  # ru_maxrss: kilobytes on Linux
    print(f"peak RSS {peak_mb:.0f} MB")
    assert peak_mb < TRACK_PEAK_MB, peak_mb
