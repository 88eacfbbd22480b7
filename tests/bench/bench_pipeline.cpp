// Replays 640 x 480 Kinect-like sequences through GrabberPipeline (insertion + incremental surface +
// improvement + regions per frame) and reports frames per second and drops:
//  - Throughput: every frame processed (backpressure), as fast as the pipeline goes;
//  - LiveRate:   frames delivered at a fixed sensor rate (30 Hz Kinect), newest frame wins: the drops
//                show how far the pipeline is from keeping up;
//  - SevenScenes: the real 7-Scenes sequence (kinect_v1 preset from its intrinsics), when the data is there.
// Run: cmake --build <build> --target bench_pipeline && <build>/tests/bench_pipeline
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/grabber_pipeline.hpp"
#include "occ_improve/pcl/sequence_sources.hpp"
#include "occ_improve/sample_scene.hpp"

#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>

namespace {

using namespace occ_improve;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

constexpr int kFrames = 10;

const std::vector<Cloud::ConstPtr>& sample_sequence() {
  static const std::vector<Cloud::ConstPtr> clouds = [] {
    std::vector<Cloud::ConstPtr> out;
    for (const sample::SampleFrame& frame : sample::generate_sequence(kFrames)) {
      out.push_back(Cloud::ConstPtr(
          new Cloud(organized_cloud(frame.points(), frame.intrinsics.width, frame.intrinsics.height))));
    }
    return out;
  }();
  return clouds;
}

void report(benchmark::State& state, const PipelineStatistics& s) {
  state.counters["frames"] = static_cast<double>(s.received);
  state.counters["processed"] = static_cast<double>(s.processed);
  state.counters["dropped"] = static_cast<double>(s.dropped);
  state.counters["fps"] = s.processed_per_second();
  state.counters["insert_ms"] = s.mean_ms(s.insert_ms);
  state.counters["improvement_ms"] = s.mean_ms(s.improvement_ms);
  state.counters["regions_ms"] = s.mean_ms(s.regions_ms);
}

/// Paper preset, every frame processed: the pipeline's throughput.
void BM_PipelineThroughput(benchmark::State& state) {
  const auto& clouds = sample_sequence();
  PipelineStatistics last;
  for (auto _ : state) {
    PipelineOptions options;
    options.backpressure = true;
    GrabberPipeline<pcl::PointXYZ> pipeline(kinect_v1_paper(), {}, options);
    pipeline.start();
    for (const auto& cloud : clouds) pipeline.pushFrame(cloud);
    pipeline.stop();
    last = pipeline.statistics();
  }
  report(state, last);
}
BENCHMARK(BM_PipelineThroughput)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

/// Paper preset, frames delivered at `state.range(0)` Hz (newest frame wins).
void BM_PipelineLiveRate(benchmark::State& state) {
  const auto& clouds = sample_sequence();
  const auto period = std::chrono::duration<double>(1.0 / static_cast<double>(state.range(0)));
  PipelineStatistics last;
  for (auto _ : state) {
    GrabberPipeline<pcl::PointXYZ> pipeline(kinect_v1_paper());
    pipeline.start();
    auto next = std::chrono::steady_clock::now();
    for (int repeat = 0; repeat < 3; ++repeat)
      for (const auto& cloud : clouds) {
        std::this_thread::sleep_until(next);
        next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
        pipeline.pushFrame(cloud);
      }
    pipeline.stop();  // the last waiting frame is still processed
    last = pipeline.statistics();
  }
  report(state, last);
}
BENCHMARK(BM_PipelineLiveRate)->Arg(30)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

/// The real 7-Scenes frames (first 10, poses applied), kinect_v1 preset, every frame processed.
void BM_PipelineSevenScenes(benchmark::State& state) {
  const char* env = std::getenv("OCC_IMPROVE_DATA_DIR");
  const std::string frames = std::string(env && *env ? env : OCC_IMPROVE_DATA_DIR_DEFAULT) +
                             "/sequences/7scenes_redkitchen/frames";
  if (!std::filesystem::exists(frames)) {
    state.SkipWithError("7-Scenes data not found (set OCC_IMPROVE_DATA_DIR)");
    return;
  }
  DepthSequence sequence = scan_depth_sequence(frames);
  sequence.frames.resize(std::min<std::size_t>(sequence.frames.size(), kFrames));
  // Frames are decoded before timing, so the figure is the pipeline's, not the PNG decoder's.
  std::vector<Cloud::ConstPtr> clouds;
  {
    DepthSequenceGrabber grabber(sequence, *sequence.intrinsics);
    std::function<void(const Cloud::ConstPtr&)> keep = [&](const Cloud::ConstPtr& c) { clouds.push_back(c); };
    grabber.registerCallback(keep);
    grabber.start();
    grabber.waitUntilDone();
    grabber.stop();
  }
  PipelineStatistics last;
  for (auto _ : state) {
    PipelineOptions options;
    options.backpressure = true;
    GrabberPipeline<pcl::PointXYZ> pipeline(kinect_v1(*sequence.intrinsics), {}, options);
    pipeline.start();
    for (const auto& cloud : clouds) pipeline.pushFrame(cloud);
    pipeline.stop();
    last = pipeline.statistics();
  }
  report(state, last);
}
BENCHMARK(BM_PipelineSevenScenes)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
