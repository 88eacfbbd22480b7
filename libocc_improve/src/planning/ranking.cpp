#include "occ_improve/planning/ranking.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <sstream>

namespace occ_improve {
namespace {

void require_same_size(const ImprovementMap& map, const SurfaceMap& surface) {
  require_shape("improvement map", map.shape(), "the surface map", surface.shape());
}

/// MurmurHash3's 32-bit finaliser: a bijection, so every column has its own spread rank.
std::uint32_t spread_rank(std::uint32_t h) {
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}

/// Unsigned key in the order of the float (larger float, larger key).
std::uint32_t ordered_bits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

}  // namespace

std::uint64_t rank_key(float value, ColumnIndex column) {
  return (std::uint64_t{ordered_bits(value)} << 32) | ~spread_rank(column);
}

namespace {
/// A histogram of the top 16 bits of the values' ordered_bits (the top of rank_key) over the eligible,
/// non-NaN values finds a bound below which none of the k largest lies, so only the few values above it
/// are sorted (the planner ranks a 640 x 480 view per shot).
struct TopBuckets {
  std::size_t eligible = 0;  ///< eligible, non-NaN values
  std::vector<std::uint32_t> histogram = std::vector<std::uint32_t>(1u << 16, 0);
  static std::uint32_t bucket(float v) { return ordered_bits(v) >> 16; }
  TopBuckets(const std::vector<float>& value, const std::uint8_t* eligible_mask) {
    for (std::size_t c = 0; c < value.size(); ++c)
      if ((!eligible_mask || eligible_mask[c]) && !std::isnan(value[c])) ++histogram[bucket(value[c])], ++eligible;
  }
  /// The largest bound whose buckets >= bound hold at least k values (all of them: 0), and how many they
  /// hold.
  std::pair<std::uint32_t, std::size_t> bound_for(std::size_t k) const {
    std::size_t above = 0;
    std::uint32_t bound = 1u << 16;
    while (bound > 0 && above < k) above += histogram[--bound];
    return {bound, above};
  }
};
}  // namespace

std::vector<ColumnIndex> best_columns(const std::vector<float>& value, const std::uint8_t* eligible, std::size_t k) {
  const std::size_t n = value.size();
  const auto takes = [&](std::size_t c) { return (!eligible || eligible[c]) && !std::isnan(value[c]); };
  const auto [bound, above] = TopBuckets(value, eligible).bound_for(k);
  struct Ranked {
    std::uint64_t key;
    ColumnIndex column;
  };
  std::vector<Ranked> candidates;
  candidates.reserve(above);
  for (std::size_t c = 0; c < n; ++c)  // the column's hash is needed only for candidates
    if (TopBuckets::bucket(value[c]) >= bound && takes(c)) {
      const auto column = static_cast<ColumnIndex>(c);
      candidates.push_back({rank_key(value[c], column), column});
    }
  k = std::min(k, candidates.size());
  const auto better = [](const Ranked& a, const Ranked& b) { return a.key > b.key; };
  std::nth_element(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(k), candidates.end(), better);
  std::sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(k), better);
  std::vector<ColumnIndex> out(k);
  for (std::size_t i = 0; i < k; ++i) out[i] = candidates[i].column;
  return out;
}

double mean_of_best_share(const std::vector<float>& value, const std::uint8_t* eligible, double share) {
  const TopBuckets buckets(value, eligible);
  const auto k = static_cast<std::size_t>(std::ceil(share * static_cast<double>(buckets.eligible)));
  if (k == 0) return 0.0;
  const auto [bound, above] = buckets.bound_for(k);
  double sum = 0;  // the values above the bound's bucket, all taken; the bucket's own, sorted
  std::vector<float> edge;
  for (std::size_t c = 0; c < value.size(); ++c) {
    if ((eligible && !eligible[c]) || std::isnan(value[c])) continue;
    const std::uint32_t b = TopBuckets::bucket(value[c]);
    if (b > bound) sum += value[c];
    else if (b == bound) edge.push_back(value[c]);
  }
  const std::size_t from_edge = k - (above - edge.size());
  std::nth_element(edge.begin(), edge.begin() + static_cast<std::ptrdiff_t>(from_edge - 1), edge.end(), std::greater<>());
  for (std::size_t i = 0; i < from_edge; ++i) sum += edge[i];
  return sum / static_cast<double>(k);
}

SamplingCells::SamplingCells(std::size_t candidates, std::size_t k, int width) {
  if (k > 0) side = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(candidates) / static_cast<double>(k))));
  across = std::max(1, (width + side - 1) / side);
}

std::vector<ColumnIndex> spread_best_columns(const std::vector<float>& value, const std::uint8_t* eligible, int width,
                                             std::size_t k) {
  std::vector<std::uint8_t> open(value.size());
  std::size_t available = 0;
  for (std::size_t c = 0; c < value.size(); ++c) {
    open[c] = (!eligible || eligible[c]) && !std::isnan(value[c]);
    available += open[c];
  }
  k = std::min(k, available);
  std::vector<ColumnIndex> out;
  if (k == 0 || width <= 0) return out;
  if (value.size() % static_cast<std::size_t>(width) != 0)
    throw InvalidInput("spread_best_columns: " + std::to_string(value.size()) + " values are not whole rows of " +
                       std::to_string(width) + " columns");
  out.reserve(k);
  const auto w = static_cast<std::size_t>(width);
  const SamplingCells cells(available, k, width);
  constexpr ColumnIndex kNone = std::numeric_limits<ColumnIndex>::max();
  struct Best {
    std::uint64_t key;
    ColumnIndex column;
  };
  std::vector<Best> best(cells.count(static_cast<int>(value.size() / w)));
  const std::size_t rows = value.size() / w, side = static_cast<std::size_t>(cells.side);
  while (out.size() < k) {  // one round: the best open column of every cell
    std::fill(best.begin(), best.end(), Best{0, kNone});
    // Row by row, the cell stepping every `side` columns (cell_of without a division per column).
    for (std::size_t v = 0, c = 0; v < rows; ++v) {
      Best* cell = best.data() + cells.cell_of(0, static_cast<int>(v));
      for (std::size_t u = 0, in_cell = 0; u < w; ++u, ++c) {
        if (in_cell == side) ++cell, in_cell = 0;
        ++in_cell;
        if (!open[c]) continue;
        const std::uint64_t key = rank_key(value[c], static_cast<ColumnIndex>(c));
        if (cell->column == kNone || key > cell->key) *cell = {key, static_cast<ColumnIndex>(c)};
      }
    }
    std::vector<Best> round;
    for (const Best& b : best)
      if (b.column != kNone) round.push_back(b);
    const std::size_t take = std::min(round.size(), k - out.size());
    const auto better = [](const Best& a, const Best& b) { return a.key > b.key; };
    std::partial_sort(round.begin(), round.begin() + static_cast<std::ptrdiff_t>(take), round.end(), better);
    for (std::size_t i = 0; i < take; ++i) {
      out.push_back(round[i].column);
      open[round[i].column] = 0;
    }
  }
  return out;
}

std::vector<RankedRay> top_rays(const ImprovementMap& map, const SurfaceMap& surface, int k) {
  detail::require_parameter(k > 0, "k", k, "> 0");
  require_same_size(map, surface);
  const std::vector<ColumnIndex> best = best_columns(map.value, nullptr, static_cast<std::size_t>(k));
  std::vector<RankedRay> rays;
  rays.reserve(best.size());
  const auto w = static_cast<ColumnIndex>(map.width);
  for (const ColumnIndex c : best)
    rays.push_back({c, static_cast<int>(c % w), static_cast<int>(c / w), map.value[c], surface.depth_m[c]});
  return rays;
}

void RegionOptions::validate() const {
  detail::require_parameter(std::isfinite(min_improvement), "min_improvement", min_improvement, "finite");
}

namespace {

/// For each position p in [lo, lo + counts.size()), the summed distance |p - x| over the members' x, from
/// their histogram `counts` (index x - lo): one pass each way instead of one per member.
std::vector<double> summed_distances(const std::vector<std::size_t>& counts) {
  const std::size_t n = counts.size();
  std::vector<double> sum(n, 0.0);
  double below = 0, carried = 0;  // members left of p, and their summed distance to p
  for (std::size_t p = 0; p < n; ++p) {
    carried += below;
    sum[p] = carried;
    below += static_cast<double>(counts[p]);
  }
  double above = 0;
  carried = 0;
  for (std::size_t p = n; p-- > 0;) {
    carried += above;
    sum[p] += carried;
    above += static_cast<double>(counts[p]);
  }
  return sum;
}

/// Bounding box, peak and medoid (L1 in columns and rows) of a region's columns; ties by rank_key.
void describe_columns(const GridGeometry& geometry, const ImprovementMap& map,
                      const std::vector<ColumnIndex>& members, Region& r) {
  r.min_u = r.min_v = std::numeric_limits<int>::max();
  r.max_u = r.max_v = std::numeric_limits<int>::min();
  ColumnIndex peak = members.front();
  for (const ColumnIndex c : members) {
    const int u = geometry.azimuth_bin_of(c), v = geometry.elevation_bin_of(c);
    r.min_u = std::min(r.min_u, u), r.max_u = std::max(r.max_u, u);
    r.min_v = std::min(r.min_v, v), r.max_v = std::max(r.max_v, v);
    if (rank_key(map.value[c], c) > rank_key(map.value[peak], peak)) peak = c;
  }
  r.peak_u = geometry.azimuth_bin_of(peak), r.peak_v = geometry.elevation_bin_of(peak);
  r.peak_improvement = map.value[peak];
  // L1 distance separates into columns and rows: a member's summed distance is su[u] + sv[v].
  std::vector<std::size_t> count_u(static_cast<std::size_t>(r.max_u - r.min_u + 1), 0);
  std::vector<std::size_t> count_v(static_cast<std::size_t>(r.max_v - r.min_v + 1), 0);
  for (const ColumnIndex c : members) {
    ++count_u[static_cast<std::size_t>(geometry.azimuth_bin_of(c) - r.min_u)];
    ++count_v[static_cast<std::size_t>(geometry.elevation_bin_of(c) - r.min_v)];
  }
  const std::vector<double> su = summed_distances(count_u), sv = summed_distances(count_v);
  const auto cost = [&](ColumnIndex c) {
    return su[static_cast<std::size_t>(geometry.azimuth_bin_of(c) - r.min_u)] +
           sv[static_cast<std::size_t>(geometry.elevation_bin_of(c) - r.min_v)];
  };
  ColumnIndex centre = members.front();
  for (const ColumnIndex c : members)
    if (cost(c) < cost(centre) || (cost(c) == cost(centre) && rank_key(map.value[c], c) > rank_key(map.value[centre], centre)))
      centre = c;
  r.centre_u = geometry.azimuth_bin_of(centre), r.centre_v = geometry.elevation_bin_of(centre);
  r.centre_direction = geometry.direction(r.centre_u, r.centre_v);
  const Eigen::Vector3d& d = r.centre_direction;
  const SphericalPoint angles = to_spherical(d.x(), d.y(), d.z());
  r.centre_azimuth_rad = angles.azimuth;
  r.centre_elevation_rad = angles.elevation;
}

}  // namespace

namespace {

// The 8-connected columns of improvement >= threshold reachable from `seed` (which must qualify) and not
// yet visited, marked visited, into `members`: the one region rule of find_regions and region_labels.
void grow_region(const GridGeometry& geometry, const ImprovementMap& map, float threshold, ColumnIndex seed,
                 std::vector<std::uint8_t>& visited, std::vector<ColumnIndex>& stack,
                 std::vector<ColumnIndex>& members) {
  const int w = map.width, h = map.height;
  visited[seed] = 1;
  stack.assign(1, seed);
  members.clear();
  while (!stack.empty()) {
    const ColumnIndex c = stack.back();
    stack.pop_back();
    members.push_back(c);
    const int a = geometry.azimuth_bin_of(c), e = geometry.elevation_bin_of(c);
    for (int de = -1; de <= 1; ++de)
      for (int da = -1; da <= 1; ++da) {
        const int na = a + da, ne = e + de;
        if (na < 0 || na >= w || ne < 0 || ne >= h) continue;
        const ColumnIndex n = geometry.column(na, ne);
        if (visited[n] || !(map.value[n] >= threshold)) continue;
        visited[n] = 1;
        stack.push_back(n);
      }
  }
}

void require_matching_grid(const GridGeometry& geometry, const ImprovementMap& map) {
  require_shape("improvement map", map.shape(), "the grid", ColumnShape::of_grid(geometry.width(), geometry.height()));
}

}  // namespace

std::vector<Region> find_regions(const GridGeometry& geometry, const ImprovementMap& map,
                                 const SurfaceMap& surface, const RegionOptions& options) {
  options.validate();
  require_same_size(map, surface);
  require_matching_grid(geometry, map);
  std::vector<std::uint8_t> visited(map.value.size(), 0);
  std::vector<ColumnIndex> stack, members;
  std::vector<Region> regions;
  for (std::size_t seed = 0; seed < map.value.size(); ++seed) {
    if (visited[seed] || !(map.value[seed] >= options.min_improvement)) continue;
    grow_region(geometry, map, options.min_improvement, static_cast<ColumnIndex>(seed), visited, stack, members);
    if (members.size() < options.min_area_columns) continue;
    Region r;
    double depth_sum = 0;
    std::size_t known = 0;
    for (const ColumnIndex c : members) {
      r.summed_improvement += map.value[c];
      if (!surface.unknown[c]) {
        depth_sum += surface.depth_m[c];
        ++known;
      }
    }
    r.area_columns = members.size();
    describe_columns(geometry, map, members, r);
    r.mean_depth_m = known ? depth_sum / static_cast<double>(known) : 0.0;
    regions.push_back(r);
  }
  std::stable_sort(regions.begin(), regions.end(),
                   [](const Region& a, const Region& b) { return a.summed_improvement > b.summed_improvement; });
  return regions;
}

std::vector<std::uint32_t> region_labels(const GridGeometry& geometry, const ImprovementMap& map,
                                         const std::vector<Region>& regions, const RegionOptions& options) {
  options.validate();
  require_matching_grid(geometry, map);
  std::vector<std::uint32_t> label(map.value.size(), 0);
  std::vector<std::uint8_t> visited(map.value.size(), 0);
  std::vector<ColumnIndex> stack, members;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const Region& r = regions[i];
    // The peak is a column of the region: growing from it gives the region's columns again.
    const bool inside = r.peak_u >= 0 && r.peak_u < map.width && r.peak_v >= 0 && r.peak_v < map.height;
    const ColumnIndex seed = inside ? geometry.column(r.peak_u, r.peak_v) : 0;
    if (!inside || visited[seed] || !(map.value[seed] >= options.min_improvement))
      throw InvalidInput("region " + std::to_string(i + 1) + " (peak " + std::to_string(r.peak_u) + "," +
                         std::to_string(r.peak_v) + ") is not a region of this map under these options");
    grow_region(geometry, map, options.min_improvement, seed, visited, stack, members);
    if (members.size() != r.area_columns)
      throw InvalidInput("region " + std::to_string(i + 1) + " has " + std::to_string(r.area_columns) +
                         " columns, the map's region at its peak " + std::to_string(members.size()));
    for (const ColumnIndex c : members) label[c] = static_cast<std::uint32_t>(i + 1);
  }
  return label;
}

void StopCriteria::validate() const {
  detail::require_parameter(std::isfinite(total_improvement_below) && total_improvement_below >= 0,
                            "total_improvement_below", total_improvement_below, "finite and >= 0");
  detail::require_parameter(std::isfinite(best_region_below) && best_region_below >= 0, "best_region_below",
                            best_region_below, "finite and >= 0");
  detail::require_parameter(std::isfinite(ray_floor) && ray_floor >= 0, "ray_floor", ray_floor, "finite and >= 0");
}

StopSignal stop_signal(const ImprovementMap& map, const std::vector<Region>& regions, const StopCriteria& criteria) {
  criteria.validate();
  require_shape("improvement map", map.shape());
  StopSignal s{false, 0.0, 0.0, {}};
  for (const float v : map.value)
    if (v >= criteria.ray_floor) s.total_improvement += v;
  for (const Region& r : regions) s.best_region_improvement = std::max(s.best_region_improvement, r.summed_improvement);
  std::ostringstream why;
  if (s.total_improvement < criteria.total_improvement_below) {
    s.stop = true;
    why << "total expected improvement " << s.total_improvement << " < " << criteria.total_improvement_below;
  } else if (s.best_region_improvement < criteria.best_region_below) {
    s.stop = true;
    why << "best region " << s.best_region_improvement << " < " << criteria.best_region_below;
  } else {
    why << "continue: total " << s.total_improvement << ", best region " << s.best_region_improvement;
  }
  s.reason = why.str();
  return s;
}

void ProgressCriteria::validate() const {
  detail::require_parameter(std::isfinite(min_relative_gain) && min_relative_gain >= 0 && min_relative_gain < 1,
                            "min_relative_gain", min_relative_gain, "in [0, 1)");
  detail::require_parameter(patience >= 1, "patience", patience, ">= 1");
}

StopMonitor::StopMonitor(const StopCriteria& criteria, const ProgressCriteria& progress)
    : criteria_(criteria), progress_(progress) {
  criteria.validate();
  progress.validate();
}

StopSignal StopMonitor::update(const ImprovementMap& map, const std::vector<Region>& regions) {
  StopSignal s = stop_signal(map, regions, criteria_);
  if (previous_total_ >= 0) {
    const double gain = previous_total_ - s.total_improvement;
    stalled_frames_ = gain < progress_.min_relative_gain * previous_total_ ? stalled_frames_ + 1 : 0;
  }
  previous_total_ = s.total_improvement;
  if (!s.stop && stalled_frames_ >= progress_.patience) {
    std::ostringstream why;
    why << "progress stalled: total expected improvement " << s.total_improvement << " fell by less than "
        << 100 * progress_.min_relative_gain << "% per frame for " << stalled_frames_ << " frames";
    s.stop = true;
    s.reason = why.str();
  }
  return s;
}

}  // namespace occ_improve
