#include "occ_improve/maps/column_map.hpp"

#include "occ_improve/errors.hpp"

#include <string>

namespace occ_improve {

std::size_t ColumnShape::count() const {
  if (width < 0 || height < 0) return 0;
  return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
}

ColumnShape ColumnShape::of_grid(int width, int height) {
  ColumnShape s{width, height, 0};
  s.values = s.count();
  return s;
}

ColumnShape ColumnShape::of_arrays(int width, int height, std::initializer_list<std::size_t> array_sizes) {
  ColumnShape s = of_grid(width, height);
  for (std::size_t size : array_sizes)
    if (size != s.values) return {width, height, size};
  return s;
}

namespace {

std::string size_text(const ColumnShape& s) { return std::to_string(s.width) + " x " + std::to_string(s.height); }

void require_whole(const char* what, const ColumnShape& s) {
  if (s.width < 0 || s.height < 0) throw InvalidInput(std::string(what) + " has a negative size, " + size_text(s));
  if (s.values != s.count())
    throw InvalidInput(std::string(what) + " of " + size_text(s) + " holds " + std::to_string(s.values) +
                       " values, not " + std::to_string(s.count()));
}

}  // namespace

void require_shape(const char* what, const ColumnShape& shape, const char* expected_what, const ColumnShape& expected) {
  require_whole(expected_what, expected);
  require_whole(what, shape);
  if (shape.width != expected.width || shape.height != expected.height)
    throw InvalidInput(std::string(what) + " is " + size_text(shape) + ", " + expected_what + " " + size_text(expected));
}

}  // namespace occ_improve
