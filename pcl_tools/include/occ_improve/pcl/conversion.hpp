#pragma once
// PCL clouds -> core point spans, without copying.
#include "occ_improve/integrate.hpp"

#include <pcl/point_cloud.h>

namespace occ_improve {

/// A view of a PCL cloud's xyz as a PointSpan (every PCL XYZ type starts with x, y, z floats).
template <typename PointT>
PointSpan span_of(const pcl::PointCloud<PointT>& cloud) {
  static_assert(sizeof(PointT) % sizeof(float) == 0, "point type size must be a whole number of floats");
  return {cloud.empty() ? nullptr : &cloud.points.front().x, cloud.size(), sizeof(PointT) / sizeof(float)};
}

}  // namespace occ_improve
