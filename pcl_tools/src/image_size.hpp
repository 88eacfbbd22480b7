#pragma once
// Shared by the image readers of frame_io.cpp and tiff_image.cpp (not installed).
#include <cstdint>
#include <string>

namespace occ_improve::detail {

/// An image's size is checked before any pixel buffer exists: against kMaxDepthImagePixels, and against
/// what the file's bytes can hold (`file_can_hold` pixels), so a 23-byte header cannot make us allocate
/// 20 GB. Throws FormatError "<kind> '<path>': width x height = W x H <problem>".
void require_image_size(const std::string& kind, const std::string& path, std::uint64_t width, std::uint64_t height,
                        std::uint64_t file_can_hold);

}  // namespace occ_improve::detail
