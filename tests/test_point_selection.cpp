// keep_points_by_map (point_selection.hpp): which points of a frame to keep by the map.
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/planning/point_selection.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
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
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    ColumnIndex c = 0;
    if (g.column_of(f.points[i].x(), f.points[i].y(), f.points[i].z(), c)) f.on_ray.push_back({i, c});
  }
  return f;
}

TEST(PointSelection, KeepsAsManyDistinctPointsAsAskedOnePerCellDeterministically) {
  Mapper mapper(kinect_v1());
  const Frame f = scene_on(mapper.geometry());
  ASSERT_GT(f.on_ray.size(), 100000u);
  const std::size_t keep = f.on_ray.size() / 20;
  const std::vector<std::uint64_t> kept = keep_points_by_map(f.on_ray, keep, view_of(mapper));
  ASSERT_EQ(kept.size(), keep);
  EXPECT_EQ(std::set<std::uint64_t>(kept.begin(), kept.end()).size(), keep);
  // Every ray ties on an empty map: the jittered grid puts at most one point in a cell.
  const SamplingCells cells(f.on_ray.size(), keep, mapper.geometry().width());
  std::map<std::uint64_t, ColumnIndex> column_of;
  for (const PointOnRay& p : f.on_ray) column_of[p.point] = p.column;
  std::map<std::size_t, int> per_cell;
  for (const std::uint64_t id : kept) {
    const ColumnIndex c = column_of.at(id);
    EXPECT_EQ(++per_cell[cells.cell_of(mapper.geometry().azimuth_bin_of(c), mapper.geometry().elevation_bin_of(c))], 1);
  }
  EXPECT_EQ(keep_points_by_map(f.on_ray, keep, view_of(mapper)), kept);
  EXPECT_EQ(keep_points_by_map(f.on_ray, f.on_ray.size() + 5, view_of(mapper)).size(), f.on_ray.size());
  EXPECT_TRUE(keep_points_by_map(f.on_ray, 0, view_of(mapper)).empty());
  EXPECT_TRUE(keep_points_by_map({}, 10, view_of(mapper)).empty());
}

// Once the kept points are in the map, the same choice keeps every one whose ray became a sample again,
// though their improvement (0.138) is now below their unmeasured neighbours' (0.324): the rays beside a
// sample are predicted from it.
TEST(PointSelection, ACellsSampleIsKeptAgainBeforeTheRaysBesideIt) {
  Mapper mapper(kinect_v1());
  const Frame f = scene_on(mapper.geometry());
  const std::size_t keep = f.on_ray.size() / 20;
  const std::vector<std::uint64_t> first = keep_points_by_map(f.on_ray, keep, view_of(mapper));
  std::vector<Eigen::Vector3f> kept_points;
  for (const std::uint64_t id : first) kept_points.push_back(f.points[id]);
  mapper.insert(PointSpan::from(kept_points));
  std::map<std::uint64_t, ColumnIndex> column_of;
  for (const PointOnRay& p : f.on_ray) column_of[p.point] = p.column;
  std::set<std::uint64_t> sampled;
  for (const std::uint64_t id : first)
    if (is_depth_sample(mapper.surface(), column_of.at(id))) sampled.insert(id);
  EXPECT_GT(sampled.size(), first.size() * 8 / 10);

  const std::vector<std::uint64_t> second = keep_points_by_map(f.on_ray, keep, view_of(mapper));
  ASSERT_EQ(second.size(), keep);
  const std::set<std::uint64_t> again(second.begin(), second.end());
  for (const std::uint64_t id : sampled) EXPECT_EQ(again.count(id), 1u) << id;
  // Samples first, best first: the sampled ones lead the order.
  for (std::size_t k = 0; k < sampled.size(); ++k) EXPECT_EQ(sampled.count(second[k]), 1u) << k;
  const float sample_level = mapper.improvement().value[column_of.at(*sampled.begin())];
  EXPECT_LT(sample_level, 0.2f);
}

TEST(PointSelection, RefusesAPointOutsideTheGridAndMapsOfAnotherSize) {
  Mapper mapper(kinect_v1());
  const std::size_t columns = mapper.geometry().column_count();
  try {
    keep_points_by_map({{0, 0}, {7, static_cast<ColumnIndex>(columns)}}, 1, view_of(mapper));
    FAIL() << "a column outside the grid was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("point 7"), std::string::npos) << e.what();
  }
  SurfaceMap small = mapper.surface();
  small.depth_m.pop_back();
  const MapView bad{mapper.geometry(), small, mapper.improvement(), mapper.pyramid()};
  EXPECT_THROW(keep_points_by_map({{0, 0}}, 1, bad), InvalidInput);
}

}  // namespace
}  // namespace occ_improve
