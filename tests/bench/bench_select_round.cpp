// One closed-loop round of selective acquisition with the real-use preset (kinect_v1) on 2 threads:
// insert the returns of a 4096-ray shot (surface kept current), update the improvement incrementally,
// plan the next shot (improvement x return model): /0 the rays shape (highest first), /1 coarse_to_fine
// refined by blocks (strategy (g), PlanRequest's default refinement), /2 coarse_to_fine refined by the
// samples' triangles (the tools' default, `-refine triangles`), the triangulation kept from round to round
// in a PlanMemory as the tools keep it, /3 the same with every plan triangulating from scratch (no
// memory: the cost the memory saves); under (g) the insertion also keeps the multi-scale pyramid, timed
// with the improvement. The map starts from one full frame of the built-in
// sample; the virtual sensor looks at the noise-free sample.
// Run: cmake --build <build> --target bench_select_round && <build>/tests/bench_select_round
#include "occ_improve/mapper.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/sim/virtual_sensor.hpp"

#include <benchmark/benchmark.h>

#include <chrono>

namespace {

using namespace occ_improve;

/// A 4096-ray shot of the benchmark's argument: 0 rays, 1 coarse_to_fine by blocks, 2 and 3 by triangles.
PlanRequest request_of(std::int64_t shape) {
  PlanRequest request;
  request.budget_rays = 4096;
  request.shape = shape == 0 ? ShotShape::rays : ShotShape::coarse_to_fine;
  if (shape >= 2) request.refine_by = RefineBy::triangles;
  return request;
}

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void BM_SelectRound(benchmark::State& state) {
  const sample::SampleFrame noisy = sample::generate_scene();
  sample::SceneOptions clean_options;
  clean_options.noise = clean_options.quantise = false;
  const sample::SampleFrame clean = sample::generate_scene(clean_options);
  Mapper mapper(kinect_v1(noisy.intrinsics));
  InsertionOptions two_threads;
  two_threads.threads = 2;
  const auto first = noisy.points();
  mapper.insert(PointSpan::from(first), two_threads);
  VirtualSensor sensor(clean.depth_m, clean.intrinsics);
  ReturnRecord returns = ReturnRecord::for_grid(mapper.geometry().width(), mapper.geometry().height());
  const PlanRequest request = request_of(state.range(0));
  PlanMemory memory;
  const auto plan = [&] {
    return state.range(0) == 3 ? plan_next_shot(mapper, returns, request) : plan_next_shot(mapper, returns, request, memory);
  };
  Shot shot = plan();
  double insert_ms = 0, improvement_ms = 0, plan_ms = 0;
  for (auto _ : state) {
    const std::vector<float> depth = sensor.shoot(shot.columns);  // the sensor's time is not the library's
    const std::vector<Eigen::Vector3f> points = sensor.points(shot.columns, depth);
    const std::vector<std::uint8_t> got = VirtualSensor::returned(depth);
    const auto start = std::chrono::steady_clock::now();
    const MapperReport report = mapper.insert(PointSpan::from(points), two_threads);
    returns.record_shot(shot.columns, got);
    const auto planned = std::chrono::steady_clock::now();
    shot = plan();
    plan_ms += ms_since(planned);
    insert_ms += 1e3 * report.insertion.seconds;
    improvement_ms += 1e3 * report.improvement_seconds;
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["insert_ms"] = insert_ms / n;
  state.counters["improvement_ms"] = improvement_ms / n;
  state.counters["plan_ms"] = plan_ms / n;
  // The memory's triangulation updates, and those that started over (many samples lost since the last plan).
  state.counters["triangulations"] = static_cast<double>(memory.triangulation.updates());
  state.counters["started_over"] = static_cast<double>(memory.triangulation.start_overs());
}
BENCHMARK(BM_SelectRound)->DenseRange(0, 3)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(200);

/// The plan alone, on the map after one frame and a record of a few shots: its share of the round.
void BM_Plan(benchmark::State& state) {
  Mapper mapper(kinect_v1());
  const auto first = sample::generate_scene().points();
  mapper.insert(PointSpan::from(first));
  ReturnRecord returns = ReturnRecord::for_grid(mapper.geometry().width(), mapper.geometry().height());
  const PlanRequest request = request_of(state.range(0));
  for (int i = 0; i < 5; ++i) {
    const Shot shot = plan_next_shot(mapper, returns, request);
    returns.record_shot(shot.columns, std::vector<std::uint8_t>(shot.columns.size(), i % 2));
  }
  for (auto _ : state) benchmark::DoNotOptimize(plan_next_shot(mapper, returns, request));
}
BENCHMARK(BM_Plan)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

void BM_ShotScores(benchmark::State& state) {
  Mapper mapper(kinect_v1());
  const auto first = sample::generate_scene().points();
  mapper.insert(PointSpan::from(first));
  ReturnRecord returns = ReturnRecord::for_grid(mapper.geometry().width(), mapper.geometry().height());
  returns.record_shot({1, 2, 3}, {1, 0, 1});
  for (auto _ : state) benchmark::DoNotOptimize(shot_scores(mapper.improvement(), returns));
}
BENCHMARK(BM_ShotScores)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
