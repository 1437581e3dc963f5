import numpy as np
import pytest

from mocap.imaging.blobs import label_blobs


def picture():
    a = np.zeros((10, 12), np.uint8)
    a[1:3, 1:4] = 1            # 6 pixels, centroid (u, v) = (2, 1.5)
    a[6, 8] = a[7, 9] = 1      # diagonal neighbours: one 8-connected region, centroid (8.5, 6.5)
    a[8:10, 0:2] = 2           # another label
    a[0, 11] = 1               # a single pixel
    return a


def test_regions_centroids_and_sizes_are_exact():
    b = label_blobs(picture(), 1)
    assert b.sizes.tolist() == [6, 2, 1]
    np.testing.assert_array_equal(b.centroids, [[2.0, 1.5], [8.5, 6.5], [11.0, 0.0]])
    assert len(b) == 3


def test_min_pixels_and_other_labels():
    assert label_blobs(picture(), 1, min_pixels=2).sizes.tolist() == [6, 2]
    other = label_blobs(picture(), 2)
    assert other.sizes.tolist() == [4]
    np.testing.assert_array_equal(other.centroids, [[0.5, 8.5]])
    none = label_blobs(picture(), 7)
    assert len(none) == 0 and none.centroids.shape == (0, 2)


@pytest.mark.parametrize("kwargs, match", [({"labels": np.zeros(5, np.uint8)}, "2D"),
                                           ({"label": 300}, "label"), ({"min_pixels": 0}, "min_pixels")])
def test_bad_input(kwargs, match):
    args = {"labels": picture(), "label": 1, **kwargs}
    with pytest.raises(ValueError, match=match):
        label_blobs(args.pop("labels"), args.pop("label"), **args)
