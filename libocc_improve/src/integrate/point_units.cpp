#include "occ_improve/integrate/point_units.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>

namespace occ_improve {

namespace {
constexpr DepthUnit kDepthUnits[] = {{1e-3, "millimetres"}, {1.0, "metres"}};
}  // namespace

std::string UnitMistake::outside(const GeometryParams& grid) const {
  std::ostringstream m;
  m << median_m << " m, outside the grid's plausible depth range [" << nearest_m << ", " << grid.depth_max_m << "] m";
  return m.str();
}

std::string UnitMistake::about_points(const GeometryParams& grid) const {
  std::ostringstream m;
  m << "the points' median range is " << outside(grid) << ": they look like " << likely.name << " (times " << likely.scale
    << " gives metres)";
  return m.str();
}

std::optional<UnitMistake> unit_mistake(std::vector<float> values, double scale, const GeometryParams& grid) {
  values.erase(std::remove_if(values.begin(), values.end(), [](float v) { return !(v > 0.0f && std::isfinite(v)); }),
               values.end());
  if (values.size() < kReturnsToJudgeUnit) return std::nullopt;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  const double median = *middle;
  const double nearest_m = std::max(grid.depth_min_m, kNearestPlausibleDepthM);
  const auto plausible = [&](double s) { return median * s >= nearest_m && median * s <= grid.depth_max_m; };
  if (plausible(scale)) return std::nullopt;
  for (const DepthUnit& unit : kDepthUnits)
    if (unit.scale != scale && plausible(unit.scale)) return UnitMistake{median * scale, nearest_m, unit};
  return std::nullopt;
}

std::optional<UnitMistake> point_unit_mistake(PointSpan points, const GeometryParams& grid) {
  std::vector<float> ranges(points.count);
  for (std::size_t i = 0; i < points.count; ++i) {
    const float* p = points.xyz + i * points.stride_floats;
    ranges[i] = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  }
  return unit_mistake(std::move(ranges), 1.0, grid);
}

}  // namespace occ_improve
