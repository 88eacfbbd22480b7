// The planner: shapes, ties, the return-model discount, re-acquisition, the stop signal, bad requests.
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/planning/good_rays.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/sim/virtual_sensor.hpp"
#include "support/small_camera.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <set>
#include <string>

namespace occ_improve {
namespace {

ImprovementMap flat_map(int w, int h, float value) {
  return {w, h, std::vector<float>(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), value)};
}

ColumnIndex at(const ImprovementMap& m, int x, int y) { return static_cast<ColumnIndex>(y * m.width + x); }

TEST(Planner, RaysAreTakenHighestFirst) {
  ImprovementMap m = flat_map(20, 10, 0.1f);
  m.value[at(m, 3, 4)] = 0.5f;
  m.value[at(m, 7, 1)] = 0.3f;
  m.value[at(m, 0, 0)] = -0.2f;
  PlanRequest r;
  r.budget_rays = 2;
  const Shot s = plan_next_shot(m, ReturnRecord::for_grid(20, 10), r);
  ASSERT_EQ(s.columns.size(), 2u);
  EXPECT_EQ(s.columns[0], at(m, 3, 4));
  EXPECT_EQ(s.columns[1], at(m, 7, 1));
  EXPECT_NEAR(s.expected_gain, 0.8, 1e-6);
  EXPECT_EQ(s.ranked_rays, 2u);
}

TEST(Planner, TiesAreSpreadOverTheViewNotTakenRowByRow) {
  const ImprovementMap m = flat_map(64, 48, 0.324f);
  PlanRequest r;
  r.budget_rays = 64 * 48 / 10;
  const Shot s = plan_next_shot(m, ReturnRecord::for_grid(64, 48), r);
  ASSERT_EQ(s.columns.size(), static_cast<std::size_t>(r.budget_rays));
  EXPECT_EQ(std::set<ColumnIndex>(s.columns.begin(), s.columns.end()).size(), s.columns.size());
  int top_half = 0;  // evenly spread: about half of them in the upper half of the view
  for (ColumnIndex c : s.columns) top_half += c < 64 * 24 ? 1 : 0;
  EXPECT_NEAR(top_half, r.budget_rays / 2, r.budget_rays / 8);
  EXPECT_EQ(plan_next_shot(m, ReturnRecord::for_grid(64, 48), r).columns, s.columns);  // deterministic
}

TEST(Planner, SilentRaysFallBehindWithTheReturnModel) {
  const ImprovementMap m = flat_map(16, 16, 0.15f);  // a ray seen once (below, the rays whose returns did not settle them)
  ReturnRecord record = ReturnRecord::for_grid(16, 16);
  // Every ray asked once; those of the left half never returned.
  std::vector<ColumnIndex> all;
  std::vector<std::uint8_t> got;
  for (ColumnIndex c = 0; c < 256; ++c) {
    all.push_back(c);
    got.push_back(c % 16 >= 8 ? 1 : 0);
  }
  record.record_shot(all, got);
  PlanRequest r;
  r.budget_rays = 100;
  const Shot s = plan_next_shot(m, record, r);
  for (ColumnIndex c : s.columns) EXPECT_GE(c % 16, 8u) << "column " << c << " never returned";
  EXPECT_NEAR(s.expected_gain, 100 * 0.15, 1e-4);  // the rays taken all returned: p = 1
  // A silent ray in a silent neighbourhood: m = 1 / 9, p = 2 m / 3 (return_model.hpp).
  EXPECT_NEAR(shot_scores(m, record)[5 * 16 + 3], 0.15 * 2.0 / 27.0, 1e-6);
}

// A ray whose returns left its improvement near the no-data level (a depth edge's foreground ray, whose
// peak its neighbours' free space carves away; a return beyond the grid's range) is discounted by
// s / (s + R) from its second return on, as silences are: without it, every shot re-asked such rays
// (capture0004: 37 rays 24 times each). A ray that settled keeps its score, and so does one seen once.
TEST(Planner, RaysWhoseReturnsDoNotSettleThemFallBehind) {
  ImprovementMap m = flat_map(16, 16, 0.3f);  // unknown: every ray at the no-data level
  ReturnRecord record = ReturnRecord::for_grid(16, 16);
  const std::vector<ColumnIndex> edge{17, 18, 19};  // asked and returned 1, 2 and 5 times, still unsettled
  for (int shot = 0; shot < 5; ++shot)
    for (std::size_t i = 0; i < edge.size(); ++i)
      if (shot < static_cast<int>(std::vector<int>{1, 2, 5}[i])) record.record_shot({edge[i]}, {1});
  m.value[40] = 0.15f;  // a ray that settled after one return
  record.record_shot({40}, {1});
  const std::vector<float> score = shot_scores(m, record);
  EXPECT_NEAR(score[17], 0.3, 1e-6);  // one return: the benefit of the doubt (a LiDAR ray seen once is ~0.19)
  EXPECT_NEAR(score[18], 0.3 * 2.0 / 4.0, 1e-6);
  EXPECT_NEAR(score[19], 0.3 * 2.0 / 7.0, 1e-6);
  EXPECT_NEAR(score[40], 0.15, 1e-6);
  EXPECT_NEAR(score[100], 0.3, 1e-6);  // never asked, in a neighbourhood that returns
  PlanRequest r;
  r.budget_rays = 256 - 4;
  const Shot s = plan_next_shot(m, record, r);
  for (ColumnIndex c : {18u, 19u}) EXPECT_EQ(std::count(s.columns.begin(), s.columns.end(), c), 0) << "column " << c;
}

TEST(Planner, NegativeShareReacquiresTransitions) {
  ImprovementMap m = flat_map(20, 10, 0.2f);
  m.value[at(m, 5, 5)] = -0.4f;
  m.value[at(m, 6, 5)] = -0.3f;
  m.value[at(m, 1, 1)] = -0.1f;
  PlanRequest r;
  r.budget_rays = 20;
  r.negative_share = 0.1;
  const Shot s = plan_next_shot(m, ReturnRecord::for_grid(20, 10), r);
  ASSERT_EQ(s.columns.size(), 20u);
  EXPECT_EQ(s.ranked_rays, 18u);
  EXPECT_EQ(s.columns[18], at(m, 5, 5));
  EXPECT_EQ(s.columns[19], at(m, 6, 5));
  EXPECT_NEAR(s.expected_gain, 18 * 0.2, 1e-5);
}

TEST(Planner, WindowIsTheRectangleOfLargestSum) {
  ImprovementMap m = flat_map(30, 20, 0.01f);
  for (int y = 12; y < 16; ++y)
    for (int x = 20; x < 25; ++x) m.value[at(m, x, y)] = 0.3f;
  PlanRequest r;
  r.shape = ShotShape::window;
  r.window_width_columns = 5;
  r.window_height_columns = 4;
  r.budget_rays = 20;
  const Shot s = plan_next_shot(m, ReturnRecord::for_grid(30, 20), r);
  ASSERT_EQ(s.columns.size(), 20u);
  EXPECT_EQ(s.columns.front(), at(m, 20, 12));
  EXPECT_EQ(s.columns.back(), at(m, 24, 15));
  EXPECT_NEAR(s.expected_gain, 20 * 0.3, 1e-5);
}

TEST(Planner, DecimationFitsTheBudgetAtTheBestOffset) {
  EXPECT_EQ(decimation_step(640, 480, 3072), 10);
  EXPECT_EQ(decimation_step(640, 480, 15360), 5);
  EXPECT_EQ(decimation_step(640, 480, 640 * 480), 1);
  ImprovementMap m = flat_map(12, 9, 0.1f);
  for (int y = 1; y < 9; y += 3)
    for (int x = 2; x < 12; x += 3) m.value[at(m, x, y)] = 0.3f;
  PlanRequest r;
  r.shape = ShotShape::decimation;
  r.budget_rays = 12;
  const Shot s = plan_next_shot(m, ReturnRecord::for_grid(12, 9), r);
  EXPECT_EQ(s.columns, decimation_pattern(12, 9, 3, 2, 1));
  EXPECT_EQ(s.columns.size(), 12u);
}

// The smallest step within the budget, checked against the straightforward search; sizes that give no
// grid, or columns beyond a 32-bit index, are InvalidParameter (they overflowed or gave 1 ray).
TEST(Planner, DecimationStepIsTheSmallestWithinTheBudgetAndSizesAreChecked) {
  for (const auto& [w, h] : {std::pair{640, 480}, {1, 1}, {7, 1000}, {1280, 720}})
    for (const int budget : {1, 2, 5, 99, 3072, 640 * 480}) {
      int step = 1;
      while (static_cast<long long>((w + step - 1) / step) * ((h + step - 1) / step) > budget) ++step;
      EXPECT_EQ(decimation_step(w, h, budget), step) << w << " x " << h << ", budget " << budget;
    }
  EXPECT_EQ(decimation_step(2147483647, 2, 1), 2147483647);
  for (const auto& [w, h] : {std::pair{-640, 480}, {640, 0}, {131072, 65536}, {2147483647, 2147483647}}) {
    EXPECT_THROW(decimation_step(w, h, 100), InvalidParameter) << w << " x " << h;
    EXPECT_THROW(decimation_pattern(w, h, 64, 0, 0), InvalidParameter) << w << " x " << h;
  }
}

TEST(Planner, StopsWhenTheBestRaysAreWorthLittle) {
  PlanRequest r;
  r.budget_rays = 10;
  EXPECT_FALSE(plan_next_shot(flat_map(8, 8, 0.324f), ReturnRecord::for_grid(8, 8), r).stop);  // no data
  EXPECT_FALSE(plan_next_shot(flat_map(8, 8, 0.138f), ReturnRecord::for_grid(8, 8), r).stop);  // seen once
  const Shot s = plan_next_shot(flat_map(8, 8, 0.05f), ReturnRecord::for_grid(8, 8), r);
  EXPECT_TRUE(s.stop);
  EXPECT_NE(s.reason.find("below"), std::string::npos);
}

TEST(Planner, CandidateMaskRestrictsTheRays) {
  const ImprovementMap m = flat_map(8, 8, 0.3f);
  PlanRequest r;
  r.budget_rays = 10;
  r.candidates.assign(64, 0);
  r.candidates[5] = r.candidates[9] = 1;
  const Shot s = plan_next_shot(m, ReturnRecord::for_grid(8, 8), r);
  EXPECT_EQ(std::set<ColumnIndex>(s.columns.begin(), s.columns.end()), (std::set<ColumnIndex>{5, 9}));
}

// Every shape keeps to the mask (a held-out trial: a window over a 10 x 10 valid patch took 4036 masked
// rays, rank 1 among them): a window or pattern is chosen by its candidates' scores and leaves the others
// out; a mask that leaves no ray stops the plan saying so.
TEST(Planner, WindowAndDecimationShotsKeepToTheMask) {
  ImprovementMap m = flat_map(8, 8, 0.1f);
  m.value[at(m, 6, 6)] = 5.0f;  // outside the mask: worth most, never taken
  PlanRequest r;
  r.budget_rays = 16;
  r.candidates.assign(64, 0);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) r.candidates[at(m, x, y)] = 1;
  for (const ShotShape shape : {ShotShape::window, ShotShape::decimation}) {
    r.shape = shape;
    r.window_width_columns = r.window_height_columns = 4;
    const Shot s = plan_next_shot(m, ReturnRecord::for_grid(8, 8), r);
    ASSERT_FALSE(s.columns.empty());
    for (const ColumnIndex c : s.columns) EXPECT_EQ(r.candidates[c], 1) << "column " << c;
    EXPECT_EQ(s.ranked_rays, s.columns.size());
    EXPECT_NEAR(s.expected_gain, 0.1 * static_cast<double>(s.columns.size()), 1e-5);
  }
  r.candidates.assign(64, 0);
  for (const ShotShape shape : {ShotShape::rays, ShotShape::window, ShotShape::decimation}) {
    r.shape = shape;
    const Shot none = plan_next_shot(m, ReturnRecord::for_grid(8, 8), r);
    EXPECT_TRUE(none.columns.empty());
    EXPECT_TRUE(none.stop);
    EXPECT_EQ(none.reason, "no candidate ray: the candidate mask leaves none");
  }
}

TEST(Planner, BadRequestsThrowNamingTheValue) {
  const ImprovementMap m = flat_map(8, 8, 0.3f);
  const ReturnRecord rec = ReturnRecord::for_grid(8, 8);
  const auto message = [&](PlanRequest r) {
    try {
      plan_next_shot(m, rec, r);
    } catch (const InvalidParameter& e) {
      return std::string(e.what());
    }
    return std::string("no throw");
  };
  PlanRequest r;
  r.budget_rays = 0;
  EXPECT_NE(message(r).find("budget_rays = 0"), std::string::npos);
  r.budget_rays = 65;
  EXPECT_NE(message(r).find("budget_rays = 65"), std::string::npos);
  r.budget_rays = 2147483647;  // a whole number as written (it read 2.14748e+09)
  EXPECT_NE(message(r).find("budget_rays = 2147483647 is invalid"), std::string::npos) << message(r);
  r.budget_rays = 10;
  r.negative_share = 1.0;
  EXPECT_NE(message(r).find("negative_share = 1"), std::string::npos);
  r.negative_share = 0;
  r.shape = ShotShape::window;
  r.window_width_columns = 9;
  EXPECT_NE(message(r).find("window_width_columns = 9"), std::string::npos);
  r.window_width_columns = 4;
  r.window_height_columns = 4;
  EXPECT_NE(message(r).find("<= budget_rays"), std::string::npos);
  PlanRequest masked;
  masked.budget_rays = 4;
  masked.candidates.assign(63, 1);
  EXPECT_THROW(plan_next_shot(m, rec, masked), InvalidInput);
  PlanRequest ok;
  ok.budget_rays = 4;
  EXPECT_THROW(plan_next_shot(m, ReturnRecord::for_grid(8, 7), ok), InvalidInput);
}

// On a real map of the sample scene (kinect_v1, one frame): the first plan takes no-data rays only.
TEST(Planner, FirstPlanOnTheSampleTakesRaysWithoutData) {
  Mapper mapper(kinect_v1());
  const auto points = sample::generate_scene().points();
  mapper.insert(PointSpan::from(points));
  PlanRequest r;
  r.budget_rays = 2000;
  const Shot s = plan_next_shot(mapper.improvement(), ReturnRecord::for_grid(mapper.geometry().width(), mapper.geometry().height()), r);
  ASSERT_EQ(s.columns.size(), 2000u);
  std::size_t unknown = 0;
  for (ColumnIndex c : s.columns) unknown += mapper.surface().unknown[c];
  EXPECT_GT(unknown, 1900u);
  EXPECT_FALSE(s.stop);
}

// The loop on the sample (kinect_v1, virtual sensor): without the return model the plan keeps
// asking for the rays that never return (they keep the no-data improvement); with it they fall behind.
// Returns the share of silent rays among the rays asked by shots 50-59 of 3072 rays.
double silent_share_late(bool return_model) {
  sample::SceneOptions clean;
  clean.noise = clean.quantise = false;
  const sample::SampleFrame scene = sample::generate_scene(clean);
  VirtualSensor sensor(scene.depth_m, scene.intrinsics);
  Mapper mapper(kinect_v1(scene.intrinsics));
  ReturnRecord record = ReturnRecord::for_grid(mapper.geometry().width(), mapper.geometry().height());
  PlanRequest request;
  request.budget_rays = 3072;
  std::size_t asked = 0, silent = 0;
  for (int shot = 0; shot < 60; ++shot) {
    const Shot plan = plan_next_shot(mapper.improvement(), record, request);
    const std::vector<float> depth = sensor.shoot(plan.columns);  // pixel-native: column = pixel
    mapper.insert(PointSpan::from(sensor.points(plan.columns, depth)));
    const std::vector<std::uint8_t> got = VirtualSensor::returned(depth);
    if (return_model) record.record_shot(plan.columns, got);
    if (shot < 50) continue;
    asked += got.size();
    silent += static_cast<std::size_t>(std::count(got.begin(), got.end(), 0));
  }
  return static_cast<double>(silent) / static_cast<double>(asked);
}

TEST(Planner, ClosedLoopWithTheReturnModelStopsAskingSilentRays) {
  const double without = silent_share_late(false), with = silent_share_late(true);
  std::printf("silent share of shots 50-59: %.3f without, %.3f with the return model\n", without, with);
  EXPECT_GT(without, 0.5) << "the sample's silent rays (poster, shadows: 3.7 %) should fill the plain plan";
  EXPECT_LT(with, 0.1);
}

// Strategy (g), coarse_to_fine, on a camera of 64 x 48 columns.
using test::small_camera;

PlanRequest coarse_to_fine(int budget, RefineBy by = RefineBy::both) {
  PlanRequest r;
  r.shape = ShotShape::coarse_to_fine;
  r.budget_rays = budget;
  r.refine_by = by;
  return r;
}

TEST(CoarseToFine, CoveragePassPutsOneRayInEveryBlockFirst) {
  const Mapper mapper(kinect_v1(small_camera()));
  const ReturnRecord none = ReturnRecord::for_grid(64, 48);
  const Shot s = plan_next_shot(mapper, none, coarse_to_fine(12));  // 4 x 3 blocks of 16
  ASSERT_EQ(s.columns.size(), 12u);
  std::set<int> blocks;
  std::set<int> offsets;  // jitter: not the same position in every block
  for (ColumnIndex c : s.columns) {
    const int u = static_cast<int>(c % 64), v = static_cast<int>(c / 64);
    blocks.insert((v / 16) * 4 + u / 16);
    offsets.insert((v % 16) * 16 + u % 16);
  }
  EXPECT_EQ(blocks.size(), 12u);
  EXPECT_GT(offsets.size(), 6u);
  EXPECT_NEAR(s.expected_gain, 12 * 0.324, 0.05);
  EXPECT_EQ(plan_next_shot(mapper, none, coarse_to_fine(12)).columns, s.columns);  // deterministic
}

// Every 4th column and row of the 64 x 48 camera (columns 1, 5, ..., 61).
std::vector<std::uint32_t> every_fourth_ray() {
  std::vector<std::uint32_t> rays;
  for (std::uint32_t v = 1; v < 48; v += 4)
    for (std::uint32_t u = 1; u < 64; u += 4) rays.push_back(v * 64 + u);
  return rays;
}

// A slanted wall (depth grows to the right: the nearest rule's constant model leaves a residual
// everywhere) seen at every 4th column and row, so every block of 16 holds samples and the whole shot is
// refinement. At most one ray per block of the refinement level, whatever the driver: 300 rays need
// 4 x 300 blocks, more than the 768 blocks of 2, so blocks of 2.
Mapper slanted_wall_seen_sparsely() {
  std::vector<float> depth(64 * 48);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) depth[static_cast<std::size_t>(v * 64 + u)] = 1.5f + 0.02f * static_cast<float>(u);
  VirtualSensorParams clean;
  clean.sigma_depth_per_m2 = 0;
  clean.disparity_step_px = 0;
  VirtualSensor sensor(depth, small_camera(), clean);
  Mapper mapper(kinect_v1(small_camera()));
  const std::vector<std::uint32_t> grid = every_fourth_ray();
  mapper.insert(PointSpan::from(sensor.points(grid, sensor.shoot(grid))));
  return mapper;
}

TEST(CoarseToFine, AtMostOneRayPerBlockPerShot) {
  const Mapper mapper = slanted_wall_seen_sparsely();
  const ReturnRecord none = ReturnRecord::for_grid(64, 48);
  for (RefineBy by : {RefineBy::improvement, RefineBy::residual, RefineBy::both}) {
    const Shot s = plan_next_shot(mapper, none, coarse_to_fine(300, by));
    EXPECT_GT(s.columns.size(), 200u);
    EXPECT_LE(s.columns.size(), 300u);
    std::map<int, int> per_block;
    for (ColumnIndex c : s.columns) {
      const int u = static_cast<int>(c % 64), v = static_cast<int>(c / 64);
      ++per_block[(v / 2) * 32 + u / 2];
    }
    for (const auto& [block, rays] : per_block) EXPECT_EQ(rays, 1) << "block " << block;
    int top_half = 0;  // spread over the view, not taken row by row
    for (ColumnIndex c : s.columns) top_half += c < 64 * 24 ? 1 : 0;
    EXPECT_NEAR(top_half, static_cast<double>(s.columns.size()) / 2, s.columns.size() / 6.0);
    EXPECT_EQ(plan_next_shot(mapper, none, coarse_to_fine(300, by)).columns, s.columns);  // deterministic
  }
}

// With a candidate mask the refinement level counts the blocks that hold a candidate, not the view's (a
// tester's 32 x 32 mask on a 640 x 480 view: 9-64 of its 1024 rays, one per block of 16, 8 or 4 it
// overlapped). An empty map, an 8 x 8 mask, 10 rays: the coverage ray (its block of 16 holds no sample),
// then 9 refinement rays, which need 36 blocks: the mask holds 1 block of 8, 4 of 4 and 16 of 2, so blocks
// of 2. Counted over the view (48 blocks of 8) it took blocks of 8, whose one with candidates holds the
// coverage ray: a shot of 1 ray, with 63 candidates at the no-data score left.
TEST(CoarseToFine, WithACandidateMaskTheLevelCountsBlocksHoldingACandidate) {
  const Mapper mapper(kinect_v1(small_camera()));
  const ReturnRecord none = ReturnRecord::for_grid(64, 48);
  PlanRequest r = coarse_to_fine(10, RefineBy::improvement);
  r.candidates.assign(64 * 48, 0);
  for (int v = 16; v < 24; ++v)
    for (int u = 16; u < 24; ++u) r.candidates[static_cast<std::size_t>(v * 64 + u)] = 1;
  const Shot s = plan_next_shot(mapper, none, r);
  ASSERT_EQ(s.columns.size(), 10u);
  EXPECT_FALSE(s.stop);
  std::set<int> blocks;
  for (ColumnIndex c : s.columns) {
    EXPECT_EQ(r.candidates[c], 1) << "column " << c;
    const int u = static_cast<int>(c % 64), v = static_cast<int>(c / 64);
    blocks.insert((v / 2) * 32 + u / 2);
  }
  EXPECT_EQ(blocks.size(), 10u);  // one ray per block of 2
  EXPECT_NEAR(s.expected_gain, 10 * 0.324, 0.05);
  EXPECT_EQ(plan_next_shot(mapper, none, r).columns, s.columns);  // deterministic
}

// A wall at 2 m, with a box at 1 m in front of its right part (columns 40-63), seen at every_fourth_ray.
Mapper wall_seen_sparsely(bool with_box) {
  std::vector<float> depth(64 * 48, 2.0f);
  for (int v = 0; v < 48; ++v)
    for (int u = 40; u < 64 && with_box; ++u) depth[static_cast<std::size_t>(v * 64 + u)] = 1.0f;
  VirtualSensorParams clean;
  clean.sigma_depth_per_m2 = 0;
  clean.disparity_step_px = 0;
  VirtualSensor sensor(depth, small_camera(), clean);
  Mapper mapper(kinect_v1(small_camera()));
  const std::vector<std::uint32_t> grid = every_fourth_ray();
  mapper.insert(PointSpan::from(sensor.points(grid, sensor.shoot(grid))));
  return mapper;
}
Mapper wall_and_box_seen_sparsely() { return wall_seen_sparsely(true); }
Mapper flat_wall_seen_sparsely() { return wall_seen_sparsely(false); }

// After a sparse pass over the wall and box, refinement by the residual goes to the box's edge.
TEST(CoarseToFine, RefinementByTheResidualGoesToTheDepthEdge) {
  const Mapper mapper = wall_and_box_seen_sparsely();
  const Shot s = plan_next_shot(mapper, ReturnRecord::for_grid(64, 48), coarse_to_fine(40, RefineBy::residual));
  // Blocks of 4 (192 >= 4 x 40): the 2 x 12 blocks whose 3 x 3 neighbourhood holds the edge (u 36-43), in
  // rank order, and nothing else: the flat rest, whose samples (the measured rays alone: their neighbours,
  // which the OPDFs reach with P just above 0.5, are not samples) lie exactly on the predictor's model, has
  // residual 0, so priority 0, and is not asked (a shot can be smaller than the budget).
  ASSERT_EQ(s.columns.size(), 24u);
  for (std::size_t i = 0; i < 24; ++i) {
    const int u = static_cast<int>(s.columns[i] % 64);
    EXPECT_TRUE(u >= 36 && u < 44) << "ray " << i << " at column " << u;
  }
}

// The same wall and box: refinement by triangles goes to the triangles across the edge (their vertices
// lie far off their neighbours' plane), each ray at a triangle's centroid, not on a sample.
TEST(CoarseToFine, RefinementByTrianglesGoesToTheDepthEdge) {
  const Mapper mapper = wall_and_box_seen_sparsely();
  ReturnRecord record = ReturnRecord::for_grid(64, 48);  // the sparse pass's rays, all returned
  const std::vector<std::uint32_t> seen = every_fourth_ray();
  record.record_shot(seen, std::vector<std::uint8_t>(seen.size(), 1));
  const Shot s = plan_next_shot(mapper, record, coarse_to_fine(40, RefineBy::triangles));
  ASSERT_EQ(s.columns.size(), 40u);
  // The triangles with a vertex on either side of the edge (columns 37 and 41) or next to one (33, 45)
  // have their non-planarity capped; of those, the largest go first.
  for (std::size_t i = 0; i < 20; ++i) {
    const int u = static_cast<int>(s.columns[i] % 64), v = static_cast<int>(s.columns[i] / 64);
    EXPECT_TRUE(u > 33 && u < 45) << "ray " << i << " at column " << u;
    EXPECT_FALSE(u % 4 == 1 && v % 4 == 1) << "ray " << i << " on a sample";
  }
  EXPECT_EQ(plan_next_shot(mapper, record, coarse_to_fine(40, RefineBy::triangles)).columns, s.columns);  // deterministic
  // The triangles are the surface's: the overload without the mapper cannot refine by them.
  EXPECT_THROW(plan_next_shot(mapper.improvement(), mapper.pyramid(), mapper.model(), record,
                              coarse_to_fine(40, RefineBy::triangles)),
               InvalidParameter);
}

// Refinement by triangles stops on the mean score of the view's best fifth of rays (stop_view_share), not
// on the shot's rays: a map's state, not a shot's size, decides (planner.hpp); nor on its centroids' own
// scores (low by construction: their neighbours' OPDFs reach them).
TEST(CoarseToFine, TrianglesStopReadsTheViewsBestShare) {
  const Mapper mapper = wall_and_box_seen_sparsely();
  ReturnRecord record = ReturnRecord::for_grid(64, 48);
  const std::vector<std::uint32_t> seen = every_fourth_ray();
  record.record_shot(seen, std::vector<std::uint8_t>(seen.size(), 1));
  std::vector<float> scores;  // recomputed here: improvement x return probability, observable rays
  for (float v : shot_scores(mapper.improvement(), record))
    if (!std::isnan(v)) scores.push_back(v);
  std::sort(scores.begin(), scores.end(), std::greater<>());
  const auto mean_of_best = [&](double share) {
    const auto k = static_cast<std::size_t>(std::ceil(share * static_cast<double>(scores.size())));
    double sum = 0;
    for (std::size_t i = 0; i < k; ++i) sum += scores[i];
    return sum / static_cast<double>(k);
  };
  for (int budget : {10, 40, 300}) {  // whatever the shot's size
    PlanRequest request = coarse_to_fine(budget, RefineBy::triangles);
    const Shot s = plan_next_shot(mapper, record, request);
    EXPECT_NEAR(s.stop_gain_per_ray, mean_of_best(0.2), 1e-6) << budget;
    EXPECT_EQ(s.stop, s.stop_gain_per_ray < 0.1);
    request.stop_view_share = 1.0;
    EXPECT_NEAR(plan_next_shot(mapper, record, request).stop_gain_per_ray, mean_of_best(1.0), 1e-6) << budget;
  }
  const Shot s = plan_next_shot(mapper, record, coarse_to_fine(40, RefineBy::triangles));
  double centroids = 0;  // what the centroids themselves score: less
  const std::vector<float> p = return_probability_map(record, PlanRequest{}.return_model);
  for (ColumnIndex c : s.columns) centroids += p[c] * mapper.improvement().value[c];
  EXPECT_LT(centroids / 40, s.stop_gain_per_ray);
  // The rays shape stops on its own rays' gain.
  PlanRequest rays;
  rays.budget_rays = 40;
  const Shot best = plan_next_shot(mapper, record, rays);
  EXPECT_NEAR(best.stop_gain_per_ray, best.expected_gain / 40, 1e-12);
}

// The expected gain of a triangles shot is in rays made good (good_rays.hpp). First shot: nothing is
// predicted anywhere and every coverage block gets rays, so the view's observable rays are expected to
// come within 2 sigma with one return's probability (an empty record: p = 1, block return rate 1).
TEST(CoarseToFine, TrianglesFirstShotExpectsTheViewPredicted) {
  const Mapper mapper(kinect_v1(small_camera()));
  const ReturnRecord none = ReturnRecord::for_grid(64, 48);
  const Shot s = plan_next_shot(mapper, none, coarse_to_fine(256, RefineBy::triangles));
  ASSERT_EQ(s.columns.size(), 256u);
  const auto observable = static_cast<double>(std::count_if(mapper.improvement().value.begin(), mapper.improvement().value.end(),
                                                            [](float v) { return !std::isnan(v); }));
  EXPECT_GT(observable, 3000.0);
  EXPECT_NEAR(s.expected_gain, within_two_sigma(1) * observable, 1e-6 * observable);
}

// Between samples of a flat wall every triangle is planar: no centroid is expected to gain anything (a
// ray between samples that no triangle ranks would even lower the count a little: a plane through them
// predicts better than one return). With the box, the triangles across its edge are off their plane by far more
// than 2 sigma: each centroid is expected to make about its triangle's area good (4 x 4 / 2 = 8 px).
TEST(CoarseToFine, TrianglesExpectRaysAtTheEdgeNotOnAFlatWall) {
  ReturnRecord record = ReturnRecord::for_grid(64, 48);
  const std::vector<std::uint32_t> seen = every_fourth_ray();
  record.record_shot(seen, std::vector<std::uint8_t>(seen.size(), 1));
  const Shot edge = plan_next_shot(wall_and_box_seen_sparsely(), record, coarse_to_fine(20, RefineBy::triangles));
  const Shot flat = plan_next_shot(flat_wall_seen_sparsely(), record, coarse_to_fine(20, RefineBy::triangles));
  ASSERT_EQ(edge.columns.size(), 20u);
  ASSERT_EQ(flat.columns.size(), 20u);
  EXPECT_LE(flat.expected_gain, 1e-6);
  EXPECT_GE(flat.expected_gain, 20 * (within_two_sigma(1) - within_two_sigma(3)) - 1e-9);
  EXPECT_GT(edge.expected_gain, 0.9 * 20 * 8);
  EXPECT_LE(edge.expected_gain, 20 * 8 + 1e-9);
}

TEST(GoodRays, WithinTwoSigmaIsTheFusedGaussiansShare) {
  EXPECT_EQ(within_two_sigma(0), 0.0);
  for (std::uint32_t k = 1; k <= 4; ++k) {  // midpoint rule over N(0, 1 / k) on [-2, 2]
    const double sd = 1.0 / std::sqrt(static_cast<double>(k));
    double share = 0;
    const int steps = 200000;
    for (int i = 0; i < steps; ++i) {
      const double x = -2.0 + 4.0 * (i + 0.5) / steps;
      share += std::exp(-0.5 * x * x / (sd * sd)) / (sd * std::sqrt(2 * M_PI)) * 4.0 / steps;
    }
    EXPECT_NEAR(within_two_sigma(k), share, 1e-8) << k;
  }
  EXPECT_NEAR(within_two_sigma(1), 0.9545, 1e-4);
}

TEST(GoodRays, OffPlaneShareIsTheTailBeyondTwoSigma) {
  EXPECT_EQ(off_plane_share(0), 0.0);
  EXPECT_EQ(off_plane_share(-1), 0.0);
  double previous = 0;
  for (double n : {0.5, 1.0, 2.0, 4.0, 8.0, 100.0}) {  // interior ~ N(0, (n / 2)^2): P(|x| > 2)
    const double sd = n / 2, tail = 1.0 - std::erf(2.0 / (sd * std::sqrt(2.0)));
    EXPECT_NEAR(off_plane_share(n), tail, 1e-12) << n;
    EXPECT_GT(off_plane_share(n), previous);
    previous = off_plane_share(n);
  }
  EXPECT_NEAR(off_plane_share(4), 0.3173, 1e-4);  // n = 4: the interior's sd is 2, its 1-sd tail
  EXPECT_GT(off_plane_share(100), 0.96);
}

// A noise-free wall at 2 m with a box at 1 m (u >= 40), optionally a silent 12 x 12 patch (no return).
VirtualSensor wall_and_box_sensor(bool silent_patch) {
  std::vector<float> depth(64 * 48, 2.0f);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) {
      if (u >= 40) depth[static_cast<std::size_t>(v * 64 + u)] = 1.0f;
      if (silent_patch && u < 12 && v < 12) depth[static_cast<std::size_t>(v * 64 + u)] = 0.0f;
    }
  VirtualSensorParams clean;
  clean.sigma_depth_per_m2 = 0;
  clean.disparity_step_px = 0;
  return VirtualSensor(depth, small_camera(), clean);
}

/// Measures a planned shot: inserts its returns and records which rays returned.
void acquire(VirtualSensor& sensor, const Shot& plan, Mapper& mapper, ReturnRecord& record) {
  const std::vector<float> depth = sensor.shoot(plan.columns);
  mapper.insert(PointSpan::from(sensor.points(plan.columns, depth)));
  record.record_shot(plan.columns, VirtualSensor::returned(depth));
}

// Closed loop over the wall and box with a silent patch: every shot is full and asks only new rays until
// every ray has been asked once (centroids of tiny triangles, which round onto their vertices, give way
// to the unasked rays of highest score), then re-asks rather than stalling.
TEST(CoarseToFine, TrianglesAskEveryRayOnceBeforeAnyTwice) {
  VirtualSensor sensor = wall_and_box_sensor(true);
  Mapper mapper(kinect_v1(small_camera()));
  ReturnRecord record = ReturnRecord::for_grid(64, 48);
  const int budget = 256, shots = 64 * 48 / budget + 2;
  std::vector<int> asked(64 * 48, 0);
  for (int shot = 0; shot < shots; ++shot) {
    const Shot plan = plan_next_shot(mapper, record, coarse_to_fine(budget, RefineBy::triangles));
    ASSERT_EQ(plan.columns.size(), static_cast<std::size_t>(budget)) << "shot " << shot;
    acquire(sensor, plan, mapper, record);
    for (ColumnIndex c : plan.columns) ++asked[c];
    const bool all_asked = std::count(asked.begin(), asked.end(), 0) == 0;
    if (!all_asked) {
      EXPECT_EQ(*std::max_element(asked.begin(), asked.end()), 1) << "a ray asked twice at shot " << shot;
    }
  }
  EXPECT_EQ(std::count(asked.begin(), asked.end(), 0), 0);
}

// A PlanMemory extends the measured samples' triangulation shot by shot (SampleTriangulator) instead of
// triangulating them all again; the triangulation and its residuals do not depend on the order the samples
// came in (sample_triangulation.cpp), so every plan of the closed loop is the plan without memory.
TEST(CoarseToFine, TrianglesWithAPlanMemoryPlanAsWithout) {
  VirtualSensor sensor = wall_and_box_sensor(true);
  Mapper mapper(kinect_v1(small_camera()));
  ReturnRecord record = ReturnRecord::for_grid(64, 48);
  PlanMemory memory;
  const int budget = 128;
  std::size_t shots = 0, started_over = 0, inserting = 0;
  for (; std::count(record.asked().begin(), record.asked().end(), 0) > budget; ++shots) {
    const Shot with = plan_next_shot(mapper, record, coarse_to_fine(budget, RefineBy::triangles), memory);
    const Shot without = plan_next_shot(mapper, record, coarse_to_fine(budget, RefineBy::triangles));
    ASSERT_EQ(with.columns, without.columns) << "shot " << shots;
    EXPECT_EQ(with.expected_gain, without.expected_gain);
    if (memory.triangulation.started_over_last()) {
      ++started_over;
    } else {
      EXPECT_LE(memory.triangulation.inserted_last(), static_cast<std::size_t>(budget)) << "shot " << shots;
      inserting += memory.triangulation.inserted_last() > 0;
    }
    acquire(sensor, with, mapper, record);
  }
  EXPECT_GE(shots, 20u);
  EXPECT_LE(started_over, 2u);  // the first plan with samples, at most one lost sample: the others insert
  EXPECT_GE(inserting + 3, shots);
}

// Once every ray has been asked (and, with every ray returning, every coverage block holds samples), no
// centroid can be taken: the plan skips the triangulation and its shot is the spread best rays by score.
TEST(CoarseToFine, TrianglesOnceEveryRayIsAskedAreTheSpreadBestRays) {
  VirtualSensor sensor = wall_and_box_sensor(false);
  Mapper mapper(kinect_v1(small_camera()));
  ReturnRecord record = ReturnRecord::for_grid(64, 48);
  const int budget = 256;
  for (int shot = 0; shot < 64 * 48 / budget; ++shot)
    acquire(sensor, plan_next_shot(mapper, record, coarse_to_fine(budget, RefineBy::triangles)), mapper, record);
  ASSERT_EQ(std::count(record.asked().begin(), record.asked().end(), 0), 0);
  const Shot plan = plan_next_shot(mapper, record, coarse_to_fine(budget, RefineBy::triangles));
  const std::vector<float> score = shot_scores(mapper.improvement(), record, PlanRequest{}.return_model);
  EXPECT_EQ(plan.columns, spread_best_columns(score, nullptr, 64, static_cast<std::size_t>(budget)));
}

TEST(CoarseToFine, BadRequestsThrowNamingTheValue) {
  const Mapper mapper(kinect_v1(small_camera()));
  const ReturnRecord none = ReturnRecord::for_grid(64, 48);
  PlanRequest r = coarse_to_fine(10);
  EXPECT_THROW(plan_next_shot(mapper.improvement(), none, r), InvalidParameter);  // needs the pyramid
  r.coverage_block_columns = 12;
  try {
    plan_next_shot(mapper, none, r);
    FAIL();
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("12"), std::string::npos) << e.what();
  }
  for (double share : {0.0, -0.1, 1.5, std::nan("")}) {
    r = coarse_to_fine(10, RefineBy::triangles);
    r.stop_view_share = share;
    EXPECT_THROW(plan_next_shot(mapper, none, r), InvalidParameter) << share;
  }
  r = coarse_to_fine(10);
  r.residual_cap_sigmas = 0;
  EXPECT_THROW(plan_next_shot(mapper, none, r), InvalidParameter);
  r = coarse_to_fine(64 * 48 + 1);
  EXPECT_THROW(plan_next_shot(mapper, none, r), InvalidParameter);
  EXPECT_THROW(plan_next_shot(mapper, ReturnRecord::for_grid(32, 48), coarse_to_fine(10)), InvalidInput);
}

}  // namespace
}  // namespace occ_improve
