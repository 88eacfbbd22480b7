// Export of one 640 x 480 Kinect frame's grid (preset kinect_v1_paper, clamped) to an OctoMap OcTree at
// 2 cm, side by side with OctoMap 1.9's own insertPointCloud of the same cloud at 2 cm (max range 5 m,
// sensor at the origin), on the generated sample frame and on a real capture
// (kinect/pcl_tutorials/pairwise/capture0001.pcd). One iteration each: insertPointCloud takes seconds.
//
// Counters: leaves_written (free + occupied leaves the export wrote), leaves (tree leaves afterwards),
// tree_MB (OcTree::memoryUsage).
#include "bench/bench_support.hpp"

#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <benchmark/benchmark.h>

#if OCC_IMPROVE_BENCH_WITH_OCTOMAP
#include "occ_improve/octomap/export.hpp"

#include <octomap/OcTree.h>

#include <cmath>
#include <memory>

namespace occ_improve {
namespace {

constexpr double kResolution = 0.02;
constexpr double kMaxRange = 5.0;

using bench::Input;
using bench::input_points;

std::unique_ptr<ColumnGrid> one_frame_grid(const std::vector<Eigen::Vector3f>& points) {
  const SensorPreset preset = kinect_v1_paper();
  auto grid = std::make_unique<ColumnGrid>(GridGeometry(preset.geometry));
  insert_points(*grid, SensorModel(preset.model), PointSpan::from(points));
  return grid;
}

void set_tree_counters(benchmark::State& state, const octomap::OcTree& tree) {
  state.counters["leaves"] = static_cast<double>(tree.getNumLeafNodes());
  state.counters["tree_MB"] = static_cast<double>(tree.memoryUsage()) / 1e6;
}

void BM_ExportGridToOcTree_2cm(benchmark::State& state, Input input) {
  const auto* points = input_points(input, state);
  if (!points) return;
  const auto grid = one_frame_grid(*points);
  std::unique_ptr<octomap::OcTree> tree;
  OctomapExportReport report;
  for (auto _ : state) tree = to_octree(*grid, Eigen::Isometry3d::Identity(), kResolution, {}, &report);
  state.counters["leaves_written"] = static_cast<double>(report.free_written + report.occupied_written);
  set_tree_counters(state, *tree);
}

void BM_OctomapInsertPointCloud_2cm(benchmark::State& state, Input input) {
  const auto* points = input_points(input, state);
  if (!points) return;
  octomap::Pointcloud cloud;
  for (const auto& p : *points)
    if (p.allFinite()) cloud.push_back(p.x(), p.y(), p.z());
  std::unique_ptr<octomap::OcTree> tree;
  for (auto _ : state) {
    tree = std::make_unique<octomap::OcTree>(kResolution);
    tree->insertPointCloud(cloud, octomap::point3d(0, 0, 0), kMaxRange);
  }
  state.counters["points"] = static_cast<double>(cloud.size());
  set_tree_counters(state, *tree);
}

BENCHMARK_CAPTURE(BM_ExportGridToOcTree_2cm, sample, Input::sample)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_OctomapInsertPointCloud_2cm, sample, Input::sample)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_ExportGridToOcTree_2cm, real, Input::real)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_OctomapInsertPointCloud_2cm, real, Input::real)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace occ_improve
#endif

BENCHMARK_MAIN();
