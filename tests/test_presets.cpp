// Presets: the paper's numbers and the intrinsics-based kinect_v1 (CONVENTIONS 2, 2b).
#include "occ_improve/errors.hpp"
#include "occ_improve/sensor/presets.hpp"

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

const PinholeIntrinsics kCameras[] = {kinect_v1_intrinsics(), PinholeIntrinsics{585, 585, 320, 240, 640, 480},
                                      PinholeIntrinsics{520.9, 521.0, 325.1, 249.7, 640, 480}};

TEST(Presets, SphericalKinectPresetContainsEveryPixel) {
  for (const PinholeIntrinsics& k : kCameras) {
    const SensorPreset p = kinect_v1_spherical(k);
    const GridGeometry g(p.geometry);
    EXPECT_EQ(g.binning(), AngularBinning::spherical);
    for (int v = 0; v < k.height; v += 1)
      for (int u : {0, 1, k.width / 2, k.width - 2, k.width - 1}) {
        ColumnIndex c;
        ASSERT_TRUE(g.column_of((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0, c)) << "pixel " << u << "," << v;
        EXPECT_TRUE(g.observable(c)) << "pixel " << u << "," << v;
      }
    // The grid's corners lie outside the pinhole image: no pixel sees them.
    EXPECT_FALSE(g.observable(g.column(0, 0)));
    EXPECT_FALSE(g.observable(g.column(g.width() - 1, g.height() - 1)));
    EXPECT_LT(g.observable_count(), g.column_count());
    EXPECT_GT(g.observable_count(), g.column_count() * 9 / 10);
    // Angular sigma is one pixel's quantisation, as the paper derives its own.
    EXPECT_NEAR(p.model.sigma_azimuth_rad, 1.0 / k.fx / std::sqrt(12.0), 0.05 / k.fx);
  }
}

TEST(Presets, KinectPresetIsPixelNative) {
  for (const PinholeIntrinsics& k : kCameras) {
    const SensorPreset p = kinect_v1(k);
    const GridGeometry g(p.geometry);
    EXPECT_EQ(g.binning(), AngularBinning::pinhole);
    EXPECT_EQ(g.width(), k.width);
    EXPECT_EQ(g.height(), k.height);
    EXPECT_EQ(g.observable_count(), g.column_count());
    // A point back-projected from pixel (u, v) lands at its column's centre, depth = z.
    for (int v : {0, 1, k.height / 2, k.height - 1})
      for (int u : {0, 1, k.width / 2, k.width - 2, k.width - 1}) {
        const double z = 2.5;
        RayPosition r;
        ASSERT_TRUE(g.project((u - k.cx) / k.fx * z, (v - k.cy) / k.fy * z, z, r)) << u << "," << v;
        EXPECT_EQ(r.horizontal_bin, u);
        EXPECT_EQ(r.vertical_bin, v);
        EXPECT_NEAR(r.horizontal, g.azimuth().centre(u), 1e-9);
        EXPECT_NEAR(r.vertical, g.elevation().centre(v), 1e-9);
        EXPECT_DOUBLE_EQ(r.depth, z);
        EXPECT_TRUE(g.point(u, v, z).isApprox(Eigen::Vector3d((u - k.cx) / k.fx * z, (v - k.cy) / k.fy * z, z)));
      }
    // Outside the image, or behind the camera: outside the field of view.
    RayPosition r;
    EXPECT_FALSE(g.project((-0.6 - k.cx) / k.fx, 0, 1, r));
    EXPECT_FALSE(g.project(0, (k.height - 0.5 - k.cy) / k.fy, 1, r));
    EXPECT_FALSE(g.project(0, 0, -1, r));
    EXPECT_NEAR(p.model.sigma_u_px, 1.0 / std::sqrt(12.0), 1e-12);
    EXPECT_EQ(p.geometry.depth_binning, DepthBinning::inverse_depth);
    EXPECT_GT(p.model.sigma_depth_per_m2, 0.0);
  }
}

TEST(Presets, PinholeBinningNeedsItsCamera) {
  GeometryParams g = kinect_v1().geometry;
  g.camera.reset();
  EXPECT_THROW(GridGeometry{g}, InvalidParameter);
  g = kinect_v1().geometry;
  g.azimuth_bins = 320;
  EXPECT_THROW(GridGeometry{g}, InvalidParameter);
}

TEST(Presets, LookupByNameAndErrors) {
  EXPECT_EQ(preset_by_name("kinect_v1").name, "kinect_v1");
  EXPECT_EQ(preset_by_name("kinect_v1_paper").name, "kinect_v1_paper");
  EXPECT_EQ(preset_by_name("kinect_v1_spherical").name, "kinect_v1_spherical");
  const PinholeIntrinsics k{575.8, 575.8, 319.5, 239.5, 640, 480};
  EXPECT_EQ(preset_by_name("kinect_v1", k).geometry.camera, k);
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
