#pragma once
// Our own check of a PLY file before PCL's reader sees it. PCL 1.13's PLYReader sizes its point buffer
// from the header before reading any data: element counts (std::size_t, "-1" wraps), `obj_info num_cols /
// num_rows` (atoi, so negative values wrap to 4 G), a list property on vertices (sized by the first
// vertex's list length). A 100-byte header could make it allocate gigabytes, and a camera element's
// viewport can change width x height after the buffer was sized. The header is checked here against
// itself and the file's size, and what PCL built is checked before anything converts it.
#include "occ_improve/pcl/pcd_header.hpp"

#include <pcl/PCLPointCloud2.h>

#include <cstdint>
#include <string>

namespace occ_improve {

struct PlyHeader {
  enum class Format { ascii, binary_little_endian, binary_big_endian };
  Format format = Format::ascii;
  std::uint64_t vertices = 0;             ///< the vertex element's count (0 without one)
  std::uint32_t columns = 0, rows = 0;    ///< obj_info num_cols / num_rows (PCL's organized clouds), 0 if absent
  std::uint64_t data_offset = 0;          ///< byte offset of the data, just after end_header
};

/// Reads and checks the header of PLY file `path`. Throws IoError when the file cannot be read,
/// FormatError naming the file for: no `ply` magic, a malformed or unknown line, a count that is not a
/// whole number, elements whose least possible size exceeds the file, a list property on vertices (PCL
/// sizes its buffer from the first vertex's list), num_cols x num_rows not given together before the
/// elements or not equal to the vertex count (the range_grid count when there is one); ResourceLimit
/// when the vertex data PCL would hold exceeds kMaxPcdDataBytes.
PlyHeader validate_ply_file(const std::string& path);

/// validate_ply_file(), then PCL's reader, then the cloud PCL built (width x height x point step = data
/// size, fields inside the point). Throws as validate_ply_file, FormatError when PCL refuses.
void read_ply_file(const std::string& path, pcl::PCLPointCloud2& blob);

}  // namespace occ_improve
