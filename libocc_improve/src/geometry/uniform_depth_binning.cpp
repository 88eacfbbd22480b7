#include "occ_improve/geometry/uniform_depth_binning.hpp"

namespace occ_improve {

void UniformDepthBinning::bins(double min_m, double max_m, int bins, std::vector<double>& edges,
                               std::vector<double>& centres) const {
  const double w = (max_m - min_m) / bins;
  edges.resize(static_cast<std::size_t>(bins) + 1);
  centres.resize(static_cast<std::size_t>(bins));
  for (int b = 0; b <= bins; ++b) edges[static_cast<std::size_t>(b)] = min_m + b * w;
  for (int b = 0; b < bins; ++b) centres[static_cast<std::size_t>(b)] = min_m + (b + 0.5) * w;
  edges.back() = max_m;
}

}  // namespace occ_improve
