"""Background subtraction: known synthetic masks, shadows, the compiled test vs its twin."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from mocap.imaging import ImagingConfig, clean_mask, median_background, subtract_background
from mocap.imaging.testing import synthetic_scene, synthetic_scene_with_labels
from tests.naive import naive_change_mask


def iou(a, b):
    return (a & b).sum() / (a | b).sum()


@pytest.mark.parametrize("size", [(160, 120), (320, 240)])
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_synthetic_scene_mask_recovered_with_noise(size, seed):
    frame, background, truth = synthetic_scene(*size, seed)
    mask = subtract_background(frame, background)
    assert mask.dtype == np.bool_ and mask.shape == truth.shape
    assert iou(mask, truth) >= 0.95


def test_heavier_noise_still_recovers_the_mask():
    scene = synthetic_scene_with_labels(320, 240, 5, noise=6.0)
    assert iou(subtract_background(scene.frame, scene.background), scene.mask) >= 0.95


def _soft_shadow_scene(seed, darkening):
    rng = np.random.default_rng(seed)
    h, w = 90, 120
    base = rng.uniform(60, 220, 3)
    texture = ndi.gaussian_filter(rng.normal(0, 1, (h, w, 3)), (4, 4, 0)) * 60
    background = np.clip(base + texture, 0, 255)
    yy, xx = np.mgrid[:h, :w]
    blob = ndi.gaussian_filter(((yy - 45) ** 2 / 30 ** 2 + (xx - 60) ** 2 / 40 ** 2 < 1) * 1.0, 4)
    frame = background * (1 - darkening * blob)[..., None]
    noisy = lambda im: np.clip(np.round(im + rng.normal(0, 3, im.shape)), 0, 255).astype(np.uint8)
    return noisy(frame), noisy(background), blob


@pytest.mark.parametrize("seed", range(5))
def test_shadow_only_change_is_not_foreground(seed):
    frame, background, blob = _soft_shadow_scene(seed, darkening=0.25)
    # the change is real: the raw colour difference exceeds the change threshold widely
    diff = np.linalg.norm(frame.astype(float) - background.astype(float), axis=2)
    assert (diff > ImagingConfig().change_threshold).mean() > 0.2
    assert not subtract_background(frame, background).any()


def test_same_brightness_colour_change_is_foreground():
    # the counterpart of the shadow test: a chromatic change of equal brightness is found
    rng = np.random.default_rng(0)
    background = np.full((60, 80, 3), (150, 150, 150), dtype=np.uint8)
    frame = background.copy()
    frame[20:40, 30:60] = (200, 120, 130)
    frame = np.clip(frame + rng.normal(0, 3, frame.shape), 0, 255).astype(np.uint8)
    mask = subtract_background(frame, background)
    truth = np.zeros((60, 80), bool)
    truth[20:40, 30:60] = True
    assert iou(mask, truth) > 0.97


def test_darker_than_shadow_range_is_foreground():
    background = np.full((40, 40, 3), 200, dtype=np.uint8)
    frame = background.copy()
    frame[10:30, 10:30] = 60  # same chromaticity, brightness ratio 0.3 < shadow range
    mask = subtract_background(frame, background)
    assert mask[10:30, 10:30].all() and mask.sum() == 400


@pytest.mark.parametrize("seed", range(3))
def test_compiled_test_equals_naive_twin(seed):
    rng = np.random.default_rng(seed)
    background = rng.integers(0, 256, (23, 31, 3), dtype=np.uint8)
    background[0, 0] = 0  # a black background pixel
    scale = rng.uniform(0.3, 1.4, (23, 31, 1))
    frame = np.clip(background * scale + rng.normal(0, 20, (23, 31, 3)), 0, 255).astype(np.uint8)
    cfg = ImagingConfig()
    args = (cfg.change_threshold, cfg.shadow_min_brightness, cfg.shadow_max_brightness,
            cfg.shadow_max_chroma, cfg.chroma_noise)
    expected = naive_change_mask(frame, background, *args)
    assert 0 < expected.sum() < expected.size
    np.testing.assert_array_equal(subtract_background(frame, background, clean=False), expected)
    # float inputs in [0, 1] give the same test (mixed dtypes too)
    frame_f = frame / 255.0
    np.testing.assert_array_equal(
        subtract_background(frame_f, background, clean=False),
        naive_change_mask(frame_f, background, *args))


def test_float_and_uint8_inputs_agree():
    frame, background, _ = synthetic_scene(160, 120, 3)
    a = subtract_background(frame, background)
    b = subtract_background(frame.astype(np.float32) / 255, background.astype(np.float64) / 255)
    assert iou(a, b) > 0.999


def test_clean_mask_removes_speckle_and_fills_small_holes():
    raw = np.zeros((100, 100), bool)
    raw[20:80, 30:70] = True
    raw[50, 50] = False  # a one-pixel hole
    raw[5, 5] = raw[90, 10] = True  # speckle
    raw[2:5, 90:93] = True  # a 3x3 blob: survives the opening, removed as a small object
    cleaned = clean_mask(raw)
    expected = np.zeros((100, 100), bool)
    expected[20:80, 30:70] = True
    np.testing.assert_array_equal(cleaned, expected)


def test_clean_mask_keeps_parts_touching_the_image_border():
    raw = np.zeros((60, 60), bool)
    raw[30:, 20:40] = True  # a torso cut by the bottom of the frame
    np.testing.assert_array_equal(clean_mask(raw), raw)


def test_median_background_is_the_per_pixel_median():
    rng = np.random.default_rng(3)
    frames = [rng.integers(0, 256, (7, 9, 3), dtype=np.uint8) for _ in range(5)]
    np.testing.assert_array_equal(median_background(frames), np.median(frames, axis=0))
    with pytest.raises(ValueError, match="at least one"):
        median_background([])
    with pytest.raises(ValueError, match="same size"):
        median_background([frames[0], frames[1][:5]])


BAD = {
    "sizes differ": (np.zeros((10, 12, 3), np.uint8), np.zeros((10, 13, 3), np.uint8), "same size"),
    "grayscale": (np.zeros((10, 12), np.uint8), np.zeros((10, 12, 3), np.uint8), "grayscale"),
    "rgba": (np.zeros((10, 12, 4), np.uint8), np.zeros((10, 12, 3), np.uint8), "RGBA"),
    "float 0-255": (np.full((10, 12, 3), 200.0), np.zeros((10, 12, 3), np.uint8), r"\[0, 1\]"),
    "nan": (np.full((10, 12, 3), np.nan), np.zeros((10, 12, 3), np.uint8), "NaN"),
    "int16": (np.zeros((10, 12, 3), np.int16), np.zeros((10, 12, 3), np.uint8), "dtype"),
    "list": ([[0, 0, 0]], np.zeros((10, 12, 3), np.uint8), "NumPy array"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_raises_value_error(case):
    frame, background, message = BAD[case]
    with pytest.raises(ValueError, match=message):
        subtract_background(frame, background)


@pytest.mark.parametrize("radius", [30.0, 7.3])
def test_densest_sample_matches_its_twin(radius):
    """The compiled mode of the background estimate equals its NumPy twin, ties included
    (few grey levels: many equal counts)."""
    from mocap.imaging.background import _densest_sample
    from tests.naive import naive_densest_sample
    rng = np.random.default_rng(5)
    video = (rng.integers(0, 9, (13, 7, 11, 3)) * 8).astype(np.uint8)
    np.testing.assert_array_equal(_densest_sample(video, radius), naive_densest_sample(video, radius))
