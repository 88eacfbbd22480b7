#include "occ_improve/pcl/grabber_pipeline.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/sequence_sources.hpp"
#include "occ_improve/planning/point_selection.hpp"
#include "occ_improve/sample_scene.hpp"
#include "support/test_data.hpp"

#include <pcl/common/io.h>
#include <pcl/common/transforms.h>
#include <pcl/io/pcd_grabber.h>
#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <future>
#include <thread>

#include <unistd.h>

namespace occ_improve {
namespace {

namespace fs = std::filesystem;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

// A small camera so the threading tests run in milliseconds.
PinholeIntrinsics tiny_camera() {
  PinholeIntrinsics k;
  k.fx = k.fy = 50.0;
  k.cx = 31.5;
  k.cy = 23.5;
  k.width = 64;
  k.height = 48;
  return k;
}

SensorPreset tiny_preset() {
  PinholePresetOptions options;
  options.depth_bins = 128;
  return preset_from_pinhole(tiny_camera(), options, "tiny");
}

/// A wall at `depth_m` seen by a camera: organized width x height (or unorganized when height == 1).
Cloud::Ptr wall(double depth_m, int width, int height) {
  const PinholeIntrinsics k = tiny_camera();
  Cloud::Ptr cloud(new Cloud);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
      cloud->push_back(pcl::PointXYZ(static_cast<float>((u - k.cx) / k.fx * depth_m),
                                     static_cast<float>((v - k.cy) / k.fy * depth_m), static_cast<float>(depth_m)));
  cloud->width = static_cast<std::uint32_t>(width);
  cloud->height = static_cast<std::uint32_t>(height);
  return cloud;
}

Cloud::Ptr tiny_frame(double depth_m = 2.0) { return wall(depth_m, 64, 48); }

void expect_consistent(const PipelineStatistics& s) {
  EXPECT_EQ(s.in_flight, 0u);
  EXPECT_EQ(s.received, s.processed + s.dropped + s.rejected + s.interrupted);
}

/// A temporary folder removed at the end of the test.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) : path(fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

TEST(GrabberPipeline, ProcessesEveryFrameInOrderWithBackpressure) {
  PipelineOptions options;
  options.backpressure = true;
  GrabberPipeline<pcl::PointXYZ> pipeline(tiny_preset(), {}, options);
  std::vector<std::uint64_t> indices;
  pipeline.setResultCallback([&](const FrameResult& r) {
    indices.push_back(r.frame_index);
    EXPECT_GT(r.report.insertion.points_inserted, 0u);
  });
  pipeline.start();
  std::thread producer([&] {
    for (int i = 0; i < 10; ++i) pipeline.pushFrame(tiny_frame(2.0 + 0.01 * i));
  });
  producer.join();
  pipeline.stop();
  const PipelineStatistics s = pipeline.statistics();
  EXPECT_EQ(s.received, 10u);
  EXPECT_EQ(s.processed, 10u);
  EXPECT_EQ(s.dropped, 0u);
  expect_consistent(s);
  ASSERT_EQ(indices.size(), 10u);
  for (std::size_t i = 0; i < indices.size(); ++i) EXPECT_EQ(indices[i], i);
  EXPECT_GT(pipeline.mapper().surface().known_count(), 0u);
  EXPECT_GT(s.insert_ms, 0.0);
}

// keep_fraction: each frame's kept points are keep_points_by_map's choice against the map before the
// frame, only they are inserted, and the rest is counted.
TEST(GrabberPipeline, KeepFractionInsertsTheMapsChoiceAndCountsTheRest) {
  PipelineOptions options;
  options.backpressure = true;
  options.keep_fraction = 0.1;
  GrabberPipeline<pcl::PointXYZ> pipeline(tiny_preset(), {}, options);
  // The same choices, made beside the pipeline on a map of our own fed the same way.
  Mapper expected_map(tiny_preset());
  std::vector<std::size_t> inserted;
  pipeline.setResultCallback([&](const FrameResult& r) { inserted.push_back(r.report.insertion.points_received); });
  pipeline.start();
  std::size_t expected_total = 0;
  for (int i = 0; i < 3; ++i) {
    const Cloud::Ptr frame = tiny_frame(2.0 + 0.05 * i);
    const MapView map{expected_map.geometry(), expected_map.surface(), expected_map.improvement(), expected_map.pyramid()};
    const PointSpan span = span_of(*frame);
    std::vector<Eigen::Vector3f> kept;
    for (const std::uint64_t k : keep_points_by_map(points_on_rays(span, expected_map.geometry()), KeepAmount::fraction(0.1), map))
      kept.push_back((*frame)[k].getVector3fMap());
    expected_map.insert(PointSpan::from(kept));
    expected_total += kept.size();
    pipeline.pushFrame(frame);
  }
  pipeline.stop();
  const PipelineStatistics s = pipeline.statistics();
  EXPECT_EQ(s.processed, 3u);
  expect_consistent(s);
  EXPECT_EQ(s.points_received, 3u * 64u * 48u);
  ASSERT_EQ(inserted.size(), 3u);
  for (const std::size_t n : inserted) EXPECT_EQ(n, static_cast<std::size_t>(std::llround(0.1 * 64 * 48)));
  EXPECT_EQ(s.points_not_kept, s.points_received - expected_total);
  EXPECT_EQ(pipeline.mapper().surface().depth_m, expected_map.surface().depth_m);
  EXPECT_GT(s.keep_ms, 0.0);
  PipelineOptions bad;
  for (const double f : {0.0, 1.5, -0.5, std::numeric_limits<double>::quiet_NaN()}) {
    bad.keep_fraction = f;
    EXPECT_THROW(bad.validate(), InvalidParameter) << f;
  }
  bad.keep_fraction = 1.0;
  EXPECT_NO_THROW(bad.validate());
}

TEST(GrabberPipeline, NewestFrameWinsWhenTheWorkerFallsBehind) {
  GrabberPipeline<pcl::PointXYZ> pipeline(tiny_preset());
  std::promise<void> first_frame_started, release;
  std::shared_future<void> released = release.get_future().share();
  std::vector<std::uint64_t> indices;
  pipeline.setResultCallback([&](const FrameResult& r) {
    indices.push_back(r.frame_index);
    if (r.frame_index == 0) {
      first_frame_started.set_value();
      released.wait();  // hold the worker while the grabber keeps delivering
    }
  });
  pipeline.start();
  pipeline.pushFrame(tiny_frame());
  first_frame_started.get_future().wait();
  for (int i = 0; i < 5; ++i) pipeline.pushFrame(tiny_frame());
  release.set_value();
  pipeline.stop();
  const PipelineStatistics s = pipeline.statistics();
  EXPECT_EQ(s.received, 6u);
  EXPECT_EQ(s.processed, 2u);
  EXPECT_EQ(s.dropped, 4u);
  expect_consistent(s);
  EXPECT_EQ(indices, (std::vector<std::uint64_t>{0, 5}));  // the newest waiting frame was processed
}

TEST(GrabberPipeline, BadFramesAreCountedReportedAndSkipped) {
  PipelineOptions options;
  options.require_organized = true;
  GrabberPipeline<pcl::PointXYZ> pipeline(tiny_preset(), {}, options);
  std::vector<std::string> messages;
  pipeline.setEventCallback([&](const PipelineEvent& e) {
    EXPECT_EQ(e.kind, PipelineEvent::Kind::rejected_frame);
    messages.push_back(e.message);
  });
  pipeline.start();
  pipeline.pushFrame(Cloud::Ptr(new Cloud));  // empty
  pipeline.waitIdle();
  pipeline.pushFrame(nullptr);
  pipeline.waitIdle();
  pipeline.pushFrame(wall(2.0, 32, 24));  // organized, but not the camera's size
  pipeline.waitIdle();
  pipeline.pushFrame(wall(2.0, 64 * 48, 1));  // unorganized
  pipeline.waitIdle();
  pipeline.pushFrame(tiny_frame());  // good: the pipeline kept running
  pipeline.stop();
  const PipelineStatistics s = pipeline.statistics();
  EXPECT_EQ(s.rejected, 4u);
  EXPECT_EQ(s.processed, 1u);
  expect_consistent(s);
  ASSERT_EQ(messages.size(), 4u);
  EXPECT_NE(messages[0].find("empty"), std::string::npos);
  EXPECT_NE(messages[1].find("empty"), std::string::npos);
  EXPECT_NE(messages[2].find("32x24"), std::string::npos);
  EXPECT_NE(messages[3].find("unorganized"), std::string::npos);
}

TEST(GrabberPipeline, SizeChangeMidStreamIsRejected) {
  // A shared map and no expected camera size: the first accepted frame fixes the stream's size.
  auto mapper = std::make_shared<Mapper>(tiny_preset());
  GrabberPipeline<pcl::PointXYZ> pipeline(mapper);
  std::vector<std::string> messages;
  pipeline.setEventCallback([&](const PipelineEvent& e) { messages.push_back(e.message); });
  pipeline.start();
  pipeline.pushFrame(tiny_frame());
  pipeline.waitIdle();
  pipeline.pushFrame(wall(2.0, 100, 1));
  pipeline.waitIdle();
  pipeline.pushFrame(tiny_frame());
  pipeline.stop();
  const PipelineStatistics s = pipeline.statistics();
  EXPECT_EQ(s.processed, 2u);
  EXPECT_EQ(s.rejected, 1u);
  expect_consistent(s);
  ASSERT_EQ(messages.size(), 1u);
  EXPECT_NE(messages[0].find("size changed"), std::string::npos);
  EXPECT_EQ(pipeline.sharedMapper(), mapper);
}

/// A grabber that fails on demand.
class FailingGrabber : public pcl::Grabber {
public:
  FailingGrabber(bool fail_start, bool fail_stop) : fail_start_(fail_start), fail_stop_(fail_stop) {
    createSignal<void(const Cloud::ConstPtr&)>();
  }
  void start() override {
    if (fail_start_) throw pcl::IOException("device unplugged");
    running_ = true;
  }
  void stop() override {
    running_ = false;
    if (fail_stop_) throw std::runtime_error("stop failed");
  }
  std::string getName() const override { return "FailingGrabber"; }
  bool isRunning() const override { return running_; }
  float getFramesPerSecond() const override { return 30.0f; }

private:
  bool fail_start_, fail_stop_, running_ = false;
};

TEST(GrabberPipeline, AGrabberThatThrowsIsCountedAndReported) {
  {
    FailingGrabber grabber(true, false);
    GrabberPipeline<pcl::PointXYZ> pipeline(tiny_preset());
    std::vector<PipelineEvent> events;
    pipeline.setEventCallback([&](const PipelineEvent& e) { events.push_back(e); });
    pipeline.attach(grabber);
    EXPECT_THROW(pipeline.start(), IoError);
    EXPECT_FALSE(pipeline.isRunning());
    EXPECT_EQ(pipeline.statistics().grabber_errors, 1u);
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].kind, PipelineEvent::Kind::grabber_error);
    EXPECT_NE(events[0].message.find("FailingGrabber"), std::string::npos);
  }
  {
    FailingGrabber grabber(false, true);
    GrabberPipeline<pcl::PointXYZ> pipeline(tiny_preset());
    pipeline.attach(grabber);
    pipeline.start();
    EXPECT_TRUE(pipeline.isRunning());
    pipeline.stop();
    pipeline.stop();  // idempotent
    EXPECT_FALSE(pipeline.isRunning());
    EXPECT_EQ(pipeline.statistics().grabber_errors, 1u);
  }
}

TEST(GrabberPipeline, AttachNeedsTheGrabbersPointType) {
  FailingGrabber grabber(false, false);  // delivers PointXYZ only
  GrabberPipeline<pcl::PointXYZRGBA> pipeline(tiny_preset());
  EXPECT_THROW(pipeline.attach(grabber), InvalidInput);
}

TEST(GrabberPipeline, DestructionWhileRunningJoinsEverything) {
  auto grabber = std::make_unique<PcdSequenceGrabber>(std::vector<std::string>{"/nonexistent/a.pcd"}, 0.0f);
  auto pipeline = std::make_unique<GrabberPipeline<pcl::PointXYZ>>(tiny_preset());
  pipeline->attach(*grabber);
  pipeline->start();
  for (int i = 0; i < 3; ++i) pipeline->pushFrame(tiny_frame());
  pipeline.reset();  // stops the grabber and the worker
  EXPECT_FALSE(grabber->isRunning());
}

TEST(GrabberPipeline, StopMidStreamKeepsTheCountsConsistent) {
  TempDir dir("occ_improve_pipeline_tiny");
  for (int f = 0; f < 40; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%03d.pcd", f);
    ASSERT_EQ(pcl::io::savePCDFileBinary((dir.path / name).string(), *tiny_frame(1.0 + 0.05 * f)), 0);
  }
  PcdSequenceGrabber grabber(dir.path.string());  // as fast as it reads: the worker falls behind
  GrabberPipeline<pcl::PointXYZ> pipeline(tiny_preset());
  pipeline.attach(grabber);
  pipeline.start();
  while (grabber.framesEmitted() < 10 && grabber.isRunning()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  pipeline.stop();  // mid-stream
  EXPECT_FALSE(grabber.isRunning());
  const PipelineStatistics s = pipeline.statistics();
  EXPECT_GE(s.received, 10u);
  EXPECT_GE(s.processed, 1u);
  EXPECT_EQ(s.rejected, 0u);
  expect_consistent(s);
  EXPECT_EQ(s.received, grabber.framesEmitted());
}

// The built-in sample sequence written as PCD files and replayed through the PCD folder source; one
// file without coordinates in the folder is reported and skipped. The result equals inserting the frames directly.
TEST(GrabberPipelineReplay, GeneratedSequenceFromPcdFiles) {
  TempDir dir("occ_improve_pipeline_pcd");
  const std::vector<sample::SampleFrame> frames = sample::generate_sequence(2);
  std::vector<Cloud> clouds;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    Cloud cloud = organized_cloud(frames[f].points(), frames[f].intrinsics.width, frames[f].intrinsics.height);
    ASSERT_EQ(pcl::io::savePCDFileBinary((dir.path / ("frame_" + std::to_string(f) + ".pcd")).string(), cloud), 0);
    clouds.push_back(std::move(cloud));
  }
  // A PCD without x/y/z (a garbage file would crash PCL 1.13's PCDReader itself).
  pcl::PointCloud<pcl::Intensity> no_xyz;
  no_xyz.push_back(pcl::Intensity());
  ASSERT_EQ(pcl::io::savePCDFileASCII((dir.path / "frame_9_no_xyz.pcd").string(), no_xyz), 0);

  PcdSequenceGrabber grabber(dir.path.string());
  ASSERT_EQ(grabber.frameCount(), 3u);
  PipelineOptions options;
  options.backpressure = true;
  GrabberPipeline<pcl::PointXYZ> pipeline(kinect_v1_paper(), {}, options);
  grabber.setErrorCallback([&](const std::string& message) { pipeline.reportSourceError(message); });
  std::vector<FrameResult> results;
  pipeline.setResultCallback([&](const FrameResult& r) { results.push_back(r); });
  pipeline.attach(grabber);
  pipeline.start();
  grabber.waitUntilDone();
  pipeline.stop();

  const PipelineStatistics s = pipeline.statistics();
  EXPECT_EQ(s.received, 2u);
  EXPECT_EQ(s.processed, 2u);
  EXPECT_EQ(s.grabber_errors, 1u);
  EXPECT_EQ(grabber.errors(), 1u);
  expect_consistent(s);
  ASSERT_EQ(results.size(), 2u);
  for (const FrameResult& r : results) {
    EXPECT_LE(r.top_regions.size(), options.top_regions);
    for (std::size_t i = 1; i < r.top_regions.size(); ++i)
      EXPECT_GE(r.top_regions[i - 1].summed_improvement, r.top_regions[i].summed_improvement);
  }
  EXPECT_LT(results[1].stop.total_improvement, results[0].stop.total_improvement)
      << "a second view of the same scene leaves less to gain";

  Mapper direct(kinect_v1_paper());
  for (const Cloud& cloud : clouds) direct.insert(span_of(cloud));
  EXPECT_EQ(pipeline.mapper().improvement().value, direct.improvement().value);
  EXPECT_EQ(pipeline.mapper().surface().depth_m, direct.surface().depth_m);
}

TEST(GrabberPipelineReplay, SevenScenesWithPosesInTheFirstFrame) {
  OCC_REQUIRE_DATA(frames_dir, "sequences/7scenes_redkitchen/frames");
  DepthSequence sequence = scan_depth_sequence(frames_dir);
  ASSERT_EQ(sequence.frames.size(), 50u);
  ASSERT_TRUE(sequence.intrinsics.has_value());
  EXPECT_DOUBLE_EQ(sequence.intrinsics->fx, 585.0);
  for (const auto& f : sequence.frames) ASSERT_TRUE(f.camera_to_world.has_value());
  sequence.frames.resize(4);  // keep the test short

  DepthSequenceGrabber grabber(sequence, *sequence.intrinsics);
  EXPECT_TRUE(grabber.posesApplied());
  std::vector<Cloud::ConstPtr> emitted;
  std::function<void(const Cloud::ConstPtr&)> keep = [&](const Cloud::ConstPtr& c) { emitted.push_back(c); };
  grabber.registerCallback(keep);
  PipelineOptions options;
  options.backpressure = true;
  GrabberPipeline<pcl::PointXYZ> pipeline(kinect_v1(*sequence.intrinsics), {}, options);
  pipeline.attach(grabber);
  pipeline.start();
  grabber.waitUntilDone();
  pipeline.stop();

  const PipelineStatistics s = pipeline.statistics();
  EXPECT_EQ(s.processed, 4u);
  expect_consistent(s);
  ASSERT_EQ(emitted.size(), 4u);
  // Frame 0 is its own sensor frame; frame 3 is moved by T0^-1 T3.
  const LoadedFrame raw0 = load_depth_frame(sequence.frames[0].depth_path, *sequence.intrinsics, DepthEncoding::millimetres);
  const LoadedFrame raw3 = load_depth_frame(sequence.frames[3].depth_path, *sequence.intrinsics, DepthEncoding::millimetres);
  const Eigen::Isometry3d to_first = sequence.frames[0].camera_to_world->inverse() * *sequence.frames[3].camera_to_world;
  ASSERT_EQ(emitted[3]->size(), raw3.cloud.size());
  EXPECT_EQ(emitted[3]->width, 640u);
  std::size_t compared = 0;
  for (std::size_t i = 0; i < raw3.cloud.size(); i += 101) {
    if (!std::isfinite(raw3.cloud[i].z)) continue;
    const Eigen::Vector3d expected = to_first * raw3.cloud[i].getVector3fMap().cast<double>();
    EXPECT_NEAR((*emitted[3])[i].x, expected.x(), 1e-4);
    EXPECT_NEAR((*emitted[3])[i].z, expected.z(), 1e-4);
    ++compared;
  }
  EXPECT_GT(compared, 100u);
  EXPECT_NEAR((*emitted[0])[320 * 640 + 320].z, raw0.cloud[320 * 640 + 320].z, 1e-4);
  EXPECT_GT(pipeline.mapper().surface().known_count(), 200000u);
}

TEST(GrabberPipelineReplay, PclPcdGrabberOnRealFrames) {
  OCC_REQUIRE_DATA(dir, "kinect/pcl_test/grabber_sequences/pcd");
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir)) files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), 3u);
  PinholeIntrinsics k;  // fx = fy = 525, principal point (320, 240) (data README)
  k.cx = 320.0;
  k.cy = 240.0;
  PipelineOptions options;
  options.backpressure = true;
  GrabberPipeline<pcl::PointXYZRGBA> pipeline(kinect_v1(k), {}, options);
  // fps > 0: PCL 1.13's PCDGrabber aborts at exit with fps = 0 (docs/ENVIRONMENT.md).
  pcl::PCDGrabber<pcl::PointXYZRGBA> grabber(files, 20.0f, false);
  pipeline.attach(grabber);
  pipeline.start();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (pipeline.statistics().received < 3 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  pipeline.waitIdle();
  pipeline.stop();
  const PipelineStatistics s = pipeline.statistics();
  EXPECT_GE(s.received, 3u);
  EXPECT_GE(s.processed, 3u);
  EXPECT_EQ(s.rejected, 0u);
  expect_consistent(s);
}

TEST(SequenceSources, TumLayoutAssociatesPosesByTimestamp) {
  TempDir dir("occ_improve_tum");
  std::ofstream(dir.path / "depth.txt") << "# depth maps\n"
                                        << "1305031102.160407 depth/1305031102.160407.png\n"
                                        << "1305031102.194330 depth/1305031102.194330.png\n"
                                        << "1305031109.000000 depth/1305031109.000000.png\n";
  std::ofstream(dir.path / "groundtruth.txt") << "# ground truth\n"
                                              << "1305031102.1600 1 2 3 0 0 0 1\n"
                                              << "1305031102.1950 4 5 6 0 0 0.7071068 0.7071068\n";
  const DepthSequence sequence = scan_depth_sequence(dir.path.string());
  ASSERT_EQ(sequence.frames.size(), 3u);
  EXPECT_TRUE(sequence.encoding == DepthEncoding::tum_5000);
  EXPECT_EQ(sequence.frames[0].depth_path, (dir.path / "depth/1305031102.160407.png").string());
  ASSERT_TRUE(sequence.frames[0].camera_to_world.has_value());
  EXPECT_NEAR(sequence.frames[0].camera_to_world->translation().x(), 1.0, 1e-12);
  ASSERT_TRUE(sequence.frames[1].camera_to_world.has_value());
  EXPECT_NEAR(sequence.frames[1].camera_to_world->translation().z(), 6.0, 1e-12);
  EXPECT_NEAR(sequence.frames[1].camera_to_world->linear()(1, 0), 1.0, 1e-6);  // 90 deg about z
  EXPECT_FALSE(sequence.frames[2].camera_to_world.has_value());  // no pose within 20 ms
}

// A depth.txt with Windows line ends (and trailing blanks, a blank line) names the same files: the '\r' stayed
// in every name, and every frame failed as "unsupported depth image type '.png'".
TEST(SequenceSources, TumListsWithWindowsLineEndsNameTheSameFiles) {
  TempDir dir("occ_improve_tum_crlf");
  std::ofstream(dir.path / "depth.txt", std::ios::binary) << "# depth maps\r\n"
                                                           << "1305031102.160407 depth/1305031102.160407.png\r\n"
                                                           << "\r\n"
                                                           << "1305031102.194330 depth/1305031102.194330.png \t\r\n";
  std::ofstream(dir.path / "groundtruth.txt", std::ios::binary) << "1305031102.1600 1 2 3 0 0 0 1\r\n";
  const DepthSequence sequence = scan_depth_sequence(dir.path.string());
  ASSERT_EQ(sequence.frames.size(), 2u);
  EXPECT_EQ(sequence.frames[0].depth_path, (dir.path / "depth/1305031102.160407.png").string());
  EXPECT_EQ(sequence.frames[1].depth_path, (dir.path / "depth/1305031102.194330.png").string());
  ASSERT_TRUE(sequence.frames[0].camera_to_world.has_value());
  EXPECT_NEAR(sequence.frames[0].camera_to_world->translation().z(), 3.0, 1e-12);
}

// Partly posed (TUM's ground truth often starts late): the posed frames are moved into the first posed
// frame's view, and the frame without a pose is skipped and counted, naming it. Poses were dropped for
// the whole sequence without a word, fusing a moving camera's frames as one view.
TEST(SequenceSources, APartlyPosedSequenceSkipsAndCountsTheFramesWithoutAPose) {
  TempDir dir("occ_improve_partly_posed");
  const PinholeIntrinsics k = tiny_camera();
  DepthSequence sequence;
  sequence.intrinsics = k;
  sequence.encoding = DepthEncoding::millimetres;
  for (int i = 0; i < 3; ++i) {
    const std::string path = (dir.path / ("frame-00000" + std::to_string(i) + ".depth.png")).string();
    write_png(path, Image16{k.width, k.height, std::vector<std::uint16_t>(static_cast<std::size_t>(k.width * k.height), 2000)});
    DepthSequenceFrame frame{path, std::nullopt};
    if (i > 0) frame.camera_to_world = Eigen::Isometry3d(Eigen::Translation3d(0.1 * i, 0, 0));
    sequence.frames.push_back(frame);
  }
  DepthSequenceGrabber grabber(sequence, k);
  EXPECT_TRUE(grabber.posesApplied());
  EXPECT_EQ(grabber.unposedFrames(), 1u);
  std::vector<Cloud::ConstPtr> emitted;
  std::vector<std::string> errors;
  std::function<void(const Cloud::ConstPtr&)> keep = [&](const Cloud::ConstPtr& c) { emitted.push_back(c); };
  grabber.registerCallback(keep);
  grabber.setErrorCallback([&](const std::string& e) { errors.push_back(e); });
  grabber.start();
  grabber.waitUntilDone();
  grabber.stop();
  ASSERT_EQ(emitted.size(), 2u);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("file 1 of 3 skipped: '" + sequence.frames[0].depth_path + "' has no pose"), std::string::npos)
      << errors[0];
  // Frame 1 is the map's view; frame 2 lies 0.1 m to its right, so its points move by +0.1 m in x.
  const std::size_t centre = static_cast<std::size_t>(k.width * (k.height / 2) + k.width / 2);
  const float x1 = (*emitted[0])[centre].x, x2 = (*emitted[1])[centre].x;
  EXPECT_NEAR(x2 - x1, 0.1f, 1e-5f);
  EXPECT_EQ(grabber.errors(), 1u);
}

TEST(SequenceSources, PlainFolderTakesTheDepthImagesOnly) {
  TempDir dir("occ_improve_plain");
  for (const char* name : {"1.png", "1_depth.png", "2.png", "2_depth.png", "notes.txt"}) std::ofstream(dir.path / name) << "x";
  const DepthSequence sequence = scan_depth_sequence(dir.path.string());
  ASSERT_EQ(sequence.frames.size(), 2u);
  EXPECT_EQ(fs::path(sequence.frames[0].depth_path).filename(), "1_depth.png");
  EXPECT_EQ(fs::path(sequence.frames[1].depth_path).filename(), "2_depth.png");
  EXPECT_FALSE(sequence.encoding.has_value());  // guessed per file
  EXPECT_FALSE(sequence.intrinsics.has_value());
}

// -depth_dir read PNG/PGM only; PCL's own image-grabber layout is 16-bit TIFF with RGB TIFFs beside it.
TEST(SequenceSources, PclGrabberTiffFolderReplaysItsDepthFrames) {
  OCC_REQUIRE_DATA(folder, "kinect/pcl_test/grabber_sequences/tiff");
  const DepthSequence sequence = scan_depth_sequence(folder);
  ASSERT_EQ(sequence.frames.size(), 3u);
  for (const DepthSequenceFrame& f : sequence.frames)
    EXPECT_NE(fs::path(f.depth_path).filename().string().find("_depth.tiff"), std::string::npos) << f.depth_path;
  PinholeIntrinsics kinect;  // the calibration of the PCLZF copy of these frames: 525, 525, 320, 240
  kinect.fx = kinect.fy = 525;
  kinect.cx = 320;
  kinect.cy = 240;
  DepthSequenceGrabber grabber(sequence, kinect);
  std::vector<std::size_t> valid;
  std::function<void(const FileSequenceGrabber::Cloud::ConstPtr&)> on_frame =
      [&](const FileSequenceGrabber::Cloud::ConstPtr& cloud) {
        valid.push_back(static_cast<std::size_t>(std::count_if(cloud->begin(), cloud->end(),
                                                               [](const pcl::PointXYZ& p) { return p.z > 0; })));
      };
  grabber.registerCallback(on_frame);
  grabber.start();
  grabber.waitUntilDone();
  ASSERT_EQ(valid.size(), 3u);
  EXPECT_EQ(grabber.errors(), 0u);
  for (std::size_t n : valid) EXPECT_GT(n, 200000u);  // 271,575 valid pixels in the first frame
}

TEST(SequenceSources, ErrorsNameTheProblem) {
  EXPECT_THROW(PcdSequenceGrabber("/nonexistent/folder"), IoError);
  TempDir empty("occ_improve_empty");
  EXPECT_THROW(PcdSequenceGrabber(empty.path.string()), InvalidInput);
  EXPECT_THROW(scan_depth_sequence(empty.path.string()), InvalidInput);
  EXPECT_THROW(PcdSequenceGrabber(std::vector<std::string>{"a.pcd"}, -1.0f), InvalidParameter);
  std::ofstream(empty.path / "bad.pose.txt") << "1 0 0\n";
  EXPECT_THROW(read_pose_matrix_file((empty.path / "bad.pose.txt").string()), FormatError);
  // Each entry is named as what it is: a NaN (a failed pose estimate) as non-finite, a word as not a number.
  const auto message = [&](const std::string& text) {
    std::ofstream(empty.path / "pose.txt") << text;
    try {
      read_pose_matrix_file((empty.path / "pose.txt").string());
    } catch (const FormatError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("1 0 0 0\nnan 1 0 0\n0 0 1 0\n0 0 0 1\n").find("non-finite value at row 2, column 1 ('nan')"),
            std::string::npos);
  EXPECT_NE(message("1 0 0 0\n0 1 0 x\n0 0 1 0\n0 0 0 1\n").find("holds 'x' at row 2, column 4: not a number"),
            std::string::npos);
  EXPECT_NE(message("1 0 0 0\n0 1 0 0\n").find("does not hold a 4x4 matrix (it holds 8 values)"), std::string::npos);
  EXPECT_NE(message("1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n5\n").find("(it holds 17 values)"), std::string::npos);
  EXPECT_EQ(message("1 0 0 0.5\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"), "accepted");
}

}  // namespace
}  // namespace occ_improve

namespace occ_improve {
namespace {

template <typename PointT>
class GrabberPipelineTyped : public ::testing::Test {};
using PointTypes = ::testing::Types<pcl::PointXYZ, pcl::PointXYZI, pcl::PointXYZRGB, pcl::PointXYZRGBA, pcl::PointXYZL>;
TYPED_TEST_SUITE(GrabberPipelineTyped, PointTypes);

TYPED_TEST(GrabberPipelineTyped, EveryInstantiatedTypeIsMapped) {
  typename pcl::PointCloud<TypeParam>::Ptr cloud(new pcl::PointCloud<TypeParam>);
  pcl::copyPointCloud(*tiny_frame(), *cloud);
  PipelineOptions options;
  options.backpressure = true;
  GrabberPipeline<TypeParam> pipeline(tiny_preset(), {}, options);
  pipeline.start();
  pipeline.pushFrame(cloud);
  pipeline.pushFrame(cloud);
  pipeline.stop();
  EXPECT_EQ(pipeline.statistics().processed, 2u);
  // The same map as the PointXYZ frame gives: the stride of each type is handled.
  Mapper direct(tiny_preset());
  direct.insert(span_of(*tiny_frame()));
  direct.insert(span_of(*tiny_frame()));
  EXPECT_EQ(pipeline.mapper().improvement().value, direct.improvement().value);
}

}  // namespace
}  // namespace occ_improve
