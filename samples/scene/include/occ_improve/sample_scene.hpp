#pragma once
// The built-in sample: a Kinect-like 640x480 depth frame the project generates itself, so the demo,
// tests and benchmarks run on a fresh checkout. Ray-cast through Kinect v1 intrinsics:
//  - a floor 0.8 m below the sensor, a back wall at 4.2 m with a recess at 6.5 m (beyond the
//    kinect_v1_paper depth range of 5 m);
//  - a box and a thin pole in front (depth discontinuities);
//  - the structured-light shadow band beside each occluder (the projector sits 7.5 cm to the right of
//    the IR camera: surfaces it cannot see give no return);
//  - a dark poster on the wall that returns nothing (a patch with no returns);
//  - Kinect disparity quantisation (1/8 pixel) and axial noise 1.425e-3 z^2 (Khoshelham 2012).
#include "occ_improve/sensor/presets.hpp"

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace occ_improve::sample {

struct SceneOptions {
  std::uint32_t seed = 1;        ///< noise seed; frames of a sequence differ only by it
  bool noise = true;             ///< axial Gaussian noise
  bool quantise = true;          ///< disparity quantisation
  bool projector_shadow = true;  ///< structured-light shadow band
};

struct SampleFrame {
  PinholeIntrinsics intrinsics;
  std::vector<float> depth_m;  ///< z-depth, row-major, 0 = no return
  /// Points in the sensor frame, one per pixel, NaN where there is no return (organized order).
  std::vector<Eigen::Vector3f> points() const;
};

SampleFrame generate_scene(const SceneOptions& options = {});

struct RangeImageOptions {
  std::uint32_t seed = 1;
  double sigma_range_m = 0.0;  ///< Gaussian range noise; 0: none
  /// Each ray leaves from a random position within its column, up to this fraction of the column's
  /// extent either side of the centre on each axis (a LiDAR fires at encoder positions, not at bin centres).
  double jitter_horizontal = 0.45, jitter_vertical = 0.1;
  double max_range_m = 100.0;  ///< no return beyond
};

/// The same scene through any grid's binning (e.g. a spinning LiDAR's range image, lidar_rings): one ray
/// per column, along the column's direction (jittered), the first surface hit as a point in the sensor
/// frame; row-major over the grid's columns, NaN where nothing is hit. No shadow band, poster or
/// disparity quantisation: those belong to the structured-light camera.
std::vector<Eigen::Vector3f> render_range_image(const GridGeometry& geometry, const RangeImageOptions& options = {});

/// `frames` frames of the same static view with different noise seeds (a static-camera sequence).
std::vector<SampleFrame> generate_sequence(int frames, std::uint32_t first_seed = 1);

}  // namespace occ_improve::sample
