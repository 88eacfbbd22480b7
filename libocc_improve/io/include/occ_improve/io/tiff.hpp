#pragma once
// TIFF images through libtiff: 16-bit depth maps (PCL's ImageGrabber / PCDGrabber `*_depth.tiff`) and the
// registered colour beside them (`*_rgb.tiff`). libtiff never prints: its errors and warnings go to
// per-file handlers, and the first error ends up in the exception (FormatError naming the file).
#include "occ_improve/io/depth_image.hpp"
#include "occ_improve/maps/image.hpp"

#include <string>

namespace occ_improve {

/// A 16-bit unsigned single-channel TIFF in strips (any rows per strip, any compression libtiff decodes).
/// Throws IoError when the file cannot be opened, FormatError naming the file for anything else: not a
/// TIFF, corrupt or truncated data, tiled layout, or a pixel format other than 16-bit unsigned x 1 sample
/// (the message says which bits, samples and sample format it found). The size is checked against
/// kMaxDepthImagePixels and against what the file can hold before the pixel buffer is allocated.
DepthImage16 read_tiff_depth16(const std::string& path);

/// Any TIFF libtiff's RGBA interface reads (8-bit RGB, grey, palette, ...) as RGB8, top row first.
/// Throws as read_tiff_depth16; the same size caps apply.
Image read_tiff_rgb8(const std::string& path);

}  // namespace occ_improve
