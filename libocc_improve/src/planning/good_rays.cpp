#include "occ_improve/planning/good_rays.hpp"

#include <cmath>

namespace occ_improve {

double within_two_sigma(std::uint32_t returns) { return std::erf(std::sqrt(2.0 * returns)); }

double off_plane_share(double non_planarity_sigmas) {
  if (!(non_planarity_sigmas > 0)) return 0.0;
  return std::erfc(2.0 * std::sqrt(2.0) / non_planarity_sigmas);
}

}  // namespace occ_improve
