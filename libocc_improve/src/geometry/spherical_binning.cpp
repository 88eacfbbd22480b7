#include "occ_improve/geometry/spherical_binning.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/geometry.hpp"

#include <cmath>

namespace occ_improve {

using detail::require_parameter;

namespace {

const GeometryParams& validated(const GeometryParams& p) {
  require_parameter(std::isfinite(p.azimuth_min_rad) && p.azimuth_min_rad > -M_PI, "azimuth_min_rad",
                    p.azimuth_min_rad, "finite and > -pi");
  require_parameter(std::isfinite(p.azimuth_max_rad) && p.azimuth_max_rad <= M_PI &&
                        p.azimuth_max_rad > p.azimuth_min_rad,
                    "azimuth_max_rad", p.azimuth_max_rad, "finite, <= pi and > azimuth_min_rad");
  require_parameter(std::isfinite(p.elevation_min_rad) && p.elevation_min_rad > -M_PI / 2, "elevation_min_rad",
                    p.elevation_min_rad, "finite and > -pi/2");
  require_parameter(std::isfinite(p.elevation_max_rad) && p.elevation_max_rad < M_PI / 2 &&
                        p.elevation_max_rad > p.elevation_min_rad,
                    "elevation_max_rad", p.elevation_max_rad, "finite, < pi/2 and > elevation_min_rad");
  return p;
}

}  // namespace

// validated() in both arguments: the order in which a call's arguments are evaluated is unspecified.
SphericalBinning::SphericalBinning(const GeometryParams& p)
    : AngularBinning(BinAxis(validated(p).azimuth_min_rad, p.azimuth_max_rad, p.azimuth_bins),
                     BinAxis(validated(p).elevation_min_rad, p.elevation_max_rad, p.elevation_bins)) {}

bool SphericalBinning::position(double x, double y, double z, double& h, double& v, double& depth) const {
  const SphericalPoint s = to_spherical(x, y, z);
  h = s.azimuth;
  v = s.elevation;
  depth = s.rho;
  return true;
}

Eigen::Vector3d SphericalBinning::direction_at(double h, double v) const { return from_spherical({1.0, h, v}); }

double SphericalBinning::curvature_angle_rad() const { return std::hypot(horizontal().width(), vertical().width()); }

}  // namespace occ_improve
