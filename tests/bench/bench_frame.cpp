// One whole 640 x 480 real frame through the Mapper, as a user runs it (issue 14, part 7): insertion with
// the surface kept current, then the improvement map, into a fresh map per iteration (the Mapper's
// construction is not timed). Args: frame (0 = capture0001, 1 = mOSD learn0), threads, preset
// (bench::PresetArg: 0 = kinect_v1 with the frame's fitted camera, 1 = kinect_v1_paper).
// Counters: insert_ms (insertion + surface), improvement_ms, total_ms; targets on kinect_v1 with 2 threads:
// 10 / 3 / 15 ms (30 ms end to end on 1 thread); store_mb, the store's heap after the frame
// (ColumnGrid::memory_bytes: its windows, records and spare capacity).
// BM_MemoryBandwidth beside it: what this machine's memory moves per second (a copy of a buffer far beyond
// the caches, on 1 and 2 threads: bytes read + written), against which a frame's memory traffic is weighed
// (docs/PERFORMANCE.md: "what bounds the time").
#include "bench_support.hpp"
#include "occ_improve/sensor/intrinsics_fit.hpp"
#include "occ_improve/mapper.hpp"

#include <benchmark/benchmark.h>

#include <cstring>
#include <memory>
#include <vector>

namespace occ_improve {
namespace {

const char* const kFrames[] = {"kinect/pcl_tutorials/pairwise/capture0001.pcd", "segmentation/mosd_learn/learn0.pcd"};

const std::vector<Eigen::Vector3f>& frame_points(int frame, std::string& error) {
  static std::string errors[2];
  static const std::vector<Eigen::Vector3f> points[2] = {bench::load_pcd_points(kFrames[0], errors[0]),
                                                         bench::load_pcd_points(kFrames[1], errors[1])};
  error = errors[frame];
  return points[frame];
}

void BM_FrameThroughMapper(benchmark::State& state) {
  const int frame = static_cast<int>(state.range(0));
  std::string error;
  const auto& points = frame_points(frame, error);
  if (points.size() != 640u * 480u) {
    state.SkipWithError(error.empty() ? "not a 640 x 480 organized frame" : error.c_str());
    return;
  }
  const bool paper = state.range(2) == bench::kPaper;
  const SensorPreset preset =
      paper ? kinect_v1_paper() : kinect_v1(fit_intrinsics(points.front().data(), 640, 480, 3).intrinsics);
  state.SetLabel(std::string(frame == 0 ? "capture0001 " : "learn0 ") + preset.name);
  InsertionOptions options;
  options.threads = static_cast<int>(state.range(1));
  double insert_s = 0, improvement_s = 0, store_bytes = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto mapper = std::make_unique<Mapper>(preset);
    state.ResumeTiming();
    const MapperReport r = mapper->insert(PointSpan::from(points), options);
    insert_s += r.insertion.seconds;
    improvement_s += r.improvement_seconds;
    state.PauseTiming();
    store_bytes = static_cast<double>(mapper->grid().memory_bytes());
    mapper.reset();
    state.ResumeTiming();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["insert_ms"] = 1e3 * insert_s / n;
  state.counters["improvement_ms"] = 1e3 * improvement_s / n;
  state.counters["total_ms"] = 1e3 * (insert_s + improvement_s) / n;
  state.counters["store_mb"] = store_bytes / 1e6;
}
BENCHMARK(BM_FrameThroughMapper)->ArgNames({"frame", "threads", "paper"})->ArgsProduct({{0, 1}, {1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)->Iterations(5)->UseRealTime();

// Each thread copies between its own two buffers of range(0) MiB (far beyond the last-level cache);
// bytes_per_second counts what is read and what is written.
void BM_MemoryBandwidth(benchmark::State& state) {
  const std::size_t bytes = static_cast<std::size_t>(state.range(0)) << 20;
  std::vector<char> a(bytes, 1), b(bytes, 2);
  for (auto _ : state) {
    std::memcpy(b.data(), a.data(), bytes);
    a.swap(b);
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(2 * bytes));
}
BENCHMARK(BM_MemoryBandwidth)->ArgName("mb")->Arg(256)->Threads(1)->Threads(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace occ_improve

BENCHMARK_MAIN();
