// The sparse store: clamping options, memory cap, tiles, uniform runs, change tracking.
#include "occ_improve/errors.hpp"
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace occ_improve {
namespace {

GridGeometry paper_geometry() { return GridGeometry(kinect_v1_paper().geometry); }

TEST(Grid, ClampingBoundsAreLogOdds) {
  const ColumnGrid g(paper_geometry());
  EXPECT_NEAR(g.log_odds_min(), std::log(0.001 / 0.999), 1e-5);
  EXPECT_NEAR(g.log_odds_max(), std::log(0.999 / 0.001), 1e-5);
  const ColumnGrid o(paper_geometry(), GridOptions::octomap_clamping());
  EXPECT_NEAR(o.log_odds_min(), std::log(0.1192 / 0.8808), 1e-5);
  EXPECT_NEAR(o.log_odds_max(), std::log(0.971 / 0.029), 1e-5);
}

TEST(Grid, BadOptionsAndMemoryCapThrow) {
  GridOptions o;
  o.probability_min = 0.6;
  EXPECT_THROW(ColumnGrid(paper_geometry(), o), InvalidParameter);
  o = {};
  o.probability_max = 1.0;
  EXPECT_THROW(ColumnGrid(paper_geometry(), o), InvalidParameter);
  o = {};
  o.memory_cap_bytes = 100u << 20;  // the paper grid's dense worst case is 629 MB
  try {
    ColumnGrid g(paper_geometry(), o);
    FAIL() << "expected ResourceLimit";
  } catch (const ResourceLimit& e) {
    EXPECT_NE(std::string(e.what()).find("memory_cap_bytes"), std::string::npos);
  }
}

TEST(Grid, UntouchedColumnsCostNoTileAndReadAsUnknown) {
  ColumnGrid g(paper_geometry());
  EXPECT_EQ(g.allocated_tile_count(), 0u);
  EXPECT_EQ(g.find(1234), nullptr);
  EXPECT_EQ(g.log_odds(1234, 10), 0.0f);
  EXPECT_DOUBLE_EQ(g.probability(1234, 10), 0.5);
  g.touch(1234).window = {1.0f};
  EXPECT_EQ(g.allocated_tile_count(), 1u);
  EXPECT_EQ(g.touched_column_count(), 1u);
  g.clear();
  EXPECT_EQ(g.allocated_tile_count(), 0u);
}

TEST(Grid, CompactMergesLeadingUniformVoxels) {
  ColumnData c;
  c.uniform_end = 3;
  c.uniform_value = -6.9f;
  c.window = {-6.9f, -6.9f, -1.0f, 2.0f};
  ColumnGrid::compact(c);
  EXPECT_EQ(c.uniform_end, 5);
  ASSERT_EQ(c.window.size(), 2u);
  EXPECT_EQ(c.value(4), -6.9f);
  EXPECT_EQ(c.value(5), -1.0f);
  EXPECT_EQ(c.value(6), 2.0f);
  EXPECT_EQ(c.value(7), 0.0f);
}

TEST(Grid, OneFrameStoresFreeSpaceAsUniformRuns) {
  const SensorPreset p = kinect_v1_paper();
  ColumnGrid g{GridGeometry(p.geometry)};
  const auto points = sample::generate_scene().points();
  insert_points(g, SensorModel(p.model), PointSpan::from(points));
  const std::size_t touched = g.touched_column_count();
  EXPECT_GT(touched, 250000u);
  // Without uniform runs every touched column would hold every bin up to its surface (~200 on average).
  const double voxels_per_column = static_cast<double>(g.stored_voxel_count()) / static_cast<double>(touched);
  EXPECT_LT(voxels_per_column, 120.0);
  // Columns beyond the depth range are one uniform run and nothing else.
  std::size_t all_free = 0;
  for (ColumnIndex c = 0; c < g.geometry().column_count(); ++c) {
    const ColumnData* col = g.find(c);
    if (col && col->uniform_end == g.geometry().depth().bins() && col->window.empty()) ++all_free;
  }
  EXPECT_GT(all_free, 10000u);
}

TEST(Grid, ChangedColumnsAreRecordedOnceAndReset) {
  const SensorPreset p = kinect_v1_paper();
  ColumnGrid g{GridGeometry(p.geometry)};
  std::vector<Eigen::Vector3f> one = {{0.0f, 0.0f, 2.0f}};
  insert_points(g, SensorModel(p.model), PointSpan::from(one));
  const auto changed = g.take_changed_columns();
  EXPECT_GE(changed.size(), 4u);
  EXPECT_LE(changed.size(), 9u);
  EXPECT_TRUE(std::is_sorted(changed.begin(), changed.end()));
  EXPECT_TRUE(g.take_changed_columns().empty());
}

}  // namespace
}  // namespace occ_improve
