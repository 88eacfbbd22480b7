#include "occ_improve/geometry.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>

namespace occ_improve {

using detail::require_parameter;

void GeometryParams::validate() const {
  require_parameter(azimuth_bins > 0, "azimuth_bins", azimuth_bins, "> 0");
  require_parameter(elevation_bins > 0, "elevation_bins", elevation_bins, "> 0");
  require_parameter(depth_bins > 0, "depth_bins", depth_bins, "> 0");
  // Column indices are 32-bit and the store's bins are int.
  require_parameter(static_cast<double>(azimuth_bins) * elevation_bins < 4.0e9, "azimuth_bins * elevation_bins",
                    static_cast<double>(azimuth_bins) * elevation_bins, "< 4e9");
  require_parameter(std::isfinite(azimuth_min_rad) && azimuth_min_rad > -M_PI, "azimuth_min_rad", azimuth_min_rad,
                    "finite and > -pi");
  require_parameter(std::isfinite(azimuth_max_rad) && azimuth_max_rad <= M_PI && azimuth_max_rad > azimuth_min_rad,
                    "azimuth_max_rad", azimuth_max_rad, "finite, <= pi and > azimuth_min_rad");
  require_parameter(std::isfinite(elevation_min_rad) && elevation_min_rad > -M_PI / 2, "elevation_min_rad",
                    elevation_min_rad, "finite and > -pi/2");
  require_parameter(std::isfinite(elevation_max_rad) && elevation_max_rad < M_PI / 2 &&
                        elevation_max_rad > elevation_min_rad,
                    "elevation_max_rad", elevation_max_rad, "finite, < pi/2 and > elevation_min_rad");
  require_parameter(std::isfinite(depth_min_m) && depth_min_m >= 0, "depth_min_m", depth_min_m, "finite and >= 0");
  require_parameter(std::isfinite(depth_max_m) && depth_max_m > depth_min_m, "depth_max_m", depth_max_m,
                    "finite and > depth_min_m");
  if (depth_binning == DepthBinning::inverse_depth)
    require_parameter(depth_min_m > 0, "depth_min_m", depth_min_m, "> 0 for inverse-depth binning");
}

SphericalPoint to_spherical(double x, double y, double z) {
  SphericalPoint s;
  // Plain sqrt, not std::hypot: inputs are floats, whose squares cannot overflow a double.
  const double horizontal = std::sqrt(x * x + z * z);
  s.rho = std::sqrt(x * x + y * y + z * z);
  s.azimuth = std::atan2(x, z);
  s.elevation = std::atan2(y, horizontal);
  return s;
}

Eigen::Vector3d from_spherical(const SphericalPoint& s) {
  const double horizontal = s.rho * std::cos(s.elevation);
  return {horizontal * std::sin(s.azimuth), s.rho * std::sin(s.elevation), horizontal * std::cos(s.azimuth)};
}

UniformAxis::UniformAxis(double min, double max, int bins)
    : min_(min), max_(max), width_((max - min) / bins), inv_width_(bins / (max - min)), bins_(bins) {}

int UniformAxis::bin(double value) const {
  if (!(value >= min_ && value < max_)) return -1;
  const int i = static_cast<int>((value - min_) * inv_width_);
  return std::min(i, bins_ - 1);  // guards rounding right below max
}

void UniformAxis::overlapping(double lo, double hi, int& first, int& last) const {
  first = static_cast<int>(std::floor((lo - min_) * inv_width_));
  last = static_cast<int>(std::floor((hi - min_) * inv_width_));
  first = std::max(first, 0);
  last = std::min(last, bins_ - 1);
}

DepthAxis::DepthAxis(DepthBinning binning, double min_m, double max_m, int bins)
    : binning_(binning),
      min_(min_m),
      max_(max_m),
      inverse_min_(1.0 / min_m),
      bins_per_unit_(binning == DepthBinning::uniform ? bins / (max_m - min_m) : bins / (1.0 / min_m - 1.0 / max_m)),
      bins_(bins) {
  edges_.resize(static_cast<std::size_t>(bins) + 1);
  centres_.resize(static_cast<std::size_t>(bins));
  if (binning == DepthBinning::uniform) {
    const double w = (max_m - min_m) / bins;
    for (int b = 0; b <= bins; ++b) edges_[static_cast<std::size_t>(b)] = min_m + b * w;
    for (int b = 0; b < bins; ++b) centres_[static_cast<std::size_t>(b)] = min_m + (b + 0.5) * w;
  } else {
    // Uniform in inverse depth; the centre is the midpoint in inverse depth.
    const double inv_min = 1.0 / min_m, step = (1.0 / min_m - 1.0 / max_m) / bins;
    for (int b = 0; b <= bins; ++b) edges_[static_cast<std::size_t>(b)] = 1.0 / (inv_min - b * step);
    for (int b = 0; b < bins; ++b) centres_[static_cast<std::size_t>(b)] = 1.0 / (inv_min - (b + 0.5) * step);
  }
  edges_.back() = max_m;
}

double DepthAxis::continuous_index(double rho) const {
  if (binning_ == DepthBinning::uniform) return (rho - min_) / (max_ - min_) * bins_;
  if (rho <= 0) return -1e300;
  const double step = (1.0 / min_ - 1.0 / max_) / bins_;
  return (1.0 / min_ - 1.0 / rho) / step;
}

int DepthAxis::bin(double rho) const {
  if (rho < min_) return -1;
  if (rho >= max_) return bins_;
  const int b = static_cast<int>(continuous_index(rho));
  return std::clamp(b, 0, bins_ - 1);
}

double DepthAxis::width_at(double rho) const {
  const int b = std::clamp(bin(rho), 0, bins_ - 1);
  return upper(b) - lower(b);
}

SphericalGeometry::SphericalGeometry(const GeometryParams& params) : params_(params) {
  params.validate();
  azimuth_ = UniformAxis(params.azimuth_min_rad, params.azimuth_max_rad, params.azimuth_bins);
  elevation_ = UniformAxis(params.elevation_min_rad, params.elevation_max_rad, params.elevation_bins);
  depth_ = DepthAxis(params.depth_binning, params.depth_min_m, params.depth_max_m, params.depth_bins);
}

bool SphericalGeometry::locate(double azimuth, double elevation, int& azimuth_bin, int& elevation_bin) const {
  azimuth_bin = azimuth_.bin(azimuth);
  elevation_bin = elevation_.bin(elevation);
  return azimuth_bin >= 0 && elevation_bin >= 0;
}

Eigen::Vector3d SphericalGeometry::direction(int azimuth_bin, int elevation_bin) const {
  return from_spherical({1.0, azimuth_.centre(azimuth_bin), elevation_.centre(elevation_bin)});
}

bool SphericalGeometry::operator==(const SphericalGeometry& o) const {
  const GeometryParams &a = params_, &b = o.params_;
  return a.azimuth_bins == b.azimuth_bins && a.elevation_bins == b.elevation_bins && a.depth_bins == b.depth_bins &&
         a.azimuth_min_rad == b.azimuth_min_rad && a.azimuth_max_rad == b.azimuth_max_rad &&
         a.elevation_min_rad == b.elevation_min_rad && a.elevation_max_rad == b.elevation_max_rad &&
         a.depth_binning == b.depth_binning && a.depth_min_m == b.depth_min_m && a.depth_max_m == b.depth_max_m;
}

}  // namespace occ_improve
