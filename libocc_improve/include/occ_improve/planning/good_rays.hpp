#pragma once
// A shot's expected gain in the predictor's terms: the expected change in the number of rays whose depth
// estimate lies within 2 sigma(z) of the truth (the tolerance docs/SELECTIVE.md's quality counts), under
// the sensor model's Gaussian depth noise. The coarse-to-fine plan refined by triangles reports it
// (planner.hpp); the paper's improvement measures how much a ray's occupancy would change, which says
// nothing of what a new sample adds to the linear prediction between samples.
//
// Per ray taken, p its return probability (return_model.hpp):
//  - a ray in a coverage block with no depth sample before the shot: nothing is predicted there, and the
//    block's rays become predicted from this shot's samples: p x the block's return rate x
//    within_two_sigma(1) x the block's observable rays / the shot's rays in the block;
//  - the centroid of a sample triangle: p x the triangle's area x off_plane_share(its non-planarity);
//  - a ray never measured, between samples: p x (within_two_sigma(1) - within_two_sigma(3)) = -0.045 p:
//    a plane through three once-measured samples predicts a point between them with at most sigma /
//    sqrt(3) of noise, better than one return of its own (measured on capture0001: the first pass's last
//    third, which asks these rays, lowers the quality by 0.011, 0.006-0.055 rays a ray);
//  - a ray measured before: 0. Gaussian fusion would give its second return 0.041 rays
//    (within_two_sigma(2) - within_two_sigma(1)), but measured on capture0001, 215 000 second returns
//    on once-measured rays spread over the view changed the count by -0.001 rays a ray: what a
//    re-measured ray gains is not a function of its count of returns, so no term is claimed.
// Every term is an approximation of the kind stated; the calibration is measured (docs/SELECTIVE.md).
#include <cstdint>

namespace occ_improve {

/// P(|error| <= 2 sigma) for a depth fused from `returns` returns of noise sigma each: the fused error's
/// deviation is sigma / sqrt(k), so erf(sqrt(2 k)): 0.9545 for one, 0.9953 for two, 0.99947 for three;
/// 0 for none (nothing measured there).
double within_two_sigma(std::uint32_t returns);

/// Share of a triangle's interior that the plane through its vertices predicts more than 2 sigma off,
/// with the interior modelled as lying N(0, (n / 2)^2) sigma off that plane, n = the largest
/// leave-one-out residual of its vertices in sigmas (SampleTriangulation::non_planarity_sigmas): the
/// interior deviates about half as much as the vertex that deviates most. erfc(2 sqrt(2) / n): 6e-5 at
/// n = 1 (noise), 0.046 at 2, 0.32 at 4, 0.62 at 8; 0 for n <= 0. The centroid's return is taken to
/// make that share good (its three sub-triangles are a third of the size).
double off_plane_share(double non_planarity_sigmas);

}  // namespace occ_improve
