// Eq. 1 evaluated stably in log space (CONVENTIONS 3) and the sensor model's parameters.
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "reference/reference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace occ_improve {
namespace {

TEST(SensorModel, LogitMatchesNaiveEvaluationWhereThatIsAccurate) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> t(-4, 6), b(0, 20);
  for (int i = 0; i < 2000; ++i) {
    const double s = 0.047, d = t(rng) * s, B = b(rng);
    const double p = opdf(d, B, s);
    EXPECT_NEAR(logit_opdf(d, B, s), std::log(p / (1 - p)), 1e-9);
    EXPECT_NEAR(logit_opdf(d, B, s), static_cast<double>(reference::logit_opdf(d, B, s)), 1e-9);
  }
}

TEST(SensorModel, ShapeInFrontAtAndBehindTheMeasurement) {
  const double s = 0.04722;
  EXPECT_NEAR(opdf(0, 0, s), 0.5 / (1 + std::exp(-4.0)) + 1.0 / 3.0, 1e-12);  // ~0.824 on the ray
  EXPECT_NEAR(opdf(0, 0, s), 0.824, 1e-3);
  EXPECT_NEAR(logit_opdf(1.0, 0, s), 0.0, 1e-6);   // behind: unknown
  EXPECT_LT(logit_opdf(-0.5, 0, s), -15.0);         // in front: free
  EXPECT_NEAR(opdf(0, 40, s), 0.5, 1e-6);           // far off the ray: unknown
}

TEST(SensorModel, FarInFrontIsFiniteAndLinear) {
  // 5 m in front with sigma 4.7 cm: u is about -208; naive evaluation loses everything there.
  const double s = 0.04722, d = -5.0, B = 0.3;
  const double l = logit_opdf(d, B, s);
  ASSERT_TRUE(std::isfinite(l));
  const double u = 2 * (d + 2 * s) / s + B;
  EXPECT_NEAR(l, std::log(0.5) + u, 1e-9);
  EXPECT_LT(l, -200);
  // Larger offsets stay finite too.
  EXPECT_TRUE(std::isfinite(logit_opdf(-1e3, 0, 1e-3)));
}

TEST(SensorModel, RangeDependentSigmaHasAFloor) {
  SensorModelParams p;
  p.sigma_depth_m = 0;
  p.sigma_depth_per_m2 = 1.425e-3;
  p.sigma_depth_floor_m = 5e-4;
  const SensorModel m(p);
  EXPECT_NEAR(m.sigma_depth_at(1.0), 1.425e-3, 1e-12);
  EXPECT_NEAR(m.sigma_depth_at(5.0), 0.035625, 1e-9);
  EXPECT_EQ(m.sigma_depth_at(0.0), 5e-4);
}

TEST(SensorModel, NonsenseParametersThrowNamingTheField) {
  const auto expect_named = [](SensorModelParams p, const char* name) {
    try {
      SensorModel m(p);
      ADD_FAILURE() << "expected InvalidParameter for " << name;
    } catch (const InvalidParameter& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  SensorModelParams p;
  p.sigma_azimuth_rad = 0;
  expect_named(p, "sigma_azimuth_rad");
  p = {};
  p.sigma_elevation_rad = -1;
  expect_named(p, "sigma_elevation_rad");
  p = {};
  p.sigma_depth_m = std::nan("");
  expect_named(p, "sigma_depth_m");
  p = {};
  p.sigma_depth_m = 0;
  p.sigma_depth_per_m2 = 0;
  expect_named(p, "sigma_depth_m");
  p = {};
  p.support_k = 0;
  expect_named(p, "support_k");
  p = {};
  p.sigma_depth_floor_m = 0;
  expect_named(p, "sigma_depth_floor_m");
}

// Sigmas beyond what the binning can mean are refused where a model meets a grid (validate_for: the
// presets, the Mapper, load_map, the tools' overrides), naming the field, its value and the bound; an
// angle of 3.2 rad on the pixel-native grid ran for hours before.
TEST(SensorModel, SigmasAreBoundedByTheBinning) {
  const SensorPreset pixel = kinect_v1();  // 1 px bins
  EXPECT_NO_THROW(pixel.model.validate_for(pixel.geometry));
  const auto error_of = [](const SensorPreset& preset) -> std::string {
    try {
      preset.model.validate_for(preset.geometry);
    } catch (const InvalidParameter& e) {
      return e.what();
    }
    return "";
  };
  SensorPreset wide = pixel;
  wide.model.sigma_u_px = 4.5;  // above 4 bin widths
  std::string e = error_of(wide);
  EXPECT_NE(e.find("sigma_u_px = 4.5"), std::string::npos) << e;
  EXPECT_NE(e.find("<= 4 bin widths = 4 px"), std::string::npos) << e;
  wide.model.sigma_u_px = 4.0;  // on the bound: the window k sigma = 8 bins, also on its bound
  EXPECT_EQ(error_of(wide), "");
  wide.model.support_k = 2.5;  // k sigma = 10 bins
  e = error_of(wide);
  EXPECT_NE(e.find("support_k x sigma_u_px = 10"), std::string::npos) << e;
  EXPECT_NE(e.find("<= 8 bin widths = 8 px"), std::string::npos) << e;
  SensorPreset paper = kinect_v1_paper();  // spherical: bins of 0.995 rad / 640 = 1.55 mrad
  EXPECT_EQ(error_of(paper), "");
  paper.model.sigma_elevation_rad = 3.2;
  e = error_of(paper);
  EXPECT_NE(e.find("sigma_elevation_rad = 3.2"), std::string::npos) << e;
  EXPECT_NE(e.find("rad for this grid"), std::string::npos) << e;
  SensorPreset deep = pixel;  // 0.5-8 m: k sigma_rho(8 m) must stay within 7.5 m
  deep.model.sigma_depth_m = 4.0;
  e = error_of(deep);
  EXPECT_NE(e.find("support_k x sigma_rho(depth_max)"), std::string::npos) << e;
  EXPECT_NE(e.find("the depth range 7.5 m"), std::string::npos) << e;
  deep.model.sigma_depth_m = 3.0;  // 2 x (3 + 1.425e-3 x 64) = 6.18 m
  EXPECT_EQ(error_of(deep), "");
  // The Mapper refuses such a model before computing anything.
  EXPECT_THROW(Mapper{wide}, InvalidParameter);
}

}  // namespace
}  // namespace occ_improve
