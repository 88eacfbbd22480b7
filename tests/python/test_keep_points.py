"""Mapper.keep_points: which points of a frame to keep by the map (point_selection.hpp from Python)."""
import numpy as np
import pytest

import occ_improve as oi


def _fresh(intrinsics):
    return oi.Mapper(oi.kinect_v1(intrinsics))


def test_keeps_the_asked_share_spread_over_the_view(sample, sample_points):
    _, intrinsics = sample
    mapper = _fresh(intrinsics)
    kept = mapper.keep_points(sample_points, fraction=0.05)
    on_ray = np.isfinite(sample_points).all(axis=1) & (sample_points[:, 2] > 0)
    assert kept.dtype == np.int64 and np.all(np.diff(kept) > 0)
    assert len(kept) == round(0.05 * on_ray.sum())
    assert on_ray[kept].all()
    # An empty map ties every ray: one point per 4 x 4 cell, the image's halves equally represented.
    rows, cols = np.divmod(kept, intrinsics.width)
    cells = set(zip(rows // 4, cols // 4))
    assert len(cells) == len(kept)
    assert abs((rows < intrinsics.height // 2).mean() - 0.5) < 0.1
    np.testing.assert_array_equal(mapper.keep_points(sample_points, fraction=0.05), kept)
    assert len(mapper.keep_points(sample_points, count=100)) == 100
    assert len(mapper.keep_points(sample_points, count=10**9)) == on_ray.sum()


def test_a_cells_sample_is_kept_again_before_the_rays_beside_it(sample, sample_points):
    _, intrinsics = sample
    mapper = _fresh(intrinsics)
    first = mapper.keep_points(sample_points, fraction=0.05)
    mapper.insert(sample_points[first])
    second = mapper.keep_points(sample_points, fraction=0.05)
    assert len(second) == len(first)
    # Pixel-native grid of the frame's own camera: row i of the points is column i. The kept rays now sit
    # below their unmeasured neighbours (0.138 against 0.324), and are kept again all the same.
    improvement = mapper.improvement().reshape(-1)
    on_ray = np.flatnonzero(np.isfinite(sample_points).all(axis=1) & (sample_points[:, 2] > 0))
    assert np.mean(improvement[second] < 0.2) > 0.8
    assert np.median(improvement[np.setdiff1d(on_ray, second)]) > 0.3
    assert len(np.intersect1d(first, second)) > 0.8 * len(first)


def test_an_image_of_points_is_counted_row_by_row(sample, sample_points):
    depth, intrinsics = sample
    image = oi.depth_to_points(depth, intrinsics)  # H x W x 3
    mapper = _fresh(intrinsics)
    kept = mapper.keep_points(image, fraction=0.05)
    np.testing.assert_array_equal(kept, mapper.keep_points(sample_points, fraction=0.05))
    np.testing.assert_array_equal(image.reshape(-1, 3)[kept], sample_points[kept])


def test_bad_arguments_are_refused_by_name(sample, sample_points):
    _, intrinsics = sample
    mapper = _fresh(intrinsics)
    with pytest.raises(oi.InvalidParameter, match="exactly one of count and fraction"):
        mapper.keep_points(sample_points)
    with pytest.raises(oi.InvalidParameter, match="exactly one of count and fraction"):
        mapper.keep_points(sample_points, count=3, fraction=0.1)
    with pytest.raises(oi.InvalidParameter, match="fraction = 1.5"):
        mapper.keep_points(sample_points, fraction=1.5)
    with pytest.raises(oi.InvalidParameter, match="fraction = nan"):
        mapper.keep_points(sample_points, fraction=float("nan"))
    with pytest.raises(oi.InvalidParameter, match="count = -1"):
        mapper.keep_points(sample_points, count=-1)
    with pytest.raises(oi.InvalidInput):
        mapper.keep_points(np.zeros((5, 2), np.float32), count=1)
    assert len(mapper.keep_points(np.full((4, 3), np.nan, np.float32), count=3)) == 0
