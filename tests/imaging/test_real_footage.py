"""The image side on real footage from ../shared/data (a few frames, kept fast)."""
from __future__ import annotations

import numpy as np
import pytest

from mocap.imaging import (ColourModel, detect_face, learn_colour_model, median_background,
                           prepare_frame)
from mocap.io.video import iter_frames

pytestmark = pytest.mark.shared_data


@pytest.fixture(scope="module")
def one_by_one(shared_data):
    path = shared_data / "video" / "intel_one-by-one-person-detection.mp4"
    frames = list(iter_frames(path, 0, 121))
    # frames 0-60 are the empty room; at 120 a woman stands at the table, seen from behind
    return median_background(frames[0:41:2]), frames[50], frames[120]


def test_real_background_subtraction(one_by_one):
    background, empty, person = one_by_one
    model = ColourModel.from_boxes(person, {"skin": (60, 430, 40, 40),  # her hair
                                            "clothes": (160, 410, 80, 80)})  # grey cardigan
    nobody = prepare_frame(empty, background, model)
    assert nobody.is_empty and not nobody.labels.any()
    found = prepare_frame(person, background, model)
    assert not found.is_empty
    fg = found.foreground
    assert 0.03 < fg.mean() < 0.2
    cols = np.flatnonzero(fg.any(axis=0))
    rows = np.flatnonzero(fg.any(axis=1))
    # hand-annotated: she spans columns ~385-515 and rows ~10-395 of the 768x432 frame
    assert 360 <= cols[0] <= 400 and 500 <= cols[-1] <= 540
    assert rows[0] <= 30 and 370 <= rows[-1] <= 410
    assert (found.labels[160:240, 410:490] == 2).mean() > 0.7  # the cardigan is clothes


def test_real_face_and_colour_model(shared_data):
    frame = next(iter_frames(shared_data / "video" / "intel_asl_sister.mkv"))
    face = detect_face(frame)
    assert face is not None
    # hand-annotated: his face is centred near row 140, column 303 of the 640x480 frame
    assert abs(face.row + face.height / 2 - 140) < 25 and abs(face.col + face.width / 2 - 303) < 25
    model = learn_colour_model(frame)
    labels = model.classify(frame)
    inner = labels[face.row + face.height // 3: face.row + 2 * face.height // 3,
                   face.col + face.width // 4: face.col + 3 * face.width // 4]
    assert (inner == 1).mean() > 0.7
