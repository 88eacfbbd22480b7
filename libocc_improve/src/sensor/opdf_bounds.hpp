#pragma once
// Bounds derived from eq. 1 (CONVENTIONS 3) that let insertion (integrate.cpp) and improvement
// (improvement.cpp) skip or shorten work. Each is a promise about the model, checked against
// sensor_model.hpp's logit_opdf / opdf by tests/test_opdf_bounds.cpp: if eq. 1 changes, that test fails,
// not the map.
//
// With t = d_rho / sigma and B the angular term: u = 2t + 4 + B, x = e^-u, g = e^-(t^2 + B) / 3 (the peak
// term) and P_s = 1/2 (1 + x)^-1 + g (opdf_kernel.hpp).

namespace occ_improve {  // private header (src/): not installed

// In exact mode, bins with u < kLinearU take logit P_s = log(1/2) + u: there log(1 + e^u) < 2.1e-9 and the
// peak term is below e^-120 of the step term (t <= -12).
constexpr double kLinearU = -20.0;

// Clamped-mode shortcuts (exact under clamping; see integrate.hpp):
//  - logit P_s <= 0 wherever t <= kNonPositiveT, for every B >= 0: P_s <= 1/2 there because
//    (2/3)(e^-B + e^(2t+4)) <= (2/3)(1 + e^1) = 2.48 < e^(t^2) = 9.49 at t = -1.5 and the gap widens below.
//    Bins of the leading L_min run stay at L_min.
//  - for t <= -3 - B/2 (u <= -2): P_s <= 1/2 e^u (1 + 6.1e-4) (the peak term is (2/3) e^-((t+1)^2 + 3 + 2B)
//    <= 6.1e-4 of the step term) and -log(1 - P_s) <= 0.071, so logit P_s <= log(1/2) + u + 0.072. An
//    untouched bin (L = 0) with log(1/2) + u <= L_min - kBoundMargin therefore ends at L_min: not evaluated.
constexpr double kNonPositiveT = -1.5;
constexpr double kBoundMargin = 0.2;
//  - for B >= kNegligibleB every bin with t > kNonPositiveT has |logit P_s| < 4.5e-7 (below half of
//    kSkipEpsilon, integrate.hpp): there x = e^-u <= e^-(1 + B) and the peak term g <= e^-B / 3, and
//    |logit P_s| <= 4 max(x, g). So a column whose leading L_min run already reaches t = kNonPositiveT is
//    left unchanged by such a measurement (the run stays at L_min, the rest moves by less than the epsilon
//    CONVENTIONS 4 allows to skip): the diagonal neighbours of a pixel-native return (B = 24) cost nothing
//    where the view is continuous.
constexpr double kNegligibleB = 15.0;

// Columns with B above this take terms of their own: e^-B (fast_exp saturates at e^-87) times e_b would
// lose e^-u where e_b is large. Up to it, e^-B >= e^-60 is exact in float and the largest e_b the kernel
// evaluates (u >= kLinearU) is e^(B - u) <= e^80, below fast_exp's clamp at e^88.
constexpr double kMaxFactoredB = 60.0;

// The improvement's kernel drops g for window offsets with B >= kPeakNegligibleB: there g / P_s and
// g / (1 - P_s) are both below (2/3)(e^-B + e^-(3 + 2B)) < 8e-8 for every d_rho, and a relative error eps in
// P_s and in 1 - P_s moves the posterior of eq. 3 by at most eps / 2, so imp_i changes by < 4e-8.
constexpr float kPeakNegligibleB = 16.0f;

}  // namespace occ_improve
