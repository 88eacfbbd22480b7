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
  std::uint64_t ray_key, point;
  float improvement, block_mean;
  ColumnIndex column;
  std::uint32_t u, v;    ///< the column's position in the grid
  std::uint32_t cell;    ///< its SamplingCells cell (cells <= columns < 2^32)
  std::uint32_t repeat;  ///< how many points of the same ray come before it
  std::uint32_t round;   ///< its rank within its cell: the round that takes it
  bool sampled;          ///< its ray holds a depth sample (is_depth_sample)
};

// Better first, by ray (header, "better"): a ray with a sample, then the ray's improvement, its block's
// mean improvement, its spread rank. No two rays tie on the spread rank (a bijection of the column), and
// two points of one ray differ in `repeat` and so in `round`, which every order compares first: the
// point's own key is never needed.
bool better(const Candidate& a, const Candidate& b) {
  if (a.sampled != b.sampled) return a.sampled;
  if (a.improvement != b.improvement) return a.improvement > b.improvement;
  if (a.block_mean != b.block_mean) return a.block_mean > b.block_mean;
  return a.ray_key > b.ray_key;
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

// Integer division by a fixed divisor for every index below `count`, as a table (a division per point
// and axis was most of the choice's time on a whole frame).
std::vector<std::uint32_t> quotients(int count, int divisor) {
  std::vector<std::uint32_t> q(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) q[static_cast<std::size_t>(i)] = static_cast<std::uint32_t>(i / divisor);
  return q;
}

// The mean improvement of every block of the tie-breaking level, NaN (which the comparator must never
// see: a pyramid out of step with the map) as -infinity.
std::vector<float> block_means(const ImprovementPyramid& pyramid) {
  std::vector<float> means(pyramid.block_count(kTieLevel));
  for (std::size_t b = 0; b < means.size(); ++b) {
    const float mean = pyramid.block_at(kTieLevel, b).mean_improvement();
    means[b] = std::isnan(mean) ? -std::numeric_limits<float>::infinity() : mean;
  }
  return means;
}

// The observable points' candidates (NaN improvement: not observable, never kept) and how many distinct
// rays they fall in.
std::vector<Candidate> candidates_of(const std::vector<PointOnRay>& points, const MapView& map, std::size_t& rays) {
  const GridGeometry& g = map.geometry;
  const int block = ImprovementPyramid::block_size(kTieLevel);
  const std::vector<std::uint32_t> block_x = quotients(g.width(), block), block_y = quotients(g.height(), block);
  const std::size_t blocks_across = static_cast<std::size_t>(map.pyramid.blocks_x(kTieLevel));
  const std::vector<float> means = block_means(map.pyramid);
  std::vector<Candidate> candidates;
  candidates.reserve(points.size());
  std::vector<std::uint32_t> points_of_ray(g.column_count(), 0);
  rays = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    poll_stop(k);
    const PointOnRay& p = points[k];
    const float value = map.improvement.value[p.column];
    if (std::isnan(value)) continue;  // not observable (improvement.hpp): never kept
    const std::uint32_t v = p.column / static_cast<ColumnIndex>(g.width()), u = p.column - v * static_cast<ColumnIndex>(g.width());
    const float block_mean = means[block_y[v] * blocks_across + block_x[u]];
    const std::uint32_t repeat = points_of_ray[p.column]++;
    if (repeat == 0) ++rays;
    candidates.push_back({rank_key(value, p.column), p.point, value, block_mean, p.column, u, v, 0, repeat, 0,
                          is_depth_sample(map.surface, p.column)});
  }
  return candidates;
}

// Sets every candidate's cell of `cells`.
void assign_cells(std::vector<Candidate>& candidates, const SamplingCells& cells, const GridGeometry& g) {
  const std::vector<std::uint32_t> cell_x = quotients(g.width(), cells.side), cell_y = quotients(g.height(), cells.side);
  const auto across = static_cast<std::uint32_t>(cells.across);
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    poll_stop(k);
    Candidate& c = candidates[k];
    c.cell = cell_y[c.v] * across + cell_x[c.u];
  }
}

// Sets every candidate's `round`, its rank within its cell in the cell's order: distinct rays before a
// second point of one ray, then better first. The candidates are grouped by cell (a counting sort of their
// positions) and sorted cell by cell: a cell holds a few dozen, so this costs a fraction of one sort of all.
void rank_within_cells(std::vector<Candidate>& candidates, std::size_t cell_count) {
  std::vector<std::size_t> begin(cell_count + 1, 0);
  for (const Candidate& c : candidates) ++begin[c.cell + 1];
  for (std::size_t c = 0; c < cell_count; ++c) begin[c + 1] += begin[c];
  std::vector<std::size_t> next(begin.begin(), begin.end() - 1);
  std::vector<std::uint32_t> order(candidates.size());
  for (std::size_t k = 0; k < candidates.size(); ++k) order[next[candidates[k].cell]++] = static_cast<std::uint32_t>(k);
  const auto in_cell_order = [&](std::uint32_t a, std::uint32_t b) {
    const Candidate &x = candidates[a], &y = candidates[b];
    if (x.repeat != y.repeat) return x.repeat < y.repeat;
    return better(x, y);
  };
  for (std::size_t c = 0; c < cell_count; ++c) {
    poll_stop(c, 1024);
    const auto first = order.begin() + static_cast<std::ptrdiff_t>(begin[c]);
    const auto end = order.begin() + static_cast<std::ptrdiff_t>(begin[c + 1]);
    std::sort(first, end, in_cell_order);
    for (auto it = first; it != end; ++it) candidates[*it].round = static_cast<std::uint32_t>(it - first);
  }
}

// The candidates (by position) of the rounds that hold the first `keep`: every round before the one
// where the count reaches `keep`, and that one (whose cells are then chosen among by `better`).
std::vector<std::uint32_t> first_rounds(const std::vector<Candidate>& candidates, std::size_t keep) {
  std::vector<std::size_t> per_round;  // per_round[r]: candidates of round r (cells with more than r)
  for (const Candidate& c : candidates) {
    if (c.round >= per_round.size()) per_round.resize(c.round + 1, 0);
    ++per_round[c.round];
  }
  std::uint32_t rounds = 0;
  for (std::size_t taken = 0; taken < keep; ++rounds) taken += per_round[rounds];
  std::vector<std::uint32_t> out;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    poll_stop(k);
    if (candidates[k].round < rounds) out.push_back(static_cast<std::uint32_t>(k));
  }
  return out;
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
  if (points.size() > std::numeric_limits<std::uint32_t>::max())  // candidates are ranked by 32-bit positions
    throw InvalidInput("keep_points_by_map: " + std::to_string(points.size()) + " points (at most 2^32 - 1 at once)");
  std::size_t rays = 0;
  std::vector<Candidate> candidates = candidates_of(points, map, rays);
  const std::size_t keep =
      amount.is_fraction ? static_cast<std::size_t>(std::llround(amount.share * static_cast<double>(candidates.size())))
                         : std::min(amount.points, candidates.size());
  if (keep == 0) return {};
  // About one kept point per cell (the cells need the count of distinct rays, known only now).
  const SamplingCells cells(rays, keep, map.geometry.width());
  assign_cells(candidates, cells, map.geometry);
  rank_within_cells(candidates, cells.count(map.geometry.height()));
  std::vector<std::uint32_t> ranked = first_rounds(candidates, keep);
  // Round by round; within a round, the cells whose candidate is better first (a selection: the kept set
  // needs no order among itself). The order is strict (two points of one ray never share a cell's round,
  // and rank_key's spread rank is a bijection of the column), so the kept set is one and the same
  // whatever the algorithm: PointSelection.ChoosesWhatTheStraightforwardOrderChooses checks it.
  const auto last = ranked.begin() + static_cast<std::ptrdiff_t>(keep);
  std::nth_element(ranked.begin(), last - 1, ranked.end(), [&](std::uint32_t a, std::uint32_t b) {
    const Candidate &x = candidates[a], &y = candidates[b];
    if (x.round != y.round) return x.round < y.round;
    return better(x, y);
  });
  std::vector<std::uint64_t> kept;
  kept.reserve(keep);
  for (auto k = ranked.begin(); k != last; ++k) kept.push_back(candidates[*k].point);
  std::sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace occ_improve
