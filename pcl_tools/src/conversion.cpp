#include "occ_improve/pcl/conversion.hpp"

#include "occ_improve/errors.hpp"

#include <cmath>
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

}  // namespace occ_improve
