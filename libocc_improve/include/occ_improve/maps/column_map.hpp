#pragma once
// Per-column maps: one value per column of a width x height grid (or per pixel of a width x height image),
// row-major: column (x, y) is at y * width + x, the order of ColumnIndex (row = elevation bin / image row).
// ColumnShape is what a shape check compares and require_shape the one check every map's reader uses:
// InvalidInput naming both shapes.
#include <cstddef>
#include <initializer_list>
#include <vector>

namespace occ_improve {

/// A map's size as its shape check sees it: width x height, and how many values its arrays hold.
struct ColumnShape {
  int width = 0, height = 0;
  /// Values each array holds: width x height for a whole map; of arrays of different sizes, the first
  /// that is not width x height.
  std::size_t values = 0;

  /// width x height (0 when either is negative).
  std::size_t count() const;
  /// A grid's or image's shape: width x height columns, all of them there.
  static ColumnShape of_grid(int width, int height);
  /// A map of width x height columns whose arrays hold `array_sizes` values.
  static ColumnShape of_arrays(int width, int height, std::initializer_list<std::size_t> array_sizes);
};

/// The one shape check of per-column maps. Throws InvalidInput unless both shapes are whole (width and
/// height >= 0, every array holding width x height values) and `shape` has `expected`'s width and height:
///   "<what> is 20 x 10, <expected_what> 30 x 10"   (e.g. "surface map is 20 x 10, the grid 30 x 10")
///   "<what> of 20 x 10 holds 150 values, not 200"
void require_shape(const char* what, const ColumnShape& shape, const char* expected_what, const ColumnShape& expected);
/// Only that `shape` is whole.
inline void require_shape(const char* what, const ColumnShape& shape) { require_shape(what, shape, what, shape); }

/// A per-column map of one value type: width x height values, row-major.
template <typename T>
struct ColumnMap {
  int width = 0, height = 0;
  std::vector<T> values;

  /// width x height copies of `value`.
  static ColumnMap filled(int width, int height, const T& value) {
    return {width, height, std::vector<T>(ColumnShape::of_grid(width, height).count(), value)};
  }
  std::size_t size() const { return values.size(); }
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
  }
  T& at(int x, int y) { return values[index(x, y)]; }
  const T& at(int x, int y) const { return values[index(x, y)]; }
  ColumnShape shape() const { return ColumnShape::of_arrays(width, height, {values.size()}); }
};

}  // namespace occ_improve
