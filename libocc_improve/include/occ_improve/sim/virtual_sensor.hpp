#pragma once
// A virtual selective sensor over a real frame, for tests and evaluation: the scene is a depth image
// (z in metres per pixel, 0 or NaN = no return); a shot asks for some pixels and gets, for those only,
// the scene's depth as a Kinect v1 would measure it:
//   z' = z + sigma(z) n,  sigma(z) = sigma_depth_per_m2 z^2   (axial noise, Khoshelham & Elberink 2012)
//   z'' = f b / (round(f b / z' / step) step)                 (disparity quantised to `step` pixels)
// with f = fx, b = baseline_m, step = disparity_step_px (1/8 px: ~2.9 mm at 1 m, ~26 mm at 3 m, as
// measured on the shared Kinect data), and no return where the scene has none. n is a standard normal
// drawn from a counter-based generator keyed by (seed, shot number, pixel): the same seed gives the same
// shots whatever the order of the pixels asked.
#include "occ_improve/sensor/presets.hpp"

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace occ_improve {

struct VirtualSensorParams {
  double sigma_depth_per_m2 = 1.425e-3;  ///< axial noise [1/m]; 0: no noise
  double baseline_m = 0.075;             ///< projector-camera baseline
  double disparity_step_px = 0.125;      ///< disparity quantisation; 0: none
  std::uint64_t seed = 1;
  void validate() const;  ///< negative or non-finite values, baseline <= 0 -> InvalidParameter
};

class VirtualSensor {
public:
  /// Throws InvalidInput when scene_depth_m does not hold width x height values, InvalidParameter for
  /// bad intrinsics or parameters.
  VirtualSensor(std::vector<float> scene_depth_m, const PinholeIntrinsics& intrinsics,
                const VirtualSensorParams& params = {});

  /// One shot: the measured z per requested pixel (row-major index), 0 = no return. A pixel outside the
  /// image throws InvalidParameter naming it before anything happens (the shot is not counted).
  std::vector<float> shoot(const std::vector<std::uint32_t>& pixels);

  /// The returns of a shot as points in the sensor frame (pixels without a return are left out).
  std::vector<Eigen::Vector3f> points(const std::vector<std::uint32_t>& pixels, const std::vector<float>& depth_m) const;
  /// Which rays of a shot returned (depth > 0), one byte per ray, as ReturnRecord::record_shot takes them.
  static std::vector<std::uint8_t> returned(const std::vector<float>& depth_m);

  std::uint64_t shots_taken() const { return shots_; }

private:
  std::vector<float> scene_;
  PinholeIntrinsics intrinsics_;
  VirtualSensorParams params_;
  std::uint64_t shots_ = 0;
};

}  // namespace occ_improve
