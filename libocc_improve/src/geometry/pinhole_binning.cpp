#include "occ_improve/geometry/pinhole_binning.hpp"

#include "occ_improve/errors.hpp"

namespace occ_improve {

using detail::require_parameter;

namespace {

const PinholeIntrinsics& validated_camera(const GeometryParams& p) {
  require_parameter(p.camera.has_value(), "camera", 0, "set (the pinhole binning's columns are its pixels)");
  require_parameter(p.azimuth_bins == p.camera->width, "azimuth_bins", p.azimuth_bins, "equal to the camera's width");
  require_parameter(p.elevation_bins == p.camera->height, "elevation_bins", p.elevation_bins,
                    "equal to the camera's height");
  return *p.camera;
}

}  // namespace

PinholeBinning::PinholeBinning(const GeometryParams& p)
    // Checked in both arguments: their order of evaluation is unspecified, and p.camera may be empty.
    : AngularBinning(BinAxis(-0.5, validated_camera(p).width - 0.5, validated_camera(p).width),
                     BinAxis(-0.5, validated_camera(p).height - 0.5, validated_camera(p).height)),
      camera_(*p.camera) {}

bool PinholeBinning::position(double x, double y, double z, double& h, double& v, double& depth) const {
  if (!(z > 0)) return false;  // behind the camera
  h = camera_.fx * x / z + camera_.cx;
  v = camera_.fy * y / z + camera_.cy;
  depth = z;
  return true;
}

Eigen::Vector3d PinholeBinning::direction_at(double h, double v) const {
  return Eigen::Vector3d((h - camera_.cx) / camera_.fx, (v - camera_.cy) / camera_.fy, 1.0).normalized();
}

Eigen::Vector3d PinholeBinning::point_at(double h, double v, double depth) const {  // depth is z
  return {(h - camera_.cx) / camera_.fx * depth, (v - camera_.cy) / camera_.fy * depth, depth};
}

}  // namespace occ_improve
