"""Bad input: wrong shapes and dtypes, NaN-only and empty frames, bad parameters."""
import subprocess
import sys

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


@pytest.mark.parametrize("rows, given", [
    ([[0, 0, 1.0], [0.1, 0]], "row 0 has 3 values, row 1 has 2 values"),
    ([[0, 0, 1.0], 2.0], "row 0 has 3 values, row 1 is a single value"),
    ([[[0, 0, 1.0], [0, 0, 2.0]], [[0, 0, 1.0], [0, 0]]], r"inhomogeneous shape"),  # ragged one level down
])
def test_ragged_point_lists_raise_invalid_input_naming_the_shape(mapper, rows, given):
    """These gave "Internal error: pybind11::error_already_set called while Python error indicator not set"."""
    with pytest.raises(oi.InvalidInput, match=r"points must be an N x 3 or H x W x 3 array of x, y, z, got .*"
                                              + given) as e:
        mapper.insert(rows)
    assert isinstance(e.value, ValueError)
    assert mapper.touched_columns() == 0


def test_ragged_depth_lists_raise_invalid_input(mapper):
    k = oi.PinholeIntrinsics(fx=2.0, fy=2.0, cx=0.5, cy=0.5, width=2, height=2)
    with pytest.raises(oi.InvalidInput, match=r"depth must be an H x W array of depths, got a ragged nested "
                                              r"sequence \(row 0 has 2 values, row 1 has 1 value\)"):
        mapper.insert_depth([[1.0, 1.0], [1.0]], k)


@pytest.mark.parametrize("threads", [-1, 1025, 40000])
def test_thread_counts_outside_the_tools_range_raise_invalid_parameter(mapper, sample, threads):
    """threads=40000 aborted the interpreter (a thread the system refused, std::terminate); -1 was taken."""
    depth, intrinsics = sample
    message = rf"threads = {threads} is invalid: must be in \[0, 1024\]"
    with pytest.raises(oi.InvalidParameter, match=message) as e:
        mapper.insert(np.zeros((4, 3), np.float32) + [0, 0, 1], threads=threads)
    assert isinstance(e.value, ValueError)
    with pytest.raises(oi.InvalidParameter, match=message):
        mapper.insert_depth(depth, intrinsics, threads=threads)
    assert mapper.touched_columns() == 0


REFUSED_THREADS = """
import resource, sys
import numpy as np
import occ_improve as oi
depth, k = oi.sample_depth()
points = oi.depth_to_points(depth, k).reshape(-1, 3)
one = oi.Mapper(oi.kinect_v1_paper())
one.insert(points, threads=1)
# 1.5 GB more address space: room for the grid, not for 1024 thread stacks of 8 MB.
size = int(next(l for l in open("/proc/self/status") if l.startswith("VmSize")).split()[1]) * 1024
resource.setrlimit(resource.RLIMIT_AS, (size + 1_500_000_000, resource.RLIM_INFINITY))
many = oi.Mapper(oi.kinect_v1_paper())
r = many.insert(points, threads=1024).insertion
print(r.points_inserted, one.touched_columns(), many.touched_columns(),
      int(np.array_equal(many.improvement(), one.improvement())), int(np.array_equal(many.depth(), one.depth())))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/status")
def test_threads_the_system_refuses_leave_their_work_to_the_caller():
    """1024 threads where the address space holds far fewer stacks: a refused thread aborted the
    interpreter ("terminate called without an active exception"); now the calling thread runs the parts
    left over, and the maps equal the single-threaded ones."""
    run = subprocess.run([sys.executable, "-c", REFUSED_THREADS], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    inserted, touched_one, touched_many, same_improvement, same_depth = map(int, run.stdout.split())
    assert inserted > 250_000 and touched_many == touched_one > 250_000
    assert (same_improvement, same_depth) == (1, 1)


@pytest.mark.parametrize("scale, unit, suggested", [(1.0, "millimetres", "0.001"), (1000.0, "millimetres", "0.001")])
def test_millimetres_with_a_metres_scale_are_refused(sample, scale, unit, suggested):
    """uint16 millimetres with scale=1 (or Open3D's depth_scale=1000 habit) put every return beyond the grid:
    the map said free to its end, with no warning. Now the scale is refused with the one to pass."""
    depth, intrinsics = sample
    millimetres = np.round(depth * 1000).astype(np.uint16)
    median_m = float(np.median(millimetres[millimetres > 0])) * scale
    for preset, far_m in ((oi.kinect_v1(intrinsics), 8), (oi.kinect_v1_paper(), 5)):
        mapper = oi.Mapper(preset)
        with pytest.raises(oi.InvalidParameter) as e:
            mapper.insert_depth(millimetres, intrinsics, scale=scale)
        text = str(e.value)
        assert text.startswith(f"scale = {scale:g} puts the median depth of this image at ")
        assert float(text.split(" at ")[1].split(" m,")[0]) == pytest.approx(median_m, rel=1e-5)
        assert f"depth range [" in text and f", {far_m}] m" in text
        assert text.endswith(f"looks like {unit}: pass scale={suggested}")
        assert mapper.touched_columns() == 0


def test_metres_with_a_millimetres_scale_are_refused(sample):
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    for scale in (0.001, 1000.0):
        with pytest.raises(oi.InvalidParameter, match=rf"^scale = {scale:g} .* looks like metres: pass scale=1$"):
            mapper.insert_depth(depth, intrinsics, scale=scale)
    assert mapper.touched_columns() == 0


def test_plausible_scales_and_scenes_beyond_the_range_are_accepted(sample):
    depth, intrinsics = sample
    millimetres = np.round(depth * 1000).astype(np.uint16)
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    r = mapper.insert_depth(millimetres, intrinsics, scale=0.001).insertion
    assert r.points_inserted == np.count_nonzero(millimetres) and r.beyond_depth_range == 0
    r = mapper.insert_depth(depth, intrinsics, scale=1).insertion
    assert r.points_inserted == np.count_nonzero(depth)
    # A far scene no other unit explains is the caller's data: inserted, counted beyond the range.
    far = np.where(depth > 0, depth * 3, 0).astype(np.float32)
    assert np.median(far[far > 0]) > 8
    r = mapper.insert_depth(far, intrinsics).insertion
    assert r.beyond_depth_range > r.points_inserted / 2
    # Too few returns to judge the unit: accepted as given.
    sparse = np.zeros_like(millimetres)
    sparse[240, :50] = 1500
    assert mapper.insert_depth(sparse, intrinsics).insertion.points_inserted == 50


def test_points_in_millimetres_are_refused_and_metres_accepted(sample, sample_points):
    """A 2 m scene given as millimetre points was inserted 'beyond the depth range' (100 times slower,
    the map free to its end) without a word; insert_depth already refused such a unit."""
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    with pytest.raises(oi.InvalidParameter) as e:
        mapper.insert(sample_points * 1000)
    text = str(e.value)
    ranges = np.linalg.norm(sample_points, axis=1)
    assert text.startswith("the points' median range is ")
    median_m = float(text.split(" is ")[1].split(" m,")[0])
    assert median_m == pytest.approx(1000 * np.median(ranges[np.isfinite(ranges) & (ranges > 0)]), rel=1e-3)
    assert text.endswith("they look like millimetres (times 0.001 gives metres): pass them in metres (a scene "
                         "that far needs a larger depth_max_m)")
    assert mapper.touched_columns() == 0
    r = mapper.insert(sample_points).insertion
    assert r.points_inserted == np.count_nonzero(depth) and r.beyond_depth_range == 0


def test_depth_images_of_another_camera_are_refused(sample):
    """A kinect_v1 grid built for fx = 585 silently dropped most pixels of a depth image given with other
    intrinsics as outside its field of view."""
    depth, k = sample
    assert (k.fx, k.width) == (585.0, 640)
    nominal = oi.kinect_v1_intrinsics()
    half = oi.PinholeIntrinsics(fx=292.5, fy=292.5, cx=159.5, cy=119.5, width=320, height=240)
    for preset in (oi.kinect_v1(k), oi.kinect_v1_spherical(k)):
        mapper = oi.Mapper(preset)
        with pytest.raises(oi.InvalidParameter, match=r"intrinsics \(fx=525.00 fy=525.00 cx=319.50 cy=239.50 640x480\) "
                                                      r"are not the camera the grid was built for \(fx=585.00 fy=585.00 "
                                                      r"cx=319.50 cy=239.50 640x480\)"):
            mapper.insert_depth(depth, nominal)
        with pytest.raises(oi.InvalidParameter, match=r"\(fx=292.50 .* 320x240\) are not the camera .*640x480"):
            mapper.insert_depth(depth[::2, ::2].copy(), half)
        # The grid's own camera, and an image of another size, still say which is wrong.
        with pytest.raises(oi.InvalidInput, match=r"\(480, 640\), got shape \(240, 320\)"):
            mapper.insert_depth(depth[::2, ::2], k)
        assert mapper.touched_columns() == 0
        r = mapper.insert_depth(depth, oi.PinholeIntrinsics(fx=585.01, fy=585, cx=319.5, cy=239.5)).insertion
        assert r.points_inserted == np.count_nonzero(depth)  # within the tools' 0.05 px: the same camera
    # A grid that does not depend on a camera takes any.
    paper = oi.Mapper(oi.kinect_v1_paper())
    assert paper.insert_depth(depth[::2, ::2].copy(), half).insertion.points_inserted > 0


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


def test_lidar_rings_without_a_ring_table_is_invalid_parameter_not_a_crash():
    # The rows were built from the empty table before it was checked: the interpreter died (exit 139).
    with pytest.raises(oi.InvalidParameter, match="row_elevations_rad size = 0"):
        oi.GeometryParams(angular_binning="lidar_rings").validate()
    with pytest.raises(oi.InvalidParameter, match="row_elevations_rad"):
        oi.preset_from_pinhole(oi.kinect_v1_intrinsics(), oi.PinholePresetOptions(angular_binning="lidar_rings"))


@pytest.mark.parametrize("make, field, value", [
    (oi.PlanRequest, "budget_rays", 2**40),
    (oi.PlanRequest, "budget_rays", -2**31 - 1),
    (oi.SegmentationParams, "min_segment_columns", -1),
    (oi.GridOptions, "memory_cap_bytes", 2**64),
    (oi.PinholeIntrinsics, "width", 2**31),
])
def test_integer_fields_out_of_their_range_raise_invalid_parameter_naming_field_and_range(make, field, value):
    name = f"{make.__name__}.{field}"
    with pytest.raises(oi.InvalidParameter, match=rf"{name} = {value} is out of range \[-?\d+, \d+\]"):
        make(**{field: value})
    params = make()
    before = getattr(params, field)
    with pytest.raises(oi.InvalidParameter, match=name):
        setattr(params, field, value)
    assert getattr(params, field) == before


def test_integer_fields_take_numpy_integers_and_refuse_floats_bools_and_strings():
    request = oi.PlanRequest(budget_rays=np.int64(5000))
    assert request.budget_rays == 5000 and isinstance(request.budget_rays, int)
    for value in (1.5, True, "3"):
        with pytest.raises(TypeError, match=r"PlanRequest.budget_rays takes an int"):
            request.budget_rays = value
    assert request.budget_rays == 5000


def test_a_thread_count_beyond_a_c_int_is_invalid_parameter_naming_threads(mapper, sample):
    depth, intrinsics = sample
    for threads in (2**40, -2**40):
        with pytest.raises(oi.InvalidParameter, match="threads"):
            mapper.insert_depth(depth, intrinsics, threads=threads)
    with pytest.raises(TypeError, match="threads takes an int"):
        mapper.insert_depth(depth, intrinsics, threads=1.5)
    assert mapper.touched_columns() == 0


@pytest.mark.parametrize("make, field", [
    (lambda: oi.GridOptions(mode=oi.UpdateMode(7)), "mode"),
    (lambda: oi.PlanRequest(shape=oi.ShotShape(9)), "shape"),
    (lambda: oi.PlanRequest(refine_by=oi.RefineBy(9)), "refine_by"),
    (lambda: oi.PlanRequest(local_model=oi.LocalModel(9)), "local_model"),
] + ([(lambda: oi.OctomapExportOptions(free_leaves=oi.FreeLeafRule(9)), "free_leaves")] if oi.HAS_OCTOMAP else []))
def test_enums_made_from_numbers_outside_their_values_are_invalid_parameter(make, field):
    """UpdateMode(7) ran as exact (and was saved so), ShotShape(9) planned as decimation: validate() passed."""
    options = make()
    with pytest.raises(oi.InvalidParameter, match=field):
        options.validate(*((640, 480) if isinstance(options, oi.PlanRequest) else ()))
