"""prepare_frame: the contract others rely on, the empty scene and bad input."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import ndimage as ndi

from mocap.imaging import (ColourModel, ImagingConfig, PreparedFrame, detect_edges, distance_map,
                           prepare_frame, subtract_background)
from mocap.imaging.colour import skin_box_of_face
from mocap.imaging.testing import synthetic_scene, synthetic_scene_with_labels
from mocap.labels import UNKNOWN


@pytest.fixture(scope="module")
def scene():
    return synthetic_scene_with_labels(160, 120, 2)


@pytest.fixture(scope="module")
def model(scene):
    return ColourModel.from_boxes(scene.frame, {"skin": skin_box_of_face(scene.face_box),
                                                "clothes": scene.clothes_box})


@pytest.mark.parametrize("config", [
    ImagingConfig(),
    ImagingConfig(edge_method="deriche", distance_method="chamfer"),
])
def test_prepared_frame_contract(scene, model, config):
    out = prepare_frame(scene.frame, scene.background, model, config)
    assert isinstance(out, PreparedFrame)
    with pytest.raises(dataclasses.FrozenInstanceError):
        out.is_empty = True
    h, w = scene.mask.shape
    assert out.labels.dtype == np.uint8 and out.labels.shape == (h, w)
    assert out.foreground.dtype == np.bool_ and out.edges.dtype == np.bool_
    assert out.distance.dtype == np.float32 and out.distance.shape == (h, w)
    assert set(np.unique(out.labels)) <= {0, 1, 2, UNKNOWN}
    np.testing.assert_array_equal(out.labels != 0, out.foreground)
    assert out.is_empty is False
    assert set(out.timings) == {"background", "colour", "edges", "distance"}
    assert all(isinstance(t, float) and t >= 0 for t in out.timings.values())
    # each stage is the public function of that stage
    np.testing.assert_array_equal(out.foreground,
                                  subtract_background(scene.frame, scene.background, config))
    np.testing.assert_array_equal(
        out.labels, model.classify(scene.frame, out.foreground, config.colour_threshold))
    np.testing.assert_array_equal(out.edges, detect_edges(
        scene.frame, out.foreground, method=config.edge_method, sigma=config.edge_sigma,
        low_threshold=config.edge_low_threshold, high_threshold=config.edge_high_threshold,
        dilation=config.edge_dilation, silhouette=config.silhouette_edges))
    np.testing.assert_array_equal(out.distance, distance_map(
        out.edges, max_distance=config.max_distance, method=config.distance_method))


def test_prepared_frame_matches_the_truth(scene, model):
    out = prepare_frame(scene.frame, scene.background, model)
    fg, truth = out.foreground, scene.mask
    assert (fg & truth).sum() / (fg | truth).sum() >= 0.95
    for label in (1, 2):
        assert (out.labels[scene.labels == label] == label).mean() > 0.9
    # the silhouette outline is found: true boundary pixels are within 2 px of an edge
    outline = truth & ~ndi.binary_erosion(truth, border_value=1)
    assert (out.distance[outline] <= 2.0).mean() > 0.95
    # the grey-level edges alone find most of it (the face has the wall's luminance here)
    grey_only = prepare_frame(scene.frame, scene.background, model,
                              ImagingConfig(silhouette_edges=False))
    assert (grey_only.distance[outline] <= 2.0).mean() > 0.6
    # edges stay near the foreground
    near = ndi.binary_dilation(fg, np.ones((2 * 4 + 1,) * 2, bool))
    assert not (out.edges & ~near).any()


def test_float_frames_give_the_same_result(scene, model):
    a = prepare_frame(scene.frame, scene.background, model)
    b = prepare_frame(scene.frame / 255.0, scene.background.astype(np.float32) / 255, model)
    assert (a.labels == b.labels).mean() > 0.999
    c = prepare_frame(scene.frame, scene.background / 255.0, model)  # mixed dtypes
    assert (a.labels == c.labels).mean() > 0.999
    d = prepare_frame((scene.frame / 255.0).astype(np.float16),
                      (scene.background / 255.0).astype(">f8"), model)
    assert (a.labels == d.labels).mean() > 0.99


def test_empty_scene_returns_an_empty_label_image(scene, model):
    rng = np.random.default_rng(0)
    empty = np.clip(scene.background + rng.normal(0, 3, scene.background.shape), 0, 255)
    out = prepare_frame(empty.astype(np.uint8), scene.background, model)
    assert out.is_empty is True
    assert not out.labels.any() and not out.foreground.any() and not out.edges.any()
    assert (out.distance == ImagingConfig().max_distance).all()


def test_without_background_the_colour_classes_make_the_foreground(scene, model):
    out = prepare_frame(scene.frame, None, model)
    np.testing.assert_array_equal(out.labels != 0, out.foreground)
    assert (out.foreground & scene.mask).sum() / scene.mask.sum() > 0.9


def test_synthetic_scene_at_any_resolution():
    for w, h in [(32, 24), (64, 48), (640, 480)]:
        frame, background, mask = synthetic_scene(w, h, 7)
        assert frame.shape == background.shape == (h, w, 3) and frame.dtype == np.uint8
        assert mask.shape == (h, w) and 0.1 < mask.mean() < 0.5
    a = synthetic_scene(64, 48, 1)
    b = synthetic_scene(64, 48, 1)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)
    with pytest.raises(ValueError, match="at least"):
        synthetic_scene(16, 16, 0)


BAD = [
    ("sizes differ", lambda f, b: (f, b[:-1]), ValueError, "same size"),
    ("grayscale frame", lambda f, b: (f[..., 0], b), ValueError, "grayscale"),
    ("grayscale background", lambda f, b: (f, b[..., :1]), ValueError, "grayscale"),
    ("rgba frame", lambda f, b: (np.dstack([f, np.full(f.shape[:2], 255, np.uint8)]), b),
     ValueError, "RGBA"),
    ("float 0-255 frame", lambda f, b: (f.astype(float), b), ValueError, r"in \[0, 1\]"),
    ("negative float background", lambda f, b: (f, b / 255.0 - 0.5), ValueError, r"in \[0, 1\]"),
    ("uint16 frame", lambda f, b: (f.astype(np.uint16) * 257, b), ValueError, "uint8"),
    ("nan frame", lambda f, b: (np.full(f.shape, np.nan), b), ValueError, "NaN"),
]


@pytest.mark.parametrize("name, make, error, message", BAD, ids=[b[0] for b in BAD])
def test_bad_input_raises_the_documented_error(scene, model, name, make, error, message):
    frame, background = make(scene.frame, scene.background)
    with pytest.raises(error, match=message):
        prepare_frame(frame, background, model)


def test_bad_model_or_config(scene, model):
    with pytest.raises(ValueError, match="ColourModel"):
        prepare_frame(scene.frame, scene.background, {"skin": 1})
    with pytest.raises(ValueError, match="ImagingConfig"):
        prepare_frame(scene.frame, scene.background, model, {"max_distance": 3})
