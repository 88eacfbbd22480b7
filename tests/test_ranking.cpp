// Ranking: top rays, 8-connected regions, the stop signal.
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sample_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <random>

namespace occ_improve {
namespace {

struct Maps {
  GridGeometry geometry;
  SurfaceMap surface;
  ImprovementMap improvement;
};

// A small grid with hand-made improvement values, surfaces known at 2 m except where noted.
Maps small_maps(int w, int h) {
  GeometryParams gp;
  gp.azimuth_bins = w;
  gp.elevation_bins = h;
  Maps m{GridGeometry(gp), {}, {}};
  m.surface.width = m.improvement.width = w;
  m.surface.height = m.improvement.height = h;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  m.surface.depth_m.assign(n, 2.0f);
  m.surface.probability.assign(n, 0.8f);
  m.surface.bin.assign(n, 10);
  m.surface.unknown.assign(n, 0);
  m.improvement.value.assign(n, 0.0f);
  return m;
}

TEST(Ranking, TopRaysAreTheLargestBestFirst) {
  Maps m = small_maps(10, 8);
  m.improvement.value[m.geometry.column(3, 4)] = 0.3f;
  m.improvement.value[m.geometry.column(7, 1)] = 0.5f;
  m.improvement.value[m.geometry.column(0, 0)] = -0.2f;
  m.surface.depth_m[m.geometry.column(7, 1)] = 3.5f;
  const auto rays = top_rays(m.improvement, m.surface, 2);
  ASSERT_EQ(rays.size(), 2u);
  EXPECT_EQ(rays[0].azimuth_bin, 7);
  EXPECT_EQ(rays[0].elevation_bin, 1);
  EXPECT_EQ(rays[0].column, m.geometry.column(7, 1));
  EXPECT_FLOAT_EQ(rays[0].improvement, 0.5f);
  EXPECT_FLOAT_EQ(rays[0].depth_m, 3.5f);
  EXPECT_EQ(rays[1].column, m.geometry.column(3, 4));
  EXPECT_EQ(top_rays(m.improvement, m.surface, 1000).size(), 80u);
  EXPECT_THROW(top_rays(m.improvement, m.surface, 0), InvalidParameter);
  Maps other = small_maps(9, 8);
  EXPECT_THROW(top_rays(m.improvement, other.surface, 3), InvalidInput);
}

// A tie over a 64 x 48 view, 5 % of it: one column per 4 x 4 cell (floor(sqrt(20)) = 4) and never two in
// one cell, spread over both halves; then values that differ: each cell gives its best column first; NaN
// and ineligible columns are never taken, and a request beyond what is left returns what is left.
// mean_of_best_share against a full sort: many equal values, values that share a histogram bucket (the
// top 16 bits) but differ, negatives, NaN and a mask, at shares down to a single value.
TEST(Ranking, MeanOfBestShareIsTheMeanOfTheSortedTop) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> fine(0.1380f, 0.1390f), any(-0.5f, 0.35f);
  std::vector<float> value(5000);
  std::vector<std::uint8_t> mask(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    value[i] = i % 5 == 0 ? 0.324f : i % 5 == 1 ? fine(rng) : i % 5 == 2 ? any(rng) : i % 97 == 0 ? NAN : 0.138f;
    mask[i] = i % 7 != 0;
  }
  const std::uint8_t* none = nullptr;
  for (const std::uint8_t* eligible : {none, static_cast<const std::uint8_t*>(mask.data())}) {
    std::vector<double> sorted;
    for (std::size_t i = 0; i < value.size(); ++i)
      if ((!eligible || eligible[i]) && !std::isnan(value[i])) sorted.push_back(value[i]);
    std::sort(sorted.begin(), sorted.end(), std::greater<>());
    for (double share : {1e-4, 0.05, 0.2, 0.21, 0.5, 0.9, 1.0}) {
      const auto k = static_cast<std::size_t>(std::ceil(share * static_cast<double>(sorted.size())));
      double sum = 0;
      for (std::size_t i = 0; i < k; ++i) sum += sorted[i];
      EXPECT_NEAR(mean_of_best_share(value, eligible, share), sum / static_cast<double>(k), 1e-9) << share;
    }
  }
  EXPECT_EQ(mean_of_best_share(std::vector<float>(10, NAN), nullptr, 0.2), 0.0);
  EXPECT_EQ(mean_of_best_share({}, nullptr, 0.2), 0.0);
}

TEST(Ranking, SpreadBestColumnsIsAJitteredGridAtTheScaleOfK) {
  const int w = 64, h = 48;
  std::vector<float> value(static_cast<std::size_t>(w * h), 0.3f);
  const std::size_t k = static_cast<std::size_t>(std::lround(0.05 * w * h));
  const std::vector<ColumnIndex> tied = spread_best_columns(value, nullptr, w, k);
  ASSERT_EQ(tied.size(), k);
  std::vector<int> per_cell(static_cast<std::size_t>((w / 4) * (h / 4)), 0);
  int top_half = 0;
  for (ColumnIndex c : tied) {
    EXPECT_EQ(++per_cell[static_cast<std::size_t>((c / w / 4) * (w / 4) + (c % w) / 4)], 1) << "column " << c;
    top_half += static_cast<int>(c) < w * h / 2 ? 1 : 0;
  }
  EXPECT_NEAR(top_half, static_cast<double>(k) / 2, k / 6.0);
  EXPECT_EQ(spread_best_columns(value, nullptr, w, k), tied);  // deterministic

  for (std::size_t c = 0; c < value.size(); ++c) value[c] = static_cast<float>(c % 7);  // 6 is each row's best
  const std::vector<ColumnIndex> best = spread_best_columns(value, nullptr, w, k);
  for (ColumnIndex c : best) {
    float cell_best = 0;
    for (int dy = 0; dy < 4; ++dy)
      for (int dx = 0; dx < 4; ++dx)
        cell_best = std::max(cell_best, value[static_cast<std::size_t>((c / w / 4 * 4 + dy) * w + c % w / 4 * 4 + dx)]);
    EXPECT_EQ(value[c], cell_best) << "column " << c;
  }

  std::vector<std::uint8_t> eligible(value.size(), 0);
  eligible[5] = eligible[6] = eligible[7] = 1;
  value[6] = std::numeric_limits<float>::quiet_NaN();
  const std::vector<ColumnIndex> few = spread_best_columns(value, eligible.data(), w, 10);
  EXPECT_EQ(few.size(), 2u);
  for (ColumnIndex c : few) EXPECT_TRUE(c == 5 || c == 7);
  EXPECT_TRUE(spread_best_columns(value, eligible.data(), w, 0).empty());
}

// The rounds of spread_best_columns written out with SamplingCells::cell_of per column: what the
// row-by-row stepping of the cells must give, on widths the cell side does not divide.
std::vector<ColumnIndex> spread_reference(const std::vector<float>& value, const std::uint8_t* eligible, int width, std::size_t k) {
  std::vector<std::uint8_t> open(value.size());
  std::size_t available = 0;
  for (std::size_t c = 0; c < value.size(); ++c) available += open[c] = (!eligible || eligible[c]) && !std::isnan(value[c]);
  k = std::min(k, available);
  const auto w = static_cast<std::size_t>(width);
  const SamplingCells cells(available, k, width);
  std::vector<ColumnIndex> out;
  while (out.size() < k) {
    std::map<std::size_t, std::pair<std::uint64_t, ColumnIndex>> best;  // cell -> (key, column)
    for (std::size_t c = 0; c < value.size(); ++c) {
      if (!open[c]) continue;
      const std::uint64_t key = rank_key(value[c], static_cast<ColumnIndex>(c));
      auto& b = best.try_emplace(cells.cell_of(static_cast<int>(c % w), static_cast<int>(c / w)), key, static_cast<ColumnIndex>(c)).first->second;
      if (key > b.first) b = {key, static_cast<ColumnIndex>(c)};
    }
    std::vector<std::pair<std::uint64_t, ColumnIndex>> round;
    for (const auto& [cell, b] : best) round.push_back(b);
    std::sort(round.begin(), round.end(), std::greater<>());
    for (std::size_t i = 0; i < round.size() && out.size() < k; ++i) out.push_back(round[i].second), open[round[i].second] = 0;
  }
  return out;
}

TEST(Ranking, SpreadBestColumnsStepsItsCellsAsCellOfOnAnyWidth) {
  for (const auto& [w, h] : {std::pair{37, 23}, std::pair{5, 9}, std::pair{1, 40}, std::pair{64, 48}}) {
    std::vector<float> value(static_cast<std::size_t>(w * h));
    std::uint32_t state = 12345;
    for (float& v : value) v = static_cast<float>((state = state * 1664525u + 1013904223u) >> 28);  // ties in 16 levels
    value[3] = std::numeric_limits<float>::quiet_NaN();
    std::vector<std::uint8_t> eligible(value.size(), 1);
    eligible[value.size() / 2] = 0;
    for (const std::size_t k : {std::size_t{1}, std::size_t{7}, value.size() / 10, value.size() / 3, value.size()})
      EXPECT_EQ(spread_best_columns(value, eligible.data(), w, k), spread_reference(value, eligible.data(), w, k))
          << w << " x " << h << ", k " << k;
  }
  EXPECT_THROW(spread_best_columns(std::vector<float>(10, 0.5f), nullptr, 3, 2), InvalidInput);  // not whole rows
}

TEST(Ranking, RegionsAreEightConnectedAndSorted) {
  Maps m = small_maps(20, 12);
  auto set = [&](int a, int e, float v) { m.improvement.value[m.geometry.column(a, e)] = v; };
  // A diagonal line of 5 (8-connected: one region), sum 1.0.
  for (int k = 0; k < 5; ++k) set(2 + k, 2 + k, 0.2f);
  // A 3 x 3 block of 0.3 with one unknown column: sum 2.7, peak 0.3.
  for (int e = 5; e <= 7; ++e)
    for (int a = 12; a <= 14; ++a) set(a, e, 0.3f);
  set(14, 7, 0.35f);  // the peak: sum 2.75
  m.surface.unknown[m.geometry.column(13, 6)] = 1;
  m.surface.depth_m[m.geometry.column(13, 6)] = 0.0f;
  m.surface.depth_m[m.geometry.column(12, 5)] = 3.0f;
  // Too small (3 columns) and below threshold.
  set(18, 0, 0.9f), set(19, 0, 0.9f), set(19, 1, 0.9f);
  set(0, 11, 0.04f), set(1, 11, 0.04f), set(2, 11, 0.04f), set(3, 11, 0.04f);
  const auto regions = find_regions(m.geometry, m.improvement, m.surface);
  ASSERT_EQ(regions.size(), 2u);
  const Region& block = regions[0];
  EXPECT_NEAR(block.summed_improvement, 2.75, 1e-5);
  EXPECT_EQ(block.area_columns, 9u);
  EXPECT_FLOAT_EQ(block.peak_improvement, 0.35f);
  EXPECT_EQ(block.peak_u, 14);
  EXPECT_EQ(block.peak_v, 7);
  EXPECT_EQ(block.min_u, 12);
  EXPECT_EQ(block.max_u, 14);
  EXPECT_EQ(block.min_v, 5);
  EXPECT_EQ(block.max_v, 7);
  EXPECT_NEAR(block.mean_depth_m, (7 * 2.0 + 3.0) / 8, 1e-6);
  EXPECT_EQ(block.centre_u, 13);  // the middle column of the block
  EXPECT_EQ(block.centre_v, 6);
  EXPECT_NEAR(block.centre_azimuth_rad, m.geometry.azimuth().centre(13), 1e-12);
  EXPECT_NEAR(block.centre_elevation_rad, m.geometry.elevation().centre(6), 1e-12);
  EXPECT_TRUE(block.centre_direction.isApprox(m.geometry.direction(13, 6), 1e-9));
  EXPECT_NEAR(block.centre_direction.norm(), 1.0, 1e-12);
  EXPECT_NEAR(regions[1].summed_improvement, 1.0, 1e-5);
  EXPECT_EQ(regions[1].area_columns, 5u);
  // Lower area threshold: the small region appears too.
  RegionOptions o;
  o.min_area_columns = 1;
  EXPECT_EQ(find_regions(m.geometry, m.improvement, m.surface, o).size(), 3u);
  o.min_improvement = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(find_regions(m.geometry, m.improvement, m.surface, o), InvalidParameter);
}

// The centre was the mean position of the region's columns: for a region wrapped around an object (its
// shadow or border, as on a real table scene) that mean lies on the object, outside the region.
TEST(Ranking, ARegionsCentreIsOneOfItsColumns) {
  Maps m = small_maps(30, 20);
  // A ring 2 columns wide around an object (improvement 0) at u 8-21, v 5-14; the ring is open at the
  // bottom right, so its mean position is inside the hole.
  for (int v = 3; v <= 16; ++v)
    for (int u = 6; u <= 23; ++u) {
      const bool hole = u >= 8 && u <= 21 && v >= 5 && v <= 14;
      const bool gap = v >= 15 && u >= 18;
      if (!hole && !gap) m.improvement.value[m.geometry.column(u, v)] = 0.3f;
    }
  const auto regions = find_regions(m.geometry, m.improvement, m.surface);
  ASSERT_EQ(regions.size(), 1u);
  const Region& ring = regions[0];
  EXPECT_GE(m.improvement.value[m.geometry.column(ring.centre_u, ring.centre_v)], 0.2f)
      << "centre (" << ring.centre_u << ", " << ring.centre_v << ") is not in the region";
  EXPECT_EQ(ring.min_u, 6);
  EXPECT_EQ(ring.max_u, 23);
  EXPECT_EQ(ring.min_v, 3);
  EXPECT_EQ(ring.max_v, 16);
  // The medoid: no column of the ring has a smaller summed L1 distance to the others.
  const auto summed_distance = [&](int cu, int cv) {
    double d = 0;
    for (int v = 0; v < 20; ++v)
      for (int u = 0; u < 30; ++u)
        if (m.improvement.value[m.geometry.column(u, v)] >= 0.2f) d += std::abs(u - cu) + std::abs(v - cv);
    return d;
  };
  const double centre_distance = summed_distance(ring.centre_u, ring.centre_v);
  for (int v = 0; v < 20; ++v)
    for (int u = 0; u < 30; ++u)
      if (m.improvement.value[m.geometry.column(u, v)] >= 0.2f) {
        EXPECT_GE(summed_distance(u, v), centre_distance) << u << ", " << v;
      }
}

// Equal values were taken in scan order by top_rays (the first ten: row 0, columns 0-9) and spread by a
// hash in the planner: one rule (rank_key) now orders both, and a region's peak among equals.
TEST(Ranking, TiesFollowOneRuleInTopRaysRegionsAndThePlanner) {
  Maps m = small_maps(64, 48);
  std::fill(m.improvement.value.begin(), m.improvement.value.end(), 0.3f);
  const auto rays = top_rays(m.improvement, m.surface, 10);
  ASSERT_EQ(rays.size(), 10u);
  int first_row = 0;
  for (const RankedRay& r : rays) first_row += r.elevation_bin == 0;
  EXPECT_LT(first_row, 3) << "ties taken in scan order";
  PlanRequest request;
  request.budget_rays = 10;
  const Shot shot = plan_next_shot(m.improvement, ReturnRecord::for_grid(64, 48), request);
  ASSERT_EQ(shot.columns.size(), 10u);
  for (std::size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(rays[i].column, shot.columns[i]) << i;
  for (std::size_t i = 1; i < rays.size(); ++i)
    EXPECT_GT(rank_key(0.3f, rays[i - 1].column), rank_key(0.3f, rays[i].column));
  const auto regions = find_regions(m.geometry, m.improvement, m.surface);
  ASSERT_EQ(regions.size(), 1u);
  EXPECT_EQ(m.geometry.column(regions[0].peak_u, regions[0].peak_v), rays[0].column);
}

TEST(Ranking, StopSignalFollowsTheThresholds) {
  Maps m = small_maps(20, 12);
  for (int a = 0; a < 10; ++a) m.improvement.value[m.geometry.column(a, 3)] = 0.3f;
  m.improvement.value[0] = 0.005f;  // below ray_floor: not counted
  const auto regions = find_regions(m.geometry, m.improvement, m.surface);
  StopCriteria c;
  c.total_improvement_below = 2.0;
  c.best_region_below = 1.0;
  StopSignal s = stop_signal(m.improvement, regions, c);
  EXPECT_NEAR(s.total_improvement, 3.0, 1e-5);
  EXPECT_NEAR(s.best_region_improvement, 3.0, 1e-5);
  EXPECT_FALSE(s.stop) << s.reason;
  c.total_improvement_below = 4.0;
  s = stop_signal(m.improvement, regions, c);
  EXPECT_TRUE(s.stop);
  EXPECT_NE(s.reason.find("total"), std::string::npos);
  c.total_improvement_below = 2.0;
  c.best_region_below = 5.0;
  s = stop_signal(m.improvement, regions, c);
  EXPECT_TRUE(s.stop);
  EXPECT_NE(s.reason.find("best region"), std::string::npos);
  c.best_region_below = std::nan("");
  EXPECT_THROW(stop_signal(m.improvement, regions, c), InvalidParameter);
}

TEST(Ranking, SampleSceneDoesNotStopAndPointsAtTheNoDataRegions) {
  const Mapper mapper = [] {
    Mapper m(kinect_v1_paper());
    m.insert(PointSpan::from(sample::generate_scene().points()));
    return m;
  }();
  const auto regions = find_regions(mapper.geometry(), mapper.improvement(), mapper.surface());
  ASSERT_FALSE(regions.empty());
  // The best region's columns are mostly unknown (no-data holes are worth the most): its peak is ~0.32.
  EXPECT_GT(regions.front().peak_improvement, 0.28f);
  const StopSignal s = stop_signal(mapper.improvement(), regions);
  EXPECT_FALSE(s.stop) << s.reason;
}

TEST(Ranking, StopMonitorFiresWhenProgressStallsOnly) {
  ImprovementMap map;
  map.width = 10;
  map.height = 10;
  map.value.assign(100, 0.3f);  // total 30: above the absolute threshold, so only stalling can stop
  StopMonitor monitor({}, ProgressCriteria{0.01, 3});  // 10% drops are progress, 0% is not
  Region big{};
  big.summed_improvement = 30.0;  // keeps the best-region threshold quiet
  const std::vector<Region> regions = {big};
  // Shrinking by 10% per frame is progress.
  for (int frame = 0; frame < 6; ++frame) {
    EXPECT_FALSE(monitor.update(map, regions).stop) << frame;
    for (float& v : map.value) v *= 0.9f;
  }
  EXPECT_FALSE(monitor.update(map, regions).stop);  // still sees the last 10% drop
  // Now stuck: the third frame in a row without a 1% gain stops.
  EXPECT_FALSE(monitor.update(map, regions).stop);
  EXPECT_FALSE(monitor.update(map, regions).stop);
  const StopSignal s = monitor.update(map, regions);
  EXPECT_TRUE(s.stop);
  EXPECT_NE(s.reason.find("stalled"), std::string::npos) << s.reason;
  EXPECT_THROW(StopMonitor({}, ProgressCriteria{-0.1, 3}), InvalidParameter);
  EXPECT_THROW(StopMonitor({}, ProgressCriteria{0.01, 0}), InvalidParameter);
}

TEST(Ranking, StaticSequenceStopsWhenGainsDiminish) {
  // The sample's poster and projector shadows never return data, so their rays keep ~0.32 forever and the
  // absolute thresholds never fire; repeated frames of the same view must still end in a stop once each
  // frame adds little.
  Mapper mapper(kinect_v1_paper());
  StopMonitor monitor;
  bool stopped = false, absolute_stop = false;
  int frame = 0;
  for (; frame < 30 && !stopped; ++frame) {
    sample::SceneOptions options;
    options.seed = static_cast<std::uint32_t>(frame + 1);
    const auto points = sample::generate_scene(options).points();
    mapper.insert(PointSpan::from(points));
    const auto regions = find_regions(mapper.geometry(), mapper.improvement(), mapper.surface());
    absolute_stop |= stop_signal(mapper.improvement(), regions).stop;
    stopped = monitor.update(mapper.improvement(), regions).stop;
  }
  EXPECT_FALSE(absolute_stop);
  EXPECT_TRUE(stopped) << "no stop after " << frame << " frames";
  EXPECT_GE(frame, 4);  // not before progress was measured over `patience` frames
}

}  // namespace
}  // namespace occ_improve
