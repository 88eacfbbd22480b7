#pragma once
// The 8-bit image buffer: what the renderer draws (sim/render.hpp) and a registered colour frame as the
// tools read it. A buffer type of its own, so readers of images need not include the renderer.
#include <cstdint>
#include <vector>

namespace occ_improve {

/// 8-bit image, row-major, channels interleaved (1 = grey, 3 = RGB).
struct Image {
  int width = 0, height = 0, channels = 1;
  std::vector<std::uint8_t> pixels;
};

}  // namespace occ_improve
