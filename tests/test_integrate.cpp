// Insertion (eq. 2) and the surface (CONVENTIONS 6) against the dense reference, ray by ray.
#include "occ_improve/errors.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/maps/surface.hpp"
#include "reference/reference.hpp"
#include "support/map_compare.hpp"

#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <thread>

namespace occ_improve {
namespace {

// A window of the paper preset's columns around the sample scene's box, pole and wall.
GridGeometry paper_crop(int a0, int e0, int w, int h, int depth_bins = 512) {
  SensorPreset p = kinect_v1_paper();
  p.geometry.depth_bins = depth_bins;
  return reference::crop(GridGeometry(p.geometry), a0, e0, w, h);
}

// The preset's 16 x 16 columns around the image centre, at 1024 depth bins (keeps the dense reference small).
GridGeometry centre_crop(SensorPreset p) {
  p.geometry.depth_bins = 1024;
  return reference::crop(GridGeometry(p.geometry), 312, 232, 16, 16);
}

TEST(Integrate, ExactModeMatchesReferenceOnSampleScene) {
  const GridGeometry g = paper_crop(150, 200, 48, 40);
  const SensorModel model(kinect_v1_paper().model);
  GridOptions o;
  o.mode = UpdateMode::exact;
  ColumnGrid fast(g, o);
  reference::DenseGrid ref(g, model, o);
  const auto points = sample::generate_scene().points();
  const InsertionReport r = insert_points(fast, model, PointSpan::from(points), {});
  ref.insert(points);
  EXPECT_GT(r.points_inserted, 500u);
  EXPECT_EQ(r.points_received, r.points_inserted + r.skipped_invalid + r.skipped_outside_fov);
  const reference::SurfaceAgreement a = reference::compare_surfaces(fast, ref);
  EXPECT_GE(a.same_bin, static_cast<std::size_t>(0.999 * a.columns)) << a.same_bin << " / " << a.columns;
  EXPECT_LE(a.max_dp, 1e-4);
}

TEST(Integrate, ClampedModeMatchesReferenceVoxelByVoxel) {
  const GridGeometry g = paper_crop(300, 220, 40, 30);
  const SensorModel model(kinect_v1_paper().model);
  ColumnGrid fast(g);
  reference::DenseGrid ref(g, model, GridOptions{});
  // Two frames with different noise, so clamping and re-visits are exercised.
  for (std::uint32_t seed : {1u, 2u}) {
    sample::SceneOptions so;
    so.seed = seed;
    const auto points = sample::generate_scene(so).points();
    insert_points(fast, model, PointSpan::from(points));
    ref.insert(points);
  }
  EXPECT_LE(reference::max_log_odds_difference(fast, ref), 1e-4);
  const reference::SurfaceAgreement a = reference::compare_surfaces(fast, ref);
  EXPECT_GE(a.same_bin, static_cast<std::size_t>(0.999 * a.columns)) << a.same_bin << " / " << a.columns;
}

// Clamped mode settles the free space a call carves in a column before applying its measurements
// (FreeSpaceBound, integrate.cpp): that leading run must stop at voxels already occupied (L > 0) that the
// call's returns do not take all the way to L_min. A plane at 1 m three times, then a step behind it:
// 4.5 sigmas (6.4 mm) behind on the left, whose returns carve the old surface by less than it holds, and
// 0.25 m behind on the right, with the pixel-native preset (neighbours at B = 12 and 24) and the paper's
// (neighbours at small B), against the dense reference voxel by voxel. Bound per frame: the one of
// IntegrateReal.PixelNativeClampedMatchesReferenceVoxelByVoxel, 2.45e-5.
TEST(Integrate, FreeSpaceOfACallStopsAtOccupiedVoxels) {
  const PinholeIntrinsics k;
  const auto frame = [&k](double left_m, double right_m) {
    std::vector<Eigen::Vector3f> points;
    for (int v = 200; v < 280; ++v)
      for (int u = 280; u < 360; ++u) {
        const double z = u < 320 ? left_m : right_m;
        points.emplace_back(static_cast<float>((u - k.cx) / k.fx * z), static_cast<float>((v - k.cy) / k.fy * z), static_cast<float>(z));
      }
    return points;
  };
  for (const SensorPreset& p : {kinect_v1(k), kinect_v1_paper()}) {
    const GridGeometry g = centre_crop(p);
    const SensorModel model(p.model);
    const double behind_m = 1.0 + 4.5 * model.sigma_depth_at(1.0);
    const std::vector<std::vector<Eigen::Vector3f>> frames{frame(1.0, 1.0), frame(1.0, 1.0), frame(1.0, 1.0),
                                                           frame(behind_m, 1.25)};
    GridOptions clamped;
    clamped.probability_min = 0.001;  // L_min = -6.9: bound b) reaches -5.2 sigmas at B = 0
    ColumnGrid fast(g, clamped);
    reference::DenseGrid ref(g, model, clamped);
    const ColumnIndex c = g.column(4, 8);  // in the left half
    int old_surface_bin = 0;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      if (f + 1 == frames.size()) old_surface_bin = column_surface(fast.find(c), fast).bin;
      insert_points(fast, model, PointSpan::from(frames[f]));
      ref.insert(frames[f]);
      EXPECT_LE(reference::max_log_odds_difference(fast, ref), static_cast<double>(f + 1) * 2.45e-5) << p.name << ", frame " << f;
    }
    // The old surface of the left half still holds more than L_min: the case where the run must stop.
    EXPECT_GT(ref.log_odds(c, old_surface_bin), fast.log_odds_min() + 1.0) << p.name;
  }
}

// Clamped mode holds a column's voxels in odds while a call updates them, but only the bins the call's
// measurements reach: the others are stored back bit for bit. (Converting a whole window there and back,
// as before, could move a voxel of a touched column by up to 5e-7 + 2e-7 |L| per call: drift for a view
// re-measured frame after frame, and most of a small shot's work.)
TEST(Integrate, BinsNoMeasurementOfACallReachesAreStoredBitForBit) {
  const PinholeIntrinsics k;
  const SensorPreset p = kinect_v1(k);
  const GridGeometry g = centre_crop(p);
  const SensorModel model(p.model);
  // A surface at about `z` whose depth varies from pixel to pixel (varied voxel values).
  const auto patch = [&k](double z, double phase) {
    std::vector<Eigen::Vector3f> points;
    for (int v = 232; v < 248; ++v)
      for (int u = 312; u < 328; ++u) {
        const double zp = z + 0.01 * std::sin(0.7 * u + 1.3 * v + phase);
        points.emplace_back(static_cast<float>((u - k.cx) / k.fx * zp), static_cast<float>((v - k.cy) / k.fy * zp),
                            static_cast<float>(zp));
      }
    return points;
  };
  ColumnGrid grid(g);
  for (double phase : {0.0, 0.4, 0.9}) insert_points(grid, model, PointSpan::from(patch(2.0, phase)));
  // A nearer surface: its measurements reach 1.01 m + their support, far in front of the 2 m returns.
  const int untouched_from = g.depth().first_centre_above(1.01 + 20.0 * model.sigma_depth_at(1.01));
  std::vector<float> before;
  for (ColumnIndex c = 0; c < g.column_count(); ++c)
    for (int b = untouched_from; b < g.depth().bins(); ++b) before.push_back(grid.log_odds(c, b));
  insert_points(grid, model, PointSpan::from(patch(1.0, 0.0)));
  std::size_t i = 0, held = 0, changed = 0;
  for (ColumnIndex c = 0; c < g.column_count(); ++c)
    for (int b = untouched_from; b < g.depth().bins(); ++b, ++i) {
      held += before[i] != 0.0f && before[i] != grid.log_odds_min() ? 1 : 0;
      changed += grid.log_odds(c, b) != before[i] ? 1 : 0;
    }
  EXPECT_GT(held, 16u * 16u * 5u);  // the 2 m surface's voxels lie in the checked bins
  EXPECT_EQ(changed, 0u);
  // The nearer return did update its own bins (carved free by the 2 m returns, so they rise from L_min).
  float peak = grid.log_odds_min();
  const double sigma = model.sigma_depth_at(1.0);
  for (int b = g.depth().first_centre_above(0.99 - 3 * sigma); b < g.depth().first_centre_above(1.01 + 3 * sigma); ++b)
    peak = std::max(peak, grid.log_odds(g.column(8, 8), b));
  EXPECT_GT(peak, grid.log_odds_min() + 1.0f);
}

// The other case FreeSpaceBound's front limit is for: two returns in one column and call, the nearer first
// (its peak raises the voxels at its depth by up to 1.6), the farther 5.3 sigmas behind it (carving them by
// about 7.3, just beyond bound b): the nearer one's voxels end above L_min, so the farther return's free
// space must not be settled over them.
TEST(Integrate, FreeSpaceOfACallStopsInFrontOfANearerReturnOfTheSameColumn) {
  const PinholeIntrinsics k;
  for (const SensorPreset& p : {kinect_v1(k), kinect_v1_paper()}) {
    const GridGeometry g = centre_crop(p);
    const SensorModel model(p.model);
    std::vector<Eigen::Vector3f> points;
    for (int v = 234; v < 246; ++v)
      for (int u = 314; u < 326; ++u)
        for (const double z : {1.3, 1.3 + 5.3 * model.sigma_depth_at(1.3)})
          points.emplace_back(static_cast<float>((u - k.cx) / k.fx * z), static_cast<float>((v - k.cy) / k.fy * z), static_cast<float>(z));
    GridOptions clamped;
    clamped.probability_min = 0.001;  // L_min = -6.9: bound b) reaches -5.2 sigmas at B = 0, short of 5.3
    ColumnGrid fast(g, clamped);
    reference::DenseGrid ref(g, model, clamped);
    insert_points(fast, model, PointSpan::from(points));
    ref.insert(points);
    EXPECT_LE(reference::max_log_odds_difference(fast, ref), 2.45e-5) << p.name;
    // The case itself: voxels of the nearer return end above L_min.
    const ColumnIndex c = g.column(8, 8);
    double highest = -1e9;
    for (int b = g.depth().first_centre_above(1.3 - 2 * model.sigma_depth_at(1.3)); g.depth().centre(b) < 1.3 + 2 * model.sigma_depth_at(1.3); ++b)
      highest = std::max(highest, ref.log_odds(c, b));
    EXPECT_GT(highest, fast.log_odds_min() + 0.5) << p.name;
  }
}

// A leading run the kernel did not make (a map from elsewhere: L = -1, or +0.5, over the first 300 bins of
// every column, not L_min): the column is loaded with it as voxels, the call's free space is settled over
// them from bin 0 where they hold L <= 0 and not at all where L > 0, and the result still matches the
// reference voxel by voxel.
TEST(Integrate, FreeSpaceOfACallOverALeadingRunTheKernelDidNotMake) {
  const PinholeIntrinsics k;
  const SensorPreset p = kinect_v1(k);
  const GridGeometry g = centre_crop(p);
  const SensorModel model(p.model);
  GridOptions clamped;
  clamped.probability_min = 0.001;
  std::vector<Eigen::Vector3f> points;
  for (int v = 228; v < 252; ++v)
    for (int u = 308; u < 332; ++u) {
      const double z = u < 320 ? 1.0 : 1.25;
      points.emplace_back(static_cast<float>((u - k.cx) / k.fx * z), static_cast<float>((v - k.cy) / k.fy * z), static_cast<float>(z));
    }
  constexpr int kRunBins = 300;
  ASSERT_LT(g.depth().centre(kRunBins), 1.0 - 10 * model.sigma_depth_at(1.0));  // the run lies in the free space
  for (const float run_value : {-1.0f, 0.5f}) {
    ColumnGrid fast(g, clamped);
    reference::DenseGrid ref(g, model, clamped);
    for (std::size_t c = 0; c < g.column_count(); ++c) {
      fast.assign({static_cast<ColumnIndex>(c), kRunBins, run_value, nullptr, 0});
      for (int b = 0; b < kRunBins; ++b) ref.set_log_odds(c, b, run_value);
    }
    insert_points(fast, model, PointSpan::from(points));
    ref.insert(points);
    EXPECT_LE(reference::max_log_odds_difference(fast, ref), 2.45e-5) << run_value;
    EXPECT_EQ(fast.log_odds(g.column(8, 8), kRunBins / 2), fast.log_odds_min()) << run_value;  // carved to L_min
  }
}

// A tile receiving more measurements in one call than the kernel lists at once (1024: a frame's tile holds
// ~100; merged or very dense clouds hold more): 64 pixels with 17 returns each, at depths in front of,
// at and behind one another in random order, in one call. The tile is taken in parts whose columns stay
// loaded, so every voxel still matches the reference's one sequence of clamped updates.
TEST(Integrate, ATileWithMoreMeasurementsThanOnePartMatchesReference) {
  const PinholeIntrinsics k;
  for (const SensorPreset& p : {kinect_v1(k), kinect_v1_paper()}) {
    const GridGeometry g = centre_crop(p);
    const SensorModel model(p.model);
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> pick(0, 3);
    const double depths_m[] = {1.0, 1.0 + 2.0 * model.sigma_depth_at(1.0), 1.4, 2.2};
    std::vector<Eigen::Vector3f> points;
    for (int repeat = 0; repeat < 17; ++repeat)  // 1088 measurements in the tile
      for (int v = 240; v < 248; ++v)  // one 8 x 8 tile of the crop (columns 8-15, rows 8-15)
        for (int u = 320; u < 328; ++u) {
          const double z = depths_m[pick(rng)];
          points.emplace_back(static_cast<float>((u - k.cx) / k.fx * z), static_cast<float>((v - k.cy) / k.fy * z), static_cast<float>(z));
        }
    GridOptions clamped;
    clamped.probability_min = 0.001;
    ColumnGrid fast(g, clamped);
    reference::DenseGrid ref(g, model, clamped);
    insert_points(fast, model, PointSpan::from(points));
    ref.insert(points);
    EXPECT_LE(reference::max_log_odds_difference(fast, ref), 2.45e-5) << p.name;
    // Not a trivial column: occupied voxels at some of the depths, free space carved in front of them.
    ColumnIndex c = 0;
    ASSERT_TRUE(g.column_of(points[100].x(), points[100].y(), points[100].z(), c));
    double highest = -1e9;
    for (int b = 0; b < g.depth().bins(); ++b) highest = std::max(highest, ref.log_odds(c, b));
    EXPECT_GT(highest, 1.0) << p.name;
    EXPECT_NEAR(ref.log_odds(c, g.depth().bin(0.9)), fast.log_odds_min(), 1e-5) << p.name;
  }
}

TEST(Integrate, RangeDependentSigmaMatchesReference) {
  // Spherical bins and the pixel-native binning, with the sample camera's own intrinsics.
  for (SensorPreset p : {kinect_v1_spherical(sample::generate_scene().intrinsics), kinect_v1(sample::generate_scene().intrinsics)}) {
    p.geometry.depth_bins = 1024;
    const GridGeometry g = reference::crop(GridGeometry(p.geometry), 280, 240, 32, 32);
    const SensorModel model(p.model);
    GridOptions o;
    o.mode = UpdateMode::exact;
    ColumnGrid fast(g, o);
    reference::DenseGrid ref(g, model, o);
    const auto points = sample::generate_scene().points();
    insert_points(fast, model, PointSpan::from(points));
    ref.insert(points);
    const reference::SurfaceAgreement a = reference::compare_surfaces(fast, ref);
    EXPECT_GE(a.same_bin, static_cast<std::size_t>(0.999 * a.columns)) << p.name << ": " << a.same_bin << " / " << a.columns;
    EXPECT_LE(a.max_dp, 1e-4) << p.name;
  }
}

TEST(Integrate, ThreadCountDoesNotChangeTheResult) {
  const SensorPreset p = kinect_v1_paper();
  const GridGeometry g(p.geometry);
  const SensorModel model(p.model);
  const auto points = sample::generate_scene().points();
  ColumnGrid one(g);
  SurfaceMap one_surface = compute_surface(one);
  std::vector<ColumnIndex> one_changed;
  insert_points(one, model, PointSpan::from(points), one_surface, one_changed, {1});
  // 3 and 5 threads: more bands than threads (insert.cpp), of uneven work, taken in turn.
  for (const int threads : {2, 3, 5}) {
    ColumnGrid many(g);
    SurfaceMap surface = compute_surface(many);
    std::vector<ColumnIndex> changed;
    insert_points(many, model, PointSpan::from(points), surface, changed, {threads});
    EXPECT_EQ(changed, one_changed) << threads << " threads";
    test::expect_identical(one, many);
    test::expect_same_surface(one_surface, surface);
  }
}

// Frames of different sizes and extents (the whole image, its top half, every third point, the bottom
// rows), so that a frame's measurements, chunks and bands differ from the previous call's.
std::vector<std::vector<Eigen::Vector3f>> frames_of_different_sizes() {
  std::vector<std::vector<Eigen::Vector3f>> frames;
  for (std::uint32_t seed : {1u, 2u, 3u, 4u}) {
    sample::SceneOptions so;
    so.seed = seed;
    const std::vector<Eigen::Vector3f> all = sample::generate_scene(so).points();
    std::vector<Eigen::Vector3f> f;
    for (std::size_t i = 0; i < all.size(); ++i) {
      const std::size_t row = i / 640;
      if (seed == 1 || (seed == 2 && row < 240) || (seed == 3 && i % 3 == 0) || (seed == 4 && row >= 400))
        f.push_back(all[i]);
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

// The per-thread insertion workspace (insert.cpp) is reused from call to call and must be the caller's in
// the workers: grids fed alternately on one thread, with 1 and 2 threads and frames of different sizes,
// equal voxel by voxel grids fed alone, single-threaded, on a fresh thread (a fresh workspace).
TEST(Integrate, ReusedWorkspaceDoesNotLeakBetweenCallsGridsOrThreadCounts) {
  SensorPreset p = kinect_v1_paper();
  p.geometry.azimuth_bins = 160;
  p.geometry.elevation_bins = 120;
  p.geometry.depth_bins = 256;
  p.model.sigma_azimuth_rad = p.model.sigma_elevation_rad = 0.003;
  const GridGeometry g(p.geometry);
  const SensorModel model(p.model);
  const auto frames = frames_of_different_sizes();
  ASSERT_GT(frames[0].size(), 2 * frames[1].size() - 1);
  ASSERT_LT(frames[3].size(), frames[2].size());
  const std::vector<std::size_t> order_a = {0, 1, 2, 3, 0}, order_b = {3, 2, 0, 1, 2};
  const auto alone = [&](const std::vector<std::size_t>& order) {
    ColumnGrid grid(g);
    std::thread([&] {
      for (std::size_t f : order) insert_points(grid, model, PointSpan::from(frames[f]), {1});
    }).join();
    return grid;
  };
  const ColumnGrid expected_a = alone(order_a), expected_b = alone(order_b);
  // a: two threads, keeping its surface current (the Mapper's path); b: one thread; c: a's frames with
  // 2, 1, 2, ... threads. All on this thread, call after call.
  ColumnGrid a(g), b(g), c(g);
  SurfaceMap a_surface = compute_surface(a);
  std::vector<ColumnIndex> a_changed;
  for (std::size_t i = 0; i < order_a.size(); ++i) {
    insert_points(a, model, PointSpan::from(frames[order_a[i]]), a_surface, a_changed, {2});
    insert_points(b, model, PointSpan::from(frames[order_b[i]]), {1});
    insert_points(c, model, PointSpan::from(frames[order_a[i]]), {i % 2 == 0 ? 2 : 1});
  }
  ASSERT_GT(expected_a.touched_column_count(), g.column_count() / 2);
  test::expect_identical(expected_a, a);
  test::expect_identical(expected_b, b);
  test::expect_identical(expected_a, c);
  test::expect_same_surface(compute_surface(expected_a), a_surface);
  test::expect_same_surface(compute_surface(expected_b), compute_surface(b));
}

TEST(Integrate, SurfaceKeptCurrentDuringInsertionMatchesASeparatePass) {
  const SensorPreset p = kinect_v1_paper();
  const GridGeometry g(p.geometry);
  const SensorModel model(p.model);
  ColumnGrid fused(g), separate(g);
  SurfaceMap fused_surface = compute_surface(fused), separate_surface = compute_surface(separate);
  for (std::uint32_t seed : {1u, 2u}) {  // the second frame changes some surfaces and leaves others
    sample::SceneOptions so;
    so.seed = seed;
    const auto points = sample::generate_scene(so).points();
    std::vector<ColumnIndex> fused_changed;
    insert_points(fused, model, PointSpan::from(points), fused_surface, fused_changed, {2});
    insert_points(separate, model, PointSpan::from(points), {2});
    const std::vector<ColumnIndex> updated = separate.take_changed_columns();
    std::vector<ColumnIndex> separate_changed = update_surface(separate, updated, separate_surface);
    std::sort(fused_changed.begin(), fused_changed.end());
    std::sort(separate_changed.begin(), separate_changed.end());
    EXPECT_GT(fused_changed.size(), 1000u);
    EXPECT_EQ(fused_changed, separate_changed);
    EXPECT_EQ(fused_surface.bin, separate_surface.bin);
    EXPECT_EQ(fused_surface.probability, separate_surface.probability);
    EXPECT_EQ(fused_surface.unknown, separate_surface.unknown);
    EXPECT_EQ(fused.take_changed_columns(), updated) << "the grid's record of updated columns is kept as well";
  }
}

TEST(Integrate, SurfaceOfAnotherSizeIsRefused) {
  const SensorPreset p = kinect_v1_paper();
  ColumnGrid grid{GridGeometry(p.geometry)};
  SurfaceMap wrong;
  std::vector<ColumnIndex> changed;
  const std::vector<Eigen::Vector3f> points{{0.0f, 0.0f, 1.0f}};
  EXPECT_THROW(insert_points(grid, SensorModel(p.model), PointSpan::from(points), wrong, changed), InvalidInput);
}

TEST(Integrate, InvalidAndOutOfFieldPointsAreCountedNotInserted) {
  SensorPreset p = kinect_v1_paper();
  p.geometry.depth_min_m = 0.5;  // the paper's grid starts at the sensor: nothing could lie nearer
  ColumnGrid grid{GridGeometry(p.geometry)};
  const SensorModel model(p.model);
  const float nan = std::nanf(""), inf = INFINITY;
  std::vector<Eigen::Vector3f> pts = {{nan, 0, 1}, {0, inf, 1}, {0, 0, 0},     // invalid
                                      {0, 0, -2}, {5, 0, 1},                     // behind, outside fov
                                      {0, 0, 2}, {0.1f, 0.1f, 7.0f},             // valid, beyond range
                                      {0, 0, 0.1f}};                             // valid, nearer than the range
  const InsertionReport r = insert_points(grid, model, PointSpan::from(pts));
  EXPECT_EQ(r.points_received, 8u);
  EXPECT_EQ(r.skipped_invalid, 3u);
  EXPECT_EQ(r.skipped_outside_fov, 2u);
  EXPECT_EQ(r.points_inserted, 3u);
  EXPECT_EQ(r.beyond_depth_range, 1u);
  EXPECT_EQ(r.nearer_than_depth_range, 1u);
  // The point beyond the range still carves its whole ray free.
  ColumnIndex c = 0;
  ASSERT_TRUE(grid.geometry().column_of(0.1, 0.1, 7.0, c));
  const SurfaceVoxel v = column_surface(grid.find(c), grid);
  EXPECT_EQ(v.bin, grid.geometry().depth().bins());
  EXPECT_NEAR(v.probability, 0.001, 1e-6);
}

// The insertion refreshes a column's surface from the contents it has just written
// (detail::refresh_written_column_surface); the store may have joined leading values equal to the run's
// value to the run, so the stored column is another representation of the same values, with the same surface.
TEST(Integrate, SurfaceOfWrittenContentsEqualsTheStoredColumns) {
  const SensorPreset p = kinect_v1_paper();
  ColumnGrid grid{GridGeometry(p.geometry)};
  const float lmin = grid.log_odds_min(), lmax = grid.log_odds_max();
  const int bins = grid.geometry().depth().bins();
  // Windows after a run of L_min: leading L_min values the store merges, a peak (clamped or not) with ties
  // and a run at the peak's value, nothing above 0 (the tail wins), and a window reaching the last bin.
  // The peak as the window's last value, a window rising to the grid's end (the surface beyond it) and a
  // run holding the maximum itself (a map loaded from elsewhere) cover every read of a value.
  // Each with the surface read by hand: its bin as an offset from the run's end (where the window starts;
  // negative: inside the run), or -1 with to_the_end for bins() (the surface past the grid), and its value.
  struct Case {
    std::vector<float> window;
    float run_value;
    bool to_the_end;
    int surface_offset;
    float surface_value;
  };
  const std::vector<Case> cases{
      {{lmin, lmin, -1.0f, 0.5f, 2.0f, 2.0f, 1.0f, 0.0f}, lmin, false, 4, 2.0f},
      {{lmin, lmax, lmax, lmax, 0.3f}, lmin, false, 2, lmax},  // saturated: the centre of the run
      {{lmin, lmin, lmin, -0.5f, -0.2f}, lmin, false, 5, 0.0f},  // the untouched tail is the highest
      {{lmin, -1.0f, 1.5f, 1.5f + 5e-6f, 0.2f}, lmin, true, 2, 1.5f},  // a tie within the tolerance
      {{lmin, -1.0f, 0.5f, 2.5f}, lmin, false, 3, 2.5f},
      {{lmin, lmin, -1.5f, -1.0f, -0.5f}, lmin, true, -1, lmin},  // rising past the grid: bins(), P of bin 0
      {{1.0f, 1.0f, 0.5f}, 1.0f, false, -40, 1.0f},  // the run holds the maximum: bin 0
      {{lmax, lmax, 0.3f}, lmax, false, -20, lmax},  // saturated from bin 0 to 41: its centre, bin 20
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const ColumnIndex column = static_cast<ColumnIndex>(k);
    const auto& w = cases[k].window;
    const std::int32_t run = cases[k].to_the_end ? bins - static_cast<std::int32_t>(w.size()) : 40;
    const ColumnContents written{column, run, cases[k].run_value, w.data(), static_cast<std::uint32_t>(w.size())};
    grid.assign(written);
    const ColumnData* stored = grid.find(column);
    ASSERT_NE(stored, nullptr);
    EXPECT_GT(stored->uniform_end, run) << "the store joined the leading values equal to the run's";
    const SurfaceVoxel from_contents = column_surface(written, grid), from_store = column_surface(stored, grid);
    EXPECT_EQ(from_contents, from_store) << "case " << k;
    EXPECT_EQ(from_store.bin, cases[k].surface_offset < 0 && cases[k].to_the_end ? bins : run + cases[k].surface_offset)
        << "case " << k;
    EXPECT_FLOAT_EQ(from_store.probability, static_cast<float>(probability_from_logit(cases[k].surface_value)))
        << "case " << k;
    EXPECT_FALSE(from_contents.unknown);
    SurfaceMap surface = compute_surface(ColumnGrid{grid.geometry()});
    EXPECT_TRUE(detail::refresh_written_column_surface(grid, written, surface));
    EXPECT_EQ(surface.at(column), from_store);
    EXPECT_FALSE(detail::refresh_written_column_surface(grid, written, surface)) << "unchanged the second time";
  }
  EXPECT_TRUE(column_surface(ColumnContents{}, grid).unknown) << "empty contents: never touched";
}

TEST(Integrate, DepthImageSizeMismatchThrows) {
  const SensorPreset p = kinect_v1_paper();
  ColumnGrid grid{GridGeometry(p.geometry)};
  std::vector<float> depth(100, 1.0f);
  DepthImage image{depth.data(), depth.size(), kinect_v1_intrinsics()};
  EXPECT_THROW(insert_depth_image(grid, SensorModel(p.model), image), InvalidInput);
}

TEST(Integrate, ThreadCountsOutsideTheToolsRangeAreRefused) {
  const SensorPreset p = kinect_v1_paper();
  ColumnGrid grid{GridGeometry(p.geometry)};
  const std::vector<Eigen::Vector3f> points{{0.0f, 0.0f, 1.0f}};
  for (const int threads : {-1, InsertionOptions::kMaxThreads + 1, 40000}) {
    try {
      insert_points(grid, SensorModel(p.model), PointSpan::from(points), {threads});
      ADD_FAILURE() << "threads = " << threads << " was accepted";
    } catch (const InvalidParameter& e) {
      EXPECT_EQ(std::string(e.what()), "threads = " + std::to_string(threads) +
                                           " is invalid: must be in [0, 1024] (0: all cores)");
    }
  }
  EXPECT_EQ(grid.touched_column_count(), 0u);
  EXPECT_EQ(insert_points(grid, SensorModel(p.model), PointSpan::from(points), {InsertionOptions::kMaxThreads})
                .points_inserted, 1u);
}

TEST(Integrate, DepthImageOfAnotherCameraThanTheGridsIsRefused) {
  PinholeIntrinsics camera;
  camera.fx = camera.fy = 585.0;
  std::vector<float> depth(static_cast<std::size_t>(camera.width * camera.height), 2.0f);
  for (const SensorPreset& p : {kinect_v1(camera), kinect_v1_spherical(camera)}) {
    ColumnGrid grid{GridGeometry(p.geometry)};
    const SensorModel model(p.model);
    try {
      insert_depth_image(grid, model, DepthImage{depth.data(), depth.size(), kinect_v1_intrinsics()});
      ADD_FAILURE() << p.name << ": the nominal camera was accepted";
    } catch (const InvalidParameter& e) {
      EXPECT_EQ(std::string(e.what()).rfind("intrinsics (fx=525.00 fy=525.00 cx=319.50 cy=239.50 640x480) are not the "
                                            "camera the grid was built for (fx=585.00 fy=585.00 cx=319.50 "
                                            "cy=239.50 640x480)", 0), 0u) << e.what();
    }
    EXPECT_EQ(grid.touched_column_count(), 0u);
    PinholeIntrinsics nearly = camera;
    nearly.cx += 0.04;  // within same_camera's 0.05 px
    EXPECT_EQ(insert_depth_image(grid, model, DepthImage{depth.data(), depth.size(), nearly}).points_inserted,
              depth.size()) << p.name;
  }
  // Intrinsics that are no camera at all (NaN, 0 x 0) are reported as such, not as another camera.
  {
    const SensorPreset p = kinect_v1(camera);
    ColumnGrid grid{GridGeometry(p.geometry)};
    PinholeIntrinsics broken = camera;
    broken.fx = std::numeric_limits<double>::quiet_NaN();
    try {
      insert_depth_image(grid, SensorModel(p.model), DepthImage{depth.data(), depth.size(), broken});
      ADD_FAILURE() << "NaN fx was accepted";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()).rfind("depth image intrinsics: fx", 0), 0u) << e.what();
    }
  }
  // A grid that does not depend on a camera takes any.
  const SensorPreset paper = kinect_v1_paper();
  ColumnGrid grid{GridGeometry(paper.geometry)};
  EXPECT_GT(insert_depth_image(grid, SensorModel(paper.model), DepthImage{depth.data(), depth.size(), camera})
                .points_inserted, 0u);
}

TEST(Integrate, SameCameraAllowsFittingNoiseButNotHalfAPixel) {
  PinholeIntrinsics a;
  PinholeIntrinsics b = a;
  b.fx += 0.049;
  EXPECT_TRUE(same_camera(a, b));
  b.cx += 0.5;
  EXPECT_FALSE(same_camera(a, b));
  b = a;
  b.width = 320;
  EXPECT_FALSE(same_camera(a, b));
  EXPECT_EQ(camera_text(a), "fx=525.00 fy=525.00 cx=319.50 cy=239.50 640x480");
}

}  // namespace
}  // namespace occ_improve
