#include "occ_improve/geometry/rotation.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>

namespace occ_improve {

std::optional<Eigen::Matrix3d> nearest_rotation(const Eigen::Matrix3d& m, double tolerance) {
  if (!m.allFinite()) return std::nullopt;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d rotation = svd.matrixU() * svd.matrixV().transpose();
  if (rotation.determinant() < 0 || !((rotation - m).norm() <= tolerance)) return std::nullopt;
  return rotation;
}

}  // namespace occ_improve
