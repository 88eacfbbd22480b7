// Presets: the paper's numbers and the intrinsics-based kinect_v1 (SPEC 2, 2b).
#include "occ_improve/errors.hpp"
#include "occ_improve/presets.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace occ_improve {
namespace {

TEST(Presets, PaperPresetHasThePapersNumbers) {
  const SensorPreset p = kinect_v1_paper();
  EXPECT_EQ(p.geometry.azimuth_bins, 640);
  EXPECT_EQ(p.geometry.elevation_bins, 480);
  EXPECT_EQ(p.geometry.depth_bins, 512);
  EXPECT_NEAR((p.geometry.azimuth_max_rad - p.geometry.azimuth_min_rad) * 180 / M_PI, 57.0, 1e-9);
  EXPECT_NEAR((p.geometry.elevation_max_rad - p.geometry.elevation_min_rad) * 180 / M_PI, 43.0, 1e-9);
  EXPECT_EQ(p.geometry.depth_max_m, 5.0);
  EXPECT_NEAR(p.model.sigma_azimuth_rad * p.model.sigma_azimuth_rad, 1.88e-7, 1e-12);
  EXPECT_NEAR(p.model.sigma_depth_m * p.model.sigma_depth_m * 1e6, 2.23e3, 1e-6);
  EXPECT_EQ(p.model.support_k, 2.0);
}

TEST(Presets, KinectPresetContainsEveryPixel) {
  for (const PinholeIntrinsics& k : {kinect_v1_intrinsics(), PinholeIntrinsics{585, 585, 320, 240, 640, 480},
                                     PinholeIntrinsics{520.9, 521.0, 325.1, 249.7, 640, 480}}) {
    const SensorPreset p = kinect_v1(k);
    const SphericalGeometry g(p.geometry);
    for (int v = 0; v < k.height; v += 1)
      for (int u : {0, 1, k.width / 2, k.width - 2, k.width - 1}) {
        const SphericalPoint s = to_spherical((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
        int a, e;
        ASSERT_TRUE(g.locate(s.azimuth, s.elevation, a, e)) << "pixel " << u << "," << v;
      }
    EXPECT_EQ(p.geometry.depth_binning, DepthBinning::inverse_depth);
    EXPECT_GT(p.model.sigma_depth_per_m2, 0.0);
    // Angular sigma is one pixel's quantisation, as the paper derives its own.
    EXPECT_NEAR(p.model.sigma_azimuth_rad, 1.0 / k.fx / std::sqrt(12.0), 0.05 / k.fx);
  }
}

TEST(Presets, LookupByNameAndErrors) {
  EXPECT_EQ(preset_by_name("kinect_v1").name, "kinect_v1");
  EXPECT_EQ(preset_by_name("kinect_v1_paper").name, "kinect_v1_paper");
  try {
    preset_by_name("kinect_v9");
    FAIL() << "expected InvalidParameter";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("kinect_v1_paper"), std::string::npos);
  }
  PinholeIntrinsics bad;
  bad.fx = -1;
  EXPECT_THROW(kinect_v1(bad), InvalidParameter);
  bad = {};
  bad.width = 0;
  EXPECT_THROW(kinect_v1(bad), InvalidParameter);
}

}  // namespace
}  // namespace occ_improve
