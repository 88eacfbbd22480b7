#pragma once
// Depth bins of equal width over [depth_min_m, depth_max_m) (the paper: 512 bins over [0, 5 m)); each
// centre is its bin's midpoint.
#include "occ_improve/geometry/depth_binning.hpp"

namespace occ_improve {

class UniformDepthBinning : public DepthBinning {
public:
  const char* tag() const override { return DepthBinning::uniform; }
  void bins(double min_m, double max_m, int bins, std::vector<double>& edges,
            std::vector<double>& centres) const override;
};

}  // namespace occ_improve
