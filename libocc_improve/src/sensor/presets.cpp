#include "occ_improve/sensor/presets.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace occ_improve {

using detail::require_parameter;

PinholeIntrinsics kinect_v1_intrinsics() { return PinholeIntrinsics{}; }

SensorPreset kinect_v1_paper() {
  SensorPreset p;
  p.name = "kinect_v1_paper";
  // GeometryParams and SensorModelParams default to the paper's values (CONVENTIONS 2).
  return p;
}

namespace {

void set_depth_and_noise(const PinholePresetOptions& o, SensorPreset& p) {
  p.geometry.depth_bins = o.depth_bins;
  p.geometry.depth_binning = o.depth_binning;
  p.geometry.depth_min_m = o.depth_min_m;
  p.geometry.depth_max_m = o.depth_max_m;
  p.model.sigma_depth_m = o.sigma_depth_m;
  p.model.sigma_depth_per_m2 = o.sigma_depth_per_m2;
  p.model.sigma_depth_floor_m = o.sigma_depth_floor_m;
  p.model.support_k = o.support_k;
}

// Spherical bins over the image's angular extent: the camera marks the columns it cannot see.
void set_spherical_field_of_view(const PinholeIntrinsics& k, SensorPreset& p) {
  // Pixel u spans [u - 0.5, u + 0.5]; the azimuth does not depend on v. The elevation of a pixel row is
  // largest in magnitude on the image's centre column (x = 0), so that column bounds the range.
  const double left = std::atan((-0.5 - k.cx) / k.fx), right = std::atan((k.width - 0.5 - k.cx) / k.fx);
  const double top = std::atan((-0.5 - k.cy) / k.fy), bottom = std::atan((k.height - 0.5 - k.cy) / k.fy);
  // A hair of margin keeps the border pixels' centres strictly inside [min, max).
  const double margin = 1e-9;
  p.geometry.azimuth_min_rad = left - margin;
  p.geometry.azimuth_max_rad = right + margin;
  p.geometry.elevation_min_rad = top - margin;
  p.geometry.elevation_max_rad = bottom + margin;
}

}  // namespace

SensorPreset preset_from_pinhole(const PinholeIntrinsics& k, const PinholePresetOptions& o, const std::string& name) {
  k.validate();
  SensorPreset p;
  p.name = name;
  p.camera = k;
  p.geometry.angular_binning = o.angular_binning;
  p.geometry.camera = k;
  p.geometry.azimuth_bins = k.width;
  p.geometry.elevation_bins = k.height;
  if (o.angular_binning == AngularBinning::spherical) set_spherical_field_of_view(k, p);
  set_depth_and_noise(o, p);
  p.geometry.validate();
  // Angular noise: the quantisation of one pixel, width/sqrt(12), as the paper derives 1.88e-7 rad^2:
  // 1/sqrt(12) px for the pixel-native binning (sigma_u_px's default), in radians the angle of one pixel
  // (its spherical bin's width, or at the image centre).
  const bool spherical = o.angular_binning == AngularBinning::spherical;
  const double azimuth_pixel_rad = spherical ? (p.geometry.azimuth_max_rad - p.geometry.azimuth_min_rad) / k.width
                                             : std::atan(1.0 / k.fx);
  const double elevation_pixel_rad =
      spherical ? (p.geometry.elevation_max_rad - p.geometry.elevation_min_rad) / k.height : std::atan(1.0 / k.fy);
  p.model.sigma_azimuth_rad = azimuth_pixel_rad / std::sqrt(12.0);
  p.model.sigma_elevation_rad = elevation_pixel_rad / std::sqrt(12.0);
  p.model.validate_for(p.geometry);
  return p;
}

SensorPreset kinect_v1(const PinholeIntrinsics& intrinsics) {
  return preset_from_pinhole(intrinsics, PinholePresetOptions{}, "kinect_v1");
}

SensorPreset kinect_v1_spherical(const PinholeIntrinsics& intrinsics) {
  PinholePresetOptions options;
  options.angular_binning = AngularBinning::spherical;
  return preset_from_pinhole(intrinsics, options, "kinect_v1_spherical");
}

std::vector<double> LidarRingsOptions::vlp16_ring_elevations_deg() {
  return {-15, -13, -11, -9, -7, -5, -3, -1, 1, 3, 5, 7, 9, 11, 13, 15};
}

namespace {

// Datasheet ring angles (degrees, up) -> row elevations phi (radians, y down), rows top to bottom.
std::vector<double> row_elevations(const std::vector<double>& rings_deg) {
  require_parameter(rings_deg.size() >= 2, "ring_elevations_deg size", static_cast<double>(rings_deg.size()), ">= 2");
  const auto name_of = [](std::size_t i) { return "ring_elevations_deg[" + std::to_string(i) + "]"; };
  for (std::size_t i = 0; i < rings_deg.size(); ++i)
    require_parameter(std::isfinite(rings_deg[i]) && std::abs(rings_deg[i]) < 90, name_of(i).c_str(), rings_deg[i],
                      "in (-90, 90) deg (the datasheet's convention: positive up)");
  const bool ascending = rings_deg[1] > rings_deg[0];
  for (std::size_t i = 1; i < rings_deg.size(); ++i)
    require_parameter(ascending ? rings_deg[i] > rings_deg[i - 1] : rings_deg[i] < rings_deg[i - 1],
                      name_of(i).c_str(), rings_deg[i],
                      "strictly monotonic like the rings before it (no repeats, one direction)");
  // The outer rows reach half a gap beyond the outer rings, and must stay short of straight up or down.
  const std::size_t n = rings_deg.size();
  require_parameter(std::abs(rings_deg[0] - (rings_deg[1] - rings_deg[0]) / 2) < 90, name_of(0).c_str(), rings_deg[0],
                    "such that its row (half the gap to the next ring beyond it) stays within (-90, 90) deg");
  require_parameter(std::abs(rings_deg[n - 1] + (rings_deg[n - 1] - rings_deg[n - 2]) / 2) < 90, name_of(n - 1).c_str(),
                    rings_deg[n - 1], "such that its row (half the gap to the ring before, beyond it) stays within (-90, 90) deg");
  std::vector<double> phi;
  for (double deg : rings_deg) phi.push_back(-deg * M_PI / 180.0);
  if (!ascending) return phi;  // descending up-angles are ascending phi
  return {phi.rbegin(), phi.rend()};
}

}  // namespace

SensorPreset lidar_rings(const LidarRingsOptions& o, const std::string& name) {
  SensorPreset p;
  p.name = name;
  GeometryParams& g = p.geometry;
  g.angular_binning = AngularBinning::lidar_rings;
  g.row_elevations_rad = row_elevations(o.ring_elevations_deg);
  g.azimuth_bins = o.azimuth_steps;
  g.elevation_bins = static_cast<int>(g.row_elevations_rad.size());
  g.azimuth_min_rad = o.azimuth_min_deg * M_PI / 180.0;
  g.azimuth_max_rad = o.azimuth_max_deg * M_PI / 180.0;
  g.depth_bins = o.depth_bins;
  g.depth_binning = o.depth_binning;
  g.depth_min_m = o.depth_min_m;
  g.depth_max_m = o.depth_max_m;
  g.validate();
  const GridGeometry geometry(g);
  double narrowest_gap = geometry.elevation().width(0);
  for (int i = 1; i < geometry.height(); ++i) narrowest_gap = std::min(narrowest_gap, geometry.elevation().width(i));
  require_parameter(std::isfinite(o.sigma_azimuth_rad) && o.sigma_azimuth_rad >= 0, "sigma_azimuth_rad",
                    o.sigma_azimuth_rad, "finite and >= 0 (0: one azimuth step's quantisation)");
  require_parameter(std::isfinite(o.sigma_elevation_rad) && o.sigma_elevation_rad >= 0, "sigma_elevation_rad",
                    o.sigma_elevation_rad, "finite and >= 0 (0: the narrowest row's quantisation; default: the beam's divergence)");
  p.model.sigma_azimuth_rad = o.sigma_azimuth_rad > 0 ? o.sigma_azimuth_rad : geometry.azimuth().width() / std::sqrt(12.0);
  p.model.sigma_elevation_rad = o.sigma_elevation_rad > 0 ? o.sigma_elevation_rad : narrowest_gap / std::sqrt(12.0);
  p.model.sigma_depth_m = o.sigma_range_m;
  p.model.sigma_depth_per_m2 = 0.0;
  p.model.support_k = o.support_k;
  p.model.validate_for(g);
  return p;
}

std::vector<std::string> preset_names() { return {"kinect_v1", "kinect_v1_paper", "kinect_v1_spherical"}; }

SensorPreset preset_by_name(const std::string& name) {
  if (name == "kinect_v1_paper") return kinect_v1_paper();
  if (name == "kinect_v1") return kinect_v1();
  if (name == "kinect_v1_spherical") return kinect_v1_spherical();
  throw InvalidParameter("unknown sensor preset '" + name +
                         "': known presets are kinect_v1, kinect_v1_paper, kinect_v1_spherical");
}

SensorPreset preset_by_name(const std::string& name, const PinholeIntrinsics& intrinsics) {
  if (name == "kinect_v1") return kinect_v1(intrinsics);
  if (name == "kinect_v1_spherical") return kinect_v1_spherical(intrinsics);
  return preset_by_name(name);
}

}  // namespace occ_improve
