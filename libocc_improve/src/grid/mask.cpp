#include "occ_improve/grid/mask.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace occ_improve {

namespace {
std::string size_text(int width, int height) { return std::to_string(width) + " x " + std::to_string(height); }
}  // namespace

void PixelMask::validate() const {
  if (width <= 0 || height <= 0)
    throw InvalidInput("mask of " + size_text(width, height) + ": need width x height > 0");
  require_shape("mask", shape());
}

std::size_t PixelMask::valid_count() const {
  return static_cast<std::size_t>(std::count_if(valid.begin(), valid.end(), [](std::uint8_t b) { return b != 0; }));
}

std::vector<std::uint8_t> mask_columns(const GridGeometry& geometry, const PixelMask& mask) {
  mask.validate();
  const std::optional<PinholeIntrinsics>& camera = geometry.params().camera;
  if (!camera)
    throw InvalidParameter("a mask names camera pixels, and this grid has no camera (give one byte per column "
                           "instead: Mapper::set_column_mask, or a camera-based preset such as kinect_v1)");
  require_shape("mask", mask.shape(), "the camera", ColumnShape::of_grid(camera->width, camera->height));
  std::vector<std::uint8_t> columns(geometry.column_count(), 0);
  if (geometry.binning().columns_are_camera_pixels()) {
    for (std::size_t c = 0; c < columns.size(); ++c) columns[c] = mask.valid[c] != 0;
    return columns;
  }
  for (int e = 0; e < geometry.height(); ++e)
    for (int a = 0; a < geometry.width(); ++a) {
      const Eigen::Vector3d d = geometry.direction(a, e);
      if (!(d.z() > 0)) continue;
      const long u = std::lround(camera->fx * d.x() / d.z() + camera->cx);
      const long v = std::lround(camera->fy * d.y() / d.z() + camera->cy);
      if (u < 0 || v < 0 || u >= mask.width || v >= mask.height) continue;
      columns[geometry.column(a, e)] = mask.valid[static_cast<std::size_t>(v) * mask.width + u] != 0;
    }
  return columns;
}

std::vector<std::uint8_t> column_mask_of(const GridGeometry& geometry, const std::vector<std::uint8_t>& valid) {
  require_shape("column mask", ColumnShape::of_arrays(geometry.width(), geometry.height(), {valid.size()}), "the grid",
                ColumnShape::of_grid(geometry.width(), geometry.height()));
  std::vector<std::uint8_t> columns(valid.size());
  std::transform(valid.begin(), valid.end(), columns.begin(), [](std::uint8_t b) { return b != 0; });
  return columns;
}

std::size_t drop_masked_points(const GridGeometry& geometry, const std::vector<std::uint8_t>& columns,
                               PointSpan points, std::vector<float>& kept) {
  require_shape("column mask", ColumnShape::of_arrays(geometry.width(), geometry.height(), {columns.size()}));
  kept.clear();
  kept.reserve(points.count * 3);
  std::size_t dropped = 0;
  for (std::size_t i = 0; i < points.count; ++i) {
    const float* p = points.xyz + i * points.stride_floats;
    ColumnIndex c = 0;
    if (geometry.column_of(p[0], p[1], p[2], c) && !columns[c]) {
      ++dropped;
      continue;
    }
    kept.insert(kept.end(), p, p + 3);
  }
  return dropped;
}

namespace {
void require_mask_fits(const std::vector<std::uint8_t>& columns, const ImprovementMap& improvement) {
  require_shape("column mask", ColumnShape::of_arrays(improvement.width, improvement.height, {columns.size()}),
                "the improvement map", improvement.shape());
}
}  // namespace

void mask_improvement(const std::vector<std::uint8_t>& columns, ImprovementMap& improvement) {
  if (columns.empty()) return;
  require_mask_fits(columns, improvement);
  for (std::size_t c = 0; c < columns.size(); ++c)
    if (!columns[c]) improvement.value[c] = std::numeric_limits<float>::quiet_NaN();
}

void mask_improvement(const std::vector<std::uint8_t>& columns, const std::vector<ColumnIndex>& rays,
                      ImprovementMap& improvement) {
  if (columns.empty()) return;
  require_mask_fits(columns, improvement);
  for (const ColumnIndex c : rays)
    if (!columns[c]) improvement.value[c] = std::numeric_limits<float>::quiet_NaN();
}

PixelMask finite_pixel_mask(PointSpan points, int width, int height) {
  if (width <= 0 || height <= 0)
    throw InvalidInput("a finite-point mask needs an organized frame, not " + size_text(width, height));
  require_shape("a finite-point mask's organized frame", ColumnShape::of_arrays(width, height, {points.count}));
  PixelMask mask;
  mask.width = width;
  mask.height = height;
  mask.valid.resize(points.count);
  for (std::size_t i = 0; i < points.count; ++i) {
    const float* p = points.xyz + i * points.stride_floats;
    mask.valid[i] = is_valid_point(p[0], p[1], p[2]);
  }
  return mask;
}

}  // namespace occ_improve
