#pragma once
// A validity / region-of-interest mask over the depth camera's pixels (nonzero = valid). Rays outside it
// are treated as rays the sensor cannot observe (CONVENTIONS 2c): their points are not inserted, their
// improvement is NaN, so they are never ranked, never in a region, never counted by the stop signal,
// never taken by the planner and drawn grey (improvement.hpp, ranking.hpp, planner.hpp, render.hpp).
//
// Why not "finite pixels" by default: on a raw sensor frame the pixels without a return (shadows, dark or
// specular surfaces) are exactly what the improvement map exists to find; only a cloud cropped on purpose
// (mOSD's floor and walls set to NaN) wants its invalid pixels masked. finite_pixel_mask() builds that
// mask when the caller says so (the tools' -mask finite).
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/maps/column_map.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/integrate/integrate.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace occ_improve {

/// Row-major, one byte per camera pixel; nonzero = the pixel's ray counts.
struct PixelMask {
  int width = 0, height = 0;
  std::vector<std::uint8_t> valid;
  /// InvalidInput when `valid` does not hold width x height bytes or the size is not positive.
  void validate() const;
  std::size_t valid_count() const;
  ColumnShape shape() const { return ColumnShape::of_arrays(width, height, {valid.size()}); }
};

/// One byte per column of `geometry` (1 = inside the mask). Pixel-native grids: the pixel itself; spherical
/// grids with a camera: the pixel the column's centre direction falls in (columns outside the image: 0).
/// Throws InvalidParameter when the geometry has no camera (the paper preset, lidar_rings: a mask names camera
/// pixels; column_mask_of takes one per column),
/// InvalidInput when the mask's size is not the camera's ("mask is W x H, the camera W x H").
std::vector<std::uint8_t> mask_columns(const GridGeometry& geometry, const PixelMask& mask);

/// A column mask given per column rather than per pixel, for any grid, with or without a camera (the paper
/// preset, lidar_rings: a vehicle's own body, a blind sector): `valid` holds one byte per column of
/// `geometry`, row by row (elevation bin), nonzero = inside. Returns the 0 / 1 bytes mask_columns would.
/// Throws InvalidInput when `valid` does not hold one byte per column.
std::vector<std::uint8_t> column_mask_of(const GridGeometry& geometry, const std::vector<std::uint8_t>& valid);

/// The valid points of `points` whose column is outside `columns` (mask_columns) left out, the others
/// copied to `kept` (x y z floats) in order; invalid and out-of-field points are kept, so that the
/// insertion counts them as it always does. Returns how many were left out.
std::size_t drop_masked_points(const GridGeometry& geometry, const std::vector<std::uint8_t>& columns,
                               PointSpan points, std::vector<float>& kept);

/// NaN improvement for every column outside `columns` (empty: none), as for columns no pixel can see.
void mask_improvement(const std::vector<std::uint8_t>& columns, ImprovementMap& improvement);
/// The same for `rays` only (the rays an incremental update recomputed): the other columns outside the
/// mask are NaN already, so an insertion costs O(changed rays), not a pass over every column.
void mask_improvement(const std::vector<std::uint8_t>& columns, const std::vector<ColumnIndex>& rays,
                      ImprovementMap& improvement);

/// The mask of an organized frame's valid points (CONVENTIONS 1: finite, not the origin): `points` holds
/// width x height points in row-major pixel order. InvalidInput when the count does not match.
PixelMask finite_pixel_mask(PointSpan points, int width, int height);

}  // namespace occ_improve
