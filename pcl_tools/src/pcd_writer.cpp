#include "occ_improve/pcl/pcd_writer.hpp"

#include "occ_improve/io/atomic_file.hpp"

#include <pcl/io/pcd_io.h>

#include <cstring>

namespace occ_improve {
namespace {

// The cloud with its fields packed one after the other (no struct padding), as PCL's typed writer stores
// them: smaller files, and the same bytes as pcl::io::savePCDFileBinary of the typed cloud.
pcl::PCLPointCloud2 packed(const pcl::PCLPointCloud2& cloud) {
  pcl::PCLPointCloud2 out;
  out.header = cloud.header;
  out.width = cloud.width;
  out.height = cloud.height;
  out.is_bigendian = cloud.is_bigendian;
  out.is_dense = cloud.is_dense;
  out.fields = cloud.fields;
  std::vector<std::uint32_t> bytes(out.fields.size());
  std::uint32_t step = 0;
  for (std::size_t f = 0; f < out.fields.size(); ++f) {
    bytes[f] = out.fields[f].count * static_cast<std::uint32_t>(pcl::getFieldSize(out.fields[f].datatype));
    out.fields[f].offset = step;
    step += bytes[f];
  }
  out.point_step = step;
  out.row_step = step * out.width;
  const std::size_t points = static_cast<std::size_t>(cloud.width) * cloud.height;
  out.data.resize(points * step);
  for (std::size_t i = 0; i < points; ++i)
    for (std::size_t f = 0; f < out.fields.size(); ++f)
      std::memcpy(&out.data[i * step + out.fields[f].offset], &cloud.data[i * cloud.point_step + cloud.fields[f].offset],
                  bytes[f]);
  return out;
}

}  // namespace

void save_pcd_binary(const std::string& path, const pcl::PCLPointCloud2& cloud, const Eigen::Vector4f& origin,
                     const Eigen::Quaternionf& orientation) {
  const pcl::PCLPointCloud2 blob = packed(cloud);
  pcl::PCDWriter writer;
  // generateHeaderBinary stops before the DATA line, which writeBinary adds itself.
  const std::string header = writer.generateHeaderBinary(blob, origin, orientation) + "DATA binary\n";
  write_file_atomically(path, "PCD file", [&](std::ostream& out) {
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    out.write(reinterpret_cast<const char*>(blob.data.data()), static_cast<std::streamsize>(blob.data.size()));
    return static_cast<bool>(out);
  });
}

}  // namespace occ_improve
