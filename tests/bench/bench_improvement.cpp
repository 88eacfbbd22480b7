// The improvement map (eqs. 3-4) on the paper preset after one sample frame: the whole 640 x 480 map
// at 1 and 2 threads (target <= 3 ms with 2 threads), one ray, a fresh map, and the incremental update
// after a second frame. Run: cmake --build <build> --target bench_improvement && <build>/tests/bench_improvement
#include "bench_support.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sample_scene.hpp"

#include <benchmark/benchmark.h>

namespace occ_improve {
namespace {

const Mapper& one_frame_mapper() {
  static const Mapper mapper = [] {
    Mapper m(kinect_v1_paper());
    m.insert(PointSpan::from(bench::sample_points()));
    return m;
  }();
  return mapper;
}

void BM_FullMap(benchmark::State& state) {
  const Mapper& m = one_frame_mapper();
  for (auto _ : state) {
    ImprovementMap map = compute_improvement(m.geometry(), m.model(), m.surface(), static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(map.value.data());
  }
  state.counters["rays"] = static_cast<double>(m.geometry().column_count());
}
BENCHMARK(BM_FullMap)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// A fresh map for a 640 x 480 camera, as every one-shot use starts (occ_segment, occ_improve_map, the
// filter, Python): the grid, the empty surface and its improvement. /0 kinect_v1, /1 kinect_v1_paper.
void BM_NewMapper(benchmark::State& state) {
  const SensorPreset preset = state.range(0) == bench::kPaper ? kinect_v1_paper() : kinect_v1();
  for (auto _ : state) {
    Mapper mapper(preset);
    benchmark::DoNotOptimize(mapper.improvement().value.data());
  }
}
BENCHMARK(BM_NewMapper)->ArgName("paper")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_OneRay(benchmark::State& state) {
  const Mapper& m = one_frame_mapper();
  for (auto _ : state) benchmark::DoNotOptimize(ray_improvement(m.geometry(), m.model(), m.surface(), 320, 240));
}
BENCHMARK(BM_OneRay)->Unit(benchmark::kMicrosecond);

void BM_IncrementalSecondFrame(benchmark::State& state) {
  const Mapper& m = one_frame_mapper();
  sample::SceneOptions o;
  o.seed = 2;
  const auto points = sample::generate_scene(o).points();
  ColumnGrid grid{m.geometry()};
  insert_points(grid, m.model(), PointSpan::from(bench::sample_points()));
  grid.take_changed_columns();
  SurfaceMap surface = compute_surface(grid);
  insert_points(grid, m.model(), PointSpan::from(points));
  const std::vector<ColumnIndex> changed = update_surface(grid, grid.take_changed_columns(), surface);
  const ImprovementMap before = compute_improvement(m.geometry(), m.model(), m.surface());
  std::size_t rays = 0;
  for (auto _ : state) {
    ImprovementMap map = before;
    rays = update_improvement(m.geometry(), m.model(), surface, changed, map).size();
    benchmark::DoNotOptimize(map.value.data());
  }
  state.counters["changed_columns"] = static_cast<double>(changed.size());
  state.counters["rays_recomputed"] = static_cast<double>(rays);
}
BENCHMARK(BM_IncrementalSecondFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

// Inserting a 64 x 64-pixel patch of a second frame into a one-frame map: the whole incremental update
// (insertion, surface, improvement) per patch, with the stages as counters.
void BM_IncrementalPatch64(benchmark::State& state) {
  sample::SceneOptions o;
  o.seed = 2;
  const sample::SampleFrame frame = sample::generate_scene(o);
  const auto all = frame.points();
  std::vector<Eigen::Vector3f> patch;
  for (int v = 200; v < 264; ++v)
    for (int u = 300; u < 364; ++u) patch.push_back(all[static_cast<std::size_t>(v * frame.intrinsics.width + u)]);
  Mapper mapper(kinect_v1_paper());
  mapper.insert(PointSpan::from(bench::sample_points()));
  double insert_s = 0, improvement_s = 0;
  std::size_t rays = 0;
  for (auto _ : state) {
    const MapperReport r = mapper.insert(PointSpan::from(patch));
    insert_s += r.insertion.seconds;
    improvement_s += r.improvement_seconds;
    rays = r.rays_recomputed;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["insert_ms"] = 1e3 * insert_s / n;
  state.counters["improvement_ms"] = 1e3 * improvement_s / n;
  state.counters["rays_recomputed"] = static_cast<double>(rays);
}
BENCHMARK(BM_IncrementalPatch64)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Regions(benchmark::State& state) {
  const Mapper& m = one_frame_mapper();
  for (auto _ : state) benchmark::DoNotOptimize(find_regions(m.geometry(), m.improvement(), m.surface()).size());
}
BENCHMARK(BM_Regions)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace occ_improve

BENCHMARK_MAIN();
