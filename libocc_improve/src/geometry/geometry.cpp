#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/geometry/camera_matrix.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace occ_improve {

using detail::require_parameter;

void PinholeIntrinsics::validate() const {
  require_parameter(std::isfinite(fx) && fx > 0, "fx", fx, "finite and > 0");
  require_parameter(std::isfinite(fy) && fy > 0, "fy", fy, "finite and > 0");
  require_parameter(std::isfinite(cx), "cx", cx, "finite");
  require_parameter(std::isfinite(cy), "cy", cy, "finite");
  require_parameter(width > 0 && width <= 65536, "width", width, "in [1, 65536]");
  require_parameter(height > 0 && height <= 65536, "height", height, "in [1, 65536]");
}

PinholeIntrinsics intrinsics_from_matrix(const std::array<double, 9>& k, int width, int height) {
  if (k[1] != 0 || k[3] != 0 || k[6] != 0 || k[7] != 0 || k[8] != 1) {
    std::ostringstream m;
    m << "K must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew), got [[" << k[0] << ", " << k[1] << ", " << k[2]
      << "], [" << k[3] << ", " << k[4] << ", " << k[5] << "], [" << k[6] << ", " << k[7] << ", " << k[8] << "]]";
    if (k[2] == 0 && k[5] == 0 && k[6] != 0 && k[7] != 0) m << ": it looks transposed (cx, cy in the last row); give K row by row";
    throw InvalidInput(m.str());
  }
  PinholeIntrinsics camera;
  camera.fx = k[0];
  camera.fy = k[4];
  camera.cx = k[2];
  camera.cy = k[5];
  camera.width = width;
  camera.height = height;
  camera.validate();
  return camera;
}

bool same_camera(const PinholeIntrinsics& a, const PinholeIntrinsics& b) {
  constexpr double kTolerancePx = 0.05;
  return a.width == b.width && a.height == b.height && std::abs(a.fx - b.fx) <= kTolerancePx &&
         std::abs(a.fy - b.fy) <= kTolerancePx && std::abs(a.cx - b.cx) <= kTolerancePx &&
         std::abs(a.cy - b.cy) <= kTolerancePx;
}

std::string camera_text(const PinholeIntrinsics& k) {
  char text[160];
  std::snprintf(text, sizeof text, "fx=%.2f fy=%.2f cx=%.2f cy=%.2f %dx%d", k.fx, k.fy, k.cx, k.cy, k.width, k.height);
  return text;
}

void GeometryParams::validate() const {
  if (camera) camera->validate();
  // An angular axis keeps its bins' centres and edges (16 bytes a bin), built by the binning validated
  // below: bounded here, before it allocates (make fuzz: a map file claiming 268 M elevation bins
  // passed the column bound and ran the loader out of memory). 2^20 bins is 6 microradians over 2 pi.
  require_parameter(azimuth_bins > 0 && azimuth_bins <= (1 << 20), "azimuth_bins", azimuth_bins, "in [1, 2^20]");
  require_parameter(elevation_bins > 0 && elevation_bins <= (1 << 20), "elevation_bins", elevation_bins, "in [1, 2^20]");
  require_parameter(depth_bins > 0, "depth_bins", depth_bins, "> 0");
  // Column indices are 32-bit and the store's bins are int.
  require_parameter(static_cast<double>(azimuth_bins) * elevation_bins < 4.0e9, "azimuth_bins * elevation_bins",
                    static_cast<double>(azimuth_bins) * elevation_bins, "< 4e9");
  make_angular_binning(*this);  // validates the fields the binning uses
  require_parameter(std::isfinite(depth_min_m) && depth_min_m >= 0, "depth_min_m", depth_min_m, "finite and >= 0");
  require_parameter(std::isfinite(depth_max_m) && depth_max_m > depth_min_m, "depth_max_m", depth_max_m,
                    "finite and > depth_min_m");
  make_depth_binning(*this);  // validates the fields the depth binning uses
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

GridGeometry::GridGeometry(const GeometryParams& params) : params_(params) {
  params.validate();
  binning_ = make_angular_binning(params);
  if (!binning_->horizontal().uniform())  // the improvement's row loop takes B_h per column offset
    throw InvalidParameter(std::string("angular_binning '") + binning_->tag() +
                           "' has a non-uniform horizontal axis: binnings must keep columns uniform");
  depth_ = DepthAxis(*make_depth_binning(params), params.depth_min_m, params.depth_max_m, params.depth_bins);
  if (params.camera && !binning_->columns_are_camera_pixels()) {
    // A column is observable when the camera sees its centre direction.
    const PinholeIntrinsics& k = *params.camera;
    observable_.assign(column_count(), 0);
    for (int e = 0; e < height(); ++e)
      for (int a = 0; a < width(); ++a) {
        const Eigen::Vector3d d = direction(a, e);
        if (!(d.z() > 0)) continue;
        const double u = k.fx * d.x() / d.z() + k.cx, v = k.fy * d.y() / d.z() + k.cy;
        observable_[column(a, e)] = u >= -0.5 && u < k.width - 0.5 && v >= -0.5 && v < k.height - 0.5;
      }
  }
}

std::size_t GridGeometry::observable_count() const {
  if (observable_.empty()) return column_count();
  return static_cast<std::size_t>(std::count(observable_.begin(), observable_.end(), std::uint8_t{1}));
}

bool GridGeometry::project(double x, double y, double z, RayPosition& p) const {
  if (!binning_->position(x, y, z, p.horizontal, p.vertical, p.depth)) return false;
  p.horizontal_bin = azimuth().bin(p.horizontal);
  p.vertical_bin = elevation().bin(p.vertical);
  return p.horizontal_bin >= 0 && p.vertical_bin >= 0;
}

Eigen::Vector3d GridGeometry::direction_at(double horizontal, double vertical) const {
  return binning_->direction_at(horizontal, vertical);
}

Eigen::Vector3d GridGeometry::direction(int azimuth_bin, int elevation_bin) const {
  return direction_at(azimuth().centre(azimuth_bin), elevation().centre(elevation_bin));
}

bool GridGeometry::column_of(double x, double y, double z, ColumnIndex& c) const {
  if (!is_valid_point(x, y, z)) return false;
  RayPosition r;
  if (!project(x, y, z, r)) return false;
  c = column(r.horizontal_bin, r.vertical_bin);
  return true;
}

bool GridGeometry::operator==(const GridGeometry& o) const {
  const GeometryParams &a = params_, &b = o.params_;
  return a.angular_binning == b.angular_binning && a.row_elevations_rad == b.row_elevations_rad && a.camera == b.camera && a.azimuth_bins == b.azimuth_bins && a.elevation_bins == b.elevation_bins && a.depth_bins == b.depth_bins &&
         a.azimuth_min_rad == b.azimuth_min_rad && a.azimuth_max_rad == b.azimuth_max_rad &&
         a.elevation_min_rad == b.elevation_min_rad && a.elevation_max_rad == b.elevation_max_rad &&
         a.depth_binning == b.depth_binning && a.depth_min_m == b.depth_min_m && a.depth_max_m == b.depth_max_m;
}

void require_column_grid_size(int width, int height) {
  detail::require_parameter(width > 0, "width", width, "> 0");
  detail::require_parameter(height > 0, "height", height, "> 0");
  const std::uint64_t columns = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  detail::require_parameter(columns <= std::numeric_limits<ColumnIndex>::max(), "width x height",
                            static_cast<double>(columns), "at most 2^32 - 1 columns (a column index is 32-bit)");
}

}  // namespace occ_improve
