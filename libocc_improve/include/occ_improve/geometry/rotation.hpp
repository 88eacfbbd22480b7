#pragma once
// Poses read from files or given by users carry rotations written with 7-8 significant digits (7-Scenes:
// |R^T R - I| = 1.5e-4): the nearest rotation stands for them, so that T^-1 T = I, while scaling, shear and
// reflections are refused. One rule for the tools' pose files and the OctoMap export's pose.
#include <Eigen/Core>

#include <optional>

namespace occ_improve {

/// How far (Frobenius) a rotation written with 7-8 digits may lie from one.
constexpr double kRotationTolerance = 1e-3;

/// The rotation nearest to `m` (SVD: U V^T) when it is proper (det +1) and lies within `tolerance` of `m`
/// (Frobenius); nullopt otherwise (scaling, shear, a reflection, a non-finite entry).
std::optional<Eigen::Matrix3d> nearest_rotation(const Eigen::Matrix3d& m, double tolerance = kRotationTolerance);

}  // namespace occ_improve
