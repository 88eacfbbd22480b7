// The Mapper facade: insertion + incremental surface + incremental improvement equal full recomputation.
#include "occ_improve/cancel.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <random>

namespace occ_improve {
namespace {

void expect_equal_to_full_recomputation(const Mapper& m) {
  const SurfaceMap surface = compute_surface(m.grid());
  ASSERT_EQ(surface.depth_m, m.surface().depth_m);
  ASSERT_EQ(surface.probability, m.surface().probability);
  const ImprovementMap full = compute_improvement(m.geometry(), m.model(), m.surface());
  ASSERT_EQ(full.value.size(), m.improvement().value.size());
  double max_d = 0;
  for (std::size_t c = 0; c < full.value.size(); ++c)
    max_d = std::max(max_d, static_cast<double>(std::abs(full.value[c] - m.improvement().value[c])));
  EXPECT_LE(max_d, 1e-6);
}

TEST(Mapper, RandomBatchesGiveTheFullRecomputation) {
  Mapper mapper(kinect_v1_paper());
  EXPECT_EQ(mapper.improvement().value.size(), mapper.geometry().column_count());
  // Two noisy frames of the sample, shuffled and cut into many batches of random size.
  std::vector<Eigen::Vector3f> points;
  for (std::uint32_t seed : {1u, 2u}) {
    sample::SceneOptions o;
    o.seed = seed;
    const auto frame = sample::generate_scene(o).points();
    points.insert(points.end(), frame.begin(), frame.end());
  }
  std::mt19937 rng(7);
  std::shuffle(points.begin(), points.end(), rng);
  std::size_t pos = 0, batches = 0, total_recomputed = 0;
  while (pos < points.size()) {
    // Small batches first (few changed columns), then large ones.
    const std::size_t cap = batches < 20 ? 50 : 60000;
    const std::size_t n = std::min(points.size() - pos, 1 + rng() % cap);
    const std::vector<Eigen::Vector3f> batch(points.begin() + static_cast<std::ptrdiff_t>(pos),
                                             points.begin() + static_cast<std::ptrdiff_t>(pos + n));
    const MapperReport r = mapper.insert(PointSpan::from(batch));
    EXPECT_EQ(r.insertion.points_received, n);
    EXPECT_GE(r.rays_recomputed, r.surface_columns_changed);
    total_recomputed += r.rays_recomputed;
    if (batches < 20) {
      EXPECT_LT(r.rays_recomputed, mapper.geometry().column_count() / 10);
    }
    pos += n;
    ++batches;
    if (batches % 10 == 0) expect_equal_to_full_recomputation(mapper);
  }
  EXPECT_GT(batches, 25u);
  EXPECT_GT(total_recomputed, 0u);
  expect_equal_to_full_recomputation(mapper);
}

// A stop during an insertion (Ctrl-C from Python) left the bands already stored in the grid and their
// surface, but not the incremental improvement, and the changed columns were lost: the improvement lagged
// the grid for good. The maps are now recomputed from the grid when next asked.
TEST(Mapper, AnInterruptedInsertionLeavesMapsThatFollowTheGrid) {
  const sample::SampleFrame scene = sample::generate_scene();
  Mapper mapper(kinect_v1(scene.intrinsics));
  const std::vector<Eigen::Vector3f> first = scene.points();
  mapper.insert(PointSpan::from(first));
  std::vector<Eigen::Vector3f> many;  // 8 noisy frames at once: long enough to be stopped part-way
  for (std::uint32_t seed = 2; seed < 10; ++seed) {
    sample::SceneOptions o;
    o.seed = seed;
    const auto frame = sample::generate_scene(o).points();
    many.insert(many.end(), frame.begin(), frame.end());
  }
  std::thread stopper([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    request_stop(2);
  });
  InsertionOptions two;
  two.threads = 2;
  // Python's copy=False views read these buffers in place for the Mapper's life.
  const float* depth_buffer = mapper.surface().depth_m.data();
  const float* improvement_buffer = mapper.improvement().value.data();
  bool cancelled = false;
  try {
    mapper.insert(PointSpan::from(many), two);
  } catch (const Cancelled&) {
    cancelled = true;
  }
  stopper.join();
  clear_stop_request();
  EXPECT_TRUE(cancelled) << "the insertion finished within 250 ms: the stop tested nothing";
  expect_equal_to_full_recomputation(mapper);
  EXPECT_EQ(mapper.surface().depth_m.data(), depth_buffer) << "the recomputed surface moved to another buffer";
  EXPECT_EQ(mapper.improvement().value.data(), improvement_buffer) << "the recomputed improvement moved";
  mapper.insert(PointSpan::from(first));  // and the next insertion carries on from there
  expect_equal_to_full_recomputation(mapper);
}

TEST(Mapper, FromGridComputesSurfaceAndImprovement) {
  const SensorPreset p = kinect_v1_paper();
  ColumnGrid grid{GridGeometry(p.geometry)};
  const SensorModel model(p.model);
  insert_points(grid, model, PointSpan::from(sample::generate_scene().points()));
  const SurfaceMap surface = compute_surface(grid);
  Mapper mapper(std::move(grid), model);
  EXPECT_EQ(mapper.surface().depth_m, surface.depth_m);
  EXPECT_EQ(mapper.improvement().value, compute_improvement(mapper.geometry(), model, surface).value);
  // Nothing pending: inserting nothing recomputes nothing.
  const MapperReport r = mapper.insert(PointSpan{});
  EXPECT_EQ(r.surface_columns_changed, 0u);
  EXPECT_EQ(r.rays_recomputed, 0u);
}

}  // namespace
}  // namespace occ_improve
