#pragma once
// Poses read from files or given by users carry rotations written with 7-8 significant digits (7-Scenes:
// |R^T R - I| = 1.5e-4): the nearest rotation stands for them, so that T^-1 T = I, while scaling, shear and
// reflections are refused. One rule for the tools' pose files and the OctoMap export's pose.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <optional>

namespace occ_improve {

/// How far (Frobenius) a rotation written with 7-8 digits may lie from one.
constexpr double kRotationTolerance = 1e-3;

/// The rotation nearest to `m` (SVD: U V^T) when it is proper (det +1) and lies within `tolerance` of `m`
/// (Frobenius); nullopt otherwise (scaling, shear, a reflection, a non-finite entry). A rotation to 1e-12
/// is returned as it is: the SVD would move its last bits, and a pose saved and loaded again would drift.
std::optional<Eigen::Matrix3d> nearest_rotation(const Eigen::Matrix3d& m, double tolerance = kRotationTolerance);

/// The rigid transform a 4 x 4 matrix stands for: finite, last row 0 0 0 1, its 3 x 3 part a rotation
/// within `tolerance` (taken as nearest_rotation); nullopt otherwise. One rule for the poses a map is saved
/// with, the OctoMap export's and Python's.
std::optional<Eigen::Isometry3d> rigid_transform(const Eigen::Matrix4d& m, double tolerance = kRotationTolerance);

}  // namespace occ_improve
