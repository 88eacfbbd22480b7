"""The planner, the return model and the intrinsics fit from Python: values checked against their
definitions (planner.hpp, return_model.hpp, intrinsics_fit.hpp), recomputed here with numpy."""
import math

import numpy as np
import pytest

import occ_improve as oi


@pytest.fixture(scope="module")
def pixel_mapper(sample):
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    mapper.insert_depth(depth, intrinsics)
    return mapper


def empty_record(mapper):
    return oi.ReturnRecord.for_grid(mapper.width, mapper.height)


def neighbour_sums(counts):
    """Sum over each cell's 8 neighbours (the cell itself left out), zero beyond the border."""
    padded = np.pad(counts.astype(np.int64), 1)
    h, w = counts.shape
    total = sum(padded[1 + dv:1 + dv + h, 1 + du:1 + du + w] for dv in (-1, 0, 1) for du in (-1, 0, 1))
    return total - counts


def test_rays_shot_takes_the_best_scores_and_sums_them(pixel_mapper):
    record = empty_record(pixel_mapper)
    shot = oi.plan_next_shot(pixel_mapper, record, oi.PlanRequest(budget_rays=500))
    scores = oi.shot_scores(pixel_mapper, record).ravel()
    assert shot.columns.dtype == np.uint32 and len(shot) == 500 == shot.ranked_rays
    assert len(set(shot.columns.tolist())) == 500
    taken = scores[shot.columns]
    assert np.all(np.diff(taken) <= 0), "ranked best first"
    others = np.delete(scores, shot.columns)
    assert taken.min() >= np.nanmax(others)
    assert shot.expected_gain == pytest.approx(float(taken.astype(np.float64).sum()), rel=1e-5)
    assert shot.stop == (shot.expected_gain < 0.1 * shot.ranked_rays)
    # An empty record discounts nothing: the scores are the improvement map itself.
    np.testing.assert_array_equal(oi.shot_scores(pixel_mapper, record), pixel_mapper.improvement())


def test_an_array_plans_as_the_mapper_does(pixel_mapper):
    record = empty_record(pixel_mapper)
    a = oi.plan_next_shot(pixel_mapper, record, oi.PlanRequest(budget_rays=300))
    b = oi.plan_next_shot(pixel_mapper.improvement(), record, oi.PlanRequest(budget_rays=300))
    np.testing.assert_array_equal(a.columns, b.columns)
    assert a.expected_gain == b.expected_gain


def test_silent_rays_are_discounted_and_not_asked_again(pixel_mapper):
    record = empty_record(pixel_mapper)
    request = oi.PlanRequest(budget_rays=200)
    first = oi.plan_next_shot(pixel_mapper, record, request)
    record.record_shot(first.columns, np.zeros(len(first), dtype=bool))
    assert record.total_asked == 200 and record.total_returned == 0 and oi.record_return_rate(record) == 0.0
    asked = record.asked
    assert asked.shape == (pixel_mapper.height, pixel_mapper.width) and asked.dtype == np.uint32
    assert asked.sum() == 200 and np.all(asked.ravel()[first.columns] == 1)
    second = oi.plan_next_shot(pixel_mapper, record, request)
    assert set(first.columns.tolist()).isdisjoint(second.columns.tolist())
    p = oi.return_probability_map(record)
    assert p.dtype == np.float32 and p.ravel()[first.columns].max() < 0.7
    np.testing.assert_allclose(oi.shot_scores(pixel_mapper, record), pixel_mapper.improvement() * p, rtol=1e-6)


def test_rays_whose_returns_do_not_settle_them_are_discounted(pixel_mapper):
    # Rays that returned twice or more but whose improvement stays >= 0.2 (near the no-data level) lose
    # s / (s + R).
    record = empty_record(pixel_mapper)
    imp = pixel_mapper.improvement()
    flat = imp.ravel()
    unsettled = np.flatnonzero(flat >= 0.2)[:50].astype(np.uint32)
    settled = np.flatnonzero((flat > 0) & (flat < 0.2))[:50].astype(np.uint32)
    assert len(unsettled) == 50 and len(settled) == 50
    for times in range(3):  # three returns each
        record.record_shot(np.concatenate([unsettled, settled]), np.ones(100, dtype=bool))
    p = oi.return_probability_map(record)
    returned = record.returned.astype(np.float32)
    s = oi.ReturnModelParams().prior_strength_shots
    expected = imp * p * np.where((returned >= 2) & (imp >= 0.2), s / (s + returned), 1.0)
    np.testing.assert_allclose(oi.shot_scores(pixel_mapper, record), expected, rtol=1e-6)
    scores = oi.shot_scores(pixel_mapper, record).ravel()
    np.testing.assert_allclose(scores[unsettled], flat[unsettled] * 0.4, rtol=1e-6)  # 2 / (2 + 3)
    np.testing.assert_allclose(scores[settled], flat[settled], rtol=1e-6)


def test_return_probability_is_the_beta_bernoulli_mean():
    rng = np.random.default_rng(3)
    w, h = 13, 9
    record = oi.ReturnRecord.for_grid(w, h)
    for _ in range(20):
        columns = rng.integers(0, w * h, size=30)
        record.record_shot(columns, rng.random(30) < 0.6)
    asked, returned = record.asked.astype(np.int64), record.returned.astype(np.int64)
    np.testing.assert_array_equal(record.asked_nearby, neighbour_sums(asked))
    np.testing.assert_array_equal(record.returned_nearby, neighbour_sums(returned))
    s = 3.5
    prior = (neighbour_sums(returned) + 1.0) / (neighbour_sums(asked) + 1.0)
    expected = (s * prior + returned) / (s + asked)
    got = oi.return_probability_map(record, oi.ReturnModelParams(prior_strength_shots=s))
    np.testing.assert_allclose(got, expected, rtol=1e-6)
    assert oi.record_return_rate(record) == pytest.approx(returned.sum() / asked.sum())
    again = oi.ReturnRecord.from_counts(w, h, record.asked, record.returned)
    np.testing.assert_array_equal(again.asked_nearby, record.asked_nearby)
    assert again.total_returned == record.total_returned


def test_return_record_refuses_bad_shots_and_counts_nothing():
    record = oi.ReturnRecord.for_grid(4, 3)
    with pytest.raises(oi.InvalidInput):
        record.record_shot([0, 1], [True])
    with pytest.raises(oi.InvalidParameter, match="12"):
        record.record_shot([0, 12], [True, True])
    assert record.empty and record.total_asked == 0
    with pytest.raises(oi.InvalidInput):
        oi.ReturnRecord.from_counts(4, 3, np.ones(12), np.full(12, 2))  # more returns than asks
    with pytest.raises(oi.InvalidInput):
        oi.ReturnRecord.from_counts(4, 3, np.ones(11), np.ones(11))
    # A W x H array has the right size but would be read scrambled (indexed [u, v]); H x W and flat are taken.
    counts = np.zeros((3, 4))
    counts[1, 2] = 5
    with pytest.raises(oi.InvalidInput, match="asked is 4 x 3: must be height x width = 3 x 4"):
        oi.ReturnRecord.from_counts(4, 3, counts.T, np.zeros((4, 3)))
    assert oi.ReturnRecord.from_counts(4, 3, counts, np.zeros((3, 4))).asked[1, 2] == 5
    assert oi.ReturnRecord.from_counts(4, 3, counts.ravel(), np.zeros(12)).asked[1, 2] == 5
    with pytest.raises(oi.InvalidInput):
        record.check_matches(640, 480)
    with pytest.raises(oi.InvalidParameter):
        oi.ReturnModelParams(prior_strength_shots=0).validate()


def test_counts_and_columns_must_be_whole_numbers_in_range():
    # A cast made -1 into 4294967295 asks (then a minute-long loop deaf to Ctrl-C) and 1.5 into 1.
    for bad, value in (([-1, 0, 0, 0], "-1"), ([1.5, 0, 0, 0], "1.5"), ([np.nan, 0, 0, 0], "nan")):
        with pytest.raises(oi.InvalidInput, match=r"asked: element 0 is " + value):
            oi.ReturnRecord.from_counts(2, 2, np.array(bad), np.zeros(4))
    with pytest.raises(oi.InvalidInput, match="2\\^28"):
        oi.ReturnRecord.from_counts(2, 2, np.full(4, 2**32 - 1), np.zeros(4))
    record = oi.ReturnRecord.for_grid(4, 3)
    with pytest.raises(oi.InvalidInput, match="columns: element 1 is -1"):
        record.record_shot([0, -1], [True, True])
    assert record.total_asked == 0
    exact = oi.ReturnRecord.from_counts(2, 2, np.array([3.0, 2, 1, 0]), np.array([1, 1, 0, 0], dtype=np.uint8))
    assert exact.asked.tolist() == [[3, 2], [1, 0]]
    assert exact.asked_nearby.tolist() == [[3, 4], [5, 6]]


def test_window_and_decimation_shapes(pixel_mapper):
    w, h = pixel_mapper.width, pixel_mapper.height
    record = empty_record(pixel_mapper)
    window = oi.plan_next_shot(pixel_mapper, record, oi.PlanRequest(
        budget_rays=40 * 30, shape=oi.ShotShape.window, window_width_columns=40, window_height_columns=30))
    v, u = np.divmod(window.columns.astype(np.int64), w)
    assert len(window) == 1200 and np.ptp(u) == 39 and np.ptp(v) == 29
    scores = oi.shot_scores(pixel_mapper, record)
    box = scores[v.min():v.max() + 1, u.min():u.max() + 1]
    assert window.expected_gain == pytest.approx(float(np.nansum(box, dtype=np.float64)), rel=1e-4)

    budget = 5000
    step = oi.decimation_step(w, h, budget)
    assert len(oi.decimation_pattern(w, h, step, 0, 0)) <= budget < len(oi.decimation_pattern(w, h, step - 1, 0, 0))
    shot = oi.plan_next_shot(pixel_mapper, record, oi.PlanRequest(budget_rays=budget, shape=oi.ShotShape.decimation))
    v, u = np.divmod(shot.columns.astype(np.int64), w)
    pattern = oi.decimation_pattern(w, h, step, int(u[0] % step), int(v[0] % step))
    np.testing.assert_array_equal(shot.columns, pattern)


def test_candidates_restrict_the_shot(pixel_mapper):
    w, h = pixel_mapper.width, pixel_mapper.height
    mask = np.zeros((h, w), dtype=bool)
    mask[:, : w // 4] = True  # the left quarter only
    request = oi.PlanRequest(budget_rays=400, candidates=mask)
    assert request.candidates.shape == (w * h,) and request.candidates.dtype == np.bool_
    shot = oi.plan_next_shot(pixel_mapper, empty_record(pixel_mapper), request)
    assert len(shot) == 400 and np.all(shot.columns % w < w // 4)
    request.candidates = None
    assert request.candidates is None
    request.candidates = np.ones(10, dtype=bool)
    with pytest.raises(oi.InvalidInput):
        oi.plan_next_shot(pixel_mapper, empty_record(pixel_mapper), request)


def test_plan_errors_name_the_problem(pixel_mapper):
    with pytest.raises(oi.InvalidParameter, match="budget"):
        oi.plan_next_shot(pixel_mapper, empty_record(pixel_mapper), oi.PlanRequest(budget_rays=0))
    with pytest.raises(oi.InvalidInput):
        oi.plan_next_shot(pixel_mapper, oi.ReturnRecord.for_grid(10, 10))
    with pytest.raises(oi.InvalidInput):
        oi.plan_next_shot(np.zeros(5, np.float32), oi.ReturnRecord.for_grid(5, 1))
    with pytest.raises(TypeError):
        oi.PlanRequest(budget=3)


def test_fit_intrinsics_recovers_the_camera(sample):
    depth, k = sample
    cloud = oi.depth_to_points(depth, k)
    fit = oi.fit_intrinsics(cloud)
    for name in ("fx", "fy", "cx", "cy"):
        assert getattr(fit.intrinsics, name) == pytest.approx(getattr(k, name), abs=1e-3)
    assert (fit.intrinsics.width, fit.intrinsics.height) == (k.width, k.height)
    assert fit.points_used == int(np.count_nonzero(depth > 0))
    assert fit.rms_residual_px < oi.MAX_INTRINSICS_FIT_RESIDUAL_PX
    # PCL-style padding (H x W x 4, read with a stride of 4 floats) and float64 give the same fit.
    padded = np.concatenate([cloud, np.ones(cloud.shape[:2] + (1,), np.float32)], axis=-1)
    assert oi.fit_intrinsics(padded[..., :3]).intrinsics.fx == fit.intrinsics.fx
    assert oi.fit_intrinsics(cloud.astype(np.float64)).intrinsics.cx == pytest.approx(fit.intrinsics.cx, abs=1e-9)


def test_fit_intrinsics_refuses_what_is_no_pinhole_image(sample):
    depth, k = sample
    cloud = oi.depth_to_points(depth, k)
    shifted = cloud.copy()
    shifted[::2, :, 0] += 0.01  # every other row moved sideways: no single pinhole explains it
    assert oi.fit_intrinsics(shifted).rms_residual_px > oi.MAX_INTRINSICS_FIT_RESIDUAL_PX
    with pytest.raises(oi.InvalidInput, match="residual|RMS|rms"):
        oi.fit_intrinsics_checked(shifted)
    with pytest.raises(oi.InvalidInput, match="organized"):
        oi.fit_intrinsics(cloud.reshape(-1, 3))
    with pytest.raises(oi.InvalidInput):
        oi.fit_intrinsics(np.full((20, 20, 3), np.nan, np.float32))


def test_a_refused_fit_names_no_command_line_flag(sample):
    """The library's message once ended "give the camera with -intrinsics", a flag of the tools that
    Python has not: from Python the way round is the camera's own intrinsics."""
    depth, k = sample
    shifted = oi.depth_to_points(depth, k)
    shifted[::2, :, 0] += 0.01
    with pytest.raises(oi.InvalidInput) as refused:
        oi.fit_intrinsics_checked(shifted)
    message = str(refused.value)
    assert "px RMS" in message and "-intrinsics" not in message and "read_intrinsics" in message


@pytest.mark.parametrize("limit", [-1.0, 0.0, float("nan"), float("inf")])
def test_fit_intrinsics_checked_refuses_a_limit_no_fit_can_meet(sample, limit):
    """max_rms_px = -1, 0 or NaN was an InvalidInput saying the cloud is no pinhole image (every fit
    "exceeds" it); inf let any fit through. The limit is checked first, as every parameter."""
    depth, k = sample
    cloud = oi.depth_to_points(depth, k)
    with pytest.raises(oi.InvalidParameter, match="max_rms_px"):
        oi.fit_intrinsics_checked(cloud, max_rms_px=limit)
    assert oi.fit_intrinsics_checked(cloud, max_rms_px=0.5).rms_residual_px < 0.5


def test_coarse_to_fine_covers_every_block_once_on_a_fresh_view(sample):
    """Strategy (g) from Python: on a map without data, a shot of one ray per 16-column block is the
    coverage pass (planner.hpp): exactly one ray in every block, none twice."""
    _, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    blocks_u, blocks_v = -(-mapper.width // 16), -(-mapper.height // 16)
    request = oi.PlanRequest(budget_rays=blocks_u * blocks_v, shape=oi.ShotShape.coarse_to_fine,
                             refine_by=oi.RefineBy.residual)
    assert request.coverage_block_columns == 16 and request.residual_cap_sigmas == 8.0
    shot = oi.plan_next_shot(mapper, empty_record(mapper), request)
    v, u = np.divmod(shot.columns.astype(np.int64), mapper.width)
    block = (v // 16) * blocks_u + u // 16
    assert len(shot) == blocks_u * blocks_v
    assert np.array_equal(np.sort(block), np.arange(blocks_u * blocks_v))


def acquire(mapper, record, shot, depth, intrinsics):
    """The shot's rays measured on the sample's depth image: returns inserted, the record updated."""
    v, u = np.divmod(shot.columns.astype(np.int64), mapper.width)
    z = depth[v, u]
    got = np.isfinite(z) & (z > 0)
    rays = np.stack([(u - intrinsics.cx) / intrinsics.fx * z, (v - intrinsics.cy) / intrinsics.fy * z, z], axis=1)
    mapper.insert(rays[got].astype(np.float32))
    record.record_shot(shot.columns, got)


def test_coarse_to_fine_by_triangles_asks_new_rays_between_samples(sample):
    """Refinement by the measured samples' triangles from Python: after a sparse first shot, the second
    shot is full, asks none of the first shot's rays, and is the same shot when planned again."""
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    record = empty_record(mapper)
    request = oi.PlanRequest(budget_rays=4000, shape=oi.ShotShape.coarse_to_fine, refine_by=oi.RefineBy.triangles)
    seen = set()
    # First shot: every observable ray is expected to come within 2 sigma with one return's probability
    # (erf(sqrt 2), good_rays.hpp); the stop reads the mean score of the view's best fifth (numpy here).
    observable = int(np.count_nonzero(~np.isnan(mapper.improvement())))
    first = oi.plan_next_shot(mapper, record, request)
    assert first.expected_gain == pytest.approx(math.erf(math.sqrt(2)) * observable, rel=1e-6)
    scores = np.sort(oi.shot_scores(mapper, record).ravel())[::-1]
    best_fifth = scores[~np.isnan(scores)][:math.ceil(0.2 * observable)]
    assert first.stop_gain_per_ray == pytest.approx(float(best_fifth.astype(np.float64).mean()), rel=1e-6)
    for _ in range(2):
        shot = oi.plan_next_shot(mapper, record, request)
        assert len(shot) == 4000 and not seen & set(shot.columns.tolist())
        acquire(mapper, record, shot, depth, intrinsics)
        seen |= set(shot.columns.tolist())
    assert np.array_equal(oi.plan_next_shot(mapper, record, request).columns,
                          oi.plan_next_shot(mapper, record, request).columns)


def test_plan_memory_plans_as_without_and_only_over_a_mapper(sample):
    """A PlanMemory kept over the shots of one acquisition extends the samples' triangulation instead of
    rebuilding it: every plan is the plan without memory (planner.hpp). An improvement array has no
    samples to keep: memory is refused there."""
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    record = empty_record(mapper)
    request = oi.PlanRequest(budget_rays=4000, shape=oi.ShotShape.coarse_to_fine, refine_by=oi.RefineBy.triangles)
    memory = oi.PlanMemory()
    for _ in range(3):
        shot = oi.plan_next_shot(mapper, record, request, memory=memory)
        assert len(shot) == 4000
        assert np.array_equal(shot.columns, oi.plan_next_shot(mapper, record, request).columns)
        acquire(mapper, record, shot, depth, intrinsics)
    assert memory.updates == 3 and 1 <= memory.start_overs < memory.updates  # the later plans inserted
    with pytest.raises(oi.InvalidParameter, match="memory"):
        oi.plan_next_shot(mapper.improvement(), record, oi.PlanRequest(budget_rays=100), memory=memory)


def test_coarse_to_fine_needs_the_mapper(pixel_mapper):
    with pytest.raises(oi.Error):
        oi.plan_next_shot(pixel_mapper.improvement(), empty_record(pixel_mapper),
                          oi.PlanRequest(budget_rays=100, shape=oi.ShotShape.coarse_to_fine))


def test_mask_leaves_rays_out_of_insertion_ranking_and_plan(sample):
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    mask = np.zeros((mapper.height, mapper.width), dtype=bool)
    mask[:, : mapper.width // 2] = True
    mapper.set_mask(mask)
    assert np.array_equal(mapper.column_mask, mask)
    report = mapper.insert_depth(depth, intrinsics)
    valid_right = int(np.count_nonzero(np.isfinite(depth[:, mapper.width // 2:]) & (depth[:, mapper.width // 2:] > 0)))
    assert report.points_masked == valid_right > 0
    improvement = mapper.improvement()
    assert np.all(np.isnan(improvement[:, mapper.width // 2:]))
    assert np.all(np.isfinite(improvement[:, : mapper.width // 2]))
    shot = oi.plan_next_shot(mapper, empty_record(mapper), oi.PlanRequest(budget_rays=2000))
    assert np.all(shot.columns % mapper.width < mapper.width // 2)
    with pytest.raises(oi.InvalidInput):
        mapper.set_mask(np.ones((10, 10), dtype=bool))
    mapper.clear_mask()
    assert mapper.column_mask is None
    assert np.all(np.isfinite(mapper.improvement()[:, mapper.width // 2:]))


def test_a_grid_without_camera_takes_a_mask_per_column():
    """A LiDAR's rear sector (its vehicle) masked by column: its returns left out and counted, NaN there, never planned."""
    mapper = oi.Mapper(oi.lidar_rings())
    mask = np.ones((mapper.height, mapper.width), dtype=np.uint8)
    mask[:, : mapper.width // 8] = 0
    with pytest.raises(oi.InvalidParameter, match="set_column_mask"):
        mapper.set_mask(mask)
    with pytest.raises(oi.InvalidInput, match="column mask"):
        mapper.set_column_mask(mask.T)
    mapper.set_column_mask(mask)
    assert np.array_equal(mapper.column_mask, mask.astype(bool))
    # One return per column, 10 m away horizontally, in the optical frame (z forward, y down).
    az = np.linspace(-np.pi, np.pi, mapper.width, endpoint=False) + np.pi / mapper.width
    el = np.radians(np.linspace(15, -15, mapper.height))
    a, e = np.meshgrid(az, el)
    points = np.stack([10 * np.sin(a), -10 * np.tan(e), 10 * np.cos(a)], axis=-1).astype(np.float32)
    report = mapper.insert(points.reshape(-1, 3))
    unmasked = oi.Mapper(oi.lidar_rings())
    columns = unmasked.insert(points.reshape(-1, 3)).insertion.points_inserted
    assert 0 < report.points_masked < columns
    assert report.insertion.points_inserted + report.points_masked == columns
    improvement = mapper.improvement()
    assert np.all(np.isnan(improvement[mask == 0])) and np.all(np.isfinite(improvement[mask != 0]))
    shot = oi.plan_next_shot(mapper, empty_record(mapper), oi.PlanRequest(budget_rays=2000))
    assert np.all(mask.reshape(-1)[shot.columns] != 0)


def test_insert_takes_the_mask_as_a_keyword(sample):
    """insert_depth(..., mask=) is set_mask then insert_depth: the same maps and counts."""
    depth, intrinsics = sample
    mask = np.zeros(depth.shape, dtype=np.uint8)
    mask[: depth.shape[0] // 2] = 1
    a = oi.Mapper(oi.kinect_v1(intrinsics))
    report = a.insert_depth(depth, intrinsics, mask=mask)
    b = oi.Mapper(oi.kinect_v1(intrinsics))
    b.set_mask(mask)
    assert report.points_masked == b.insert_depth(depth, intrinsics).points_masked > 0
    assert np.array_equal(a.column_mask, mask.astype(bool))
    np.testing.assert_array_equal(a.improvement(), b.improvement())


def test_plan_names_a_record_of_another_size_and_refuses_infinite_improvement():
    # The budget check came first and blamed budget_rays = 4096; an all-inf map gave expected_gain = inf.
    with pytest.raises(oi.InvalidInput, match="return record"):
        oi.plan_next_shot(np.zeros((10, 10), np.float32), oi.ReturnRecord.for_grid(640, 480), oi.PlanRequest())
    improvement = np.full((10, 10), 0.3, np.float32)
    improvement[2, 3] = np.inf
    with pytest.raises(oi.InvalidInput, match="row 2, column 3"):
        oi.plan_next_shot(improvement, oi.ReturnRecord.for_grid(10, 10), oi.PlanRequest(budget_rays=5))
    improvement[2, 3] = np.nan  # not observable: never planned
    shot = oi.plan_next_shot(improvement, oi.ReturnRecord.for_grid(10, 10), oi.PlanRequest(budget_rays=5))
    assert len(shot) == 5 and 23 not in list(shot.columns)


def test_candidates_and_return_flags_are_nonzero_flags_and_anything_else_is_named():
    # A float or wide-integer mask was cast to 8 bits (0.5 and 256 became 0: a shot of nothing, stop=True);
    # a string gave pybind11's internal RuntimeError.
    improvement = np.full((10, 10), 0.3, np.float32)
    returns = oi.ReturnRecord.for_grid(10, 10)
    for marked in (0.5, 256, -1):
        mask = np.zeros((10, 10))
        mask[:2] = marked
        shot = oi.plan_next_shot(improvement, returns, oi.PlanRequest(budget_rays=5, candidates=mask))
        assert len(shot) == 5 and all(c < 20 for c in shot.columns), marked
    with pytest.raises(oi.InvalidInput, match="candidates: element 3 is NaN"):
        oi.PlanRequest(candidates=np.array([0, 1, 0, np.nan]))
    # Not numbers (strings, objects, complex): a TypeError naming the argument, as the other arrays give.
    for bad in ("abc", {}, [None], np.array([1j, 0])):
        with pytest.raises(TypeError, match="candidates must be a real numeric array or booleans"):
            oi.PlanRequest(candidates=bad)
    # An empty array would mean every ray (the request's own empty mask): refused, None says that.
    with pytest.raises(oi.InvalidInput, match="empty mask"):
        oi.PlanRequest(candidates=np.zeros(0, bool))
    returns.record_shot([0, 1], np.array([0.5, 0.0]))
    assert returns.returned.ravel()[:2].tolist() == [1, 0]


def test_improvement_arrays_and_masks_of_other_types_raise_type_error_naming_them(pixel_mapper):
    # A string or object used to leak pybind11's "error_already_set ... indicator not set" RuntimeError,
    # a bool map was planned as numbers, a complex one lost its imaginary part with a warning only.
    returns = oi.ReturnRecord.for_grid(10, 10)
    for bad in ("abc", {}, object(), np.zeros((10, 10), bool), np.zeros((10, 10), complex)):
        with pytest.raises(TypeError, match="improvement must be a real numeric array"):
            oi.plan_next_shot(bad, returns)
        with pytest.raises(TypeError, match="improvement must be a real numeric array"):
            oi.shot_scores(bad, returns)
    with pytest.raises(TypeError, match="mask must be a real numeric array or booleans"):
        pixel_mapper.set_mask(np.full((480, 640), "x"))
    nan_mask = np.ones((480, 640))
    nan_mask[0, 0] = np.nan
    with pytest.raises(oi.InvalidInput, match="mask: element 0 is NaN"):
        pixel_mapper.set_mask(nan_mask)
    assert pixel_mapper.column_mask is None
