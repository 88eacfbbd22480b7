// The PCL-pipeline comparison (filter_eval.hpp) on the first frames of the 7-Scenes sequence: every
// strategy keeps the asked number of points, qualities are shares, and the reference scores 1 against
// itself. The voxel bisection is also checked on a synthetic plane (no data needed).
#include "occ_improve/errors.hpp"
#include "occ_improve/eval/filter_eval.hpp"
#include "support/test_data.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>

namespace occ_improve {
namespace {

constexpr KeepStrategy kStrategies[] = {KeepStrategy::improvement, KeepStrategy::improvement_shuffled,
                                        KeepStrategy::random_sample, KeepStrategy::voxel_grid};

struct Sequence {
  DepthSequence sequence;
  SensorPreset preset;
  Frames frames;
  std::unique_ptr<Mapper> reference;
};

Sequence first_frames(const std::string& folder, std::size_t count) {
  Sequence s{scan_depth_sequence(folder), {}, {}, nullptr};
  s.preset = kinect_v1(*s.sequence.intrinsics);
  s.frames = read_posed_frames(s.sequence, *s.sequence.intrinsics, Mapper(s.preset).geometry(), count);
  s.reference = std::make_unique<Mapper>(map_of_all_points(s.frames, s.preset));
  return s;
}

TEST(FilterEval, EveryStrategyKeepsTheAskedCountAndQualitiesAreShares) {
  OCC_REQUIRE_DATA(folder, "sequences/7scenes_redkitchen/frames");
  const Sequence s = first_frames(folder, 3);
  ASSERT_EQ(s.frames.size(), 3u);
  for (double fraction : {0.05, 0.2})
    for (KeepStrategy strategy : kStrategies) {
      SCOPED_TRACE(std::string(keep_strategy_name(strategy)) + " " + std::to_string(fraction));
      const std::vector<FilterStep> steps = run_keep_strategy(strategy, fraction, s.frames, s.preset, *s.reference);
      ASSERT_EQ(steps.size(), 3u);
      std::size_t points = 0;
      for (const FilterStep& step : steps) {
        EXPECT_NEAR(static_cast<double>(step.asked), fraction * static_cast<double>(s.frames[step.frame]->size()), 0.5);
        EXPECT_LE(std::abs(static_cast<double>(step.kept) - static_cast<double>(step.asked)), 0.05 * step.asked);
        EXPECT_EQ(step.points, points += step.kept);
        EXPECT_GT(step.columns, 0u);
        EXPECT_LE(step.columns, step.kept);
        EXPECT_GT(step.quality, 0.0);
        EXPECT_LE(step.quality, 1.0);
      }
      EXPECT_LT(steps.back().quality, 1.0);  // a fifth of the points does not rebuild the map from all
    }
}

// Issue 20's question on the real sequence, shortened to 10 frames: keeping 5 % of each frame by the map
// (a cell's sample measured again before a ray beside it, filter header) ends closer to the map of all
// points than PCL's filters keeping as many (make filter-eval runs the 50 frames at 5 and 20 %).
TEST(FilterEval, KeepingByTheMapBeatsPclFiltersOverTenFrames) {
  OCC_REQUIRE_DATA(folder, "sequences/7scenes_redkitchen/frames");
  const Sequence s = first_frames(folder, 10);
  ASSERT_EQ(s.frames.size(), 10u);
  const auto final_quality = [&](KeepStrategy strategy) {
    return run_keep_strategy(strategy, 0.05, s.frames, s.preset, *s.reference).back().quality;
  };
  const double ours = final_quality(KeepStrategy::improvement);
  const double random = final_quality(KeepStrategy::random_sample), voxel = final_quality(KeepStrategy::voxel_grid);
  EXPECT_GT(ours, random + 0.02);
  EXPECT_GT(ours, voxel + 0.02);
}

TEST(FilterEval, TheMapFromAllPointsScoresOneAgainstItself) {
  OCC_REQUIRE_DATA(folder, "sequences/7scenes_redkitchen/frames");
  const Sequence s = first_frames(folder, 2);
  EXPECT_DOUBLE_EQ(quality_against(*s.reference, *s.reference, 16), 1.0);
  // Keeping every point is the reference again, whatever strategy keeps it.
  const std::vector<FilterStep> all = run_keep_strategy(KeepStrategy::improvement, 1.0, s.frames, s.preset, *s.reference);
  EXPECT_DOUBLE_EQ(all.back().quality, 1.0);
  // Frame 1 alone is not the map from both frames.
  const Frames second_only{s.frames[1]};
  EXPECT_LT(quality_against(map_of_all_points(second_only, s.preset), *s.reference, 16), 1.0);
}

TEST(FilterEval, RefusesUnposedSequencesAndBadFractions) {
  OCC_REQUIRE_DATA(folder, "sequences/7scenes_redkitchen/frames");
  DepthSequence sequence = scan_depth_sequence(folder);
  sequence.frames.resize(2);
  const SensorPreset preset = kinect_v1(*sequence.intrinsics);
  const Mapper empty(preset);
  sequence.frames[1].camera_to_world.reset();
  EXPECT_THROW(read_posed_frames(sequence, *sequence.intrinsics, empty.geometry(), 0), InvalidInput);
  EXPECT_THROW(run_keep_strategy(KeepStrategy::random_sample, 0.0, {}, preset, empty), InvalidParameter);
  EXPECT_THROW(run_keep_strategy(KeepStrategy::random_sample, 1.5, {}, preset, empty), InvalidParameter);
}

TEST(FilterEval, VoxelBisectionReachesTheAskedCountOnAPlane) {
  FrameCloud::Ptr plane(new FrameCloud);
  for (int y = 0; y < 200; ++y)
    for (int x = 0; x < 200; ++x) plane->push_back({0.005f * x, 0.005f * y, 2.0f});  // 1 m x 1 m, 5 mm apart
  for (std::size_t count : {400u, 2500u, 10000u}) {
    const VoxelKeep kept = voxel_grid_keeping(plane, count);
    EXPECT_LE(std::abs(static_cast<double>(kept.cloud.size()) - static_cast<double>(count)), 0.05 * count) << count;
    EXPECT_GT(kept.leaf_m, 0.0f);
  }
  EXPECT_TRUE(voxel_grid_keeping(FrameCloud::Ptr(new FrameCloud), 10).cloud.empty());
}

}  // namespace
}  // namespace occ_improve
