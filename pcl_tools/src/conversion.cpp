#include "occ_improve/pcl/conversion.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/integrate/point_units.hpp"

#include <cmath>
#include <optional>
#include <string>

namespace occ_improve {

std::size_t valid_point_count(PointSpan points) {
  std::size_t valid = 0;
  for (std::size_t i = 0; i < points.count; ++i) {
    const float* p = points.xyz + i * points.stride_floats;
    const bool finite = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
    valid += finite && (p[0] != 0 || p[1] != 0 || p[2] != 0) ? 1 : 0;
  }
  return valid;
}

void require_valid_points(PointSpan points, const std::string& name) {
  if (valid_point_count(points) == 0)
    throw InvalidInput("'" + name + "' holds no valid point (" + std::to_string(points.count) +
                       " points, all NaN, infinite or at the origin)");
}

void require_points_in_metres(PointSpan points, const std::string& name, const GeometryParams& grid,
                              const std::string& what, const std::string& hint) {
  const std::optional<UnitMistake> mistake = point_unit_mistake(points, grid);
  if (!mistake) return;
  throw InvalidInput("'" + name + "': " + mistake->about_points(grid) + (what.empty() ? "" : " (the " + what + ")") + hint);
}

pcl::PointCloud<pcl::PointXYZ> organized_cloud(const std::vector<Eigen::Vector3f>& points, int width, int height) {
  if (width <= 0 || height <= 0 ||
      points.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    throw InvalidInput("organized_cloud: " + std::to_string(points.size()) + " points do not make a " +
                       std::to_string(width) + " x " + std::to_string(height) + " image");
  pcl::PointCloud<pcl::PointXYZ> cloud(static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height));
  for (std::size_t i = 0; i < points.size(); ++i) cloud[i] = pcl::PointXYZ(points[i].x(), points[i].y(), points[i].z());
  cloud.is_dense = false;
  return cloud;
}

std::vector<float> depth_of_organized(const pcl::PointCloud<pcl::PointXYZ>& cloud) {
  if (!cloud.isOrganized() || cloud.height <= 1)
    throw InvalidInput("depth_of_organized: the cloud is not organized (height " + std::to_string(cloud.height) + ")");
  std::vector<float> depth(cloud.size(), 0.0f);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (std::isfinite(cloud[i].z) && cloud[i].z > 0) depth[i] = cloud[i].z;
  return depth;
}

template <typename PointT>
IntrinsicsFit estimate_intrinsics_fit(const pcl::PointCloud<PointT>& cloud, double max_rms_px) {
  if (!cloud.isOrganized() || cloud.height <= 1)
    throw InvalidInput("intrinsics can only be estimated from an organized cloud (height > 1)");
  // PCL lays an organized cloud's points out row-major at a float stride.
  static_assert(sizeof(PointT) % sizeof(float) == 0, "PCL points are float-aligned");
  return fit_intrinsics_checked(&cloud.points[0].x, static_cast<int>(cloud.width), static_cast<int>(cloud.height),
                                sizeof(PointT) / sizeof(float), max_rms_px);
}

template <typename PointT>
PinholeIntrinsics estimate_intrinsics(const pcl::PointCloud<PointT>& cloud) {
  return estimate_intrinsics_fit(cloud, kMaxIntrinsicsFitResidualPx).intrinsics;
}

// The filter's and the pipeline's point types (ImprovementFilter fits its default map's camera), and XYZRGBL.
#define OCC_IMPROVE_INSTANTIATE_INTRINSICS(T)                                      \
  template IntrinsicsFit estimate_intrinsics_fit(const pcl::PointCloud<T>&, double); \
  template PinholeIntrinsics estimate_intrinsics(const pcl::PointCloud<T>&);
OCC_IMPROVE_INSTANTIATE_INTRINSICS(pcl::PointXYZ)
OCC_IMPROVE_INSTANTIATE_INTRINSICS(pcl::PointXYZI)
OCC_IMPROVE_INSTANTIATE_INTRINSICS(pcl::PointXYZL)
OCC_IMPROVE_INSTANTIATE_INTRINSICS(pcl::PointXYZRGB)
OCC_IMPROVE_INSTANTIATE_INTRINSICS(pcl::PointXYZRGBA)
OCC_IMPROVE_INSTANTIATE_INTRINSICS(pcl::PointXYZRGBL)
#undef OCC_IMPROVE_INSTANTIATE_INTRINSICS

}  // namespace occ_improve
