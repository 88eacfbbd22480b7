"""Regions, top rays and the stop signal on the sample (tests/test_ranking.cpp through Python)."""
import numpy as np
import pytest

import occ_improve as oi


def test_top_rays_are_the_largest_best_first(paper_mapper):
    improvement, depth = paper_mapper.improvement(), paper_mapper.depth()
    rays = paper_mapper.top_rays(1000)
    assert rays.dtype.names == ("column", "azimuth_bin", "elevation_bin", "improvement", "depth_m")
    assert len(rays) == 1000 and np.all(np.diff(rays["improvement"]) <= 0)
    np.testing.assert_array_equal(rays["improvement"], improvement[rays["elevation_bin"], rays["azimuth_bin"]])
    np.testing.assert_array_equal(rays["depth_m"], depth[rays["elevation_bin"], rays["azimuth_bin"]])
    np.testing.assert_array_equal(rays["column"], rays["elevation_bin"] * paper_mapper.width + rays["azimuth_bin"])
    assert rays["improvement"][-1] >= np.sort(improvement, axis=None)[-1000]
    assert len(paper_mapper.top_rays(10**7)) == improvement.size


def test_regions_are_sorted_and_above_the_threshold(paper_mapper):
    options = oi.RegionOptions(min_improvement=0.2, min_area_columns=10)
    regions = paper_mapper.regions(options)
    assert len(regions) > 1
    sums = [r.summed_improvement for r in regions]
    assert sums == sorted(sums, reverse=True)
    improvement = paper_mapper.improvement()
    for r in regions:
        assert r.area_columns >= 10 and r.peak_improvement >= 0.2
        assert r.summed_improvement <= r.area_columns * r.peak_improvement + 1e-6
        assert np.linalg.norm(r.centre_direction) == pytest.approx(1.0)
    # Every column above the threshold is in at most one region: the areas cannot add up to more.
    assert sum(r.area_columns for r in regions) <= np.count_nonzero(improvement >= 0.2)
    assert len(paper_mapper.regions(oi.RegionOptions(min_improvement=10.0))) == 0


def test_region_positions_are_columns_of_the_region(sample):
    """The centre was the mean position, which can lie outside the region; it is now one of its rays."""
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    mapper.insert_depth(depth, intrinsics)
    improvement = mapper.improvement()
    regions = mapper.regions()
    assert len(regions) >= 2
    for r in regions:
        assert improvement[r.centre_v, r.centre_u] >= 0.2
        assert improvement[r.peak_v, r.peak_u] == pytest.approx(r.peak_improvement)
        assert r.min_u <= r.centre_u <= r.max_u and r.min_v <= r.centre_v <= r.max_v
        assert r.min_u <= r.peak_u <= r.max_u and r.min_v <= r.peak_v <= r.max_v
        assert 0 <= r.min_u and r.max_u < mapper.width and 0 <= r.min_v and r.max_v < mapper.height
        inside = improvement[r.min_v:r.max_v + 1, r.min_u:r.max_u + 1] >= 0.2
        assert np.count_nonzero(inside) >= r.area_columns  # the box holds the whole region
        np.testing.assert_allclose(r.centre_direction, mapper.direction(r.centre_u, r.centre_v), atol=1e-12)
        x, y, z = r.centre_direction
        assert r.centre_azimuth_rad == pytest.approx(np.arctan2(x, z))
        assert r.centre_elevation_rad == pytest.approx(np.arctan2(y, np.hypot(x, z)))
        assert (y > 0) == (r.centre_v > intrinsics.cy)  # elevation and v grow downwards


def test_equal_rays_are_spread_over_the_view_not_taken_in_scan_order(sample):
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    mapper.insert_depth(depth, intrinsics)
    rays = mapper.top_rays(50)
    assert np.all(rays["improvement"][:10] == rays["improvement"][0])  # the no-data rays all tie
    assert len(set(rays["elevation_bin"][:10].tolist())) >= 8
    assert not np.all(np.diff(rays["column"][:10].astype(np.int64)) > 0)


def test_stop_signal_follows_its_thresholds(paper_mapper):
    go = paper_mapper.stop_signal()
    assert not go and not go.stop and go.total_improvement > 10 and "continue" in go.reason
    stop = paper_mapper.stop_signal(oi.StopCriteria(total_improvement_below=1e9))
    assert stop and stop.total_improvement == pytest.approx(go.total_improvement)


def test_stop_monitor_stops_when_frames_stop_paying():
    """Static view, paper preset: diminishing returns stop the sequence (~19 frames, ranking.hpp)."""
    mapper, monitor = oi.Mapper(oi.kinect_v1_paper()), oi.StopMonitor()
    for frame in range(1, 41):
        mapper.insert_depth(*oi.sample_depth(seed=frame))
        if monitor.update(mapper).stop:
            break
    assert 8 <= frame <= 35
    assert monitor.stalled_frames >= 3
