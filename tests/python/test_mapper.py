"""The Mapper on the built-in sample: counts, layouts, incremental = full, views, threads
(tests/test_mapper.cpp and tests/test_integrate.cpp through Python)."""
import gc
import threading
import time

import numpy as np
import pytest

import occ_improve as oi
from conftest import assert_same_maps


def test_every_point_is_accounted_for(sample):
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    r = mapper.insert_depth(depth, intrinsics).insertion
    assert r.points_received == depth.size
    assert r.points_received == r.points_inserted + r.skipped_invalid + r.skipped_outside_fov
    assert r.skipped_invalid == np.count_nonzero(depth == 0)  # the sample's no-return pixels
    assert r.skipped_outside_fov == 0  # kinect_v1 from these intrinsics holds every pixel
    assert mapper.touched_columns() > 0.9 * r.points_inserted


def windows(a):
    """The 3 x 3 neighbourhood of every interior ray: shape (H - 2, W - 2, 3, 3)."""
    return np.lib.stride_tricks.sliding_window_view(a, (3, 3))


def test_paper_preset_maps_have_the_papers_values(paper_mapper):
    """CONVENTIONS 7's picture as medians over masks of 3 x 3 windows (tests/test_improvement.cpp)."""
    depth, probability = paper_mapper.depth(), paper_mapper.probability()
    unknown, improvement, bins = paper_mapper.unknown(), paper_mapper.improvement(), paper_mapper.surface_bin()
    assert depth.shape == (480, 640) and depth.dtype == np.float32 and improvement.dtype == np.float32
    assert unknown.dtype == np.bool_ and bins.dtype == np.int32 and 0 < unknown.sum() < unknown.size
    assert np.all(depth[unknown] == 0) and np.all(probability[unknown] == 0.5) and np.all(bins[unknown] == -1)
    assert np.all(np.isfinite(improvement))
    depth_bins, depth_max = paper_mapper.geometry.depth_bins, paper_mapper.geometry.depth_max_m
    w_unknown, w_depth = windows(unknown), windows(depth)
    lo, hi = w_depth.min(axis=(2, 3)), w_depth.max(axis=(2, 3))
    centre = (slice(1, -1), slice(1, -1))
    imp, p, d, u, b = improvement[centre], probability[centre], depth[centre], unknown[centre], bins[centre]
    in_range = ~w_unknown.any(axis=(2, 3)) & (hi < depth_max)
    masks = {
        "unknown": w_unknown.all(axis=(2, 3)),
        "once": in_range & (hi - lo < 0.05) & (p > 0.78) & (p < 0.86),
        "beyond": (windows(bins) == depth_bins).all(axis=(2, 3)),
        "far_side_of_edge": in_range & (d - lo > 0.5),
        "beside_hole": ~u & (b < depth_bins) & (w_unknown.sum(axis=(2, 3)) >= 3),
    }
    for name, mask in masks.items():
        assert mask.sum() > 100, name
    assert np.median(imp[masks["unknown"]]) == pytest.approx(0.32, abs=0.02)
    assert np.median(imp[masks["once"]]) == pytest.approx(0.13, abs=0.03)
    assert np.median(imp[masks["beyond"]]) == pytest.approx(0.0, abs=0.01)
    assert np.median(imp[masks["far_side_of_edge"]]) < -0.1  # the far side would carve the near side free
    assert np.median(imp[masks["beside_hole"]]) < -0.5


def test_one_ray_improvement_agrees_with_the_map(paper_mapper):
    improvement = paper_mapper.improvement()
    for a, e in ((0, 0), (320, 240), (639, 479), (100, 300), (500, 50)):
        assert paper_mapper.ray_improvement(a, e) == pytest.approx(float(improvement[e, a]), abs=1e-5)
    with pytest.raises(oi.InvalidParameter):
        paper_mapper.ray_improvement(640, 0)


def test_one_ray_improvement_is_nan_where_the_map_is(sample):
    """A masked ray gave eq. 4's value (0.324 unseen, -1.18) where improvement() holds NaN."""
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    mask = np.ones(depth.shape, bool)
    mask[:, 600:] = False
    mapper.insert_depth(depth, intrinsics, mask=mask)
    improvement = mapper.improvement()
    assert np.isnan(improvement[240, 620]) and np.isnan(mapper.ray_improvement(620, 240))
    assert mapper.ray_improvement(300, 240) == pytest.approx(float(improvement[240, 300]), abs=1e-5)


def test_depth_image_and_points_give_the_same_maps(sample, sample_points):
    depth, intrinsics = sample
    from_depth, from_points = oi.Mapper(oi.kinect_v1_paper()), oi.Mapper(oi.kinect_v1_paper())
    from_depth.insert_depth(depth, intrinsics)
    from_points.insert(sample_points)
    assert_same_maps(from_depth, from_points)


@pytest.mark.parametrize("layout", ["float64", "hw3", "slice_of_n4", "fortran", "big_endian", "list"])
def test_every_input_layout_gives_the_maps_of_the_packed_float32_one(sample_points, layout):
    """Read in place or converted, the same points give the same maps."""
    pts = sample_points[::7]  # a seventh of the frame keeps the test fast
    reference = oi.Mapper(oi.kinect_v1_paper())
    reference.insert(np.ascontiguousarray(pts))
    padded = np.concatenate([pts, np.ones((len(pts), 1), np.float32)], axis=1)
    variants = {
        "float64": pts.astype(np.float64),
        "hw3": np.ascontiguousarray(pts[: (len(pts) // 10) * 10]).reshape(-1, 10, 3),
        "slice_of_n4": padded[:, :3],  # PCL-like padding, read in place with a stride of 4 floats
        "fortran": np.asfortranarray(pts),
        "big_endian": pts.astype(">f4"),
        "list": pts[:500].tolist(),
    }
    mapper = oi.Mapper(oi.kinect_v1_paper())
    report = mapper.insert(variants[layout])
    if layout == "hw3":
        reference = oi.Mapper(oi.kinect_v1_paper())
        reference.insert(np.ascontiguousarray(pts[: (len(pts) // 10) * 10]))
    if layout == "list":
        reference = oi.Mapper(oi.kinect_v1_paper())
        reference.insert(pts[:500])
    assert report.insertion.points_received == len(np.asarray(variants[layout]).reshape(-1, 3))
    assert_same_maps(mapper, reference)


def test_incremental_maps_equal_their_full_recomputation(tmp_path, sample_points):
    """Random batches, then a Mapper rebuilt from the saved grid (which recomputes everything)."""
    rng = np.random.default_rng(7)
    second = oi.depth_to_points(*oi.sample_depth(seed=2)).reshape(-1, 3)
    points = np.concatenate([sample_points, second])[rng.permutation(2 * len(sample_points))]
    mapper, pos, batches = oi.Mapper(oi.kinect_v1_paper()), 0, 0
    while pos < len(points):
        n = int(1 + rng.integers(50 if batches < 20 else 60000))
        r = mapper.insert(points[pos : pos + n])
        assert r.insertion.points_received == min(n, len(points) - pos)
        assert r.rays_recomputed >= r.surface_columns_changed
        pos, batches = pos + n, batches + 1
    assert batches > 25
    mapper.save(tmp_path / "m.occmap")
    full = oi.load_map(tmp_path / "m.occmap")
    np.testing.assert_array_equal(mapper.depth(), full.depth())
    np.testing.assert_array_equal(mapper.probability(), full.probability())
    np.testing.assert_allclose(mapper.improvement(), full.improvement(), atol=1e-6, rtol=0)


def test_more_frames_lower_the_expected_improvement():
    mapper, totals = oi.Mapper(oi.kinect_v1_paper()), []
    for seed in (1, 2, 3):
        mapper.insert_depth(*oi.sample_depth(seed=seed))
        totals.append(mapper.stop_signal().total_improvement)
    assert totals[0] > totals[1] > totals[2]


def test_views_are_read_only_live_and_keep_the_mapper_alive(sample):
    mapper = oi.Mapper(oi.kinect_v1_paper())
    view = mapper.improvement(copy=False)
    depth_view = mapper.depth(copy=False)
    before = mapper.improvement()
    assert not view.flags.writeable and mapper.improvement().flags.writeable
    with pytest.raises(ValueError):
        view[0, 0] = 1.0
    mapper.insert_depth(*sample)
    np.testing.assert_array_equal(view, mapper.improvement())  # the view follows the insert
    assert not np.array_equal(before, view)  # the earlier copy does not
    expected = mapper.depth()
    del mapper
    gc.collect()
    np.testing.assert_array_equal(depth_view, expected)  # still valid: the view owns the Mapper


def test_views_stay_valid_when_the_maps_are_recomputed(sample):
    """clear_mask() and the recomputation after an interrupted call replaced the buffers a copy=False view
    read: the view read freed memory (a crash, or values of 1e38)."""
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    mask = np.zeros(depth.shape, bool)
    mask[:, : depth.shape[1] // 2] = True
    mapper.set_mask(mask)
    mapper.insert_depth(depth, intrinsics)
    view = mapper.improvement(copy=False)
    assert np.isnan(view[:, -1]).all()  # masked
    mapper.clear_mask()
    np.testing.assert_array_equal(view, mapper.improvement())
    assert not np.isnan(view).any()


def test_insertion_releases_the_gil(sample):
    """A Python thread keeps ticking while another inserts: gaps far shorter than the insertion."""
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1_paper())
    result = {}
    worker = threading.Thread(target=lambda: result.update(r=mapper.insert_depth(depth, intrinsics, threads=1)))
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    seconds = result["r"].insertion.seconds + result["r"].improvement_seconds
    assert seconds > 0.05, "the insertion was too short to tell"
    assert len(ticks) > 100
    assert np.max(np.diff(ticks)) < 0.5 * seconds


def test_calls_from_two_threads_are_serialised(sample):
    depth, intrinsics = sample
    shared, sequential = oi.Mapper(oi.kinect_v1_paper()), oi.Mapper(oi.kinect_v1_paper())
    workers = [threading.Thread(target=shared.insert_depth, args=(depth, intrinsics)) for _ in range(2)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    sequential.insert_depth(depth, intrinsics)
    sequential.insert_depth(depth, intrinsics)
    assert_same_maps(shared, sequential)


def test_the_documented_layouts_are_read_in_place_and_the_others_copied(sample_points, sample):
    read_in_place = oi._core._points_read_in_place
    pts = np.ascontiguousarray(sample_points[:1000])
    padded = np.concatenate([pts, np.zeros((len(pts), 1), np.float32)], axis=1)
    organized = np.ascontiguousarray(pts).reshape(10, 100, 3)
    organized_padded = np.concatenate([organized, np.zeros((10, 100, 1), np.float32)], axis=2)
    assert read_in_place(pts) and read_in_place(organized)
    assert read_in_place(padded[:, :3]) and read_in_place(organized_padded[..., :3])
    assert read_in_place(pts[::2])  # a constant stride of 6 floats
    assert read_in_place(organized[:, ::2])  # every other point of each row: still one stride throughout
    for copied in (pts.astype(np.float64), np.asfortranarray(pts), pts.astype(">f4"), pts[::-1],
                   organized[:, :50], pts.tolist()):  # organized[:, :50]: rows jump after 50 points
        assert not read_in_place(copied)
    depth, k = sample
    assert oi._core._depth_read_in_place(depth, k)
    for copied in (depth.astype(np.float64), np.asfortranarray(depth), (depth * 1000).astype(np.uint16)):
        assert not oi._core._depth_read_in_place(copied, k)
