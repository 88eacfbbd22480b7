#pragma once
// Images of the maps (SPEC 9) and a dependency-free PNG writer (stored deflate blocks, CRC-32, Adler-32).
//
// Improvement colour map (docs/METHOD.md, "Rendering"), piecewise linear in RGB between breakpoints:
//   <= -0.3 dark blue (0,0,128), -0.1 blue (0,64,255), 0 green (0,200,0), 0.1 yellow (255,255,0),
//   0.2 orange (255,140,0), >= 0.3 red (255,0,0).
// It is non-linear in value: most of the colour range is spent on [-0.1, 0.3], where the paper's
// picture lives (observed-once ~0.13, no data ~0.32, discontinuities negative).
#include "occ_improve/improvement.hpp"
#include "occ_improve/surface.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

/// 8-bit image, row-major, channels interleaved (1 = grey, 3 = RGB).
struct Image {
  int width = 0, height = 0, channels = 1;
  std::vector<std::uint8_t> pixels;
};

/// Grey: 0 m black .. depth_max_m white (clipped). depth_max_m <= 0 or NaN -> InvalidParameter.
Image render_depth(const SurfaceMap& surface, double depth_max_m);
/// Grey: P 0 black, 0.5 mid grey (128), 1 white.
Image render_occupancy(const SurfaceMap& surface);
/// RGB through improvement_colour.
Image render_improvement(const ImprovementMap& map);
/// RGB legend: the colour bar from -0.4 to 0.4, ticks every 0.1 labelled with a built-in 3 x 5 digit font.
Image render_improvement_legend();

/// The colour map above (NaN -> black).
std::array<std::uint8_t, 3> improvement_colour(float value);

/// Writes an 8-bit grey or RGB PNG. Throws IoError when the file cannot be written, InvalidInput for an
/// inconsistent image.
void write_png(const std::string& path, const Image& image);

/// The PNG file bytes (exposed for tests).
std::vector<std::uint8_t> encode_png(const Image& image);

}  // namespace occ_improve
