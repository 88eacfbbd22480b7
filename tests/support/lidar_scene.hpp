#pragma once
// The LiDAR the lidar_rings tests share: 16 rings at uneven elevations (denser near the horizon, as
// Ouster's and Hesai's tables are), 96 azimuth steps over 80 deg, ranges [0.3, 8 m) in 256 bins; the
// sample scene rendered through it (samples/scene: one jittered ray per column, 1 cm range noise).
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <Eigen/Core>
#include <vector>

namespace occ_improve::test {

inline SensorPreset small_lidar() {
  LidarRingsOptions o;
  o.ring_elevations_deg = {-22, -18, -15, -12.5, -10.5, -8.5, -6.5, -4.5, -3, -1.5, 0, 1.5, 3, 5, 8, 12};
  o.azimuth_steps = 96;
  o.azimuth_min_deg = -40;
  o.azimuth_max_deg = 40;
  o.depth_bins = 256;
  o.depth_min_m = 0.3;
  o.depth_max_m = 8.0;
  // Rows as pixels (their width / sqrt 12), not beams: supports reach the neighbouring rings, so the
  // comparisons with the dense reference cover a window across rows of uneven widths.
  o.sigma_elevation_rad = 0;
  return lidar_rings(o, "small_lidar");
}

inline std::vector<Eigen::Vector3f> lidar_scan(const GridGeometry& g, std::uint32_t seed = 1) {
  sample::RangeImageOptions o;
  o.seed = seed;
  o.sigma_range_m = 0.01;
  return sample::render_range_image(g, o);
}

}  // namespace occ_improve::test
