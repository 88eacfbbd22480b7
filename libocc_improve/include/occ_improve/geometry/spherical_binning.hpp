#pragma once
// The paper's binning (CONVENTIONS 2): columns uniform in azimuth theta = atan2(x, z) and elevation
// phi = atan2(y, hypot(x, z)) over [azimuth_min_rad, azimuth_max_rad) x [elevation_min_rad,
// elevation_max_rad), radians; the depth coordinate is the range. Sigmas: sigma_azimuth_rad, sigma_elevation_rad.
#include "occ_improve/geometry/angular_binning.hpp"

namespace occ_improve {

class SphericalBinning : public AngularBinning {
public:
  /// Validates the angular ranges (InvalidParameter naming the field).
  explicit SphericalBinning(const GeometryParams& params);
  const char* tag() const override { return AngularBinning::spherical; }
  AngularUnit unit() const override { return AngularUnit::radians; }
  bool position(double x, double y, double z, double& h, double& v, double& depth) const override;
  Eigen::Vector3d direction_at(double h, double v) const override;
  Eigen::Vector3d point_at(double h, double v, double depth) const override { return direction_at(h, v) * depth; }
  double curvature_angle_rad() const override;

protected:
  /// Spherical positions over other axes (lidar_rings).
  SphericalBinning(BinAxis horizontal, BinAxis vertical) : AngularBinning(std::move(horizontal), std::move(vertical)) {}
};

}  // namespace occ_improve
