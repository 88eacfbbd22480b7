#pragma once
// Shared by the image readers of occ_improve::io (not installed).
#include "occ_improve/io/depth_image.hpp"

#include <cstdint>
#include <string>

namespace occ_improve::detail {

/// An image's size is checked before any pixel buffer exists: against kMaxDepthImagePixels, and against
/// what the file's bytes can hold (`file_can_hold` pixels), so a 23-byte header cannot make us allocate
/// 20 GB. Throws FormatError "<kind> '<path>': width x height = W x H <problem>".
void require_image_size(const std::string& kind, const std::string& path, std::uint64_t width, std::uint64_t height,
                        std::uint64_t file_can_hold);

/// A grey PNG's values widened to 16 bits: 16-bit only for depth images, also 8-bit (and 1/2/4-bit,
/// expanded) for masks. `what` names the file's role in messages ("depth image", "mask").
DepthImage16 read_grey_png(const std::string& path, const std::string& what, bool accept_8bit);

}  // namespace occ_improve::detail
