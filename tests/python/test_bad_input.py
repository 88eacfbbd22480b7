"""Bad input: wrong shapes and dtypes, NaN-only and empty frames, bad parameters."""
import numpy as np
import pytest

import occ_improve as oi


@pytest.fixture()
def mapper():
    return oi.Mapper(oi.kinect_v1_paper())


@pytest.mark.parametrize("shape", [(10,), (10, 2), (10, 4), (4, 5, 2), (2, 2, 2, 3), ()])
def test_wrong_point_shapes_raise_invalid_input(mapper, shape):
    with pytest.raises(oi.InvalidInput, match=r"N x 3 or H x W x 3 .* got shape") as e:
        mapper.insert(np.ones(shape, np.float32))
    assert isinstance(e.value, ValueError)


@pytest.mark.parametrize("dtype", [np.complex64, np.bool_, object, "U3"])
def test_non_numeric_points_raise_type_error(mapper, dtype):
    with pytest.raises(TypeError, match="real numeric array"):
        mapper.insert(np.zeros((5, 3), dtype=dtype))


def test_nan_only_and_empty_frames_change_nothing(mapper):
    empty_improvement = mapper.improvement()
    r = mapper.insert(np.full((1000, 3), np.nan, np.float32)).insertion
    assert (r.points_received, r.points_inserted, r.skipped_invalid) == (1000, 0, 1000)
    r = mapper.insert(np.zeros((0, 3), np.float32)).insertion
    assert r.points_received == 0
    r = mapper.insert(np.array([[np.inf, 0, 1], [0, 0, 0], [0, -np.inf, 2]])).insertion
    assert r.skipped_invalid == 3  # infinite coordinates and the origin (no return)
    assert mapper.touched_columns() == 0
    np.testing.assert_array_equal(mapper.improvement(), empty_improvement)


def test_points_outside_the_field_of_view_are_counted(mapper):
    r = mapper.insert(np.array([[0, 0, -1], [5, 0, 1], [0, 0, 2]], np.float32)).insertion
    assert (r.skipped_outside_fov, r.points_inserted) == (2, 1)


def test_depth_images_must_match_their_intrinsics(mapper, sample):
    depth, intrinsics = sample
    with pytest.raises(oi.InvalidInput, match=r"\(480, 640\), got shape \(640, 480\)"):
        mapper.insert_depth(depth.T, intrinsics)
    with pytest.raises(oi.InvalidInput, match="got shape"):
        mapper.insert_depth(depth[None], intrinsics)
    bad = oi.PinholeIntrinsics(fx=0.0)
    with pytest.raises(oi.InvalidInput, match="depth image intrinsics: .*fx"):
        mapper.insert_depth(depth, bad)
    with pytest.raises(oi.InvalidParameter, match="scale"):
        mapper.insert_depth(depth, intrinsics, scale=0.0)
    with pytest.raises(TypeError):
        mapper.insert_depth(depth.astype(np.complex64), intrinsics)


def test_nan_only_depth_image_inserts_nothing(mapper, sample):
    _, intrinsics = sample
    r = mapper.insert_depth(np.full((480, 640), np.nan, np.float32), intrinsics).insertion
    assert r.points_received == 480 * 640 and r.skipped_invalid == r.points_received


def test_integer_millimetres_with_a_scale_equal_metres(sample):
    depth, intrinsics = sample
    millimetres = np.round(depth * 1000).astype(np.uint16)
    a, b = oi.Mapper(oi.kinect_v1_paper()), oi.Mapper(oi.kinect_v1_paper())
    a.insert_depth(millimetres, intrinsics, scale=0.001)
    # The scale is applied in double and rounded to float once, as here.
    b.insert_depth((millimetres.astype(np.float64) * 0.001).astype(np.float32), intrinsics)
    np.testing.assert_array_equal(a.depth(), b.depth())
    np.testing.assert_array_equal(a.improvement(), b.improvement())


def test_bad_query_parameters_raise_invalid_parameter(mapper):
    with pytest.raises(oi.InvalidParameter):
        mapper.top_rays(0)
    with pytest.raises(oi.InvalidParameter):
        mapper.regions(oi.RegionOptions(min_improvement=float("nan")))
    with pytest.raises(oi.InvalidParameter):
        mapper.stop_signal(oi.StopCriteria(total_improvement_below=-1))
    with pytest.raises(oi.InvalidParameter):
        oi.StopMonitor(progress=oi.ProgressCriteria(patience=0)).update(mapper)
    with pytest.raises(oi.InvalidParameter, match="azimuth_bin"):
        mapper.direction(-1, 0)
    with pytest.raises(TypeError):
        mapper.top_rays("ten")
