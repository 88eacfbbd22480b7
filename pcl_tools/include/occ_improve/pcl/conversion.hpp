#pragma once
// PCL clouds -> core point spans, without copying.
#include "occ_improve/integrate.hpp"

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <string>
#include <vector>

namespace occ_improve {

/// A view of a PCL cloud's xyz as a PointSpan (every PCL XYZ type starts with x, y, z floats).
template <typename PointT>
PointSpan span_of(const pcl::PointCloud<PointT>& cloud) {
  static_assert(sizeof(PointT) % sizeof(float) == 0, "point type size must be a whole number of floats");
  return {cloud.empty() ? nullptr : &cloud.points.front().x, cloud.size(), sizeof(PointT) / sizeof(float)};
}

/// How many points the insertion can use at all: finite and not at the origin (insert_points counts the
/// others as skipped_invalid).
std::size_t valid_point_count(PointSpan points);

/// Throws InvalidInput "'<name>' holds no valid point (...)" when valid_point_count(points) is 0. This
/// is the one rule by which every tool refuses an empty, all-NaN or all-zero frame (docs: README, Errors).
void require_valid_points(PointSpan points, const std::string& name);

/// An organized width x height cloud from per-pixel points in row-major order, NaN where there is no
/// return (sample::SampleFrame::points(), depth_image_to_points()). Throws InvalidInput on a size mismatch.
pcl::PointCloud<pcl::PointXYZ> organized_cloud(const std::vector<Eigen::Vector3f>& points, int width, int height);

/// The other way: an organized cloud's z per pixel, row-major, 0 where it has no return (the depth image a
/// VirtualSensor takes as its scene). Throws InvalidInput for a cloud that is not organized.
std::vector<float> depth_of_organized(const pcl::PointCloud<pcl::PointXYZ>& cloud);

}  // namespace occ_improve
