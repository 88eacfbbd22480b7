// keep_points_by_map (point_selection.hpp): which points of a frame to keep by the map.
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/planning/point_selection.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/grid/mask.hpp"
#include "support/small_camera.hpp"

#include "support/expect_throw.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <utility>

namespace occ_improve {
namespace {

MapView view_of(const Mapper& m) { return {m.geometry(), m.surface(), m.improvement(), m.pyramid()}; }

// The built-in scene's points that have a ray, each with its id = its index in the scene.
struct Frame {
  std::vector<Eigen::Vector3f> points;
  std::vector<PointOnRay> on_ray;
};
Frame scene_on(const GridGeometry& g) {
  Frame f{sample::generate_scene().points(), {}};
  f.on_ray = points_on_rays(PointSpan::from(f.points), g);
  return f;
}

std::size_t distinct_rays(const std::vector<PointOnRay>& points) {
  std::set<ColumnIndex> rays;
  for (const PointOnRay& p : points) rays.insert(p.column);
  return rays.size();
}

TEST(PointSelection, KeepsAsManyDistinctPointsAsAskedOnePerCellDeterministically) {
  Mapper mapper(kinect_v1());
  const Frame f = scene_on(mapper.geometry());
  ASSERT_GT(f.on_ray.size(), 100000u);
  const std::size_t keep = f.on_ray.size() / 20;
  const std::vector<std::uint64_t> kept = keep_points_by_map(f.on_ray, KeepAmount::count(keep), view_of(mapper));
  ASSERT_EQ(kept.size(), keep);
  EXPECT_EQ(std::set<std::uint64_t>(kept.begin(), kept.end()).size(), keep);
  // Every ray ties on an empty map: the jittered grid puts at most one point in a cell.
  const SamplingCells cells(distinct_rays(f.on_ray), keep, mapper.geometry().width());
  std::map<std::uint64_t, ColumnIndex> column_of;
  for (const PointOnRay& p : f.on_ray) column_of[p.point] = p.column;
  std::map<std::size_t, int> per_cell;
  for (const std::uint64_t id : kept) {
    const ColumnIndex c = column_of.at(id);
    EXPECT_EQ(++per_cell[cells.cell_of(mapper.geometry().azimuth_bin_of(c), mapper.geometry().elevation_bin_of(c))], 1);
  }
  EXPECT_EQ(keep_points_by_map(f.on_ray, KeepAmount::count(keep), view_of(mapper)), kept);
  EXPECT_EQ(keep_points_by_map(f.on_ray, KeepAmount::count(f.on_ray.size() + 5), view_of(mapper)).size(), f.on_ray.size());
  EXPECT_TRUE(keep_points_by_map(f.on_ray, KeepAmount::count(0), view_of(mapper)).empty());
  EXPECT_TRUE(keep_points_by_map({}, KeepAmount::count(10), view_of(mapper)).empty());
  // A fraction counts the points on an observable ray, rounded to the nearest.
  EXPECT_EQ(keep_points_by_map(f.on_ray, KeepAmount::fraction(0.05), view_of(mapper)).size(),
            static_cast<std::size_t>(std::llround(0.05 * static_cast<double>(f.on_ray.size()))));
  // points_on_rays: every valid point of the scene in the field of view, ids in order.
  for (std::size_t k = 1; k < f.on_ray.size(); ++k) EXPECT_LT(f.on_ray[k - 1].point, f.on_ray[k].point);
}

// Once the kept points are in the map, the same choice keeps every one whose ray became a sample again,
// though their improvement (0.138) is now below their unmeasured neighbours' (0.324): the rays beside a
// sample are predicted from it.
TEST(PointSelection, ACellsSampleIsKeptAgainBeforeTheRaysBesideIt) {
  Mapper mapper(kinect_v1());
  const Frame f = scene_on(mapper.geometry());
  const std::size_t keep = f.on_ray.size() / 20;
  const std::vector<std::uint64_t> first = keep_points_by_map(f.on_ray, KeepAmount::count(keep), view_of(mapper));
  std::vector<Eigen::Vector3f> kept_points;
  for (const std::uint64_t id : first) kept_points.push_back(f.points[id]);
  mapper.insert(PointSpan::from(kept_points));
  std::map<std::uint64_t, ColumnIndex> column_of;
  for (const PointOnRay& p : f.on_ray) column_of[p.point] = p.column;
  std::set<std::uint64_t> sampled;
  for (const std::uint64_t id : first)
    if (is_depth_sample(mapper.surface(), column_of.at(id))) sampled.insert(id);
  EXPECT_GT(sampled.size(), first.size() * 8 / 10);

  const std::vector<std::uint64_t> second = keep_points_by_map(f.on_ray, KeepAmount::count(keep), view_of(mapper));
  ASSERT_EQ(second.size(), keep);
  const std::set<std::uint64_t> again(second.begin(), second.end());
  for (const std::uint64_t id : sampled) EXPECT_EQ(again.count(id), 1u) << id;
  EXPECT_TRUE(std::is_sorted(second.begin(), second.end()));  // ids ascending
  // ... though their improvement is now below that of the unmeasured rays around them.
  double sampled_mean = 0, unmeasured_mean = 0;
  std::size_t unmeasured = 0;
  for (const std::uint64_t id : sampled) sampled_mean += mapper.improvement().value[column_of.at(id)];
  sampled_mean /= static_cast<double>(sampled.size());
  for (const PointOnRay& p : f.on_ray)
    if (mapper.surface().unknown[p.column]) {
      unmeasured_mean += mapper.improvement().value[p.column];
      ++unmeasured;
    }
  ASSERT_GT(unmeasured, 0u);
  unmeasured_mean /= static_cast<double>(unmeasured);
  EXPECT_LT(sampled_mean + 0.1, unmeasured_mean);
}

// The straightforward order of the header, on the public pieces: every observable point's sample flag,
// improvement, block mean and ray key; one sort of all by (cell, repeat, better), ranks within cells, the
// first `keep` by (round, better). (Two points of one ray never share a cell's rank, and different rays
// never tie on the ray key, so no tie reaches the point's own key.)
std::vector<std::uint64_t> reference_choice(const std::vector<PointOnRay>& points, std::size_t keep, const Mapper& m) {
  struct Ref {
    std::size_t cell;
    std::uint32_t repeat, round;
    bool sampled;
    float improvement, block_mean;
    std::uint64_t ray_key, id;
  };
  const GridGeometry& g = m.geometry();
  std::vector<Ref> refs;
  std::map<ColumnIndex, std::uint32_t> seen;
  for (const PointOnRay& p : points) {
    const float value = m.improvement().value[p.column];
    if (std::isnan(value)) continue;
    const float mean = m.pyramid().block_at(1, m.pyramid().block_of_column(1, p.column)).mean_improvement();
    refs.push_back({p.column, seen[p.column]++, 0, is_depth_sample(m.surface(), p.column), value,
                    std::isnan(mean) ? -std::numeric_limits<float>::infinity() : mean, rank_key(value, p.column), p.point});
  }
  keep = std::min(keep, refs.size());
  if (keep == 0) return {};
  const SamplingCells cells(seen.size(), keep, g.width());
  for (Ref& r : refs) r.cell = cells.cell_of(g.azimuth_bin_of(static_cast<ColumnIndex>(r.cell)), g.elevation_bin_of(static_cast<ColumnIndex>(r.cell)));
  const auto better = [](const Ref& a, const Ref& b) {
    if (a.sampled != b.sampled) return a.sampled;
    if (a.improvement != b.improvement) return a.improvement > b.improvement;
    if (a.block_mean != b.block_mean) return a.block_mean > b.block_mean;
    return a.ray_key > b.ray_key;
  };
  std::sort(refs.begin(), refs.end(), [&](const Ref& a, const Ref& b) {
    if (a.cell != b.cell) return a.cell < b.cell;
    if (a.repeat != b.repeat) return a.repeat < b.repeat;
    return better(a, b);
  });
  for (std::size_t k = 0; k < refs.size(); ++k) refs[k].round = k > 0 && refs[k - 1].cell == refs[k].cell ? refs[k - 1].round + 1 : 0;
  std::sort(refs.begin(), refs.end(), [&](const Ref& a, const Ref& b) {
    if (a.round != b.round) return a.round < b.round;
    return better(a, b);
  });
  std::vector<std::uint64_t> ids;
  for (std::size_t k = 0; k < keep; ++k) ids.push_back(refs[k].id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

// The fast path (cells bucketed, sorted cell by cell, nth_element) chooses the reference's set: random
// points on a small camera (64 x 48: cells of 3 and 5 do not divide it), several points on some rays, a
// map with samples, free and unseen rays, a masked corner; keeps from none to all, full and partial rounds.
TEST(PointSelection, ChoosesWhatTheStraightforwardOrderChooses) {
  PinholePresetOptions options;
  options.depth_bins = 256;
  Mapper mapper(preset_from_pinhole(test::small_camera(), options, "small"));
  std::mt19937 random(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<Eigen::Vector3f> frame;
  for (int i = 0; i < 1500; ++i) {
    const float z = 1.0f + 2.0f * unit(random);
    frame.emplace_back((unit(random) - 0.5f) * z, (unit(random) - 0.5f) * 0.75f * z, z);
  }
  PixelMask mask{64, 48, std::vector<std::uint8_t>(64 * 48, 1)};
  for (int v = 0; v < 8; ++v)
    for (int u = 0; u < 8; ++u) mask.valid[static_cast<std::size_t>(v) * 64 + static_cast<std::size_t>(u)] = 0;
  mapper.set_mask(mask);
  mapper.insert(PointSpan::from(frame));
  std::uniform_int_distribution<ColumnIndex> column(0, 64 * 48 - 1);
  std::vector<PointOnRay> points;
  for (std::uint64_t id = 0; id < 4000; ++id) points.push_back({id * 3 + 11, id % 5 == 0 && id > 0 ? points[id - 1].column : column(random)});
  for (const std::size_t keep : {std::size_t{0}, std::size_t{1}, std::size_t{37}, std::size_t{400}, std::size_t{1500},
                                 std::size_t{3000}, std::size_t{3999}, std::size_t{5000}}) {
    SCOPED_TRACE(keep);
    EXPECT_EQ(keep_points_by_map(points, KeepAmount::count(keep), view_of(mapper)), reference_choice(points, keep, mapper));
  }
}

TEST(PointSelection, RefusesAPointOutsideTheGridABadFractionAndMapsOfAnotherSize) {
  Mapper mapper(kinect_v1());
  const std::size_t columns = mapper.geometry().column_count();
  test::expect_throw_naming<InvalidInput>([&] { keep_points_by_map({{0, 0}, {7, static_cast<ColumnIndex>(columns)}}, KeepAmount::count(1), view_of(mapper)); },
                 "point 7");
  for (const double share : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()})
    test::expect_throw_naming<InvalidParameter>([&] { keep_points_by_map({{0, 0}}, KeepAmount::fraction(share), view_of(mapper)); }, "fraction");
  SurfaceMap small_surface = mapper.surface();
  small_surface.depth_m.pop_back();
  test::expect_throw_naming<InvalidInput>([&] { keep_points_by_map({{0, 0}}, KeepAmount::count(1), {mapper.geometry(), small_surface, mapper.improvement(), mapper.pyramid()}); },
                 "surface map");
  ImprovementMap small_improvement = mapper.improvement();
  small_improvement.value.pop_back();
  test::expect_throw_naming<InvalidInput>([&] { keep_points_by_map({{0, 0}}, KeepAmount::count(1), {mapper.geometry(), mapper.surface(), small_improvement, mapper.pyramid()}); },
                 "improvement map");
}

}  // namespace
}  // namespace occ_improve
