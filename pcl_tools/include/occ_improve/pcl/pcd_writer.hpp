#pragma once
// Binary PCD files written the way every other output of occ_improve is written: to a temporary beside the
// target, renamed into place once complete (write_file_atomically), so that a failed write leaves no
// partial file and its error names the cause ("no space left on device") and the path. The bytes are
// pcl::io::savePCDFileBinary's for the typed cloud: PCL's own header, then the points with their fields packed.
#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/point_cloud.h>

#include <string>

namespace occ_improve {

/// Writes `cloud` as a binary PCD. Throws IoError naming `path` and the cause.
void save_pcd_binary(const std::string& path, const pcl::PCLPointCloud2& cloud);

template <typename PointT>
void save_pcd_binary(const std::string& path, const pcl::PointCloud<PointT>& cloud) {
  pcl::PCLPointCloud2 blob;
  pcl::toPCLPointCloud2(cloud, blob);
  save_pcd_binary(path, blob);
}

}  // namespace occ_improve
