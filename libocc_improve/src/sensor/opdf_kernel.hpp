#pragma once
// The float OPDF kernel of eq. 1 (CONVENTIONS 3) shared by insertion (integrate.cpp) and improvement
// (improvement.cpp); sensor_model.cpp's logit_opdf is the double reference both are tested against.
//
// With t = d_rho / sigma and B the angular term, eq. 1 is P_s = 1/2 (1 + x)^-1 + g with
//   x = e^-u = e^-(2t + 4 + B)   and   g = e^-(t^2 + B) / 3.
// Both kernels need P_s as a ratio: with gx = g (1 + x),
//   P_s = (1/2 + gx) / (1 + x),   1 - P_s = (1/2 + x - gx) / (1 + x),
// so the odds are n / m with n = 1/2 + gx and m = 1/2 + x - gx; numerator and denominator both stay
// accurate near P_s = 1/2 (no 1 - P cancellation), and far in front x is large and P_s -> 1/(2x).
// B and log 3 are kept inside the exponents: fast_exp clamps its argument to [-87, 88], so x and g never
// leave the normal float range.
#include "support/fast_math.hpp"

namespace occ_improve::detail {

constexpr float kLog3 = 1.09861228866811f;

/// x = e^-u of eq. 1.
inline float opdf_x(float t, float angular_term) { return fast_exp(-(2.0f * t + 4.0f + angular_term)); }

/// g, the peak term of eq. 1.
inline float opdf_g(float t, float angular_term) { return fast_exp(-(t * t + angular_term) - kLog3); }

/// P_s / (1 - P_s) = n / m from x and g (which may carry a common factor e^-B applied by the caller).
struct OpdfOdds {
  float n, m;
};
inline OpdfOdds opdf_odds(float x, float g) {
  const float gx = g * (1.0f + x);
  return {0.5f + gx, 0.5f + x - gx};
}

}  // namespace occ_improve::detail
