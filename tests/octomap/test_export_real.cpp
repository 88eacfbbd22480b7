// The OctoMap export against OctoMap itself on real Kinect frames (../shared/data, skipped where absent):
// the frame inserted by OctoMap's own insertPointCloud and the grid built from the same frame and
// exported, both in the same z-up world frame at the same resolution. Every leaf OctoMap calls occupied
// holds a measured point; the export must call (almost) all of them occupied and (almost) none free. The
// few it does not are where the grid itself does not hold the point's voxel occupied (free space carved by
// neighbouring rays at depth edges); every point whose voxel is occupied lies in an occupied leaf.
// Needs PCL to read the frames: without it the tests skip.
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/octomap/export.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "octomap/export_agreement.hpp"
#include "support/test_data.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <tuple>

#ifdef OCC_IMPROVE_TEST_WITH_PCL
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#endif

namespace occ_improve {
namespace {

#ifdef OCC_IMPROVE_TEST_WITH_PCL

// world <- optical with z up (occ_to_octomap's -frame z_up): optical z (forward) is world x, x (right) is
// -y, y (down) is -z.
Eigen::Isometry3d z_up_from_optical() {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return pose;
}

// A frame read once per test program, with the intrinsics fitted to its organized cloud (as the tools do).
const LoadedFrame& frame(const std::string& path) {
  static std::map<std::string, std::unique_ptr<LoadedFrame>> frames;
  auto& slot = frames[path];
  if (!slot) slot = std::make_unique<LoadedFrame>(load_pcd_frame(path));
  return *slot;
}

// The grid of a frame in a preset, built once per (frame, preset).
const ColumnGrid& grid_of(const std::string& path, const std::string& preset_name) {
  static std::map<std::pair<std::string, std::string>, std::unique_ptr<ColumnGrid>> grids;
  auto& slot = grids[{path, preset_name}];
  if (!slot) {
    const LoadedFrame& f = frame(path);
    const SensorPreset preset = preset_by_name(preset_name, estimate_intrinsics(f.cloud));
    slot = std::make_unique<ColumnGrid>(GridGeometry(preset.geometry));
    insert_points(*slot, SensorModel(preset.model), span_of(f.cloud));
  }
  return *slot;
}

// OctoMap's own map of the frame: insertPointCloud from the sensor's origin with OctoMap's default
// sensor model, built once per (frame, resolution). Only the points the grid holds (depth coordinate in
// its range) are inserted, so both maps see the same measurements.
const octomap::OcTree& reference_of(const std::string& path, const GridGeometry& geometry, double resolution) {
  static std::map<std::pair<std::string, double>, std::unique_ptr<octomap::OcTree>> trees;
  auto& slot = trees[{path, resolution}];
  if (!slot) {
    const Eigen::Isometry3d pose = z_up_from_optical();
    octomap::Pointcloud cloud;
    for (const auto& p : frame(path).cloud) {
      if (!is_valid_point(p.x, p.y, p.z)) continue;
      RayPosition ray;
      if (!geometry.project(p.x, p.y, p.z, ray) || ray.depth < geometry.depth().min() ||
          ray.depth >= geometry.depth().max())
        continue;
      const Eigen::Vector3d w = pose * Eigen::Vector3d(p.x, p.y, p.z);
      cloud.push_back(static_cast<float>(w.x()), static_cast<float>(w.y()), static_cast<float>(w.z()));
    }
    const Eigen::Vector3d origin = pose.translation();
    slot = std::make_unique<octomap::OcTree>(resolution);
    slot->insertPointCloud(cloud, octomap::point3d(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                                                   static_cast<float>(origin.z())));
  }
  return *slot;
}

enum Class { kUnknown = 0, kFree = 1, kOccupied = 2 };

Class class_of(const octomap::OcTree& tree, const octomap::OcTreeKey& key) {
  const octomap::OcTreeNode* node = tree.search(key);
  if (!node) return kUnknown;
  return tree.isNodeOccupied(node) ? kOccupied : kFree;
}

// counts[b]: finest-level leaves of class `of` in tree `from` (pruned leaves expanded) that are of class b
// in tree `in`.
std::array<std::size_t, 3> leaves_classified(const octomap::OcTree& from, const octomap::OcTree& in, Class of,
                                             const std::function<bool(const octomap::OcTreeKey&)>& counted = nullptr) {
  std::array<std::size_t, 3> counts{};
  const unsigned max_depth = from.getTreeDepth();
  for (auto it = from.begin_leafs(), end = from.end_leafs(); it != end; ++it) {
    if (from.isNodeOccupied(*it) != (of == kOccupied)) continue;
    const unsigned span = 1u << (max_depth - it.getDepth());
    const octomap::OcTreeKey k0 = it.getIndexKey();
    octomap::OcTreeKey k;
    for (unsigned x = 0; x < span; ++x)
      for (unsigned y = 0; y < span; ++y)
        for (unsigned z = 0; z < span; ++z) {
          k[0] = static_cast<octomap::key_type>(k0[0] + x);
          k[1] = static_cast<octomap::key_type>(k0[1] + y);
          k[2] = static_cast<octomap::key_type>(k0[2] + z);
          if (!counted || counted(k)) ++counts[class_of(in, k)];
        }
  }
  return counts;
}

double share(std::size_t part, const std::array<std::size_t, 3>& counts) {
  const std::size_t total = counts[0] + counts[1] + counts[2];
  return total ? static_cast<double>(part) / static_cast<double>(total) : 0.0;
}

using Case = std::tuple<std::string, std::string, double, FreeLeafRule>;  // frame, preset, resolution [m], rule

class ExportAgainstInsertPointCloud : public ::testing::TestWithParam<Case> {};

// OctoMap's occupied leaves are occupied in the export, and (almost) never free; with the crossed rule (the
// default) most of OctoMap's free leaves are free in it too (with wholly_free 26 % at 10 cm on a held-out
// cloud: the leaves a free-space boundary passes stayed unknown).
TEST_P(ExportAgainstInsertPointCloud, OccupiedLeavesAgree) {
  const auto& [relative, preset, resolution, rule] = GetParam();
  OCC_REQUIRE_DATA(path, relative);
  const ColumnGrid& grid = grid_of(path, preset);
  const octomap::OcTree& reference = reference_of(path, grid.geometry(), resolution);
  OctomapExportReport report;
  OctomapExportOptions options;
  options.free_leaves = rule;
  const auto exported = to_octree(grid, z_up_from_optical(), resolution, options, &report);

  // Of the leaves OctoMap calls occupied, how the export classifies them; and the other way round.
  const std::array<std::size_t, 3> recall = leaves_classified(reference, *exported, kOccupied);
  const std::array<std::size_t, 3> precision = leaves_classified(*exported, reference, kOccupied);
  // OctoMap's free leaves whose centre lies in the grid's depth range (OctoMap carves from the origin, the
  // grid from its 0.5 m).
  const Eigen::Isometry3d sensor_from_world = z_up_from_optical().inverse();
  const auto in_grid = [&](const octomap::OcTreeKey& k) {
    const octomap::point3d c = reference.keyToCoord(k);
    const Eigen::Vector3d p = sensor_from_world * Eigen::Vector3d(c.x(), c.y(), c.z());
    RayPosition ray;
    return grid.geometry().project(p.x(), p.y(), p.z(), ray) && ray.depth >= grid.geometry().depth().min() &&
           ray.depth < grid.geometry().depth().max();
  };
  const std::array<std::size_t, 3> free_recall = leaves_classified(reference, *exported, kFree, in_grid);
  const double free_recall_share = share(free_recall[kFree], free_recall);
  const double occupied_share = share(recall[kOccupied], recall), free_share = share(recall[kFree], recall);
  // The rule itself: every measured point whose grid voxel is occupied lies in an occupied leaf.
  const Eigen::Isometry3d pose = z_up_from_optical();
  std::size_t points_in_occupied_voxels = 0, points_in_holes = 0;
  for (const auto& p : frame(path).cloud) {
    if (!is_valid_point(p.x, p.y, p.z)) continue;
    const Eigen::Vector3d w = pose * Eigen::Vector3d(p.x, p.y, p.z);
    if (test::spherical_occupancy(grid, pose, w, {}) != test::Occupancy::occupied) continue;
    ++points_in_occupied_voxels;
    points_in_holes += test::octree_occupancy(*exported, w) == test::Occupancy::occupied ? 0 : 1;
  }
  char line[640];
  std::snprintf(line, sizeof line,
                "%s %s %.0f cm %s: OctoMap occupied %zu -> export occupied %zu (%.1f%%), free %zu (%.2f%%), unknown %zu; "
                "export occupied %zu -> OctoMap occupied %zu (%.1f%%), free %zu, unknown %zu; OctoMap free %zu (in the "
                "grid's range) -> export free %.1f%%, occupied %.1f%%; points in occupied voxels %zu, in non-occupied leaves %zu; "
                "export %.2f s",
                relative.c_str(), preset.c_str(), resolution * 100, rule == FreeLeafRule::crossed ? "crossed" : "wholly_free",
                recall[0] + recall[1] + recall[2], recall[kOccupied], 100 * occupied_share, recall[kFree],
                100 * free_share, recall[kUnknown], precision[0] + precision[1] + precision[2], precision[kOccupied],
                100 * share(precision[kOccupied], precision), precision[kFree], precision[kUnknown],
                free_recall[0] + free_recall[1] + free_recall[2], 100 * free_recall_share,
                100 * share(free_recall[kOccupied], free_recall), points_in_occupied_voxels, points_in_holes,
                report.seconds);
  std::printf("%s\n", line);
  ::testing::Test::RecordProperty("agreement", line);
  EXPECT_GT(recall[kOccupied] + recall[kFree] + recall[kUnknown], 100u) << "too few occupied leaves to compare";
  EXPECT_GE(occupied_share, 0.95) << "see the line above";
  // Leaves OctoMap calls occupied that the export writes free: where the grid holds the point's voxel free
  // (neighbouring rays carve it at depth edges); crossed writes a few more of them (its leaves need free
  // space at their centre or a corner only), measured 1.08 % at most (capture0001, kinect_v1, 1 cm).
  EXPECT_LE(free_share, rule == FreeLeafRule::crossed ? 0.0125 : 0.01) << "see the line above";
  // OctoMap's free space in the grid's depth range: crossed keeps most of it at every resolution (measured
  // 93-99 %), wholly_free loses much of it at 5-10 cm (13-60 %).
  if (rule == FreeLeafRule::crossed) {
    EXPECT_GE(free_recall_share, 0.7) << "see the line above";
  }
  EXPECT_GT(points_in_occupied_voxels, 10000u);
  EXPECT_EQ(points_in_holes, 0u) << "see the line above";
}

// e.g. capture0001_kinect_v1_2cm
std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  const std::string& frame = std::get<0>(info.param);
  const std::size_t slash = frame.rfind('/'), dot = frame.rfind('.');
  const long centimetres = std::lround(std::get<2>(info.param) * 100);
  return frame.substr(slash + 1, dot - slash - 1) + "_" + std::get<1>(info.param) + "_" + std::to_string(centimetres) +
         "cm" + (std::get<3>(info.param) == FreeLeafRule::crossed ? "_crossed" : "_wholly_free");
}

INSTANTIATE_TEST_SUITE_P(RealFrames, ExportAgainstInsertPointCloud,
                         ::testing::Combine(::testing::Values("kinect/pcl_tutorials/pairwise/capture0001.pcd",
                                                              "segmentation/mosd_learn/learn0.pcd"),
                                            ::testing::Values("kinect_v1", "kinect_v1_spherical"),
                                            ::testing::Values(0.01, 0.02, 0.05, 0.1),
                                            ::testing::Values(FreeLeafRule::crossed, FreeLeafRule::wholly_free)),
                         case_name);

#else

TEST(ExportAgainstInsertPointCloud, NeedsPcl) { GTEST_SKIP() << "built without PCL: the real frames cannot be read"; }

#endif

}  // namespace
}  // namespace occ_improve
