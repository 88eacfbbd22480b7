#include "occ_improve/ranking.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace occ_improve {
namespace {

void require_same_size(const ImprovementMap& map, const SurfaceMap& surface) {
  if (map.width != surface.width || map.height != surface.height || map.value.size() != surface.size() ||
      map.value.size() != static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height))
    throw InvalidInput("improvement map (" + std::to_string(map.width) + " x " + std::to_string(map.height) +
                       ") and surface map (" + std::to_string(surface.width) + " x " + std::to_string(surface.height) +
                       ") differ in size");
}

}  // namespace

std::vector<RankedRay> top_rays(const ImprovementMap& map, const SurfaceMap& surface, int k) {
  detail::require_parameter(k > 0, "k", k, "> 0");
  require_same_size(map, surface);
  // Columns that are not observable hold NaN (improvement.hpp): never ranked.
  std::vector<ColumnIndex> order;
  order.reserve(map.value.size());
  for (std::size_t c = 0; c < map.value.size(); ++c)
    if (!std::isnan(map.value[c])) order.push_back(static_cast<ColumnIndex>(c));
  const auto better = [&](ColumnIndex a, ColumnIndex b) {
    return map.value[a] > map.value[b] || (map.value[a] == map.value[b] && a < b);
  };
  const std::size_t n = std::min(order.size(), static_cast<std::size_t>(k));
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n), order.end(), better);
  std::vector<RankedRay> rays;
  rays.reserve(n);
  const auto w = static_cast<ColumnIndex>(map.width);
  for (std::size_t r = 0; r < n; ++r) {
    const ColumnIndex c = order[r];
    rays.push_back({c, static_cast<int>(c % w), static_cast<int>(c / w), map.value[c], surface.depth_m[c]});
  }
  return rays;
}

void RegionOptions::validate() const {
  detail::require_parameter(std::isfinite(min_improvement), "min_improvement", min_improvement, "finite");
}

std::vector<Region> find_regions(const SphericalGeometry& geometry, const ImprovementMap& map,
                                 const SurfaceMap& surface, const RegionOptions& options) {
  options.validate();
  require_same_size(map, surface);
  if (map.width != geometry.width() || map.height != geometry.height())
    throw InvalidInput("improvement map (" + std::to_string(map.width) + " x " + std::to_string(map.height) +
                       ") does not match the grid (" + std::to_string(geometry.width()) + " x " +
                       std::to_string(geometry.height()) + ")");
  const int w = map.width, h = map.height;
  std::vector<std::uint8_t> visited(map.value.size(), 0);
  std::vector<ColumnIndex> stack;
  std::vector<Region> regions;
  for (std::size_t seed = 0; seed < map.value.size(); ++seed) {
    if (visited[seed] || !(map.value[seed] >= options.min_improvement)) continue;
    // Flood fill, 8-connected.
    Region r{0.0, 0, map.value[seed], 0.0, 0.0, 0.0, 0.0, Eigen::Vector3d::Zero(), 0.0};
    double depth_sum = 0;
    std::size_t known = 0;
    visited[seed] = 1;
    stack.assign(1, static_cast<ColumnIndex>(seed));
    while (!stack.empty()) {
      const ColumnIndex c = stack.back();
      stack.pop_back();
      const int a = geometry.azimuth_bin_of(c), e = geometry.elevation_bin_of(c);
      const float v = map.value[c];
      r.summed_improvement += v;
      ++r.area_columns;
      r.peak_improvement = std::max(r.peak_improvement, v);
      r.centroid_horizontal += geometry.azimuth().centre(a);
      r.centroid_vertical += geometry.elevation().centre(e);
      if (!surface.unknown[c]) {
        depth_sum += surface.depth_m[c];
        ++known;
      }
      for (int de = -1; de <= 1; ++de)
        for (int da = -1; da <= 1; ++da) {
          const int na = a + da, ne = e + de;
          if (na < 0 || na >= w || ne < 0 || ne >= h) continue;
          const ColumnIndex n = geometry.column(na, ne);
          if (visited[n] || !(map.value[n] >= options.min_improvement)) continue;
          visited[n] = 1;
          stack.push_back(n);
        }
    }
    if (r.area_columns < options.min_area_columns) continue;
    r.centroid_horizontal /= static_cast<double>(r.area_columns);
    r.centroid_vertical /= static_cast<double>(r.area_columns);
    r.centroid_direction = geometry.direction_at(r.centroid_horizontal, r.centroid_vertical);
    const Eigen::Vector3d& d = r.centroid_direction;
    const SphericalPoint angles = to_spherical(d.x(), d.y(), d.z());
    r.centroid_azimuth_rad = angles.azimuth;
    r.centroid_elevation_rad = angles.elevation;
    r.mean_depth_m = known ? depth_sum / static_cast<double>(known) : 0.0;
    regions.push_back(r);
  }
  std::stable_sort(regions.begin(), regions.end(),
                   [](const Region& a, const Region& b) { return a.summed_improvement > b.summed_improvement; });
  return regions;
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
  if (map.value.size() != static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height))
    throw InvalidInput("improvement map holds " + std::to_string(map.value.size()) + " values for " +
                       std::to_string(map.width) + " x " + std::to_string(map.height) + " rays");
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
