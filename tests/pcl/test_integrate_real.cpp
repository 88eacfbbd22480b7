// Insertion and surface on real Kinect frames, ray by ray against the dense reference (issue 2):
//  - exact mode: the same surface bin on >= 99.9% of columns and |delta P| <= 1e-4;
//  - clamped and exact modes: the same surface bin on >= 99% of the columns of a whole frame;
//  - clamped mode on the pixel-native grid users run (kinect_v1, two successive frames): voxel by voxel
//    within the documented bounds of the fast path's skips (issue 21).
// The reference is dense and slow, so it runs on windows of the full grid (identical column extents).
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/maps/surface.hpp"
#include "reference/reference.hpp"
#include "support/test_data.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace occ_improve {
namespace {

struct Window {
  int azimuth_first, elevation_first, width, height;
};

void expect_exact_matches_reference(const pcl::PointCloud<pcl::PointXYZ>& cloud, const SensorPreset& preset,
                                    const std::vector<Window>& windows) {
  const GridGeometry full(preset.geometry);
  const SensorModel model(preset.model);
  std::vector<Eigen::Vector3f> points;
  for (const auto& p : cloud) points.emplace_back(p.x, p.y, p.z);
  GridOptions exact;
  exact.mode = UpdateMode::exact;
  // Counted over all windows: the 99.9% of the issue is a share of columns, not of each small window.
  std::size_t same = 0, columns = 0;
  for (const Window& w : windows) {
    const GridGeometry g = reference::crop(full, w.azimuth_first, w.elevation_first, w.width, w.height);
    ColumnGrid fast(g, exact);
    reference::DenseGrid ref(g, model, exact);
    const InsertionReport r = insert_points(fast, model, span_of(cloud));
    ref.insert(points);
    ASSERT_GT(r.points_inserted, static_cast<std::size_t>(w.width * w.height / 4));
    const SurfaceMap s = compute_surface(fast);
    double max_dp = 0;
    columns += s.size();
    for (std::size_t c = 0; c < s.size(); ++c) {
      const auto rs = ref.surface(c);
      same += (rs.bin == s.bin[c] && rs.unknown == (s.unknown[c] != 0)) ? 1 : 0;
      max_dp = std::max(max_dp, std::abs(rs.probability - static_cast<double>(s.probability[c])));
    }
    EXPECT_LE(max_dp, 1e-4) << preset.name << ", window at " << w.azimuth_first << "," << w.elevation_first;
  }
  EXPECT_GE(same, static_cast<std::size_t>(std::ceil(0.999 * static_cast<double>(columns))))
      << preset.name << ": " << same << " / " << columns;
}

double clamped_exact_agreement(const pcl::PointCloud<pcl::PointXYZ>& cloud, const SensorPreset& preset) {
  const GridGeometry g(preset.geometry);
  const SensorModel model(preset.model);
  GridOptions exact;
  exact.mode = UpdateMode::exact;
  ColumnGrid clamped_grid(g), exact_grid(g, exact);
  insert_points(clamped_grid, model, span_of(cloud));
  insert_points(exact_grid, model, span_of(cloud));
  const SurfaceMap a = compute_surface(clamped_grid), b = compute_surface(exact_grid);
  std::size_t same = 0, known = 0;
  for (std::size_t c = 0; c < a.size(); ++c) {
    if (a.unknown[c] && b.unknown[c]) continue;
    ++known;
    same += a.bin[c] == b.bin[c] ? 1 : 0;
  }
  return static_cast<double>(same) / static_cast<double>(known);
}

const std::vector<Window> kWindows = {{150, 120, 40, 30}, {300, 220, 40, 30}, {500, 380, 40, 30}};

TEST(IntegrateReal, PairwiseCaptureExactMatchesReference) {
  OCC_REQUIRE_DATA(path, "kinect/pcl_tutorials/pairwise/capture0001.pcd");
  const LoadedFrame f = load_pcd_frame(path);
  expect_exact_matches_reference(f.cloud, kinect_v1_paper(), kWindows);
}

TEST(IntegrateReal, SevenScenesDepthImageExactMatchesReference) {
  OCC_REQUIRE_DATA(path, "sequences/7scenes_redkitchen/frames/frame-000150.depth.png");
  OCC_REQUIRE_DATA(intrinsics, "sequences/7scenes_redkitchen/camera-intrinsics.txt");
  const LoadedFrame f = load_depth_frame(path, read_intrinsics_file(intrinsics), DepthEncoding::millimetres);
  expect_exact_matches_reference(f.cloud, kinect_v1_paper(), kWindows);
  for (SensorPreset k : {kinect_v1_spherical(*f.intrinsics), kinect_v1(*f.intrinsics)}) {
    k.geometry.depth_bins = 1024;  // keeps the dense reference small
    expect_exact_matches_reference(f.cloud, k, {{300, 220, 32, 32}, {100, 60, 32, 32}, {520, 400, 32, 32}});
  }
}

// Every voxel of windows with depth edges (a table's rim, a no-data hole's border), after two frames of
// the same camera, so that clamping, re-visits and neighbours arriving before a column's own return are
// exercised. Bound: per column and frame up to 9 updates (3 x 3 pixels) each within 2e-6 of eq. 1 (float
// kernel) plus the skipped |logit P_s| < 5e-7 (CONVENTIONS 4), plus the odds round trip (< 5e-7 + 2e-7 |L|,
// |L| <= 6.9) once per frame in the bins the frame reaches; clamping is 1-Lipschitz, so two frames stay
// below 2 x (9 x 2.5e-6 + 2e-6) = 4.9e-5.
TEST(IntegrateReal, PixelNativeClampedMatchesReferenceVoxelByVoxel) {
  OCC_REQUIRE_DATA(first, "kinect/pcl_tutorials/pairwise/capture0001.pcd");
  OCC_REQUIRE_DATA(second, "kinect/pcl_tutorials/pairwise/capture0002.pcd");
  const LoadedFrame f1 = load_pcd_frame(first), f2 = load_pcd_frame(second);
  SensorPreset preset = kinect_v1(estimate_intrinsics(f1.cloud));
  preset.geometry.depth_bins = 1024;  // keeps the dense reference small (about 0.8 bins per sigma)
  const GridGeometry full(preset.geometry);
  const SensorModel model(preset.model);
  std::size_t free_voxels = 0, changed_voxels = 0;
  for (const Window& w : std::vector<Window>{{300, 220, 16, 16}, {100, 60, 16, 16}, {520, 400, 16, 16}}) {
    const GridGeometry g = reference::crop(full, w.azimuth_first, w.elevation_first, w.width, w.height);
    ColumnGrid fast(g);
    reference::DenseGrid ref(g, model, GridOptions{});
    for (const LoadedFrame* f : {&f1, &f2}) {
      std::vector<Eigen::Vector3f> points;
      for (const auto& p : f->cloud) points.emplace_back(p.x, p.y, p.z);
      insert_points(fast, model, span_of(f->cloud));
      ref.insert(points);
    }
    double max_dl = 0;
    for (std::size_t c = 0; c < g.column_count(); ++c)
      for (int b = 0; b < g.depth().bins(); ++b) {
        const double r = ref.log_odds(c, b);
        free_voxels += r <= fast.log_odds_min() + 1e-3 ? 1 : 0;
        changed_voxels += std::abs(r) > 1e-3 ? 1 : 0;
        max_dl = std::max(max_dl, std::abs(r - fast.log_odds(static_cast<ColumnIndex>(c), b)));
      }
    RecordProperty("max_dl_" + std::to_string(w.azimuth_first), std::to_string(max_dl));
    EXPECT_LE(max_dl, 4.9e-5) << "window at " << w.azimuth_first << "," << w.elevation_first;
  }
  // The windows hold carved free space and returns, not just untouched voxels.
  EXPECT_GT(free_voxels, 3u * 16u * 16u * 100u);
  EXPECT_GT(changed_voxels, free_voxels + 3u * 16u * 16u);
}

TEST(IntegrateReal, ClampedAndExactAgreeOnAWholeFrame) {
  OCC_REQUIRE_DATA(path, "kinect/pcl_tutorials/pairwise/capture0001.pcd");
  const LoadedFrame f = load_pcd_frame(path);
  EXPECT_GE(clamped_exact_agreement(f.cloud, kinect_v1_paper()), 0.99);
}

}  // namespace
}  // namespace occ_improve
