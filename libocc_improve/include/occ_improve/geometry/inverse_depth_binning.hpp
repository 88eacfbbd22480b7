#pragma once
// Depth bins uniform in 1/depth between depth_min_m > 0 and depth_max_m: a bin's width grows as depth^2,
// like a disparity sensor's quantisation (kinect_v1: 2048 bins over [0.5, 8 m]). Each centre is its bin's
// midpoint in inverse depth.
#include "occ_improve/geometry/depth_binning.hpp"

namespace occ_improve {

class InverseDepthBinning : public DepthBinning {
public:
  /// Validates depth_min_m > 0 (InvalidParameter naming it).
  explicit InverseDepthBinning(const GeometryParams& params);
  const char* tag() const override { return DepthBinning::inverse_depth; }
  void bins(double min_m, double max_m, int bins, std::vector<double>& edges,
            std::vector<double>& centres) const override;
};

}  // namespace occ_improve
