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
#: Frames of the long run, and the frame after which memory must stay flat.
N_FRAMES, WARM_UP = 1000, 200
#: Allowed change of traced Python memory over the last frames, bytes (the unbounded history of
#: accepted poses grew by about 300 bytes a frame: 240 kB here; the beam tracker's window and its
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
