#include "occ_improve/sim/virtual_sensor.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/maps/column_map.hpp"

#include <cmath>
#include <string>

namespace occ_improve {
namespace {

/// SplitMix64's finaliser: a well-mixed 64-bit value per key (the generator is counter-based).
std::uint64_t mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/// A standard normal for (seed, shot, pixel) by Box-Muller on two uniforms in (0, 1].
double standard_normal(std::uint64_t seed, std::uint64_t shot, std::uint32_t pixel) {
  const std::uint64_t a = mix(seed ^ mix(shot * 0x9e3779b97f4a7c15ull + pixel));
  const std::uint64_t b = mix(a + 0x9e3779b97f4a7c15ull);
  const double u1 = (static_cast<double>(a >> 11) + 1.0) * 0x1.0p-53, u2 = static_cast<double>(b >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

}  // namespace

void VirtualSensorParams::validate() const {
  detail::require_parameter(std::isfinite(sigma_depth_per_m2) && sigma_depth_per_m2 >= 0, "sigma_depth_per_m2",
                            sigma_depth_per_m2, "finite and >= 0");
  detail::require_parameter(std::isfinite(baseline_m) && baseline_m > 0, "baseline_m", baseline_m, "finite and > 0");
  detail::require_parameter(std::isfinite(disparity_step_px) && disparity_step_px >= 0, "disparity_step_px",
                            disparity_step_px, "finite and >= 0");
}

VirtualSensor::VirtualSensor(std::vector<float> scene_depth_m, const PinholeIntrinsics& intrinsics,
                             const VirtualSensorParams& params)
    : scene_(std::move(scene_depth_m)), intrinsics_(intrinsics), params_(params) {
  intrinsics.validate();
  params.validate();
  require_shape("virtual sensor scene", ColumnShape::of_arrays(intrinsics.width, intrinsics.height, {scene_.size()}));
  for (float& z : scene_)
    if (!(z > 0) || !std::isfinite(z)) z = 0.0f;  // one encoding of "no return"
}

std::vector<float> VirtualSensor::shoot(const std::vector<std::uint32_t>& pixels) {
  for (std::uint32_t p : pixels) detail::require_parameter(p < scene_.size(), "shot pixel", p, "inside the image");
  const double fb = intrinsics_.fx * params_.baseline_m, step = params_.disparity_step_px;
  std::vector<float> out(pixels.size(), 0.0f);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const double z = scene_[pixels[i]];
    if (z <= 0) continue;
    double measured = z + params_.sigma_depth_per_m2 * z * z * standard_normal(params_.seed, shots_, pixels[i]);
    if (step > 0 && measured > 0) {
      const double disparity = std::round(fb / measured / step) * step;
      measured = disparity > 0 ? fb / disparity : 0.0;  // zero disparity: at infinity, no return
    }
    out[i] = measured > 0 ? static_cast<float>(measured) : 0.0f;
  }
  ++shots_;
  return out;
}

std::vector<Eigen::Vector3f> VirtualSensor::points(const std::vector<std::uint32_t>& pixels,
                                                   const std::vector<float>& depth_m) const {
  if (pixels.size() != depth_m.size())
    throw InvalidInput("virtual sensor: " + std::to_string(pixels.size()) + " pixels but " +
                       std::to_string(depth_m.size()) + " depths");
  for (std::uint32_t p : pixels) detail::require_parameter(p < scene_.size(), "shot pixel", p, "inside the image");
  const auto w = static_cast<std::uint32_t>(intrinsics_.width);
  std::vector<Eigen::Vector3f> out;
  out.reserve(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const float z = depth_m[i];
    if (!(z > 0)) continue;
    const double u = pixels[i] % w, v = pixels[i] / w;
    out.emplace_back(static_cast<float>((u - intrinsics_.cx) / intrinsics_.fx * z),
                     static_cast<float>((v - intrinsics_.cy) / intrinsics_.fy * z), z);
  }
  return out;
}

std::vector<std::uint8_t> VirtualSensor::returned(const std::vector<float>& depth_m) {
  std::vector<std::uint8_t> got(depth_m.size());
  for (std::size_t i = 0; i < depth_m.size(); ++i) got[i] = depth_m[i] > 0.0f;
  return got;
}

}  // namespace occ_improve
