// fit_intrinsics (intrinsics_fit.hpp): the camera of an organized cloud, and the residual that tells a
// pinhole range image from a cloud that is not one.
#include "occ_improve/errors.hpp"
#include "occ_improve/sensor/intrinsics_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace occ_improve {
namespace {

// An organized cloud back-projected through k, depth varying over the image, some pixels without return.
std::vector<float> cloud_from(const PinholeIntrinsics& k) {
  std::vector<float> xyz(static_cast<std::size_t>(k.width) * static_cast<std::size_t>(k.height) * 3);
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      float* p = &xyz[(static_cast<std::size_t>(v) * static_cast<std::size_t>(k.width) + static_cast<std::size_t>(u)) * 3];
      const float z = (u + v) % 17 == 0 ? std::nanf("") : 1.0f + 0.01f * static_cast<float>((u * 7 + v * 3) % 300);
      p[0] = static_cast<float>((u - k.cx) * z / k.fx);
      p[1] = static_cast<float>((v - k.cy) * z / k.fy);
      p[2] = z;
    }
  return xyz;
}

TEST(IntrinsicsFit, RecoversTheCameraOfAPinholeRangeImage) {
  for (const PinholeIntrinsics& k : {PinholeIntrinsics{525, 525, 319.5, 239.5, 640, 480},
                                     PinholeIntrinsics{575.8, 577.1, 322.25, 236.75, 320, 240}}) {
    const std::vector<float> xyz = cloud_from(k);
    const IntrinsicsFit fit = fit_intrinsics_checked(xyz.data(), k.width, k.height, 3);
    EXPECT_NEAR(fit.intrinsics.fx, k.fx, 1e-3);
    EXPECT_NEAR(fit.intrinsics.fy, k.fy, 1e-3);
    EXPECT_NEAR(fit.intrinsics.cx, k.cx, 1e-3);
    EXPECT_NEAR(fit.intrinsics.cy, k.cy, 1e-3);
    EXPECT_EQ(fit.intrinsics.width, k.width);
    EXPECT_LT(fit.rms_residual_px, 1e-3);
    EXPECT_LT(fit.points_used, static_cast<std::size_t>(k.width * k.height));  // the NaN pixels are left out
  }
}

TEST(IntrinsicsFit, APoorFitIsRefusedNamingTheResidualNotAToolsFlag) {
  const PinholeIntrinsics k{525, 525, 319.5, 239.5, 160, 120};
  std::vector<float> xyz = cloud_from(k);
  // Points moved off their pixels (a resampled cloud): each swapped with a random other one nearby.
  std::mt19937 rng(7);
  for (std::size_t i = 0; i + 30 < xyz.size() / 3; ++i) {
    const std::size_t j = i + rng() % 30;
    for (int a = 0; a < 3; ++a) std::swap(xyz[i * 3 + a], xyz[j * 3 + a]);
  }
  const IntrinsicsFit fit = fit_intrinsics(xyz.data(), k.width, k.height, 3);
  EXPECT_GT(fit.rms_residual_px, kMaxIntrinsicsFitResidualPx);
  try {
    fit_intrinsics_checked(xyz.data(), k.width, k.height, 3);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    // The library does not know the tools: their flag is added where they catch it (tool_frames.cpp).
    EXPECT_NE(std::string(e.what()).find("px RMS"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("-intrinsics"), std::string::npos) << e.what();
  }
}

TEST(IntrinsicsFit, ALimitNoFitCanMeetIsInvalidParameter) {
  const PinholeIntrinsics k{525, 525, 319.5, 239.5, 160, 120};
  const std::vector<float> xyz = cloud_from(k);
  for (const double limit : {-1.0, 0.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    try {
      fit_intrinsics_checked(xyz.data(), k.width, k.height, 3, limit);
      FAIL() << "expected InvalidParameter for max_rms_px = " << limit;
    } catch (const InvalidParameter& e) {
      EXPECT_NE(std::string(e.what()).find("max_rms_px"), std::string::npos) << e.what();
    }
  }
}

TEST(IntrinsicsFit, TooFewPointsOrNoImageAreRefused) {
  std::vector<float> xyz(10 * 10 * 3, std::nanf(""));
  EXPECT_THROW(fit_intrinsics(xyz.data(), 10, 10, 3), InvalidInput);
  EXPECT_THROW(fit_intrinsics(xyz.data(), 100, 1, 3), InvalidInput);
  EXPECT_THROW(fit_intrinsics(nullptr, 10, 10, 3), InvalidInput);
}

}  // namespace
}  // namespace occ_improve
