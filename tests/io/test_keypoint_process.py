"""A keypoint detector in a process of its own: results in order and equal to the detector run
here, its errors, its death (one line), and no orphan when the parent is killed."""
from __future__ import annotations

import functools
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from mocap.io.keypoint_pipeline import KeypointPipeline
from mocap.io.keypoint_process import DetectorEnded, KeypointProcess
from tests.io.detectors import BrightestPixel, InProcess, to_keypoints

REPO_ROOT = Path(__file__).resolve().parents[2]


def _images(n, seed=0, shape=(24, 32, 3)):
    rng = np.random.default_rng(seed)
    return [rng.integers(0, 256, shape, dtype=np.uint8) for _ in range(n)]


def _same(a, b) -> bool:
    return a.uv.tobytes() == b.uv.tobytes() and a.confidence.tobytes() == b.confidence.tobytes()


def test_frames_ahead_come_back_in_order_equal_to_the_detector_run_here():
    images = _images(9) + _images(3, seed=1, shape=(40, 50, 3))     # a larger frame: its slot grows
    here = InProcess()
    expected = [here.keypoints(i, image) for i, image in enumerate(images)]
    with KeypointProcess(BrightestPixel, to_keypoints, depth=3) as process, \
            KeypointPipeline(process, depth=3) as pipeline:
        got = []
        for i, image in enumerate(images):
            if pipeline.pending == pipeline.depth:
                got.append(pipeline.take(len(got)))
            pipeline.submit(i, image)
            assert process.pending <= 3
        while pipeline.pending:
            got.append(pipeline.take(len(got)))
        assert len(process.milliseconds) == len(images)
        assert _same(process.keypoints(99, images[0]), expected[0])         # one frame there and back
        with pytest.raises(ValueError, match="more than the source's own"):
            KeypointPipeline(process, depth=4)
    assert all(_same(a, b) for a, b in zip(got, expected, strict=True))
    assert process._process.poll() == 0                 # closed: the child ended of itself


def test_the_detectors_errors_come_out_of_take_and_misuse_is_refused():
    images = _images(4)
    with KeypointProcess(functools.partial(BrightestPixel, fail_on=(2,)), to_keypoints, depth=2) as process:
        process.submit(0, images[0])
        process.submit(1, images[1])
        with pytest.raises(ValueError, match="take one first"):
            process.submit(2, images[2])
        with pytest.raises(ValueError, match="not the next frame"):
            process.take(1)
        process.take(0)
        with pytest.raises(RuntimeError, match="failed on its call 2"):
            process.take(1)
        assert process.keypoints(2, images[2]).present.sum() == 9     # it goes on
        with pytest.raises(ValueError, match="RGB uint8"):
            process.submit(3, images[3].astype(np.float32))
    with pytest.raises(ValueError, match="closed"):
        process.submit(3, images[3])
    process.close()                                     # twice: nothing happens
    with KeypointProcess(functools.partial(BrightestPixel, broken=True), to_keypoints) as process:
        with pytest.raises(ValueError, match="cannot open"):            # make() failed in the child
            process.keypoints(0, images[0])


def test_a_dead_detector_stops_with_one_line_saying_so():
    images = _images(5)
    with KeypointProcess(functools.partial(BrightestPixel, die_on=3), to_keypoints, depth=3) as process:
        for i in range(3):
            process.submit(i, images[i])
        process.take(0)
        process.take(1)
        with pytest.raises(DetectorEnded) as info:
            process.take(2)
    message = str(info.value)
    assert "\n" not in message and "signal 9 (SIGKILL)" in message and "frame 2" in message
    assert isinstance(info.value, ValueError)           # the commands' one-line errors


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a stopped process is told by /proc (Linux)")
def test_a_stopped_detector_is_killed_and_stops_the_run_with_one_line():
    """SIGSTOP on the second frame: take() does not hang; it kills the child and says so."""
    from mocap.io.keypoint_process import DetectorHung
    images = _images(3)
    process = KeypointProcess(functools.partial(BrightestPixel, stop_on=2), to_keypoints, depth=2)
    with process:
        process.submit(0, images[0])
        process.submit(1, images[1])
        process.take(0)
        with pytest.raises(DetectorHung) as info:
            process.take(1)
    message = str(info.value)
    assert "\n" not in message and "stopped (SIGSTOP)" in message and "frame 1" in message
    assert isinstance(info.value, DetectorEnded)           # the run layer treats it as an ended detector
    assert process._process.returncode == -signal.SIGKILL
    with pytest.raises(ValueError, match="closed"):
        process.submit(2, images[2])


def test_a_detector_that_never_answers_is_killed_after_the_time_out():
    """A child that runs but never answers (not stopped): the time-out. Whatever the machine's
    speed, the answer never comes, so the outcome does not depend on it."""
    from mocap.io.keypoint_process import DetectorHung
    with pytest.raises(ValueError, match="positive number of seconds"):
        KeypointProcess(BrightestPixel, to_keypoints, hung_after_s=0)
    with KeypointProcess(functools.partial(BrightestPixel, hang_on=1), to_keypoints, hung_after_s=1.0) as process:
        process.submit(0, _images(1)[0])
        with pytest.raises(DetectorHung, match="answered nothing for 1 s before frame 0"):
            process.take(0)
    assert process._process.returncode == -signal.SIGKILL


ORPHAN_SCRIPT = textwrap.dedent("""
    import sys, time
    import numpy as np
    from mocap.io.keypoint_process import KeypointProcess
    from tests.io.detectors import BrightestPixel, to_keypoints
    process = KeypointProcess(BrightestPixel, to_keypoints)
    process.keypoints(0, np.zeros((8, 8, 3), np.uint8))
    print(process.pid, process._slots[0].name, flush=True)
    time.sleep(600)
""")


def _ended(pid: int) -> bool:
    """Process ``pid`` has ended (gone, or a zombie nobody has reaped yet)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return True
    return state in ("Z", "X")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc and /dev/shm (Linux)")
def test_the_child_ends_when_its_parent_is_killed():
    parent = subprocess.Popen([sys.executable, "-c", ORPHAN_SCRIPT], cwd=REPO_ROOT, stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True)
    try:
        child, memory = parent.stdout.readline().split()
        child = int(child)
        assert not _ended(child)
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait()
        deadline = time.monotonic() + 60
        while not _ended(child) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _ended(child), "the detector's process outlived its parent"
        # the parent's resource tracker unlinks the shared memory once the parent has gone
        while Path("/dev/shm", memory).exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not Path("/dev/shm", memory).exists()
    finally:
        if parent.poll() is None:
            parent.kill()


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    from mocap.synth import generate_sequence
    return generate_sequence("gestures-1", tmp_path_factory.mktemp("seq") / "gestures-1", frames=10, seed=5,
                             progress=False)


def test_a_run_with_the_detector_in_its_process_writes_what_one_with_it_here_writes_even_resumed_after_it_died(
        sequence, tmp_path, monkeypatch):
    """poses.csv (timing columns aside), run.json's settings, poses.bvh and keypoints.csv are
    the same byte for byte with the detector in this process (on a thread) and in its own; a run
    whose detector's process is killed stops with one line, and the same command resumes it to
    the same files."""
    import mocap.run.journal
    import mocap.run.options
    from mocap.run import OwnVideoOptions, track
    from mocap.track import TrackerConfig
    from tests.io.test_keypoint_pipeline import _outputs

    monkeypatch.setattr(mocap.run.journal, "CHECKPOINT_EVERY", 4)      # checkpoints at frames 4 and 8
    options = OwnVideoOptions(tracker=TrackerConfig(evaluations=60, hypothesis_evaluations=20, jump_evaluations=10,
                                                    proposal_evaluations=10), overlay=False, keypoints="auto")

    def run(folder, source):
        monkeypatch.setattr(mocap.run.options, "_source", lambda resolved, auto: source)
        return track(sequence, tmp_path / folder, options, progress=False)

    class Described(InProcess):
        description = "a keypoint detector in its own process"      # the setting a resume compares

    run("here", Described())
    run("process", KeypointProcess(BrightestPixel, to_keypoints))
    with pytest.raises(DetectorEnded) as info:       # frame 8: after the checkpoint at 4
        run("resumed", KeypointProcess(functools.partial(BrightestPixel, die_on=9), to_keypoints))
    assert "\n" not in str(info.value) and "SIGKILL" in str(info.value)
    assert (tmp_path / "resumed" / mocap.run.journal.STATE_FILE).is_file()       # a checkpoint to resume from
    run("resumed", KeypointProcess(BrightestPixel, to_keypoints))
    names = ["here", "process", "resumed"]
    if sys.platform.startswith("linux"):          # a hung (stopped) detector: the same, from its checkpoint
        with pytest.raises(DetectorEnded, match="stopped"):
            run("after-hang", KeypointProcess(functools.partial(BrightestPixel, stop_on=9), to_keypoints))
        run("after-hang", KeypointProcess(BrightestPixel, to_keypoints))
        names.append("after-hang")
    here, *others = (_outputs(tmp_path / name) for name in names)
    assert len(here[0]) == 11 and here[4] is not None
    for other in others:
        assert other[0] == here[0] and other[1:] == here[1:]
