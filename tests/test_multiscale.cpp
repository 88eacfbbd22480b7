// The improvement at coarser pixel-native binnings (multiscale.hpp): what a block says where it is flat
// and settled, where it holds a depth transition, where it has no data; incremental = recomputed.
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/maps/multiscale.hpp"
#include "occ_improve/sim/virtual_sensor.hpp"
#include "support/small_camera.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numeric>

namespace occ_improve {
namespace {

using test::small_camera;

// Rows 0-15: no return (no data); below, a wall at 2 m for u < 42 and a box face at 1 m from u = 42 on.
std::vector<float> step_scene(const PinholeIntrinsics& k) {
  std::vector<float> depth(static_cast<std::size_t>(k.width * k.height), 0.0f);
  for (int v = 16; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) depth[static_cast<std::size_t>(v * k.width + u)] = u < 42 ? 2.0f : 1.0f;
  return depth;
}

// Shots of every `stride`-th pixel, offset cycled: many small incremental updates.
void acquire(Mapper& mapper, VirtualSensor& sensor, int shots, int stride) {
  const auto pixels = static_cast<std::uint32_t>(mapper.geometry().column_count());
  for (int s = 0; s < shots; ++s) {
    std::vector<std::uint32_t> asked;
    for (std::uint32_t p = static_cast<std::uint32_t>(s % stride); p < pixels; p += static_cast<std::uint32_t>(stride))
      asked.push_back(p);
    mapper.insert(PointSpan::from(sensor.points(asked, sensor.shoot(asked))));
  }
}

class MultiScaleStep : public ::testing::Test {
protected:
  void SetUp() override {
    VirtualSensorParams clean;
    clean.sigma_depth_per_m2 = 0;
    clean.disparity_step_px = 0;
    VirtualSensor sensor(step_scene(small_camera()), small_camera(), clean);
    mapper.pyramid();  // asked before the shots: kept incrementally by them from then on
    acquire(mapper, sensor, 14, 7);  // every pixel twice, in 14 sparse shots
  }
  Mapper mapper{kinect_v1(small_camera())};
};

TEST_F(MultiScaleStep, FlatSettledLowTransitionNegativeNoDataHigh) {
  const ImprovementPyramid& p = mapper.pyramid();
  const int level = 1;  // blocks of 4: (bx, by) covers u in [4 bx, 4 bx + 4), v in [4 by, 4 by + 4)
  const float flat = p.block(level, 3, 8).mean_improvement();        // u 12-15, v 32-35: the wall
  const float transition = p.block(level, 10, 8).mean_improvement();  // u 40-43: wall | box edge at 42
  const float no_data = p.block(level, 3, 1).mean_improvement();      // v 4-7: nothing returns
  std::printf("mean improvement of 4-blocks: flat %.4f, transition %.4f, no data %.4f\n", flat, transition, no_data);
  EXPECT_GT(flat, 0.0f);
  EXPECT_LT(flat, 0.15f);  // below a ray seen once (0.138) on average
  EXPECT_LT(transition, 0.0f);
  EXPECT_NEAR(no_data, 0.324f, 0.01f);
  // The coarser levels agree: the 16-block over the wall's middle is low, the top row of 16-blocks high
  // (below 0.324: its last row borders the measured rows, whose OPDFs reach it).
  EXPECT_LT(p.block(3, 1, 2).mean_improvement(), 0.15f);
  EXPECT_GT(p.block(3, 1, 0).mean_improvement(), 0.2f);
  EXPECT_NEAR(p.block(2, 1, 0).mean_improvement(), 0.324f, 0.01f);  // rows 0-7
}

TEST_F(MultiScaleStep, ResidualIsSmallOnTheWallAndLargeAtTheEdge) {
  const ImprovementPyramid& p = mapper.pyramid();
  const SensorModel& model = mapper.model();
  for (LocalModel local : {LocalModel::constant, LocalModel::plane}) {
    EXPECT_LT(p.residual_sigmas(1, 3, 8, model, local), 0.5);   // the flat wall, noise-free
    EXPECT_GT(p.residual_sigmas(1, 10, 8, model, local), 8.0);  // 1 m in front of 2 m
    EXPECT_TRUE(std::isnan(p.residual_sigmas(1, 3, 1, model, local)));  // no sample around
  }
  EXPECT_EQ(p.block(1, 3, 8).samples, 16u);
  EXPECT_EQ(p.block(1, 3, 1).samples, 0u);
}

bool same_block(const BlockSummary& a, const BlockSummary& b) {
  return a.improvement_sum == b.improvement_sum && a.observable_rays == b.observable_rays && a.samples == b.samples &&
         a.su == b.su && a.sv == b.sv && a.sz == b.sz && a.suu == b.suu && a.suv == b.suv && a.svv == b.svv &&
         a.suz == b.suz && a.svz == b.svz && a.szz == b.szz;
}

TEST_F(MultiScaleStep, IncrementalEqualsRecomputedExactly) {
  const ImprovementPyramid rebuilt(mapper.improvement(), mapper.surface());
  const ImprovementPyramid& kept = mapper.pyramid();
  std::size_t blocks = 0;
  for (int level = 0; level < ImprovementPyramid::kLevels; ++level)
    for (int by = 0; by < kept.blocks_y(level); ++by)
      for (int bx = 0; bx < kept.blocks_x(level); ++bx, ++blocks)
        ASSERT_TRUE(same_block(kept.block(level, bx, by), rebuilt.block(level, bx, by)))
            << "level " << level << " block " << bx << ", " << by;
  EXPECT_EQ(blocks, 32u * 24 + 16 * 12 + 8 * 6 + 4 * 3);
  // A level summarises its children: the 16-block's rays are the sum of its 4-blocks'.
  std::uint32_t rays = 0;
  for (int by = 0; by < 4; ++by)
    for (int bx = 0; bx < 4; ++bx) rays += kept.block(1, bx, by).observable_rays;
  EXPECT_EQ(kept.block(3, 0, 0).observable_rays, rays);
  EXPECT_LT(kept.memory_bytes(), mapper.geometry().column_count() * 40);  // a fraction of the fine grid's maps
}

TEST(MultiScale, PartialEdgeBlocksAndBadInput) {
  ImprovementMap imp{5, 3, std::vector<float>(15, 0.2f)};
  imp.value[14] = std::nanf("");
  SurfaceMap surface;
  surface.width = 5;
  surface.height = 3;
  surface.depth_m.assign(15, 0.0f);
  surface.probability.assign(15, 0.5f);
  surface.bin.assign(15, -1);
  surface.unknown.assign(15, 1);
  ImprovementPyramid p(imp, surface);
  EXPECT_EQ(p.blocks_x(0), 3);
  EXPECT_EQ(p.blocks_y(0), 2);
  EXPECT_EQ(p.block(0, 2, 1).observable_rays, 0u);  // column (4, 2) only, and it is NaN
  EXPECT_TRUE(std::isnan(p.block(0, 2, 1).mean_improvement()));
  EXPECT_EQ(p.block(3, 0, 0).observable_rays, 14u);
  EXPECT_THROW(p.update(imp, surface, {15}), InvalidInput);
  ImprovementMap other{4, 3, std::vector<float>(12, 0.2f)};
  EXPECT_THROW(p.update(other, surface, {0}), InvalidInput);
  EXPECT_THROW(p.block(4, 0, 0), InvalidParameter);
  EXPECT_THROW(p.block(0, 3, 0), InvalidParameter);
  EXPECT_THROW(ImprovementPyramid::level_of_block_size(3), InvalidParameter);
  EXPECT_EQ(p.block(3, 0, 0).observable_rays, 14u);  // nothing half-updated by the refused calls
}

}  // namespace
}  // namespace occ_improve
