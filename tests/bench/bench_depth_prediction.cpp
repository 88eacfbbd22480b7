// A dense depth from 5 % random samples of a 640 x 480 frame (issue 20: linear <= 10 ms on one thread),
// both rules in the same run, and the triangulation alone (what a planner calls once per shot). The frame
// is the real capture0001 (its organized points' z), or the built-in sample for the `sample` rows.
// Run: cmake --build <build> --target bench_depth_prediction && <build>/tests/bench_depth_prediction
#include "bench_support.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/planning/sample_triangulation.hpp"

#include <cmath>
#include <random>

namespace {

using namespace occ_improve;
using bench::Input;

/// z of every pixel (0 where there is no return) of the input frame, 640 x 480; empty when absent.
std::vector<float> frame_depth(Input input, benchmark::State& state) {
  const std::vector<Eigen::Vector3f>* points = bench::input_points(input, state);
  if (!points) return {};
  std::vector<float> z(points->size(), 0.0f);
  for (std::size_t i = 0; i < z.size(); ++i) z[i] = std::isfinite((*points)[i].z()) ? (*points)[i].z() : 0.0f;
  return z;
}

/// Every pixel with a return kept with probability 5 % (fixed seed).
std::vector<float> sparse_samples(const std::vector<float>& depth) {
  std::mt19937 rng(20);
  std::bernoulli_distribution keep(0.05);
  std::vector<float> sparse(depth.size(), 0.0f);
  for (std::size_t i = 0; i < depth.size(); ++i)
    if (depth[i] > 0 && keep(rng)) sparse[i] = depth[i];
  return sparse;
}

void run(benchmark::State& state, Input input, DepthPredictionRule rule, bool triangulation_only) {
  const std::vector<float> depth = frame_depth(input, state);
  if (depth.empty()) return;
  const std::vector<float> sparse = sparse_samples(depth);
  const SensorModel model(bench::input_preset(input, bench::kRealUse).model);
  DepthPredictionParams params;
  params.rule = rule;
  std::size_t samples = 0;
  for (float z : sparse) samples += z > 0;
  for (auto _ : state) {
    if (triangulation_only)
      benchmark::DoNotOptimize(triangulate_samples(sparse, 640, 480, model).triangles.data());
    else
      benchmark::DoNotOptimize(predict_dense_depth(sparse, 640, 480, model, params).depth_m.data());
  }
  state.counters["samples"] = static_cast<double>(samples);
}

void BM_PredictNearest(benchmark::State& state) { run(state, static_cast<Input>(state.range(0)), DepthPredictionRule::nearest, false); }
void BM_PredictLinear(benchmark::State& state) { run(state, static_cast<Input>(state.range(0)), DepthPredictionRule::linear, false); }
void BM_TriangulateSamples(benchmark::State& state) { run(state, static_cast<Input>(state.range(0)), DepthPredictionRule::linear, true); }

// Argument: 0 = the built-in sample, 1 = the real capture0001.
BENCHMARK(BM_PredictNearest)->ArgName("real")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PredictLinear)->ArgName("real")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TriangulateSamples)->ArgName("real")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
