// The insertion kernel's float exp/log (an internal header of the library) against double std::exp/log,
// and the kernel's logit P_s profile against the double logit_opdf of sensor_model.hpp.
#include "../libocc_improve/src/support/fast_math.hpp"  // internal: not installed, tested here directly

#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace occ_improve {
namespace {

using detail::fast_exp;
using detail::fast_log;

TEST(FastMath, ExpRelativeErrorOverItsRange) {
  double worst = 0;
  for (int i = 0; i <= 2000000; ++i) {
    const float x = -87.0f + 175.0f * static_cast<float>(i) / 2000000.0f;
    const double exact = std::exp(static_cast<double>(x));
    worst = std::max(worst, std::abs(fast_exp(x) - exact) / exact);
  }
  EXPECT_LT(worst, 2e-7);
}

TEST(FastMath, ExpSaturatesOutsideItsRange) {
  EXPECT_NEAR(fast_exp(-200.0f) / std::exp(-87.0), 1.0, 2e-7);
  EXPECT_NEAR(fast_exp(200.0f) / std::exp(88.0), 1.0, 2e-7);
  EXPECT_TRUE(std::isfinite(fast_exp(1e30f)));
}

TEST(FastMath, LogErrorOverNormalFloats) {
  // Absolute error within a few ulps of the result: the polynomial itself is accurate to ~1e-7 and
  // a float result of magnitude |log x| carries a rounding of 6e-8 |log x|.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> exponent(-125.0f, 127.0f);
  double worst = 0;
  for (int i = 0; i < 2000000; ++i) {
    const float x = std::exp2(exponent(rng));
    if (!std::isnormal(x)) continue;
    const double exact = std::log(static_cast<double>(x));
    worst = std::max(worst, std::abs(fast_log(x) - exact) / (1.0 + std::abs(exact)));
  }
  EXPECT_LT(worst, 2e-7);
}

TEST(FastMath, LogIsRelativelyAccurateNearOne) {
  // Log-odds behind a measurement are tiny: log of odds within 1e-3 of 1 must keep their relative accuracy.
  double worst = 0;
  for (int i = -200000; i <= 200000; ++i) {
    const float x = 1.0f + static_cast<float>(i) * 5e-9f * static_cast<float>(std::abs(i) + 1);
    if (x == 1.0f) continue;
    const double exact = std::log(static_cast<double>(x));
    worst = std::max(worst, std::abs(fast_log(x) - exact) / std::abs(exact));
  }
  EXPECT_LT(worst, 4e-7);
}

TEST(FastMath, KernelProfileMatchesLogitOpdf) {
  // Many random measurements: depth bins 1 cm apart around rho_bar, angular terms up to 30 (beyond any
  // column of the support at k = 2). Bound: 2e-6 absolute plus 1e-6 of |logit| (float inputs t and B).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> rho(0.5, 5.0), angular(0.0, 30.0), sigma(0.002, 0.1);
  std::vector<double> centres(400);
  std::vector<float> out(centres.size());
  double worst = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const double r = rho(rng), b = angular(rng), s = sigma(rng);
    // From 12 sigmas in front to 8 behind: covers the whole evaluated range of the clamped mode.
    for (std::size_t i = 0; i < centres.size(); ++i)
      centres[i] = r + s * (-12.0 + 20.0 * static_cast<double>(i) / static_cast<double>(centres.size() - 1));
    logit_opdf_profile(centres.data(), centres.size(), r, b, s, out.data());
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const double exact = logit_opdf(centres[i] - r, b, s);
      worst = std::max(worst, std::abs(out[i] - exact) / (2e-6 + 1e-6 * std::abs(exact)));
    }
  }
  EXPECT_LT(worst, 1.0);
}

TEST(FastMath, ProfileIsNonPositiveFarInFront) {
  // The clamped mode leaves L_min runs alone where t <= -1.5, relying on logit P_s <= 0 there for all B.
  std::vector<double> centres;
  for (double t = -1.5; t > -30.0; t -= 0.01) centres.push_back(t);
  std::vector<float> out(centres.size());
  for (double b : {0.0, 0.01, 0.1, 0.5, 1.0, 3.0, 10.0, 40.0}) {
    logit_opdf_profile(centres.data(), centres.size(), 0.0, b, 1.0, out.data());
    for (std::size_t i = 0; i < centres.size(); ++i) {
      ASSERT_LE(logit_opdf(centres[i], b, 1.0), 0.0) << "t = " << centres[i] << ", B = " << b;
      ASSERT_LE(out[i], 0.0f) << "t = " << centres[i] << ", B = " << b;
    }
  }
}

TEST(FastMath, FarFrontBoundHolds) {
  // For t <= -3 - B/2: logit P_s <= log(1/2) + u + 0.072 (the clamped mode's bound for untouched voxels).
  for (double b = 0.0; b <= 40.0; b += 0.25)
    for (double t = -3.0 - b / 2; t > -60.0; t -= 0.05) {
      const double u = 2.0 * (t + 2.0) + b;
      ASSERT_LE(logit_opdf(t, b, 1.0), std::log(0.5) + u + 0.072) << "t = " << t << ", B = " << b;
    }
}

}  // namespace
}  // namespace occ_improve
