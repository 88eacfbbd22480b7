#pragma once
// Binary PCD files written the way every other output of occ_improve is written: to a temporary beside the
// target, renamed into place once complete (write_file_atomically), so that a failed write leaves no
// partial file and its error names the cause ("no space left on device") and the path. The bytes are
// pcl::io::savePCDFileBinary's for the typed cloud: PCL's own header, then the points with their fields packed.
#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/point_cloud.h>

#include <Eigen/Geometry>

#include <string>

namespace occ_improve {

/// Writes `cloud` as a binary PCD with the VIEWPOINT `origin`, `orientation` (PCL's sensor pose of the
/// cloud). Throws IoError naming `path` and the cause.
void save_pcd_binary(const std::string& path, const pcl::PCLPointCloud2& cloud,
                     const Eigen::Vector4f& origin = Eigen::Vector4f::Zero(),
                     const Eigen::Quaternionf& orientation = Eigen::Quaternionf::Identity());

/// The typed cloud with its own VIEWPOINT (sensor_origin_, sensor_orientation_), as PCL writes it.
template <typename PointT>
void save_pcd_binary(const std::string& path, const pcl::PointCloud<PointT>& cloud) {
  pcl::PCLPointCloud2 blob;
  pcl::toPCLPointCloud2(cloud, blob);
  save_pcd_binary(path, blob, cloud.sensor_origin_, cloud.sensor_orientation_);
}

}  // namespace occ_improve
