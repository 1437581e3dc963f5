"""The keypoint pipeline: a detector on its own thread, frames ahead, results in order; a run's
outputs are the same with and without it."""
import json
import threading

import numpy as np
import pytest

from mocap.io.keypoint_pipeline import KeypointPipeline
from mocap.io.keypoints import Keypoints


class ImageDetector:
    """A deterministic stand-in for a detector: joints placed from the image's content (its mean
    colour and brightest pixel) and the frame index, with the calls recorded."""

    def __init__(self, fail_on: int | None = None) -> None:
        self.calls: list[int] = []
        self.threads: set[str] = set()
        self.fail_on = fail_on

    def keypoints(self, frame_index, image):
        self.calls.append(int(frame_index))
        self.threads.add(threading.current_thread().name)
        if frame_index == self.fail_on:
            raise RuntimeError(f"detector failed on frame {frame_index}")
        h, w = image.shape[:2]
        grey = image.mean(axis=2)
        row, col = np.unravel_index(int(np.argmax(grey)), grey.shape)
        base = np.array([col + 0.5, row + 0.5])
        spread = np.linspace(-0.2, 0.2, 10)[:, None] * np.array([w, h]) * (0.5 + image.mean() / 510)
        uv = np.clip(base + spread + 0.1 * (frame_index % 5), 0.5, [w - 0.5, h - 0.5])
        confidence = np.full(10, 0.9)
        confidence[1] = 0.0                              # the neck: absent, as MediaPipe gives it
        return Keypoints(uv, confidence)


def _images(n, seed=0):
    rng = np.random.default_rng(seed)
    return [rng.integers(0, 256, (24, 32, 3), dtype=np.uint8) for _ in range(n)]


def test_results_come_in_order_equal_to_the_source_called_in_order():
    images = _images(9)
    direct = ImageDetector()
    expected = [direct.keypoints(i, im) for i, im in enumerate(images)]
    detector = ImageDetector()
    with KeypointPipeline(detector, depth=3) as pipeline:
        got = []
        for i, image in enumerate(images):
            if pipeline.pending == pipeline.depth:
                got.append(pipeline.take(len(got)))
            pipeline.submit(i, image)
            assert pipeline.pending <= 3                 # memory bounded
        while pipeline.pending:
            got.append(pipeline.take(len(got)))
    assert detector.calls == list(range(9))
    assert detector.threads == {"mocap-detector"}
    for a, b in zip(got, expected):
        np.testing.assert_array_equal(a.uv, b.uv)
        np.testing.assert_array_equal(a.confidence, b.confidence)


def test_its_errors_and_misuse():
    images = _images(5)
    with KeypointPipeline(ImageDetector(fail_on=2), depth=2) as pipeline:
        pipeline.submit(0, images[0])
        assert pipeline.take(0).present.sum() == 9
        pipeline.submit(1, images[1])
        with pytest.raises(ValueError, match="already"):
            pipeline.submit(1, images[1])
        with pytest.raises(ValueError, match="not the next frame"):
            pipeline.take(2)
        pipeline.submit(2, images[2])
        with pytest.raises(ValueError, match="take one first"):     # depth 2: a third waits for a take
            pipeline.submit(3, images[3])
        pipeline.take(1)
        with pytest.raises(RuntimeError, match="failed on frame 2"):
            pipeline.take(2)
        pipeline.submit(3, images[3])                   # the detector goes on after an error
        assert pipeline.take(3).present.sum() == 9
        pipeline.submit(4, images[4])                   # in flight at the close: dropped
    with pytest.raises(ValueError, match="closed"):
        pipeline.submit(5, images[0])
    pipeline.close()                                     # twice: nothing happens
    with pytest.raises(ValueError, match="depth"):
        KeypointPipeline(ImageDetector(), depth=0)


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    from mocap.synth import generate_sequence
    return generate_sequence("gestures-1", tmp_path_factory.mktemp("seq") / "gestures-1", frames=10, seed=5,
                             progress=False)


#: Columns of poses.csv and keys of run.json that are clock readings.
TIMING_COLUMNS = ("ms_",)


def _outputs(folder):
    lines = (folder / "poses.csv").read_text().splitlines()
    header = lines[0].split(",")
    keep = [i for i, name in enumerate(header) if not name.startswith(TIMING_COLUMNS)]
    rows = [[line.split(",")[i] for i in keep] for line in lines]
    run = json.loads((folder / "run.json").read_text())
    journal = folder / "keypoints.csv"
    return (rows, run["settings"], (folder / "poses.bvh").read_bytes(), run.get("metrics", {}).get("mpjpe_mm"),
            journal.read_bytes() if journal.is_file() else None)


def test_a_run_with_the_detector_ahead_writes_what_a_sequential_run_writes(sequence, tmp_path, monkeypatch):
    """poses.csv (timing columns aside), run.json's settings and metrics, poses.bvh and the
    keypoints' journal are the same byte for byte whether the detector runs ahead on its own thread or frame by frame on the
    reader thread; the detector sees the same frames in the same order."""
    import functools

    import mocap.run.options
    import mocap.run.tracking
    from mocap.run import OwnVideoOptions, track
    from mocap.run.loop import RunParams
    from mocap.track import TrackerConfig

    detectors = {}
    for ahead in (0, 3):
        detectors[ahead] = detector = ImageDetector()
        monkeypatch.setattr(mocap.run.tracking, "RunParams", functools.partial(RunParams, detect_ahead=ahead))
        monkeypatch.setattr(mocap.run.options, "_source", lambda resolved, auto, d=detector: d)
        options = OwnVideoOptions(tracker=TrackerConfig(evaluations=60, hypothesis_evaluations=20,
                                                        jump_evaluations=10, proposal_evaluations=10),
                                  overlay=False, keypoints="auto")
        track(sequence, tmp_path / f"ahead{ahead}", options, progress=False)
    assert detectors[0].calls == detectors[3].calls and len(detectors[0].calls) >= 10
    assert "mocap-detector" in detectors[3].threads and "mocap-detector" not in detectors[0].threads
    sequential, pipelined = _outputs(tmp_path / "ahead0"), _outputs(tmp_path / "ahead3")
    assert sequential[0] == pipelined[0] and len(sequential[0]) == 11
    assert sequential[1:] == pipelined[1:]
