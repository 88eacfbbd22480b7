#pragma once
// Sensor presets: a grid geometry and a sensor model that belong together (SPEC 2, 2b).
#include "occ_improve/geometry.hpp"
#include "occ_improve/sensor_model.hpp"

#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// A pinhole depth camera (pixels; u right, v down).
struct PinholeIntrinsics {
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
  int width = 640, height = 480;
  void validate() const;
};

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

/// For real use (SPEC 2b): field of view from the intrinsics (the whole image falls inside the grid),
/// inverse-depth bins over [0.5 m, 8 m], sigma_rho = 1.425e-3 rho^2 (Khoshelham & Elberink 2012),
/// angular sigmas = pixel quantisation (1/(f sqrt 12)), as the paper derives its own.
SensorPreset kinect_v1(const PinholeIntrinsics& intrinsics = kinect_v1_intrinsics());

struct PinholePresetOptions {
  int depth_bins = 2048;
  DepthBinning depth_binning = DepthBinning::inverse_depth;
  double depth_min_m = 0.5;
  double depth_max_m = 8.0;
  double sigma_depth_m = 0.0;
  double sigma_depth_per_m2 = 1.425e-3;
  double sigma_depth_floor_m = 5e-4;
  double support_k = 2.0;
};

/// A preset for any pinhole depth camera: one column per pixel over the image's angular extent.
SensorPreset preset_from_pinhole(const PinholeIntrinsics& intrinsics, const PinholePresetOptions& options = {},
                                 const std::string& name = "pinhole");

/// "kinect_v1_paper" or "kinect_v1"; throws InvalidParameter listing the known names.
SensorPreset preset_by_name(const std::string& name);
std::vector<std::string> preset_names();

}  // namespace occ_improve
