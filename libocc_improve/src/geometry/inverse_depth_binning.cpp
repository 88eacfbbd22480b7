#include "occ_improve/geometry/inverse_depth_binning.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/geometry.hpp"

namespace occ_improve {

InverseDepthBinning::InverseDepthBinning(const GeometryParams& params) {
  detail::require_parameter(params.depth_min_m > 0, "depth_min_m", params.depth_min_m,
                            "> 0 for inverse-depth binning");
}

void InverseDepthBinning::bins(double min_m, double max_m, int bins, std::vector<double>& edges,
                               std::vector<double>& centres) const {
  const double inv_min = 1.0 / min_m, step = (1.0 / min_m - 1.0 / max_m) / bins;
  edges.resize(static_cast<std::size_t>(bins) + 1);
  centres.resize(static_cast<std::size_t>(bins));
  for (int b = 0; b <= bins; ++b) edges[static_cast<std::size_t>(b)] = 1.0 / (inv_min - b * step);
  for (int b = 0; b < bins; ++b) centres[static_cast<std::size_t>(b)] = 1.0 / (inv_min - (b + 0.5) * step);
  edges.front() = min_m;  // 1 / (1 / min) may differ from min in the last bit
  edges.back() = max_m;
}

}  // namespace occ_improve
