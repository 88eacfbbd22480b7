// Saving and loading a one-frame map: the sample frame in preset kinect_v1_paper (clamped), the map
// written to the system's temporary folder. Counters: file_MB, stored_voxels, touched_columns.
#include "bench/bench_support.hpp"

#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

namespace occ_improve {
namespace {

const ColumnGrid& one_frame_grid() {
  static const auto grid = [] {
    const SensorPreset preset = kinect_v1_paper();
    auto g = std::make_unique<ColumnGrid>(GridGeometry(preset.geometry));
    insert_points(*g, SensorModel(preset.model), PointSpan::from(bench::sample_points()));
    return g;
  }();
  return *grid;
}

std::string map_path() { return (std::filesystem::temp_directory_path() / "occ_bench_map_io.occmap").string(); }

void BM_SaveOneFrameMap(benchmark::State& state) {
  const ColumnGrid& grid = one_frame_grid();
  for (auto _ : state) save_map(map_path(), grid, kinect_v1_paper().model);
  state.counters["file_MB"] = static_cast<double>(std::filesystem::file_size(map_path())) / 1e6;
  state.counters["stored_voxels"] = static_cast<double>(grid.stored_voxel_count());
  state.counters["touched_columns"] = static_cast<double>(grid.touched_column_count());
}

void BM_LoadOneFrameMap(benchmark::State& state) {
  save_map(map_path(), one_frame_grid(), kinect_v1_paper().model);
  for (auto _ : state) benchmark::DoNotOptimize(load_map(map_path()));
  state.counters["file_MB"] = static_cast<double>(std::filesystem::file_size(map_path())) / 1e6;
  std::filesystem::remove(map_path());
}

BENCHMARK(BM_SaveOneFrameMap)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_LoadOneFrameMap)->Unit(benchmark::kMillisecond)->Iterations(5);

}  // namespace
}  // namespace occ_improve

BENCHMARK_MAIN();
