#include "occ_improve/pcl/conversion.hpp"

#include "occ_improve/errors.hpp"

#include <string>

namespace occ_improve {

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

}  // namespace occ_improve
