#pragma once
// 16-bit depth images (PNG, PGM, TIFF) decoded without PCL: the raw values with their size, the encodings
// that turn them into metres, and a guess of the encoding for when the user gives none. occ_improve::pcl
// turns them into clouds (frame_io.hpp).
#include "occ_improve/maps/column_map.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

enum class DepthEncoding {
  millimetres,      ///< 16-bit, 1 unit = 1 mm, 0 = no return (Kinect/OpenNI, 7-Scenes, SUN3D/3DMatch)
  tum_5000,         ///< 16-bit, 1 unit = 0.2 mm (TUM RGB-D, depth_m = value / 5000)
  sun_rotated_mm,   ///< 16-bit, depth_mm = (v >> 3) | (v << 13) (SUN RGB-D)
  kinect_disparity, ///< 11-bit raw disparity, 2047 = invalid, depth_m = 351.3 / (1092.5 - raw) (NYU)
};

/// "mm", "tum", "sun", "nyu" -> encoding; throws InvalidParameter otherwise.
DepthEncoding parse_depth_encoding(const std::string& name);
/// The inverse: "mm", "tum", "sun", "nyu".
const char* depth_encoding_name(DepthEncoding encoding);

/// A 16-bit single-channel image (PNG 16-bit grey, PGM P5 16-bit, or TIFF 16-bit unsigned), row-major.
using DepthImage16 = ColumnMap<std::uint16_t>;
/// The largest depth image read: 2^26 pixels (128 MiB of 16-bit values; a 4K depth map is 8.3 Mpx).
inline constexpr std::uint64_t kMaxDepthImagePixels = std::uint64_t{1} << 26;

/// Reads a 16-bit PNG, PGM or TIFF (.tif/.tiff, see tiff.hpp). Its size is checked against
/// kMaxDepthImagePixels and against what the file can hold before any pixel buffer is allocated
/// (FormatError naming the file and its width x height); any other pixel format is a FormatError.
DepthImage16 read_depth_image16(const std::string& path);

/// The file name's extension in lower case without the dot ("" without one): what the readers go by.
std::string lowercase_extension(const std::string& path);

/// True for the extensions read as depth images (.png, .pgm, .tif, .tiff, any case): these need camera
/// intrinsics to become a cloud.
bool is_depth_image_path(const std::string& path);

/// The encoding a 16-bit depth image most likely uses, for when the user did not say:
///  - .pgm whose values all fit in 11 bits: kinect_disparity (NYU's raw dumps);
///  - >= 90% of nonzero values multiples of 8 but < 90% multiples of 10, and a median of 4 m or more as
///    millimetres (0.5 m or more as SUN): sun_rotated_mm (millimetres below 8.192 m rotate to v << 3);
///  - >= 99% multiples of 5 but < 90% multiples of 10: tum_5000 (TUM stores the sensor's millimetres
///    times 5);
///  - steps between distinct values ~1/5 of a Kinect's millimetre quantisation at the quartiles and the
///    median alike (a Kinect's steps grow as z^2, a synthetic ramp's do not): tum_5000;
///  - neither TUM rule when the median would lie nearer than 0.5 m at TUM's scale;
///  - otherwise millimetres (also for an image with fewer than 100 nonzero values), so that an image of
///    round millimetres (2000 everywhere, whole centimetres, a smooth ramp) reads as what it is.
DepthEncoding guess_depth_encoding(const std::string& path, const DepthImage16& image);

/// The image's depth per pixel in metres through `encoding`, row-major; 0 = no return.
std::vector<float> depth_in_metres(const DepthImage16& image, DepthEncoding encoding);

}  // namespace occ_improve
