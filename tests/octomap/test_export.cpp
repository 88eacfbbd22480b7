// Export of the spherical grid to OctoMap (octomap/export.hpp): files read back with OctoMap agree with
// the grid, maps from two poses merge by the documented rule, writing leaves the caller's tree alone, and
// bad input is refused with typed errors and no half-written file.
#include "support/temp_folder.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/integrate.hpp"
#include "occ_improve/octomap/export.hpp"
#include "occ_improve/presets.hpp"
#include "occ_improve/sample_scene.hpp"
#include "octomap/export_agreement.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace occ_improve {
namespace {

namespace fs = std::filesystem;
using test::Occupancy;

constexpr double kResolution = 0.03;

// The sample frame in the paper preset (clamped) and in an exact-mode grid, built once.
const SphericalGrid& sample_grid(UpdateMode mode) {
  auto build = [](UpdateMode m) {
    const SensorPreset preset = kinect_v1_paper();
    GridOptions options;
    options.mode = m;
    auto grid = std::make_unique<SphericalGrid>(SphericalGeometry(preset.geometry), options);
    const auto points = sample::generate_scene().points();
    insert_points(*grid, SensorModel(preset.model), PointSpan::from(points));
    return grid;
  };
  if (mode == UpdateMode::clamped) {
    static const auto clamped = build(UpdateMode::clamped);
    return *clamped;
  }
  static const auto exact = build(UpdateMode::exact);
  return *exact;
}

Eigen::Isometry3d some_pose() {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Eigen::Vector3d(1.0, -2.0, 0.5));
  pose.rotate(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1.0, -0.2).normalized()));
  return pose;
}

// A finest-level leaf centre inside a (possibly pruned) leaf: its lowest corner leaf. Pruning merges 8
// children only when all exist with one value, so every finest leaf inside was written with that value.
Eigen::Vector3d finest_centre(const octomap::OcTree::leaf_iterator& it, double resolution) {
  const double inset = 0.5 * (it.getSize() - resolution);
  return Eigen::Vector3d(it.getX() - inset, it.getY() - inset, it.getZ() - inset);
}

using OctomapExport = test::TempFolderTest;

void expect_agreement(const test::Agreement& a) {
  EXPECT_GT(a.compared, 2000u);
  EXPECT_GT(a.per_class[static_cast<int>(Occupancy::free)], 500u);
  EXPECT_GT(a.per_class[static_cast<int>(Occupancy::occupied)], 0u);
  EXPECT_GT(a.per_class[static_cast<int>(Occupancy::unknown)], 100u);
  ::testing::Test::RecordProperty("agreement", std::to_string(a.agreed) + "/" + std::to_string(a.compared));
  EXPECT_GE(a.fraction(), 0.99) << a.agreed << " / " << a.compared << " (" << a.near_boundary << " near boundaries)";
}

// The grid exported from some_pose(), with the report's counts checked.
std::unique_ptr<octomap::OcTree> exported(const SphericalGrid& grid, const OctomapExportOptions& options) {
  OctomapExportReport report;
  auto tree = to_octree(grid, some_pose(), kResolution, options, &report);
  EXPECT_GT(report.free_written, 100000u);
  EXPECT_GT(report.occupied_written, 1000u);
  return tree;
}

TEST_F(OctomapExport, FilesReadBackAgreeWithTheGrid) {
  const SphericalGrid& grid = sample_grid(UpdateMode::clamped);
  const Eigen::Isometry3d pose = some_pose();
  const OctomapExportOptions options;
  const auto tree = exported(grid, options);
  // OctoMap keeps its thresholds as float log-odds: equal to float precision.
  EXPECT_NEAR(tree->getClampingThresMin(), grid.options().probability_min, 1e-7);
  EXPECT_NEAR(tree->getClampingThresMax(), grid.options().probability_max, 1e-7);

  expect_agreement(test::compare_occupancy(grid, pose, *tree, options, 20000));

  write_octree(*tree, file("map.ot"));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(file("map.ot")));
  auto* full = dynamic_cast<octomap::OcTree*>(read.get());
  ASSERT_NE(full, nullptr);
  expect_agreement(test::compare_occupancy(grid, pose, *full, options, 20000, 11));

  write_octree(*tree, file("map.bt"));
  const octomap::OcTree binary(file("map.bt"));
  ASSERT_GT(binary.size(), 0u);
  expect_agreement(test::compare_occupancy(grid, pose, binary, options, 20000, 13));
  EXPECT_EQ(entry_count(), 2u) << "no temporary file may be left behind";
}

TEST_F(OctomapExport, PixelNativeGridAgreesToo) {
  const SensorPreset preset = kinect_v1(sample::generate_scene().intrinsics);
  SphericalGrid grid(SphericalGeometry(preset.geometry));
  insert_points(grid, SensorModel(preset.model), PointSpan::from(sample::generate_scene().points()));
  const OctomapExportOptions options;
  expect_agreement(test::compare_occupancy(grid, some_pose(), *exported(grid, options), options, 20000));
}

TEST_F(OctomapExport, LogOddsAreCarriedOverAndExactModeIsNotClampedAtTheGridsBounds) {
  for (UpdateMode mode : {UpdateMode::clamped, UpdateMode::exact}) {
    const SphericalGrid& grid = sample_grid(mode);
    const Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    const OctomapExportOptions options;
    const auto tree = to_octree(grid, pose, kResolution, options);
    std::size_t checked = 0, equal = 0;
    float lowest = 0;
    for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
      if (++checked % 7 != 0) continue;  // every 7th leaf keeps the test short
      const auto expected = test::spherical_log_odds(grid, pose, finest_centre(it, kResolution), options);
      ASSERT_TRUE(expected.has_value()) << "a leaf was written for an unknown voxel";
      equal += std::abs(*expected - it->getLogOdds()) <= 1e-6f ? 1 : 0;
      lowest = std::min(lowest, it->getLogOdds());
    }
    EXPECT_GE(equal, static_cast<std::size_t>(0.999 * (checked / 7))) << equal << " / " << checked / 7 << " mode " << static_cast<int>(mode);
    if (mode == UpdateMode::exact) {
      EXPECT_LT(lowest, grid.log_odds_min() - 10.0f) << "exact-mode free space must keep its large log-odds";
    } else {
      EXPECT_EQ(lowest, grid.log_odds_min());
    }
  }
}

TEST_F(OctomapExport, TwoPosesMergeByAddingLogOddsThenClamping) {
  const SphericalGrid& grid = sample_grid(UpdateMode::clamped);
  const Eigen::Isometry3d a = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d b = Eigen::Isometry3d::Identity();
  b.translate(Eigen::Vector3d(0.4, 0.0, 0.6));
  b.rotate(Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitY()));
  const OctomapExportOptions options;
  auto tree = to_octree(grid, a, kResolution, options);
  add_to_octree(*tree, grid, b, options);
  const float lo = grid.log_odds_min(), hi = grid.log_odds_max();

  std::size_t both = 0, checked = 0, matching = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
    const Eigen::Vector3d w = finest_centre(it, kResolution);
    const auto la = test::spherical_log_odds(grid, a, w, options), lb = test::spherical_log_odds(grid, b, w, options);
    ASSERT_TRUE(la || lb) << "a leaf neither view knows";
    const float expected = std::clamp(std::clamp(la.value_or(0.0f), lo, hi) + lb.value_or(0.0f), lo, hi);
    both += (la && lb) ? 1 : 0;
    ++checked;
    matching += std::abs(expected - it->getLogOdds()) <= 1e-5f ? 1 : 0;
  }
  EXPECT_GT(both, 10000u) << "the two views must overlap for the test to mean something";
  EXPECT_GE(matching, static_cast<std::size_t>(0.999 * checked)) << matching << " / " << checked;
}

// A digest of every leaf (key and log-odds) and of the node count, to see any change to the tree.
std::pair<std::size_t, double> digest(const octomap::OcTree& tree) {
  double sum = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey k = it.getKey();
    sum += it->getLogOdds() * (1.0 + k[0] * 1e-5 + k[1] * 1e-7 + k[2] * 1e-9 + it.getDepth() * 1e-3);
  }
  return {tree.size(), sum};
}

TEST_F(OctomapExport, WritingLeavesTheCallersTreeUnchanged) {
  const auto tree = to_octree(sample_grid(UpdateMode::clamped), Eigen::Isometry3d::Identity(), 0.05);
  const auto before = digest(*tree);
  write_octree(*tree, file("a.bt"));
  EXPECT_EQ(digest(*tree), before) << ".bt writing pruned or thresholded the caller's tree";
  write_octree(*tree, file("a.ot"));
  EXPECT_EQ(digest(*tree), before);
  // The same tree written with OctoMap's own pruning writer does change (what this test guards against).
  octomap::OcTree copy(*tree);
  copy.writeBinary(file("pruned.bt"));
  EXPECT_NE(digest(copy), before);
}

TEST_F(OctomapExport, BadResolutionPoseAndPathsAreRefused) {
  const SphericalGrid& grid = sample_grid(UpdateMode::clamped);
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  EXPECT_THROW(to_octree(grid, identity, 0.0), InvalidParameter);
  EXPECT_THROW(to_octree(grid, identity, -0.02), InvalidParameter);
  EXPECT_THROW(to_octree(grid, identity, 1e-4), ResourceLimit);

  auto tree = make_octree(grid, 0.05);
  Eigen::Isometry3d scaled = identity;
  scaled.linear() *= 2.0;
  EXPECT_THROW(add_to_octree(*tree, grid, scaled), InvalidParameter);
  Eigen::Isometry3d reflected = identity;
  reflected.linear()(0, 0) = -1.0;
  EXPECT_THROW(add_to_octree(*tree, grid, reflected), InvalidParameter);
  Eigen::Isometry3d not_finite = identity;
  not_finite.translation().x() = std::nan("");
  EXPECT_THROW(add_to_octree(*tree, grid, not_finite), InvalidParameter);
  Eigen::Isometry3d far_away = identity;
  far_away.translation() = Eigen::Vector3d(1e4, 0, 0);
  EXPECT_THROW(add_to_octree(*tree, grid, far_away), InvalidParameter);
  EXPECT_EQ(tree->size(), 0u) << "a refused export must not touch the tree";

  add_to_octree(*tree, grid, identity);
  EXPECT_THROW(write_octree(*tree, file("no_such_folder/map.bt")), IoError);
  fs::create_directory(file("taken.ot"));
  EXPECT_THROW(write_octree(*tree, file("taken.ot")), IoError);
  EXPECT_THROW(write_octree(*tree, file("map.pcd")), InvalidParameter);
  EXPECT_EQ(entry_count(), 1u) << "only the folder standing in the way may remain";
}

}  // namespace
}  // namespace occ_improve
