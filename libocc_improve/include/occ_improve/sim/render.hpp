#pragma once
// Images of the maps (CONVENTIONS 9). Files of them: occ_improve::io (occ_improve/io/png.hpp), which needs libpng.
//
// Improvement colour map (docs/METHOD.md, "Rendering"), piecewise linear in RGB between breakpoints:
//   <= -0.3 dark blue (0,0,128), -0.1 blue (0,64,255), 0 green (0,200,0), 0.1 yellow (255,255,0),
//   0.26 orange (255,160,0), 0.31 (255,100,0), >= 0.322 red (255,0,0) = the no-data level.
// Columns that are not observable (NaN) are neutral grey (128,128,128), unlike the no-data red.
// It is non-linear in value: most of the colour range is spent on [-0.1, 0.3], where the paper's
// picture lives (observed-once ~0.13, no data ~0.32, discontinuities negative).
#include "occ_improve/maps/image.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/maps/surface.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

/// Grey: 0 m black .. depth_max_m white (clipped). depth_max_m <= 0 or NaN -> InvalidParameter.
Image render_depth(const SurfaceMap& surface, double depth_max_m);
/// Grey: P 0 black, 0.5 mid grey (128), 1 white.
Image render_occupancy(const SurfaceMap& surface);
/// RGB through improvement_colour.
Image render_improvement(const ImprovementMap& map);
/// RGB legend: the colour bar from -0.4 to 0.4, ticks every 0.1 labelled with a built-in 3 x 5 digit font.
Image render_improvement_legend();

/// The colour map above (NaN -> neutral grey).
std::array<std::uint8_t, 3> improvement_colour(float value);
constexpr std::uint8_t kNotObservableGrey = 128;

/// The improvement colours blended over a registered RGB image of the same size (pixel-native grids
/// are pixel-aligned with the depth camera): improvement_weight * colour map + (1 - w) * image.
/// Throws InvalidInput for a colour image of another size, InvalidParameter for a weight outside [0, 1].
Image render_overlay(const ImprovementMap& map, const Image& colour, double improvement_weight = 0.5);

/// RGB line plot of y against x (a polyline in blue on white inside a black frame), x scaled from its
/// minimum to its maximum, y over the smallest range that holds its values and 0 (so that a nearly
/// constant series reads flat, not as its rounding); for a quick look at a run (the numbers go in a CSV
/// beside it). Throws
/// InvalidInput when x and y differ in length or hold fewer than 2 points, InvalidParameter for a size
/// under 16 x 16.
Image render_curve(const std::vector<double>& x, const std::vector<double>& y, int width = 640, int height = 400);

}  // namespace occ_improve
