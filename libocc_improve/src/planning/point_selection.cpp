#include "occ_improve/planning/point_selection.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/planning/ranking.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace occ_improve {

namespace {

constexpr int kTieLevel = 1;  ///< pyramid level of the tie-breaking block (4 x 4 columns)

struct Candidate {
  bool sampled;  ///< its ray holds a depth sample (is_depth_sample)
  float improvement, block_mean;
  std::uint64_t ray_key, point_key;
  ColumnIndex column;
  std::size_t cell;      ///< its SamplingCells cell
  std::uint32_t repeat;  ///< how many points of the same ray come before it
  std::uint32_t round;   ///< its rank within its cell: the round that takes it
  std::uint64_t point;
};

// Better first, by ray (header, "better"): a ray with a sample, then the ray's improvement, its block's
// mean improvement, its spread rank, then the point's own spread rank.
bool better(const Candidate& a, const Candidate& b) {
  if (a.sampled != b.sampled) return a.sampled;
  if (a.improvement != b.improvement) return a.improvement > b.improvement;
  if (a.block_mean != b.block_mean) return a.block_mean > b.block_mean;
  if (a.ray_key != b.ray_key) return a.ray_key > b.ray_key;
  return a.point_key > b.point_key;
}

void check_maps(const std::vector<PointOnRay>& points, const MapView& map) {
  const GridGeometry& g = map.geometry;
  const ColumnShape grid = ColumnShape::of_grid(g.width(), g.height());
  require_shape("keep_points_by_map: surface map", map.surface.shape(), "the grid", grid);
  require_shape("keep_points_by_map: improvement map", map.improvement.shape(), "the grid", grid);
  require_shape("keep_points_by_map: improvement pyramid", map.pyramid.shape(), "the grid", grid);
  for (const PointOnRay& p : points)
    if (p.column >= g.column_count())
      throw InvalidInput("keep_points_by_map: point " + std::to_string(p.point) + " falls in column " +
                         std::to_string(p.column) + ", outside the grid's " + std::to_string(g.column_count()));
}

// A spread key from a 64-bit id (rank_key hashes 32 bits: the halves folded, so ids 2^32 apart differ).
std::uint64_t point_key(std::uint64_t id) {
  return rank_key(0.0f, static_cast<ColumnIndex>(id ^ (id >> 32) ^ (id >> 40)));
}

// The observable points' candidates (NaN improvement: not observable, never kept) and how many distinct
// rays they fall in.
std::vector<Candidate> candidates_of(const std::vector<PointOnRay>& points, const MapView& map, std::size_t& rays) {
  std::vector<Candidate> candidates;
  candidates.reserve(points.size());
  std::vector<std::uint32_t> points_of_ray(map.geometry.column_count(), 0);
  rays = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    poll_stop(k);
    const PointOnRay& p = points[k];
    const float value = map.improvement.value[p.column];
    if (std::isnan(value)) continue;  // not observable (improvement.hpp): never kept
    const float mean = map.pyramid.block_at(kTieLevel, map.pyramid.block_of_column(kTieLevel, p.column)).mean_improvement();
    // A pyramid out of step with the map could give NaN, which the comparator must never see.
    const float block_mean = std::isnan(mean) ? -std::numeric_limits<float>::infinity() : mean;
    const std::uint32_t repeat = points_of_ray[p.column]++;
    if (repeat == 0) ++rays;
    candidates.push_back({is_depth_sample(map.surface, p.column), value, block_mean, rank_key(value, p.column),
                          point_key(p.point), p.column, 0, repeat, 0, p.point});
  }
  return candidates;
}

}  // namespace

std::vector<PointOnRay> points_on_rays(PointSpan points, const GridGeometry& geometry) {
  std::vector<PointOnRay> out;
  out.reserve(points.count);
  for (std::size_t i = 0; i < points.count; ++i) {
    poll_stop(i);
    const float* p = points.xyz + i * points.stride_floats;
    ColumnIndex column = 0;
    if (geometry.column_of(p[0], p[1], p[2], column)) out.push_back({i, column});
  }
  return out;
}

std::vector<std::uint64_t> keep_points_by_map(const std::vector<PointOnRay>& points, KeepAmount amount,
                                              const MapView& map) {
  if (amount.is_fraction)
    detail::require_parameter(amount.share >= 0.0 && amount.share <= 1.0, "fraction", amount.share, "in [0, 1]");
  check_maps(points, map);
  std::size_t rays = 0;
  std::vector<Candidate> candidates = candidates_of(points, map, rays);
  const std::size_t keep =
      amount.is_fraction ? static_cast<std::size_t>(std::llround(amount.share * static_cast<double>(candidates.size())))
                         : std::min(amount.points, candidates.size());
  if (keep == 0) return {};
  // About one kept point per cell (the cells need the count of distinct rays, known only now).
  const GridGeometry& g = map.geometry;
  const SamplingCells cells(rays, keep, g.width());
  for (Candidate& c : candidates) c.cell = cells.cell_of(g.azimuth_bin_of(c.column), g.elevation_bin_of(c.column));
  // Within a cell: distinct rays before a second point of one ray, then better first.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    if (a.cell != b.cell) return a.cell < b.cell;
    if (a.repeat != b.repeat) return a.repeat < b.repeat;
    return better(a, b);
  });
  for (std::size_t k = 0; k < candidates.size(); ++k)
    candidates[k].round = k > 0 && candidates[k - 1].cell == candidates[k].cell ? candidates[k - 1].round + 1 : 0;
  // Round by round; within a round, the cells whose candidate is better first.
  const auto last = candidates.begin() + static_cast<std::ptrdiff_t>(keep);
  std::partial_sort(candidates.begin(), last, candidates.end(), [](const Candidate& a, const Candidate& b) {
    if (a.round != b.round) return a.round < b.round;
    return better(a, b);
  });
  std::vector<std::uint64_t> kept;
  kept.reserve(keep);
  for (auto c = candidates.begin(); c != last; ++c) kept.push_back(c->point);
  return kept;
}

}  // namespace occ_improve
