#pragma once
// A spinning LiDAR's range image (Velodyne, Ouster and Hesai organized clouds): columns are uniform
// azimuth steps theta = atan2(x, z) over [azimuth_min_rad, azimuth_max_rad) (up to the whole turn
// [-pi, pi)), rows are the rings at their own elevations phi = atan2(y, hypot(x, z)) in
// GeometryParams::row_elevations_rad, which need not be evenly spaced. Positions in radians: a row spans
// halfway to its neighbouring rings (its centre is the ring's angle); the depth coordinate is the range.
// Sigmas: sigma_azimuth_rad, sigma_elevation_rad (beam divergence and encoder jitter are angles).
// Frame: the library's optical frame (y down): a ring a datasheet lists at +15 deg (up) has phi = -15 deg.
// The azimuth axis is not wrapped: a support crossing +-pi is clipped there (CONVENTIONS 2's clipping at the
// field of view's edge).
#include "occ_improve/geometry/spherical_binning.hpp"

namespace occ_improve {

class LidarRingsBinning : public SphericalBinning {
public:
  /// Validates the ring table and the azimuth span (InvalidParameter naming the field).
  explicit LidarRingsBinning(const GeometryParams& params);
  const char* tag() const override { return AngularBinning::lidar_rings; }
  double curvature_angle_rad() const override;
};

}  // namespace occ_improve
