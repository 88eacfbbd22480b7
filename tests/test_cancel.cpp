// Cancellation (cancel.hpp): a stop request makes every long loop of the library throw Cancelled
// promptly, from the calling thread and from worker threads alike.
#include "occ_improve/cancel.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/maps/surface.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <string>
#include <thread>

namespace occ_improve {
namespace {

// Every test starts and ends without a pending request (the flag is process-wide).
class Cancel : public ::testing::Test {
protected:
  void SetUp() override { clear_stop_request(); }
  void TearDown() override { clear_stop_request(); }
};

TEST_F(Cancel, RequestKeepsTheFirstReasonUntilCleared) {
  EXPECT_EQ(stop_requested(), 0);
  EXPECT_NO_THROW(throw_if_stop_requested());
  request_stop(SIGTERM);
  request_stop(SIGINT);
  EXPECT_EQ(stop_requested(), SIGTERM);
  try {
    throw_if_stop_requested();
    FAIL() << "no throw";
  } catch (const Cancelled& e) {
    EXPECT_EQ(e.reason(), SIGTERM);
    EXPECT_STREQ(e.what(), "interrupted by SIGTERM");
  }
  clear_stop_request();
  EXPECT_EQ(stop_requested(), 0);
}

// Each long computation, called with a request pending, throws Cancelled instead of running to its end;
// after the request is withdrawn the same calls succeed.
TEST_F(Cancel, EveryLongComputationStopsOnARequest) {
  const sample::SampleFrame frame = sample::generate_scene();
  const std::vector<Eigen::Vector3f> points = frame.points();
  Mapper mapper(kinect_v1(frame.intrinsics));
  mapper.insert(PointSpan::from(points));
  const ColumnGrid& grid = mapper.grid();
  request_stop(SIGINT);
  EXPECT_THROW(compute_surface(grid), Cancelled);
  EXPECT_THROW(compute_improvement(mapper.geometry(), mapper.model(), mapper.surface()), Cancelled);
  EXPECT_THROW(predict_depth(mapper.surface()), Cancelled);
  ColumnGrid fresh(mapper.geometry());
  EXPECT_THROW(insert_points(fresh, mapper.model(), PointSpan::from(points)), Cancelled);
  EXPECT_THROW(Mapper(ColumnGrid(mapper.geometry()), mapper.model()), Cancelled);
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("occ_cancel_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + ".occmap"))
                               .string();
  EXPECT_THROW(save_map(path, grid, mapper.model().params()), Cancelled);  // and leaves nothing
  EXPECT_FALSE(std::filesystem::exists(path));
  clear_stop_request();
  save_map(path, grid, mapper.model().params());
  request_stop(SIGINT);
  EXPECT_THROW(load_map(path), Cancelled);
  clear_stop_request();
  EXPECT_EQ(load_map(path).grid.touched_column_count(), grid.touched_column_count());
  std::filesystem::remove(path);
  EXPECT_EQ(compute_surface(grid).depth_m, mapper.surface().depth_m);
}

// A request from another thread (as from a signal handler) stops a long call within milliseconds: the
// improvement map with the widest window the sigma bounds allow (k sigma = 7.8 bins), in a loop.
TEST_F(Cancel, ARequestDuringALongCallStopsItPromptly) {
  SensorPreset preset = kinect_v1_paper();  // bins of 1.55 mrad
  preset.model.support_k = 3.9;
  preset.model.sigma_azimuth_rad = preset.model.sigma_elevation_rad = 3.1e-3;  // 2 bins
  const Mapper mapper(preset);
  std::chrono::steady_clock::time_point requested;
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    requested = std::chrono::steady_clock::now();
    request_stop(SIGINT);
  });
  try {
    for (int i = 0; i < 1000; ++i) compute_improvement(mapper.geometry(), mapper.model(), mapper.surface());
    stopper.join();
    FAIL() << "1000 improvement maps finished before the request";
  } catch (const Cancelled& e) {
    const auto stopped = std::chrono::steady_clock::now();
    stopper.join();  // before reading `requested`: the join orders the stopper's write before this read
    const double seconds = std::chrono::duration<double>(stopped - requested).count();
    EXPECT_EQ(e.reason(), SIGINT);
    EXPECT_LT(seconds, 1.0) << "the request was obeyed after " << seconds << " s";
  }
}

}  // namespace
}  // namespace occ_improve
