#pragma once
// Unit mistakes in a frame's depths or points, told before they are inserted: a cloud in millimetres given
// as metres put every return beyond the grid's range (the map free to its end, 100 times as slow) or, at
// ~340 m and beyond, a sensor sigma so wide that its Gaussian reached back into the grid and made a phantom
// wall at the grid's end; depths in metres read as millimetres crammed the scene near the sensor.
// A median is judged, not each value: a few far or near returns are the scene's own.
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/integrate/integrate.hpp"

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// A usual unit of depth, as a scale to metres.
struct DepthUnit {
  double scale;
  const char* name;  ///< "millimetres", "metres"
};

/// Nearer than this no depth camera measures; a median below it is a unit mistake, as one beyond the grid.
constexpr double kNearestPlausibleDepthM = 0.05;
/// Fewer returns than this say nothing about the unit.
constexpr std::size_t kReturnsToJudgeUnit = 100;

/// A unit mistake: the median of some depths or ranges, in metres under the scale given, and the usual unit
/// that would put it inside the grid's plausible depth range [nearest_m, depth_max_m].
struct UnitMistake {
  double median_m, nearest_m;
  DepthUnit likely;
  /// "<median> m, outside the grid's plausible depth range [a, b] m"
  std::string outside(const GeometryParams& grid) const;
  /// "the points' median range is <outside>: they look like <unit> (times <scale> gives metres)"
  std::string about_points(const GeometryParams& grid) const;
};

/// The mistake, when `scale` puts the median of `values` (0, NaN, inf: none) outside the grid's plausible
/// depth range and one of the usual units (millimetres, metres) would put it inside. Nothing otherwise, and
/// for fewer than kReturnsToJudgeUnit values.
std::optional<UnitMistake> unit_mistake(std::vector<float> values, double scale, const GeometryParams& grid);

/// The same for points in metres, judged by their ranges from the sensor.
std::optional<UnitMistake> point_unit_mistake(PointSpan points, const GeometryParams& grid);

}  // namespace occ_improve
