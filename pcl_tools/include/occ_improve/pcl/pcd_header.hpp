#pragma once
// Our own check of a PCD file before PCL's reader sees it. PCL 1.13's PCDReader trusts the header:
// WIDTH x HEIGHT wrapping in 32 bits, COUNT or SIZE of -1, binary_compressed size fields that disagree
// with the header or the file crash it, spin it or make it allocate gigabytes. Every value is checked
// here, products in 64 bits, declared data sizes against the file's size and a memory cap.
#include <pcl/PCLPointCloud2.h>

#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

/// The largest point data (POINTS x bytes per point) a PCD file may declare: 2 GiB, PCL's int offsets.
inline constexpr std::uint64_t kMaxPcdDataBytes = (std::uint64_t{1} << 31) - 1;

struct PcdField {
  std::string name;
  std::uint32_t size = 0;   ///< bytes per value: 1, 2, 4 or 8
  char type = 'F';          ///< I (signed), U (unsigned), F (float)
  std::uint32_t count = 1;  ///< values per point
};

struct PcdHeader {
  enum class Data { ascii, binary, binary_compressed };
  std::vector<PcdField> fields;
  std::uint32_t width = 0, height = 0;
  std::uint64_t points = 0;
  Data data = Data::ascii;
  std::uint64_t data_offset = 0;  ///< byte offset of the data, just after the DATA line

  std::uint64_t point_bytes() const;
};

/// Reads and checks the header of PCD file `path` and its data's size. Throws IoError when the file
/// cannot be read, FormatError naming the file and the field for any value that is malformed, out of
/// range or inconsistent with the other fields or the file's size (binary_compressed data is also
/// decompressed once to check that it holds exactly the declared bytes), ResourceLimit when the data
/// exceeds kMaxPcdDataBytes.
PcdHeader validate_pcd_file(const std::string& path);

/// Throws FormatError naming `path` unless `blob` has a field `name` of one value of PCL type `datatype`
/// (pcl::PCLPointField::FLOAT32, ...): PCL's conversion would otherwise fill the point with zeros silently.
/// For any blob PCL read (PCD or PLY).
void require_pcd_field(const pcl::PCLPointCloud2& blob, const std::string& path, const std::string& name,
                       std::uint8_t datatype);

/// validate_pcd_file(), then PCL's reader. Throws as validate_pcd_file, and FormatError when PCL refuses.
void read_pcd_file(const std::string& path, pcl::PCLPointCloud2& blob);
/// The same, also returning the VIEWPOINT line as PCL parsed it (zero and identity without one).
void read_pcd_file(const std::string& path, pcl::PCLPointCloud2& blob, Eigen::Vector4f& origin,
                   Eigen::Quaternionf& orientation);

}  // namespace occ_improve
