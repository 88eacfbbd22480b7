#pragma once
// Sensor presets: a grid geometry and a sensor model that belong together (CONVENTIONS 2, 2b).
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// Kinect v1 depth camera as OpenNI reports it (fx = fy = 525, principal point at the image centre).
PinholeIntrinsics kinect_v1_intrinsics();

struct SensorPreset {
  std::string name;
  GeometryParams geometry;
  SensorModelParams model;
  std::optional<PinholeIntrinsics> camera;  ///< set when the preset was built from a camera
};

/// The paper's set-up: 640 x 480 x 512 bins, 57 x 43 deg, rho in [0, 5 m), constant sigmas, k = 2.
SensorPreset kinect_v1_paper();

/// For real use (CONVENTIONS 2b, 2c), what every tool runs by default: pixel-native binning (one column per
/// pixel of the camera, depth along z), inverse-depth bins over [0.5 m, 8 m], sigma_z = 1.425e-3 z^2
/// (Khoshelham & Elberink 2012), angular sigmas = pixel quantisation (1/sqrt 12 px), as the paper
/// derives its own.
SensorPreset kinect_v1(const PinholeIntrinsics& intrinsics = kinect_v1_intrinsics());

/// kinect_v1's depth bins and noise over spherical bins spanning the image's field of view (the
/// real-use preset before the pixel-native binning; kept for comparison). Columns outside the image
/// are marked not observable.
SensorPreset kinect_v1_spherical(const PinholeIntrinsics& intrinsics = kinect_v1_intrinsics());

struct PinholePresetOptions {
  /// AngularBinning::pinhole or AngularBinning::spherical.
  std::string angular_binning = AngularBinning::pinhole;
  int depth_bins = 2048;
  std::string depth_binning = DepthBinning::inverse_depth;  ///< a depth binning's tag
  double depth_min_m = 0.5;
  double depth_max_m = 8.0;
  double sigma_depth_m = 0.0;
  double sigma_depth_per_m2 = 1.425e-3;
  double sigma_depth_floor_m = 5e-4;
  double support_k = 2.0;
};

/// A preset for any pinhole depth camera: one column per pixel (pixel-native), or spherical bins over
/// the image's angular extent with options.angular_binning = spherical.
SensorPreset preset_from_pinhole(const PinholeIntrinsics& intrinsics, const PinholePresetOptions& options = {},
                                 const std::string& name = "pinhole");

/// A spinning LiDAR's range image (the lidar_rings binning): one column per azimuth step, one row per ring.
struct LidarRingsOptions {
  /// The rings' elevation angles as datasheets list them (degrees, positive up), strictly monotonic in
  /// either direction; e.g. vlp16_ring_elevations_deg(). Rows are ordered top to bottom.
  std::vector<double> ring_elevations_deg = vlp16_ring_elevations_deg();
  int azimuth_steps = 1800;  ///< columns over the azimuth span (VLP-16 at 10 Hz: 0.2 deg)
  double azimuth_min_deg = -180.0, azimuth_max_deg = 180.0;
  int depth_bins = 2048;
  std::string depth_binning = DepthBinning::uniform;  ///< a depth binning's tag
  double depth_min_m = 0.3;
  double depth_max_m = 50.0;
  double sigma_range_m = 0.03;  ///< range noise (VLP-16 datasheet: +-3 cm)
  /// Azimuth sigma; 0 takes the quantisation of one column (azimuth step / sqrt 12), as the camera presets
  /// take one pixel's: a return's azimuth is where in its step the laser fired.
  double sigma_azimuth_rad = 0.0;
  /// Elevation sigma: the beam's vertical divergence (Velodyne's manuals: 1.5 mrad, a full angle taken as
  /// sigma, so on the generous side). A ring is a beam at its own elevation, not a pixel: what lies between
  /// two rings is never measured. (0 takes the narrowest row's quantisation, its width / sqrt 12, as for a
  /// pixel; on a VLP-16 that is 0.58 deg, whose 2 sigma reaches into the next ring's row, and each return's
  /// free space carved the ground rings beside it: 89-100 % of the ground columns put their surface at the
  /// next ring's range, a held-out trial's street scan.)
  double sigma_elevation_rad = 1.5e-3;
  double support_k = 2.0;

  /// Static: the defaults above (a Velodyne VLP-16) need it.
  static std::vector<double> vlp16_ring_elevations_deg();
};

/// A preset for a spinning LiDAR (lidar_rings binning, range along each ring's ray, constant range noise).
/// Throws InvalidParameter naming the bad field (ring_elevations_deg[i] out of order, ...).
SensorPreset lidar_rings(const LidarRingsOptions& options = {}, const std::string& name = "lidar_rings");

/// "kinect_v1", "kinect_v1_paper" or "kinect_v1_spherical"; throws InvalidParameter listing the known
/// names. The camera presets take Kinect v1 intrinsics; the second form gives them the camera's own
/// (kinect_v1_paper ignores them: the paper's grid is fixed).
SensorPreset preset_by_name(const std::string& name);
SensorPreset preset_by_name(const std::string& name, const PinholeIntrinsics& intrinsics);
std::vector<std::string> preset_names();

}  // namespace occ_improve
