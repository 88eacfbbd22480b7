// The bounds insertion and improvement derive from eq. 1 (src/sensor/opdf_bounds.hpp), each checked for
// exactly what its comment promises, with the double-precision model (logit_opdf, opdf, opdf_peak)
// evaluated over a grid of t = d_rho / sigma, B and sigma: a change of eq. 1 that breaks a bound fails here.
#include "../libocc_improve/src/sensor/opdf_bounds.hpp"  // internal: not installed, tested here directly
#include "../libocc_improve/src/support/fast_math.hpp"

#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace occ_improve {
namespace {

const std::vector<double> kSigmas = {1e-3, 0.0472228758124704, 0.3};

// B from `first` to `last`, finely near `first` (where the bounds are tight), then coarser.
std::vector<double> angular_terms(double first, double last) {
  std::vector<double> b;
  for (double v = first; v < std::min(first + 10.0, last); v += 0.05) b.push_back(v);
  for (double v = first + 10.0; v < last; v += 1.0) b.push_back(v);
  b.push_back(last);
  return b;
}

double t_of(double u, double b) { return (u - 4.0 - b) / 2.0; }

TEST(OpdfBounds, BelowLinearUTheLogitIsLinearInU) {
  double worst = 0, worst_peak_ratio = 0;
  for (double s : kSigmas)
    for (double b : angular_terms(0.0, 120.0))
      for (double u = kLinearU; u > kLinearU - 150.0; u -= 0.25) {
        const double t = t_of(u, b), d = t * s;
        ASSERT_LE(t, -12.0);
        worst = std::max(worst, std::abs(logit_opdf(d, b, s) - (std::log(0.5) + u)));
        const double peak = opdf_peak(d, b, s), step = opdf(d, b, s) - peak;
        worst_peak_ratio = std::max(worst_peak_ratio, peak / step);
      }
  EXPECT_LT(worst, 2.1e-9);
  EXPECT_LT(worst_peak_ratio, std::exp(-120.0));
}


TEST(OpdfBounds, AtOrBelowNonPositiveTTheLogitIsNotPositiveForEveryB) {
  std::vector<double> b = angular_terms(0.0, 200.0);
  b.insert(b.begin(), {1e-9, 1e-6, 1e-3});
  double largest = -1e300;
  for (double s : kSigmas)
    for (double angular : b)
      for (double t = kNonPositiveT; t > kNonPositiveT - 60.0; t -= 0.005)
        largest = std::max(largest, logit_opdf(t * s, angular, s));
  EXPECT_LE(largest, 0.0);
  // Just beyond the bound the logit is positive for B = 0: the constant is where the sign changes, not a
  // loose figure (the peak term lifts P_s above 1/2 from t ~ -1.17 on).
  EXPECT_GT(logit_opdf(-1.1 * kSigmas[1], 0.0, kSigmas[1]), 0.0);
}

TEST(OpdfBounds, FarInFrontTheLogitExceedsTheLinearTermByLessThanTheMargin) {
  // For u <= -2: logit P_s <= log(1/2) + u + 0.072, and 0.072 < kBoundMargin, so an untouched bin with
  // log(1/2) + u <= L_min - kBoundMargin ends below L_min.
  double worst_excess = -1e300;
  for (double s : kSigmas)
    for (double b : angular_terms(0.0, 120.0))
      for (double u = -2.0; u > -200.0; u -= 0.01) {
        const double d = t_of(u, b) * s;
        worst_excess = std::max(worst_excess, logit_opdf(d, b, s) - (std::log(0.5) + u));
      }
  EXPECT_LE(worst_excess, 0.072);
  EXPECT_LT(0.072, kBoundMargin);
}

TEST(OpdfBounds, AboveNegligibleBTheLogitBeyondNonPositiveTIsBelowHalfTheSkipEpsilon) {
  std::vector<double> b = angular_terms(kNegligibleB, 200.0);
  b.push_back(1e3);
  double worst = 0;
  for (double s : kSigmas)
    for (double angular : b)
      for (double t = kNonPositiveT; t < 60.0; t += 0.005) worst = std::max(worst, std::abs(logit_opdf(t * s, angular, s)));
  EXPECT_LT(worst, 4.5e-7);
  EXPECT_LT(4.5e-7, kSkipEpsilon / 2.0);
}

TEST(OpdfBounds, UpToMaxFactoredBTheFactoredFloatTermsKeepEMinusU) {
  // The factors fast_exp(-B) and e_b = fast_exp(B - u) stay unsaturated floats for every bin the kernel
  // evaluates (u >= kLinearU), so their product is e^-u to float accuracy: fast_exp's 2e-7 twice plus the
  // rounding of exponents up to kMaxFactoredB - kLinearU = 80 to float (80 x 2^-24 = 4.8e-6). A saturated
  // factor would be off by orders of magnitude ...
  double worst_factor = 0;
  for (double b : angular_terms(0.0, kMaxFactoredB))
    for (double u = kLinearU; u < 30.0; u += 0.25) {
      const float a = detail::fast_exp(static_cast<float>(-b)), e = detail::fast_exp(static_cast<float>(b - u));
      ASSERT_TRUE(std::isnormal(a) && std::isfinite(e)) << "B = " << b << ", u = " << u;
      worst_factor = std::max(worst_factor, std::abs(static_cast<double>(a) * static_cast<double>(e) / std::exp(-u) - 1.0));
    }
  EXPECT_LT(worst_factor, 5.5e-6);
  // ... and the factored profile (integrate.hpp's logit_opdf_profile takes that path up to kMaxFactoredB)
  // follows the model there: 2e-6 absolute plus 1e-6 of |logit|, the kernel's tolerance (test_fast_math).
  double worst = 0;
  for (double s : kSigmas)
    for (double b : angular_terms(0.0, kMaxFactoredB)) {
      std::vector<double> centres;
      for (double t = t_of(kLinearU, b); t < 8.0; t += 0.05) centres.push_back(2.0 + t * s);
      std::vector<float> out(centres.size());
      logit_opdf_profile(centres.data(), centres.size(), 2.0, b, s, out.data());
      for (std::size_t i = 0; i < centres.size(); ++i) {
        const double exact = logit_opdf(centres[i] - 2.0, b, s);
        worst = std::max(worst, std::abs(out[i] - exact) / (2e-6 + 1e-6 * std::abs(exact)));
      }
    }
  EXPECT_LT(worst, 1.0);
}

TEST(OpdfBounds, AbovePeakNegligibleBDroppingThePeakMovesTheImprovementByLessThan4e8) {
  const std::vector<double> priors = {1e-6, 1e-3, 0.05, 0.2, 0.4, 0.5, 0.6, 0.8, 0.95, 0.999, 1 - 1e-6};
  const auto posterior = [](double p, double ps) { return p * ps / (p * ps + (1 - p) * (1 - ps)); };
  double worst_ratio = 0, worst_imp = 0;
  for (double s : kSigmas)
    for (double b : angular_terms(kPeakNegligibleB, 200.0))
      for (double t = -60.0; t < 60.0; t += 0.01) {
        const double d = t * s, ps = opdf(d, b, s), g = opdf_peak(d, b, s);
        worst_ratio = std::max({worst_ratio, g / ps, g / (1 - ps)});
        for (double p : priors) worst_imp = std::max(worst_imp, std::abs(posterior(p, ps) - posterior(p, ps - g)));
      }
  EXPECT_LT(worst_ratio, 8e-8);
  EXPECT_LT(worst_imp, 4e-8);
}

}  // namespace
}  // namespace occ_improve
