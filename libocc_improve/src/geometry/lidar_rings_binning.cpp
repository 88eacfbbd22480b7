#include "occ_improve/geometry/lidar_rings_binning.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace occ_improve {

using detail::require_parameter;

namespace {

const GeometryParams& validated(const GeometryParams& p) {
  require_parameter(std::isfinite(p.azimuth_min_rad) && p.azimuth_min_rad >= -M_PI, "azimuth_min_rad",
                    p.azimuth_min_rad, "finite and >= -pi");
  require_parameter(std::isfinite(p.azimuth_max_rad) && p.azimuth_max_rad <= M_PI &&
                        p.azimuth_max_rad > p.azimuth_min_rad,
                    "azimuth_max_rad", p.azimuth_max_rad, "finite, <= pi and > azimuth_min_rad");
  const std::vector<double>& rings = p.row_elevations_rad;
  require_parameter(rings.size() >= 2, "row_elevations_rad size", static_cast<double>(rings.size()),
                    ">= 2 (one elevation per ring)");
  require_parameter(static_cast<int>(rings.size()) == p.elevation_bins, "elevation_bins", p.elevation_bins,
                    "equal to the number of rings in row_elevations_rad");
  for (std::size_t i = 0; i < rings.size(); ++i) {
    const std::string name = "row_elevations_rad[" + std::to_string(i) + "]";
    require_parameter(std::isfinite(rings[i]), name.c_str(), rings[i], "finite");
    if (i > 0)
      require_parameter(rings[i] > rings[i - 1], name.c_str(), rings[i],
                        "> the ring before it (strictly increasing: rows top to bottom, y down)");
  }
  // The outer rows reach half a gap beyond the outer rings.
  const double top = rings[0] - 0.5 * (rings[1] - rings[0]);
  const double bottom = rings.back() + 0.5 * (rings.back() - rings[rings.size() - 2]);
  require_parameter(top > -M_PI / 2, "row_elevations_rad[0]", rings[0],
                    "with its row's upper edge (half the gap to the next ring above it) > -pi/2");
  require_parameter(bottom < M_PI / 2, "row_elevations_rad (last)", rings.back(),
                    "with its row's lower edge (half the gap to the ring before) < pi/2");
  return p;
}

}  // namespace

// validated() in both arguments: their order of evaluation is unspecified, and GCC built the rows first,
// from_centres reading an empty table (a crash from Python: GeometryParams(angular_binning="lidar_rings")).
LidarRingsBinning::LidarRingsBinning(const GeometryParams& p)
    : SphericalBinning(BinAxis(validated(p).azimuth_min_rad, p.azimuth_max_rad, p.azimuth_bins),
                     BinAxis::from_centres(validated(p).row_elevations_rad)) {}

double LidarRingsBinning::curvature_angle_rad() const {
  double widest_row = 0;
  for (int i = 0; i < vertical().bins(); ++i) widest_row = std::max(widest_row, vertical().width(i));
  return std::hypot(horizontal().width(), widest_row);
}

}  // namespace occ_improve
