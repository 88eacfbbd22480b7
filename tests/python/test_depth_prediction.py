"""predict_dense_depth and Mapper.predict_depth: the linear rule reproduces a slanted plane that the
nearest rule steps over, never interpolates across a depth step, and bad input raises typed errors."""
import numpy as np
import pytest

import occ_improve as oi


def kinect_noise():
    return oi.SensorModelParams(sigma_depth_m=0.0, sigma_depth_per_m2=1.425e-3)


def plane(h=48, w=64):
    y, x = np.mgrid[0:h, 0:w]
    return (1.0 / (0.5 - 0.0004 * x - 0.0003 * y)).astype(np.float32)  # 1/z affine: a plane, 2.0-2.15 m


def sparse_of(dense, share=0.05, seed=3):
    rng = np.random.default_rng(seed)
    keep = rng.random(dense.shape) < share
    keep[[0, -1], :] = True  # the border, so that the samples' hull is the whole image
    keep[:, [0, -1]] = True
    return np.where(keep, dense, 0.0).astype(np.float32)


def test_linear_reproduces_a_slanted_plane_where_nearest_is_off():
    truth = plane()
    sparse = sparse_of(truth)
    sigma = 1.425e-3 * truth ** 2
    linear, dist_l = oi.predict_dense_depth(sparse, kinect_noise(), oi.DepthPredictionParams(rule=oi.DepthPredictionRule.linear))
    nearest, dist_n = oi.predict_dense_depth(sparse, kinect_noise())
    assert linear.dtype == np.float32 and dist_l.dtype == np.int32 and linear.shape == truth.shape
    assert np.array_equal(dist_l, dist_n) and (dist_l >= 0).all()
    assert (np.abs(linear - truth) / sigma).max() < 0.02
    assert (np.abs(nearest - truth) / sigma).max() > 1.0
    assert linear[sparse > 0].tolist() == sparse[sparse > 0].tolist()  # samples keep their depth


def test_a_depth_step_is_not_interpolated_and_the_nearer_surface_wins_at_a_tie():
    sparse = np.zeros((5, 19), np.float32)
    for y in (0, 4):
        for x in (3, 7, 11, 15):
            sparse[y, x] = 1.0 if x < 10 else 2.0
    depth, _ = oi.predict_dense_depth(sparse, kinect_noise(), oi.DepthPredictionParams(rule=oi.DepthPredictionRule.linear))
    assert set(np.unique(depth).tolist()) == {1.0, 2.0}
    assert depth[0, 9] == 1.0 and depth[2, 9] == 1.0 and depth[2, 10] == 2.0


def test_radius_and_nan_samples():
    sparse = np.full((11, 21), np.nan, np.float32)  # NaN: no sample, as 0
    sparse[0, 0], sparse[0, 20], sparse[10, 0] = 2.0, 2.01, 2.0
    params = oi.DepthPredictionParams(rule=oi.DepthPredictionRule.linear, radius_columns=4)
    depth, dist = oi.predict_dense_depth(sparse, kinect_noise(), params)
    assert dist[0, 10] == -1 and depth[0, 10] == 0.0 and depth[0, 4] == 2.0
    params.radius_columns = 12
    depth, _ = oi.predict_dense_depth(sparse, kinect_noise(), params)
    assert depth[0, 4] == pytest.approx(1.0 / (0.8 / 2.0 + 0.2 / 2.01), abs=1e-6)


def test_bad_input_raises_typed_errors_naming_the_value():
    model = kinect_noise()
    with pytest.raises(oi.InvalidParameter, match="discontinuity_sigmas"):
        oi.predict_dense_depth(np.zeros((3, 4)), model, oi.DepthPredictionParams(discontinuity_sigmas=0.0))
    with pytest.raises(oi.InvalidParameter, match="radius_columns = -1"):
        oi.predict_dense_depth(np.zeros((3, 4)), model, oi.DepthPredictionParams(radius_columns=-1))
    bad = np.zeros((3, 4))
    bad[1, 2] = -1.0
    with pytest.raises(oi.InvalidInput, match=r"pixel \(2, 1\)"):
        oi.predict_dense_depth(bad, model)
    with pytest.raises(oi.InvalidInput, match="dimensions"):
        oi.predict_dense_depth(np.zeros(12), model)


def test_mapper_predicts_from_its_surface():
    depth, k = oi.sample_depth()
    full = oi.Mapper(oi.kinect_v1(k))
    full.insert_depth(depth, k)
    sparse = sparse_of(depth, seed=5)
    sparse[[0, -1], :] = 0
    sparse[:, [0, -1]] = 0
    mapper = oi.Mapper(oi.kinect_v1(k))
    mapper.insert_depth(sparse, k)
    sigma = 1.425e-3 * depth ** 2
    has = depth > 0
    share = {}
    for rule in (oi.DepthPredictionRule.nearest, oi.DepthPredictionRule.linear):
        predicted, dist = mapper.predict_depth(oi.DepthPredictionParams(rule=rule))
        assert predicted.shape == depth.shape and (dist[has] >= 0).mean() > 0.95
        share[rule] = (np.abs(predicted - depth)[has] <= 2 * sigma[has]).mean()
    assert share[oi.DepthPredictionRule.linear] > share[oi.DepthPredictionRule.nearest]
