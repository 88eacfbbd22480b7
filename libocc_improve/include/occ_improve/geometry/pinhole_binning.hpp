#pragma once
// The pixel-native binning (CONVENTIONS 2c): column (u, v) is pixel (u, v) of GeometryParams::camera, positions
// in pixels (u = fx x / z + cx, v = fy y / z + cy, column i spans [i - 0.5, i + 0.5)); the depth coordinate
// is z. Sigmas: sigma_u_px, sigma_v_px.
#include "occ_improve/geometry/angular_binning.hpp"
#include "occ_improve/geometry/geometry.hpp"

namespace occ_improve {

class PinholeBinning : public AngularBinning {
public:
  /// Needs the camera, its size equal to the bin counts (InvalidParameter naming the field).
  explicit PinholeBinning(const GeometryParams& params);
  const char* tag() const override { return AngularBinning::pinhole; }
  AngularUnit unit() const override { return AngularUnit::pixels; }
  bool position(double x, double y, double z, double& h, double& v, double& depth) const override;
  Eigen::Vector3d direction_at(double h, double v) const override;
  Eigen::Vector3d point_at(double h, double v, double depth) const override;
  double curvature_angle_rad() const override { return 0.0; }
  bool columns_are_camera_pixels() const override { return true; }

private:
  PinholeIntrinsics camera_;
};

}  // namespace occ_improve
