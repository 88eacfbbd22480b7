#pragma once
// PNG files of the core's images (render.hpp), written through libpng (deflate, zlib levels 0-9), and masks
// read from PNG (depth PNGs: depth_image.hpp).
#include "occ_improve/grid/mask.hpp"
#include "occ_improve/sim/render.hpp"

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

/// A 16-bit grey image: label ids (regions.png, labels.png) or depth in millimetres (depth_mm.png), row-major.
struct Image16 {
  int width = 0, height = 0;
  std::vector<std::uint16_t> pixels;
};

/// The PNG file bytes of a 16-bit grey image (PNG stores 16-bit samples big-endian; readers such as
/// OpenCV's imread(..., IMREAD_UNCHANGED), PIL and PCL's PNG reader give back the values). Throws as
/// encode_png.
std::vector<std::uint8_t> encode_png(const Image16& image, int compression_level = 6);
/// Writes encode_png(image) to `path` atomically, as write_png.
void write_png(const std::string& path, const Image16& image);

/// A validity / region-of-interest mask (mask.hpp): an 8-bit or 16-bit grey PNG (1, 2, 4-bit expanded),
/// nonzero = valid. Size checks as read_depth_image16; any other pixel format is a FormatError naming the
/// file.
PixelMask read_mask_png(const std::string& path);

}  // namespace occ_improve
