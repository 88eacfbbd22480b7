#pragma once
// PNG files of the core's images (render.hpp) and 16-bit grey images (depth in millimetres), written
// through libpng (deflate, zlib levels 0-9).
#include "occ_improve/render.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

/// The PNG file bytes of an 8-bit grey or RGB image at zlib `compression_level` (0 = stored .. 9 = smallest;
/// 6, zlib's default, is within a few per cent of 9 at a fraction of its time). Throws InvalidInput for an
/// inconsistent image, InvalidParameter for a level outside [0, 9], IoError when libpng fails.
std::vector<std::uint8_t> encode_png(const Image& image, int compression_level = 6);

/// Writes encode_png(image) to `path` atomically (write_file_atomically: a failed write leaves an existing
/// file as it was). Throws IoError when the file cannot be written, InvalidInput for an inconsistent image.
void write_png(const std::string& path, const Image& image);

/// A 16-bit grey PNG (row-major, width x height values), e.g. a depth image in millimetres as Kinect
/// datasets store it. Throws InvalidInput when `grey` does not hold width x height values, otherwise as
/// encode_png / write_png.
std::vector<std::uint8_t> encode_png16(int width, int height, const std::vector<std::uint16_t>& grey,
                                       int compression_level = 6);
void write_png16(const std::string& path, int width, int height, const std::vector<std::uint16_t>& grey);

}  // namespace occ_improve
