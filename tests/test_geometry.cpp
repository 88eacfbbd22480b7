// Spherical geometry: coordinates (CONVENTIONS 1), angular and depth binning (CONVENTIONS 2, 2b).
#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace occ_improve {
namespace {

TEST(Geometry, SphericalRoundTripFollowsOpticalFrame) {
  // x right, y down, z forward: a point to the right has positive azimuth, one below positive elevation.
  const SphericalPoint right = to_spherical(1, 0, 1), down = to_spherical(0, 1, 1);
  EXPECT_NEAR(right.azimuth, M_PI / 4, 1e-12);
  EXPECT_NEAR(right.elevation, 0, 1e-12);
  EXPECT_NEAR(down.elevation, M_PI / 4, 1e-12);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), std::abs(u(rng)) + 0.1);
    const Eigen::Vector3d q = from_spherical(to_spherical(p.x(), p.y(), p.z()));
    EXPECT_LT((p - q).norm(), 1e-12);
  }
}

TEST(Geometry, UniformAxisBinsAndOverlaps) {
  const UniformAxis a(-1.0, 1.0, 8);
  EXPECT_EQ(a.bin(-1.0), 0);
  EXPECT_EQ(a.bin(0.999999), 7);
  EXPECT_EQ(a.bin(1.0), -1);
  EXPECT_EQ(a.bin(-1.0001), -1);
  EXPECT_EQ(a.bin(std::nan("")), -1);
  int first, last;
  a.overlapping(-0.3, 0.3, first, last);  // bins of width 0.25: [-0.5,-0.25) ... [0.25,0.5)
  EXPECT_EQ(first, 2);
  EXPECT_EQ(last, 5);
  a.overlapping(-5, 5, first, last);
  EXPECT_EQ(first, 0);
  EXPECT_EQ(last, 7);
}

TEST(Geometry, PaperPresetSupportTouchesTwoToThreeColumns) {
  // CONVENTIONS 4: 2 sigma (0.87 mrad) is a little more than half a bin (0.78 mrad).
  const SensorPreset p = kinect_v1_paper();
  const GridGeometry g(p.geometry);
  const double support = p.model.support_k * p.model.sigma_azimuth_rad;
  EXPECT_NEAR(g.azimuth().width() / 2, 0.777e-3, 1e-5);
  EXPECT_NEAR(support, 0.867e-3, 1e-5);
  int first, last;
  const double centre = g.azimuth().centre(100);
  g.azimuth().overlapping(centre - support, centre + support, first, last);
  EXPECT_EQ(last - first + 1, 3);
  const double near_edge = g.azimuth().lower(100) + 0.2 * g.azimuth().width();
  g.azimuth().overlapping(near_edge - support, near_edge + support, first, last);
  EXPECT_EQ(last - first + 1, 2);
}

class DepthAxisTest : public ::testing::TestWithParam<std::string> {};

TEST_P(DepthAxisTest, EdgesCentresAndLookupsAgree) {
  const DepthAxis d(GetParam(), GetParam() == DepthBinning::uniform ? 0.0 : 0.5, 8.0, 300);
  for (int b = 0; b < d.bins(); ++b) {
    EXPECT_LT(d.lower(b), d.upper(b));
    EXPECT_GT(d.centre(b), d.lower(b));
    EXPECT_LT(d.centre(b), d.upper(b));
    EXPECT_EQ(d.bin(d.centre(b)), b);
    EXPECT_EQ(d.first_centre_above(d.centre(b)), b + 1);
    EXPECT_EQ(d.first_centre_above(std::nextafter(d.centre(b), 0.0)), b);
  }
  EXPECT_EQ(d.bin(8.0), d.bins());
  EXPECT_EQ(d.bin(100.0), d.bins());
  EXPECT_EQ(d.first_centre_above(-1.0), 0);
  EXPECT_EQ(d.first_centre_above(9.0), d.bins());
}

INSTANTIATE_TEST_SUITE_P(Binnings, DepthAxisTest,
                         ::testing::Values(std::string(DepthBinning::uniform), std::string(DepthBinning::inverse_depth)));

TEST(Geometry, InverseDepthBinsGrowWithTheSquareOfRange) {
  const DepthAxis d(DepthBinning::inverse_depth, 0.5, 8.0, 2048);
  const double w1 = d.width_at(1.0), w4 = d.width_at(4.0);
  EXPECT_NEAR(w4 / w1, 16.0, 0.2);
}

TEST(Geometry, InvalidParametersNameTheField) {
  GeometryParams p;
  p.depth_bins = 0;
  try {
    GridGeometry g(p);
    FAIL() << "expected InvalidParameter";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("depth_bins"), std::string::npos);
  }
  p = GeometryParams{};
  p.depth_max_m = 0.0;
  EXPECT_THROW(GridGeometry{p}, InvalidParameter);
  p = GeometryParams{};
  p.depth_binning = DepthBinning::inverse_depth;  // needs depth_min_m > 0
  EXPECT_THROW(GridGeometry{p}, InvalidParameter);
  p = GeometryParams{};
  p.azimuth_max_rad = p.azimuth_min_rad;
  EXPECT_THROW(GridGeometry{p}, InvalidParameter);
  p = GeometryParams{};
  p.elevation_min_rad = std::nan("");
  EXPECT_THROW(GridGeometry{p}, InvalidParameter);
  // An axis beyond 2^20 bins is refused before its centres and edges are allocated (make fuzz: a map
  // file's 268 M elevation bins passed the column bound and ran out of memory).
  p = GeometryParams{};
  p.azimuth_bins = (1 << 28) + 1;
  p.elevation_bins = 8;
  try {
    GridGeometry g(p);
    FAIL() << "expected InvalidParameter";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("azimuth_bins"), std::string::npos) << e.what();
  }
  p = GeometryParams{};
  p.elevation_bins = (1 << 20) + 1;
  EXPECT_THROW(GridGeometry{p}, InvalidParameter);
  p = GeometryParams{};
  p.azimuth_bins = 1 << 20;  // the limit itself is a grid
  p.elevation_bins = 4;
  EXPECT_EQ(GridGeometry(p).width(), 1 << 20);
}

TEST(Geometry, ColumnIndexingIsRowMajorLikeAnImage) {
  const GridGeometry g(kinect_v1_paper().geometry);
  const ColumnIndex c = g.column(17, 5);
  EXPECT_EQ(c, 5u * 640u + 17u);
  EXPECT_EQ(g.azimuth_bin_of(c), 17);
  EXPECT_EQ(g.elevation_bin_of(c), 5);
  const Eigen::Vector3d dir = g.direction(17, 5);
  ColumnIndex located;
  ASSERT_TRUE(g.column_of(dir.x(), dir.y(), dir.z(), located));
  EXPECT_EQ(located, c);
}

}  // namespace
}  // namespace occ_improve
