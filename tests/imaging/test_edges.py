"""Edges and the truncated distance map against brute force and analytic answers."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra.numpy import arrays
from scipy import ndimage as ndi
from skimage import color

from mocap.imaging import detect_edges, distance_map
from mocap.imaging.edges import SOBEL_GAIN, _deriche_coefficients, deriche_gradient
from tests.naive import naive_deriche_1d, naive_deriche_edges, naive_distance


# -- distance map

@pytest.mark.parametrize("method, metric", [("edt", "euclidean"), ("chamfer", "chamfer34")])
@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("max_distance", [2.5, 7.0, 50.0])
def test_distance_map_equals_brute_force(method, metric, seed, max_distance):
    rng = np.random.default_rng(seed)
    shape = tuple(rng.integers(5, 30, 2))
    edges = rng.random(shape) < rng.choice([0.005, 0.03, 0.2])
    edges[rng.integers(shape[0]), rng.integers(shape[1])] = True
    got = distance_map(edges, max_distance=max_distance, method=method)
    assert got.dtype == np.float32 and got.shape == shape
    np.testing.assert_allclose(got, naive_distance(edges, max_distance, metric), atol=1e-5)
    assert got.max() <= max_distance and (got[edges] == 0).all()


@settings(max_examples=40, deadline=None)
@given(arrays(bool, st.tuples(st.integers(1, 24), st.integers(1, 24))),
       st.floats(0.5, 30.0), st.sampled_from(["edt", "chamfer"]))
def test_distance_map_property(edges, max_distance, method):
    metric = "euclidean" if method == "edt" else "chamfer34"
    got = distance_map(edges, max_distance=max_distance, method=method)
    np.testing.assert_allclose(got, naive_distance(edges, max_distance, metric), atol=1e-4)


def test_edges_in_one_corner_of_a_large_image():
    # the bounding-box shortcut must still give the exact values far from the edges
    edges = np.zeros((120, 160), bool)
    edges[3, 5] = edges[10, 2] = True
    got = distance_map(edges, max_distance=30.0)
    np.testing.assert_allclose(got, naive_distance(edges, 30.0), atol=1e-5)
    assert (got[60:, 60:] == 30.0).all()


def test_no_edges_gives_the_truncation_everywhere():
    for method in ("edt", "chamfer"):
        got = distance_map(np.zeros((8, 9), bool), max_distance=12.0, method=method)
        assert (got == 12.0).all()


def test_chamfer_is_close_to_euclidean():
    edges = np.zeros((61, 61), bool)
    edges[30, 30] = True
    e = distance_map(edges, max_distance=100, method="edt")
    c = distance_map(edges, max_distance=100, method="chamfer")
    ratio = c[e > 0] / e[e > 0]
    # 3-4 chamfer: exact on the axes, 4/3 vs sqrt(2) on diagonals, +4.3 % at (1, 2)
    assert ratio.min() == pytest.approx((4 / 3) / np.sqrt(2), abs=1e-6)
    assert ratio.max() <= 1.06 and np.isclose(ratio, 1.0).any()


@pytest.mark.parametrize("kwargs, message", [
    ({"max_distance": 0.0}, "max_distance"),
    ({"max_distance": float("inf")}, "max_distance"),
    ({"method": "manhattan"}, "method"),
])
def test_distance_map_rejects_bad_parameters(kwargs, message):
    with pytest.raises(ValueError, match=message):
        distance_map(np.zeros((4, 4), bool), **kwargs)


def test_distance_map_rejects_non_boolean_edges():
    with pytest.raises(ValueError, match="boolean"):
        distance_map(np.zeros((4, 4), np.uint8))


# -- edges

def _disk_image(radius=20.0, size=(80, 90), centre=(40.3, 44.7)):
    yy, xx = np.mgrid[:size[0], :size[1]]
    inside = (yy - centre[0]) ** 2 + (xx - centre[1]) ** 2 < radius ** 2
    image = np.where(inside[..., None], (200, 90, 60), (40, 60, 90)).astype(np.uint8)
    return image, inside, np.hypot(yy - centre[0], xx - centre[1])


@pytest.mark.parametrize("method", ["canny", "deriche"])
def test_edges_of_a_disk_lie_on_its_circle(method):
    image, inside, radius = _disk_image()
    edges = detect_edges(image, method=method)
    assert edges.dtype == np.bool_ and edges.shape == inside.shape
    assert np.abs(radius[edges] - 20.0).max() <= 1.5
    # the circle is closed: every direction around the centre has an edge pixel
    angles = np.arctan2(*np.nonzero(edges) - np.array([[40.3], [44.7]]))
    hist, _ = np.histogram(angles, bins=36, range=(-np.pi, np.pi))
    assert (hist > 0).all()


@pytest.mark.parametrize("method", ["canny", "deriche"])
def test_edges_are_kept_only_near_the_foreground(method):
    image, inside, _ = _disk_image()
    rng = np.random.default_rng(0)
    image[:, :15] = rng.integers(0, 256, (80, 15, 3))  # texture away from the person
    foreground = inside.copy()
    everywhere = detect_edges(image, method=method)
    near = detect_edges(image, foreground, method=method, dilation=3, silhouette=False)
    assert everywhere[:, :15].sum() > 50 and near[:, :15].sum() == 0
    from scipy import ndimage as ndi
    allowed = ndi.binary_dilation(foreground, np.ones((7, 7), bool))
    assert not (near & ~allowed).any()
    np.testing.assert_array_equal(near, everywhere & allowed)


def test_silhouette_edges_outline_an_isoluminant_person():
    # actor and background have the same grey level: only the mask outline can be an edge
    from skimage.color import rgb2gray

    _, inside, _ = _disk_image()
    image = np.where(inside[..., None], (150, 100, 100), (100, 100, 150)).astype(np.uint8)
    grey = rgb2gray(image)
    assert np.ptp(grey) < 0.05  # below the hysteresis thresholds' step
    assert not detect_edges(image, inside, silhouette=False).any()
    edges = detect_edges(image, inside)
    from scipy import ndimage as ndi
    outline = inside & ~ndi.binary_erosion(inside, np.ones((3, 3), bool), border_value=1)
    np.testing.assert_array_equal(edges, outline)


def test_empty_foreground_has_no_edges():
    image, _, _ = _disk_image()
    assert not detect_edges(image, np.zeros(image.shape[:2], bool)).any()


def test_deriche_gradient_equals_naive_recursion():
    rng = np.random.default_rng(1)
    image = rng.random((17, 23))
    alpha = 1.3
    smooth, deriv, b = _deriche_coefficients(alpha)
    sx = np.apply_along_axis(naive_deriche_1d, 1, image, smooth, b)
    sy = np.apply_along_axis(naive_deriche_1d, 0, image, smooth, b)
    gx = np.apply_along_axis(naive_deriche_1d, 1, sy, deriv, b)
    gy = np.apply_along_axis(naive_deriche_1d, 0, sx, deriv, b)
    got_y, got_x = deriche_gradient(image, alpha)
    np.testing.assert_allclose(got_x, gx, atol=1e-10)
    np.testing.assert_allclose(got_y, gy, atol=1e-10)


@pytest.mark.parametrize("seed, sigma, low, high", [(0, 1.0, 0.05, 0.15), (1, 1.5, 0.08, 0.20), (2, 2.0, 0.02, 0.3)])
def test_deriche_edges_equal_naive_suppression_and_hysteresis(seed, sigma, low, high):
    # the compiled magnitude and non-maximum kernels and the hysteresis against tests/naive.py
    # (bilinear ring samples by scipy, flood fill), on a noisy image with blobs
    rng = np.random.default_rng(seed)
    grey = ndi.gaussian_filter(rng.random((31, 37)), 1.0) + 0.3 * (rng.random((31, 37)) > 0.8)
    rgb = np.repeat(np.clip(grey / grey.max(), 0, 1)[..., None], 3, axis=2)
    got = detect_edges(rgb, method="deriche", sigma=sigma, low_threshold=low, high_threshold=high, silhouette=False)
    gy, gx = deriche_gradient(color.rgb2gray(rgb), np.sqrt(np.pi) / sigma)
    expect = naive_deriche_edges(gy, gx, SOBEL_GAIN, low, high)
    assert expect.any() and not expect.all()
    np.testing.assert_array_equal(got, expect)


@pytest.mark.parametrize("alpha", [0.5, 1.0, 2.5])
def test_deriche_gradient_of_a_ramp_is_its_slope(alpha):
    yy, xx = np.mgrid[:80, :90]
    gy, gx = deriche_gradient(0.3 * xx - 0.7 * yy, alpha)
    m = int(np.ceil(16 / alpha))  # borders are replicated, so the slope fades near them
    inner = (slice(m, -m), slice(m, -m))
    np.testing.assert_allclose(gx[inner], 0.3, atol=1e-5)
    np.testing.assert_allclose(gy[inner], -0.7, atol=1e-5)


@pytest.mark.parametrize("kwargs, message", [
    ({"method": "sobel"}, "method"),
    ({"sigma": 0.0}, "sigma"),
    ({"low_threshold": 0.5, "high_threshold": 0.1}, "threshold"),
    ({"dilation": -1}, "dilation"),
])
def test_detect_edges_rejects_bad_parameters(kwargs, message):
    with pytest.raises(ValueError, match=message):
        detect_edges(np.zeros((10, 10, 3), np.uint8), **kwargs)


def test_detect_edges_rejects_bad_images():
    with pytest.raises(ValueError, match="RGBA"):
        detect_edges(np.zeros((10, 10, 4), np.uint8))
    with pytest.raises(ValueError, match="foreground"):
        detect_edges(np.zeros((10, 10, 3), np.uint8), np.zeros((10, 11), bool))
