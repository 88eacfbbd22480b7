#include "occ_improve/geometry/rotation.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>

namespace occ_improve {

std::optional<Eigen::Matrix3d> nearest_rotation(const Eigen::Matrix3d& m, double tolerance) {
  if (!m.allFinite()) return std::nullopt;
  if ((m.transpose() * m - Eigen::Matrix3d::Identity()).norm() <= 1e-12 && m.determinant() > 0) return m;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d rotation = svd.matrixU() * svd.matrixV().transpose();
  if (rotation.determinant() < 0 || !((rotation - m).norm() <= tolerance)) return std::nullopt;
  return rotation;
}

std::optional<Eigen::Isometry3d> rigid_transform(const Eigen::Matrix4d& m, double tolerance) {
  if (!m.allFinite() || m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) return std::nullopt;
  const std::optional<Eigen::Matrix3d> rotation = nearest_rotation(m.topLeftCorner<3, 3>(), tolerance);
  if (!rotation) return std::nullopt;
  Eigen::Isometry3d rigid = Eigen::Isometry3d::Identity();
  rigid.linear() = *rotation;
  rigid.translation() = m.topRightCorner<3, 1>();
  return rigid;
}

}  // namespace occ_improve
