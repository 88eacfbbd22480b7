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
        assert np.linalg.norm(r.centroid_direction) == pytest.approx(1.0)
    # Every column above the threshold is in at most one region: the areas cannot add up to more.
    assert sum(r.area_columns for r in regions) <= np.count_nonzero(improvement >= 0.2)
    assert len(paper_mapper.regions(oi.RegionOptions(min_improvement=10.0))) == 0


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
