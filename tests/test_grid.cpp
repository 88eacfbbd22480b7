// The sparse store: clamping options, memory cap, tiles, uniform runs, change tracking.
#include "occ_improve/errors.hpp"
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
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
  const float one = 1.0f;
  g.assign({1234, 0, 0.0f, &one, 1});
  EXPECT_EQ(g.allocated_tile_count(), 1u);
  EXPECT_EQ(g.touched_column_count(), 1u);
  g.clear();
  EXPECT_EQ(g.allocated_tile_count(), 0u);
}

// prefetch_tile is a hint: on a tile never written, a written one and columns outside the grid it neither
// allocates, changes a value nor marks a column changed.
TEST(Grid, PrefetchingATileChangesNothing) {
  ColumnGrid g(paper_geometry());
  const ColumnIndex outside = static_cast<ColumnIndex>(g.geometry().column_count());
  g.prefetch_tile(1234);
  EXPECT_EQ(g.allocated_tile_count(), 0u);
  const std::vector<float> window{-1.0f, 2.0f, 0.5f};
  g.assign({1234, 4, -6.9f, window.data(), 3});
  g.take_changed_columns();
  for (const ColumnIndex c : {ColumnIndex{1234}, ColumnIndex{1235}, ColumnIndex{0}, outside, outside + 100000})
    g.prefetch_tile(c);
  EXPECT_EQ(g.allocated_tile_count(), 1u);
  EXPECT_TRUE(g.take_changed_columns().empty());
  const ColumnData& c = *g.find(1234);
  EXPECT_EQ(c.uniform_end, 4);
  EXPECT_EQ(c.value(3), -6.9f);
  EXPECT_EQ(c.value(4), -1.0f);
  EXPECT_EQ(c.value(6), 0.5f);
  EXPECT_EQ(c.value(7), 0.0f);
}

TEST(Grid, WrittenLeadingVoxelsEqualToTheRunJoinIt) {
  ColumnGrid g(paper_geometry());
  const std::vector<float> window{-6.9f, -6.9f, -1.0f, 2.0f};
  g.assign({77, 3, -6.9f, window.data(), 4});
  const ColumnData& c = *g.find(77);
  EXPECT_EQ(c.uniform_end, 5);
  ASSERT_EQ(c.window.size(), 2u);
  EXPECT_EQ(c.value(4), -6.9f);
  EXPECT_EQ(c.value(5), -1.0f);
  EXPECT_EQ(c.value(6), 2.0f);
  EXPECT_EQ(c.value(7), 0.0f);
  g.assign({78, 0, 0.0f, window.data(), 4});  // no run: nothing joins it
  EXPECT_EQ(g.find(78)->uniform_end, 0);
  EXPECT_EQ(g.find(78)->window.size(), 4u);
}

// The tiles' window storage against plain per-column vectors: windows growing, shrinking and emptying,
// written one by one and a tile at a time, in random order; every value read back after every write.
TEST(Grid, TileStorageKeepsEveryWindowThroughGrowingAndShrinkingWrites) {
  ColumnGrid g(paper_geometry());
  const int width = g.geometry().width();
  std::vector<ColumnIndex> columns;  // two tiles' columns: the first tile's 64 and 3 of the next
  for (int e = 0; e < ColumnGrid::kTileSize; ++e)
    for (int a = 0; a < ColumnGrid::kTileSize; ++a) columns.push_back(static_cast<ColumnIndex>(e * width + a));
  for (int a = 8; a < 11; ++a) columns.push_back(static_cast<ColumnIndex>(a));
  std::vector<std::vector<float>> expected(columns.size());
  std::uint32_t state = 12345;
  auto next = [&](std::uint32_t n) { return ((state = state * 1664525u + 1013904223u) >> 8) % n; };
  auto contents = [&](std::size_t i) {
    expected[i].resize(next(40));  // 0..39 bins
    for (float& v : expected[i]) v = static_cast<float>(next(1000)) - 500.0f;  // never the run's value
    return ColumnContents{columns[i], 10, 600.0f, expected[i].data(), static_cast<std::uint32_t>(expected[i].size())};
  };
  auto check_all = [&](int round) {
    for (std::size_t i = 0; i < columns.size(); ++i) {
      const ColumnData* c = g.find(columns[i]);
      if (!c) continue;
      ASSERT_EQ(c->window.size(), expected[i].size()) << "round " << round << " column " << columns[i];
      for (std::size_t k = 0; k < expected[i].size(); ++k) ASSERT_EQ(c->window[k], expected[i][k]);
    }
  };
  for (int round = 0; round < 200; ++round) {
    if (round % 2 == 0) {
      g.assign(contents(next(static_cast<std::uint32_t>(columns.size()))));
    } else {  // a random subset of the first tile, in one write
      std::vector<ColumnContents> batch;
      for (std::size_t i = 0; i < 64; ++i)
        if (next(3) == 0) batch.push_back(contents(i));
      g.store_windows(batch.data(), batch.size());
    }
    check_all(round);
  }
  g.shrink_to_fit();
  check_all(-1);
  // Trimmed, the storage holds the windows and nothing else: the same tiles with empty windows cost the
  // rest.
  ColumnGrid empty_windows(paper_geometry());
  std::size_t bins = 0;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    bins += expected[i].size();
    empty_windows.assign({columns[i], 10, 600.0f, nullptr, 0});
  }
  EXPECT_EQ(g.memory_bytes(), empty_windows.memory_bytes() + bins * sizeof(float));
}

// A tile whose windows narrow (a static view's first frames) gives the room back once a quarter of it
// is spare, and a tile's first store holds no spare room at all.
TEST(Grid, TileStorageIsExactAtFirstAndTrimmedWhenWindowsNarrow) {
  ColumnGrid g(paper_geometry());
  ColumnGrid empty_windows(paper_geometry());
  const std::vector<float> wide(40, 1.0f);
  std::vector<ColumnContents> tile(64);
  for (std::size_t i = 0; i < tile.size(); ++i) {
    const auto column = static_cast<ColumnIndex>((i / 8) * static_cast<std::size_t>(g.geometry().width()) + i % 8);
    tile[i] = {column, 0, 0.0f, wide.data(), 40};
    empty_windows.assign({column, 10, -1.0f, nullptr, 0});
  }
  g.store_windows(tile.data(), tile.size());
  const std::size_t overhead = empty_windows.memory_bytes();
  EXPECT_EQ(g.memory_bytes(), overhead + 64 * 40 * sizeof(float));
  for (auto& c : tile) c.count = 2;
  g.store_windows(tile.data(), tile.size());
  EXPECT_EQ(g.memory_bytes(), overhead + 64 * 2 * sizeof(float));
  EXPECT_EQ(g.find(tile[5].column)->window.size(), 2u);
}

// assign's values may be a window of the same tile: another column's, or the written column's own (in
// its place, moved after the windows, or through a rebuild).
TEST(Grid, AssignTakesAWindowOfTheSameTile) {
  ColumnGrid g(paper_geometry());
  const std::vector<float> values{1.0f, 2.0f, 3.0f, 4.0f, 5.0f};
  g.assign({0, 0, 0.0f, values.data(), 5});
  g.assign({1, 0, 0.0f, g.find(0)->window.data() + 1, 3});  // another column's bins: 2, 3, 4
  g.assign({0, 0, 0.0f, g.find(0)->window.data() + 2, 3});  // its own, shifted in place: 3, 4, 5
  for (int round = 0; round < 20; ++round) {  // then column 0 shrinks from its own bins: always in place
    const ColumnData& c = *g.find(1);
    std::vector<float> grown(c.window.begin(), c.window.end());  // column 1 grows a bin a round: spare, rebuilds
    grown.push_back(static_cast<float>(round));
    g.assign({1, 0, 0.0f, grown.data(), static_cast<std::uint32_t>(grown.size())});
    ASSERT_TRUE(std::equal(grown.begin(), grown.end(), g.find(1)->window.begin(), g.find(1)->window.end()));
  }
  EXPECT_EQ(g.log_odds(0, 0), 3.0f);
  EXPECT_EQ(g.log_odds(0, 2), 5.0f);
  EXPECT_EQ(g.log_odds(1, 0), 2.0f);
  EXPECT_EQ(g.log_odds(1, 2), 4.0f);
}

TEST(Grid, StoreWindowsRefusesColumnsOfTwoTiles) {
  ColumnGrid g(paper_geometry());
  const float v = 1.0f;
  const ColumnContents two[2] = {{0, 0, 0.0f, &v, 1}, {8, 0, 0.0f, &v, 1}};  // columns 0 and 8: tiles 0 and 1
  EXPECT_THROW(g.store_windows(two, 2), InvalidInput);
}

// The insertion's overload: the slots it gives are checked against the columns (a multiplication each),
// and a tile written through it holds what the overload that finds each column's tile writes.
TEST(Grid, StoreWindowsWithSlotsChecksThemAndStoresTheSame) {
  ColumnGrid by_slots(paper_geometry()), by_columns(paper_geometry());
  const auto width = static_cast<ColumnIndex>(by_slots.geometry().width());
  const ColumnIndex origin = 3 * 8 * width + 16;  // tile (2, 3)
  const std::vector<float> values{1.0f, 2.0f, 3.0f};
  std::vector<ColumnContents> tile;
  std::vector<std::size_t> slots;
  for (std::size_t slot : {0u, 9u, 63u}) {
    tile.push_back({origin + static_cast<ColumnIndex>((slot / 8) * width + slot % 8), 2, -1.0f, values.data(), 3});
    slots.push_back(slot);
  }
  by_slots.store_windows(tile.data(), slots.data(), tile.size());
  by_columns.store_windows(tile.data(), tile.size());
  for (const ColumnContents& c : tile)
    for (int bin = 0; bin < 6; ++bin) EXPECT_EQ(by_slots.log_odds(c.column, bin), by_columns.log_odds(c.column, bin));
  EXPECT_EQ(by_slots.log_odds(tile[2].column, 4), 3.0f);
  std::vector<std::size_t> wrong = slots;
  wrong[1] = 10;  // column (1, 1) of the tile given as (2, 1)
  EXPECT_THROW(by_slots.store_windows(tile.data(), wrong.data(), tile.size()), InvalidInput);
  wrong[1] = 64;  // outside any tile
  EXPECT_THROW(by_slots.store_windows(tile.data(), wrong.data(), tile.size()), InvalidInput);
  const ColumnContents other_tile[2] = {tile[0], {origin + 8, 0, 0.0f, values.data(), 1}};  // slot 8 is (0, 1), not 8 columns right
  const std::size_t claimed[2] = {0, 8};
  EXPECT_THROW(by_slots.store_windows(other_tile, claimed, 2), InvalidInput);
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

// Columns at both ends and on either side of the scan's 8-column words, each listed once, in order.
TEST(Grid, ChangedColumnsAtTheEndsAndWordEdgesAreAllTaken) {
  ColumnGrid g(paper_geometry());
  const auto last = static_cast<ColumnIndex>(g.geometry().column_count() - 1);
  const std::vector<ColumnIndex> marked{0, 7, 8, 15, 16, 1000, last - 8, last - 1, last};
  for (auto it = marked.rbegin(); it != marked.rend(); ++it) g.mark_changed(*it);
  g.mark_changed(8);  // twice: listed once
  EXPECT_EQ(g.take_changed_columns(), marked);
  EXPECT_TRUE(g.take_changed_columns().empty());
}

}  // namespace
}  // namespace occ_improve
