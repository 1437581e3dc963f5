"""Colour model: HSV kernel, classification vs its twin, circular hue, learning, JSON."""
from __future__ import annotations

import json

import numpy as np
import pytest
from skimage import data

from mocap.imaging import (Box, ColourModel, detect_face, learn_colour_model, rgb_to_hsv,
                           subtract_background)
from mocap.imaging.colour import clothes_box_of_face, skin_box_of_face
from mocap.imaging.config import DEFAULT_COLOUR_THRESHOLD
from mocap.imaging.testing import synthetic_scene_with_labels
from mocap.labels import UNKNOWN
from tests.naive import naive_classify, naive_hsv


def hsv_to_rgb_pixels(h_deg, s, v):
    from skimage.color import hsv2rgb

    hsv = np.stack([np.asarray(h_deg, float) / 360.0, np.broadcast_to(s, np.shape(h_deg)),
                    np.broadcast_to(v, np.shape(h_deg))], axis=-1)
    return hsv2rgb(hsv[np.newaxis])[0]


# -- HSV and classification kernels vs twins

def test_rgb_to_hsv_equals_skimage():
    rng = np.random.default_rng(0)
    image = rng.integers(0, 256, (20, 30, 3), dtype=np.uint8)
    image[0, :3] = [[7, 7, 7], [0, 0, 0], [255, 0, 255]]  # grey, black, magenta
    np.testing.assert_allclose(rgb_to_hsv(image), naive_hsv(image), atol=1e-9)
    np.testing.assert_allclose(rgb_to_hsv(image / 255.0), naive_hsv(image / 255.0), atol=1e-9)


def _random_model(rng, m):
    means = np.column_stack([rng.uniform(0, 360, m), rng.uniform(0.1, 0.9, m),
                             rng.uniform(0.2, 0.9, m)])
    covs = []
    for _ in range(m):
        a = rng.normal(0, 1, (3, 3)) * [40.0, 0.1, 0.1]
        covs.append(a.T @ a + np.diag([25.0, 0.002, 0.002]))
    return ColourModel([f"c{i}" for i in range(m)], means, covs)


@pytest.mark.parametrize("m", [1, 2, 4])
def test_classify_equals_naive_twin(m):
    rng = np.random.default_rng(m)
    model = _random_model(rng, m)
    image = rng.integers(0, 256, (24, 32, 3), dtype=np.uint8)
    foreground = rng.random((24, 32)) < 0.8
    expected = naive_classify(image, foreground, model.means, model.covariances,
                              DEFAULT_COLOUR_THRESHOLD)
    got = model.classify(image, foreground)
    np.testing.assert_array_equal(got, expected)
    assert (got[~foreground] == 0).all()
    # a loose threshold labels more pixels (the test can see a difference)
    loose = model.classify(image, foreground, threshold=1e6)
    assert (loose != UNKNOWN).sum() >= (got != UNKNOWN).sum()
    np.testing.assert_array_equal(loose, naive_classify(image, foreground, model.means,
                                                        model.covariances, 1e6))


# -- circular hue

def test_red_hues_either_side_of_zero_fall_in_the_same_class():
    rng = np.random.default_rng(0)
    hues = np.concatenate([rng.uniform(350, 360, 200), rng.uniform(0, 10, 200)])
    skin = hsv_to_rgb_pixels(hues, rng.uniform(0.45, 0.55, 400), rng.uniform(0.75, 0.85, 400))
    green = hsv_to_rgb_pixels(rng.uniform(110, 130, 400), 0.5, 0.5)
    model = ColourModel.from_samples({"skin": skin, "clothes": green})
    # the circular mean is red (near 0/360), not cyan (180) as a linear mean would give
    assert min(model.means[0, 0], 360 - model.means[0, 0]) < 3
    assert np.sqrt(model.covariances[0, 0, 0]) < 10  # spread of about 6 degrees, not 180
    test = hsv_to_rgb_pixels(np.array([357.0, 359.5, 0.5, 3.0]), 0.5, 0.8)[np.newaxis]
    np.testing.assert_array_equal(model.classify(test)[0], [1, 1, 1, 1])
    # cyan with the same saturation and value is not skin
    cyan = hsv_to_rgb_pixels(np.array([180.0]), 0.5, 0.8)[np.newaxis]
    assert model.classify(cyan)[0, 0] == UNKNOWN


def test_learning_ignores_a_minority_colour_in_the_sample_box():
    rng = np.random.default_rng(1)
    blue = hsv_to_rgb_pixels(rng.uniform(215, 225, 700), 0.7, 0.6)
    white = np.full((300, 3), 0.97)  # a logo or a strap
    model = ColourModel.from_samples({"clothes": np.concatenate([blue, white])})
    assert abs(model.means[0, 0] - 220) < 3 and abs(model.means[0, 1] - 0.7) < 0.03
    assert model.classify(white[np.newaxis, :5])[0].tolist() == [UNKNOWN] * 5


def test_achromatic_class_ignores_hue():
    rng = np.random.default_rng(2)
    grey = np.clip(0.2 + rng.normal(0, 0.01, (500, 3)), 0, 1)  # dark clothes: hue is noise
    model = ColourModel.from_samples({"clothes": grey})
    tinted = np.array([[[0.21, 0.2, 0.19], [0.19, 0.2, 0.21], [0.2, 0.21, 0.2]]])
    np.testing.assert_array_equal(model.classify(tinted), [[1, 1, 1]])


# -- face detection and learning on scikit-image's astronaut

@pytest.fixture(scope="module")
def astronaut():
    return data.astronaut()


def test_detect_face_finds_the_astronaut_face(astronaut):
    face = detect_face(astronaut)
    assert face is not None
    centre = (face.row + face.height / 2, face.col + face.width / 2)
    # hand-annotated: her face spans rows ~65-180, columns ~165-290 of the 512x512 photo
    assert 95 <= centre[0] <= 150 and 195 <= centre[1] <= 260
    assert 60 <= face.height <= 130


def test_colour_model_learned_on_astronaut(astronaut):
    model = learn_colour_model(astronaut)
    assert model.names == ("skin", "clothes")
    labels = model.classify(astronaut)
    face = labels[92:143, 194:245]  # central face: skin but eyes, brows and mouth
    assert (face == 1).mean() > 0.85
    for r, c, h, w in [(330, 40, 120, 70), (290, 280, 60, 60)]:  # orange suit: arm, chest
        suit = labels[r:r + h, c:c + w]
        assert (suit == 2).mean() > 0.8
        assert (suit == 1).mean() < 0.05
    sky = labels[20:60, 300:360]  # grey backdrop: neither class
    assert (sky == UNKNOWN).mean() > 0.9


def test_no_face_and_no_boxes_is_a_clear_error():
    scene = synthetic_scene_with_labels(160, 120, 0)  # a drawn face the cascade does not see
    assert detect_face(scene.frame) is None
    with pytest.raises(ValueError, match="no face found.*skin_box and clothes_box"):
        learn_colour_model(scene.frame)
    with pytest.raises(ValueError, match="no face found.*clothes_box"):
        learn_colour_model(scene.frame, skin_box=skin_box_of_face(scene.face_box))


def test_learning_from_user_boxes_labels_the_synthetic_person():
    scene = synthetic_scene_with_labels(320, 240, 1)
    model = learn_colour_model(scene.frame, scene.background,
                               skin_box=skin_box_of_face(scene.face_box),
                               clothes_box=scene.clothes_box)
    fg = subtract_background(scene.frame, scene.background)
    labels = model.classify(scene.frame, fg)
    for label in (1, 2):
        truth = scene.labels == label
        assert (labels[truth & fg] == label).mean() > 0.95
    assert (labels[(scene.labels == 2) & fg] == 1).mean() < 0.01


def test_boxes_must_be_valid():
    frame = np.zeros((50, 60, 3), np.uint8)
    with pytest.raises(ValueError, match="outside"):
        ColourModel.from_boxes(frame, {"skin": (100, 100, 5, 5)})
    with pytest.raises(ValueError, match="four integers"):
        ColourModel.from_boxes(frame, {"skin": (1, 2, 3)})
    with pytest.raises(ValueError, match="only 4 sample pixels"):
        ColourModel.from_boxes(frame, {"skin": (0, 0, 2, 2)})
    fg = np.zeros((50, 60), bool)
    with pytest.raises(ValueError, match="foreground pixels"):
        ColourModel.from_boxes(frame, {"skin": (0, 0, 20, 20)}, foreground=fg)


def test_clothes_box_is_under_the_face():
    face = Box(10, 50, 20, 16)
    clothes = clothes_box_of_face(face)
    assert clothes.row >= face.row + face.height
    assert clothes.col < face.col + face.width / 2 < clothes.col + clothes.width


# -- persistence and validation

def test_json_round_trip(tmp_path):
    model = _random_model(np.random.default_rng(5), 3)
    path = tmp_path / "colours.json"
    model.to_json(path)
    again = ColourModel.from_json(path)
    assert again.names == model.names
    np.testing.assert_array_equal(again.means, model.means)
    np.testing.assert_array_equal(again.covariances, model.covariances)
    data_ = json.loads(path.read_text())
    data_["extra"] = 1
    with pytest.raises(ValueError, match="unknown"):
        ColourModel.from_dict(data_)
    path.write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        ColourModel.from_json(path)
    with pytest.raises(FileNotFoundError):
        ColourModel.from_json(tmp_path / "missing.json")


@pytest.mark.parametrize("means, covs, message", [
    ([[0, 0.5, 0.5]], [np.eye(3) * -1], "positive-definite"),
    ([[0, 0.5, 0.5]], [[[1, 2, 0], [0, 1, 0], [0, 0, 1]]], "symmetric"),
    ([[0, 0.5]], [np.eye(3)], "means must be"),
    ([[np.nan, 0.5, 0.5]], [np.eye(3)], "finite"),
])
def test_invalid_models_are_rejected(means, covs, message):
    with pytest.raises(ValueError, match=message):
        ColourModel(["skin"], means, covs)


def test_classify_rejects_bad_input():
    model = _random_model(np.random.default_rng(0), 2)
    with pytest.raises(ValueError, match="grayscale"):
        model.classify(np.zeros((5, 5), np.uint8))
    with pytest.raises(ValueError, match="foreground"):
        model.classify(np.zeros((5, 5, 3), np.uint8), np.zeros((5, 6), bool))
    with pytest.raises(ValueError, match="threshold"):
        model.classify(np.zeros((5, 5, 3), np.uint8), threshold=-1.0)


# -- optional classes: merged when the image does not tell them apart

def _pixels(rng, h_deg, s, v, n=200, spread=(3.0, 0.03, 0.03)):
    return hsv_to_rgb_pixels(rng.normal(h_deg, spread[0], n) % 360, np.clip(rng.normal(s, spread[1], n), 0, 1),
                             np.clip(rng.normal(v, spread[2], n), 0, 1))


def test_optional_classes_merge_when_the_image_lacks_them():
    from mocap.labels import CLASS_MERGES_INTO
    rng = np.random.default_rng(3)
    skin, clothes = _pixels(rng, 25, 0.45, 0.8), _pixels(rng, 220, 0.6, 0.5)
    hair, trousers = _pixels(rng, 25, 0.6, 0.3), _pixels(rng, 100, 0.5, 0.3)
    kept = ColourModel.from_samples({"skin": skin, "clothes": clothes, "hair": hair, "lower_body": trousers},
                                    CLASS_MERGES_INTO)
    assert kept.names == ("skin", "clothes", "hair", "lower_body")
    assert abs(kept.means[2, 2] - 0.3) < 0.02                  # the hair's own value, not the face's
    # a bald head (its "hair" is skin), trousers like the shirt, and a sample too small to learn
    bald = ColourModel.from_samples({"skin": skin, "clothes": clothes, "hair": _pixels(rng, 25, 0.45, 0.8),
                                     "lower_body": _pixels(rng, 220, 0.6, 0.5)}, CLASS_MERGES_INTO)
    assert bald.names == ("skin", "clothes")
    small = ColourModel.from_samples({"skin": skin, "clothes": clothes, "hair": hair[:5]}, CLASS_MERGES_INTO)
    assert small.names == ("skin", "clothes")
    # without merges every class is learnt, and a class that merges into nothing must be given
    assert ColourModel.from_samples({"skin": skin, "hair": _pixels(rng, 25, 0.45, 0.8)}).names == ("skin", "hair")
    with pytest.raises(ValueError, match="merges into no other"):
        ColourModel.from_samples({"hair": hair}, CLASS_MERGES_INTO)


def test_learn_colour_model_takes_hair_and_lower_body_boxes():
    scene = synthetic_scene_with_labels(160, 120, 0)
    frame = scene.frame.copy()
    face = skin_box_of_face(scene.face_box)
    hair_box = Box(max(face.row - 6, 0), face.col, 4, face.width)
    frame[hair_box.slices] = (40, 25, 15)                     # dark-brown hair painted above the face
    lower = Box(frame.shape[0] - 6, scene.clothes_box.col, 6, scene.clothes_box.width)
    frame[lower.slices] = (20, 60, 30)                        # dark-green trousers at the bottom
    model = learn_colour_model(frame, skin_box=face, clothes_box=scene.clothes_box, hair_box=hair_box,
                               lower_body_box=lower)
    assert model.names == ("skin", "clothes", "hair", "lower_body")
    labels = model.classify(frame)
    assert np.mean(labels[hair_box.slices] == 3) > 0.9 and np.mean(labels[lower.slices] == 4) > 0.9
    # the same boxes painted in the face's and the clothes' colours merge away
    same = scene.frame.copy()
    same[hair_box.slices] = same[face.slices].reshape(-1, 3)[: hair_box.height * hair_box.width].reshape(
        hair_box.height, hair_box.width, 3)
    merged = learn_colour_model(same, skin_box=face, clothes_box=scene.clothes_box, hair_box=hair_box)
    assert merged.names == ("skin", "clothes")



def test_chi_square_figures_are_scipy_stats():
    """The colour model's chi-square figures come from scipy.special (scipy.stats is slow to
    import): the same numbers as scipy.stats.chi2's."""
    from scipy import stats
    from mocap.imaging import colour
    assert colour.MERGE_DISTANCE2 == float(stats.chi2.ppf(0.5, 3))
    assert colour.MODE_CUT2 == stats.chi2.ppf(0.95, 3)
    cut = stats.chi2.ppf(0.95, 3)
    assert colour.MODE_CONSISTENCY == stats.chi2.cdf(cut, 3) / stats.chi2.cdf(cut, 5)
