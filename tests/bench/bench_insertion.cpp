// Insertion of one 640 x 480 Kinect frame (preset kinect_v1_paper, clamped mode) at 1 and 2 threads, the
// store's memory after 1 and 100 frames of the same static view, and OctoMap 1.9's insertPointCloud of
// the same cloud side by side (max range 5 m, sensor at the origin).
//
// Counters: points (received), ms (insertion alone, the timed part), store_MB (ColumnGrid::memory_bytes
// after one frame), B_per_col (store bytes per touched column), column_updates.
#include "bench/bench_support.hpp"

#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>

#if OCC_IMPROVE_BENCH_WITH_OCTOMAP
#include <octomap/OcTree.h>
#endif

namespace occ_improve {
namespace {

using bench::Input;
using bench::input_points;

void set_store_counters(benchmark::State& state, const ColumnGrid& grid, const InsertionReport& r) {
  state.counters["points"] = static_cast<double>(r.points_received);
  state.counters["column_updates"] = static_cast<double>(r.column_updates);
  state.counters["store_MB"] = static_cast<double>(grid.memory_bytes()) / 1e6;
  const std::size_t touched = grid.touched_column_count();
  state.counters["B_per_col"] = touched ? static_cast<double>(grid.memory_bytes()) / static_cast<double>(touched) : 0.0;
}

// One frame into an empty grid per iteration; args: threads, preset (bench::PresetArg).
void insert_one_frame(benchmark::State& state, Input input) {
  const auto* points = input_points(input, state);
  if (!points) return;
  const SensorPreset preset = bench::input_preset(input, static_cast<int>(state.range(1)));
  state.SetLabel(bench::preset_label(static_cast<int>(state.range(1))));
  const SensorModel model(preset.model);
  ColumnGrid grid{GridGeometry(preset.geometry)};
  InsertionOptions options;
  options.threads = static_cast<int>(state.range(0));
  InsertionReport last;
  double total_seconds = 0;
  for (auto _ : state) {
    state.PauseTiming();
    grid.clear();
    state.ResumeTiming();
    last = insert_points(grid, model, PointSpan::from(*points), options);
    total_seconds += last.seconds;
  }
  set_store_counters(state, grid, last);
  state.counters["ms"] = 1e3 * total_seconds / static_cast<double>(state.iterations());
}

void BM_InsertSampleFrame(benchmark::State& state) { insert_one_frame(state, Input::sample); }
void BM_InsertRealFrame(benchmark::State& state) { insert_one_frame(state, Input::real); }
BENCHMARK(BM_InsertSampleFrame)->ArgNames({"threads", "paper"})->ArgsProduct({{1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_InsertRealFrame)->ArgNames({"threads", "paper"})->ArgsProduct({{1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);

// Memory after 1 and after 100 frames of the same static view (the same frame inserted again: a static
// camera). The figure to watch is growth = MB after 100 / MB after 1.
void insert_static_view(benchmark::State& state, Input input) {
  const auto* points = input_points(input, state);
  if (!points) return;
  const SensorPreset preset = bench::input_preset(input, static_cast<int>(state.range(0)));
  state.SetLabel(bench::preset_label(static_cast<int>(state.range(0))));
  const SensorModel model(preset.model);
  InsertionOptions options;
  options.threads = 2;
  constexpr int kFrames = 100;
  for (auto _ : state) {
    ColumnGrid grid{GridGeometry(preset.geometry)};
    const InsertionReport first = insert_points(grid, model, PointSpan::from(*points), options);
    const double first_mb = static_cast<double>(grid.memory_bytes()) / 1e6;
    const double first_bytes_per_col =
        static_cast<double>(grid.memory_bytes()) / static_cast<double>(grid.touched_column_count());
    for (int f = 1; f < kFrames; ++f) insert_points(grid, model, PointSpan::from(*points), options);
    const double last_mb = static_cast<double>(grid.memory_bytes()) / 1e6;
    state.counters["MB_1_frame"] = first_mb;
    state.counters["MB_100_frames"] = last_mb;
    state.counters["growth"] = last_mb / first_mb;
    state.counters["B_per_col_1"] = first_bytes_per_col;
    state.counters["B_per_col_100"] =
        static_cast<double>(grid.memory_bytes()) / static_cast<double>(grid.touched_column_count());
    state.counters["points"] = static_cast<double>(first.points_received);
  }
}

void BM_StaticView100FramesSample(benchmark::State& state) { insert_static_view(state, Input::sample); }
void BM_StaticView100FramesReal(benchmark::State& state) { insert_static_view(state, Input::real); }
BENCHMARK(BM_StaticView100FramesSample)->ArgName("paper")->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StaticView100FramesReal)->ArgName("paper")->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond);

#if OCC_IMPROVE_BENCH_WITH_OCTOMAP
// OctoMap's insertPointCloud of the same cloud; args: resolution in mm. ratio = OctoMap seconds over
// occ_improve's single-threaded insertion of the same cloud, timed here too.
void insert_octomap(benchmark::State& state, Input input) {
  const auto* points = input_points(input, state);
  if (!points) return;
  octomap::Pointcloud cloud;
  for (const auto& p : *points)
    if (p.allFinite() && p.squaredNorm() > 0) cloud.push_back(p.x(), p.y(), p.z());
  const double resolution_m = static_cast<double>(state.range(0)) * 1e-3;
  double octomap_seconds = 0;
  std::size_t octomap_bytes = 0;
  for (auto _ : state) {
    octomap::OcTree tree(resolution_m);
    const auto start = std::chrono::steady_clock::now();
    tree.insertPointCloud(cloud, octomap::point3d(0, 0, 0), 5.0);
    octomap_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    octomap_bytes = tree.memoryUsage();
  }
  const SensorPreset preset = kinect_v1_paper();
  const SensorModel model(preset.model);
  ColumnGrid grid{GridGeometry(preset.geometry)};
  insert_points(grid, model, PointSpan::from(*points), {1});  // warm-up
  grid.clear();
  const InsertionReport ours = insert_points(grid, model, PointSpan::from(*points), {1});
  state.counters["octomap_s"] = octomap_seconds;
  state.counters["octomap_MB"] = static_cast<double>(octomap_bytes) / 1e6;
  state.counters["occ_improve_1t_ms"] = ours.seconds * 1e3;
  state.counters["ratio"] = octomap_seconds / ours.seconds;
  state.counters["points"] = static_cast<double>(cloud.size());
}

void BM_OctoMapSampleFrame(benchmark::State& state) { insert_octomap(state, Input::sample); }
void BM_OctoMapRealFrame(benchmark::State& state) { insert_octomap(state, Input::real); }
BENCHMARK(BM_OctoMapSampleFrame)->ArgName("res_mm")->Arg(10)->Arg(20)->Iterations(1)->Unit(benchmark::kSecond);
BENCHMARK(BM_OctoMapRealFrame)->ArgName("res_mm")->Arg(10)->Arg(20)->Iterations(1)->Unit(benchmark::kSecond);
#endif

}  // namespace
}  // namespace occ_improve

BENCHMARK_MAIN();
