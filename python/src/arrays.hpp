#pragma once
// numpy <-> library buffers. Inputs are read in place where the library can read the layout (float32,
// native byte order, xyz contiguous, one constant positive stride between points); anything else is
// converted once to a float32 C-contiguous copy, kept alive beside the span that reads it.
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <cstring>
#include <vector>

namespace occ_improve::python {

namespace py = pybind11;

/// Points (N x 3 or H x W x 3) as a PointSpan; `keep` owns the converted copy when one was needed.
struct PointsInput {
  PointSpan span;
  py::object keep;
  bool copied = false;
};
/// Any array-like. Raises InvalidInput for another shape, TypeError for a non-numeric dtype.
PointsInput points_from_array(const py::handle& points);

/// A depth image (H x W) in the units `scale` converts to metres; `keep` owns the converted copy.
struct DepthInput {
  const float* depth = nullptr;
  std::size_t pixels = 0;
  py::object keep;
  bool copied = false;
};
/// Raises InvalidInput when the shape is not intrinsics.height x intrinsics.width.
DepthInput depth_from_array(const py::handle& depth, const PinholeIntrinsics& intrinsics);

/// Whether an array of booleans is taken as numbers (0 and 1): masks and flags, not coordinates or maps.
enum class Booleans { refused, taken };

/// Any array-like (nested lists too) as an ndarray of real numbers, without a copy when it already is
/// one. A dtype that is not a real number (complex, strings, objects; booleans unless taken) is a
/// TypeError naming `what`, as numpy gives; a nested sequence numpy cannot make an array of is
/// InvalidInput naming `expected`.
py::array real_array(const py::handle& object, const char* what, const char* expected, Booleans booleans);

/// `a` as a C-contiguous array of T: itself when it already is one, else a converted copy (numpy's own
/// error, MemoryError when the copy does not fit, propagates: `ensure` would have cleared it).
template <class T>
py::array_t<T, py::array::c_style | py::array::forcecast> c_array_of(const py::array& a) {
  return py::array_t<T, py::array::c_style | py::array::forcecast>(py::reinterpret_borrow<py::object>(a));
}

/// A flag array-like (bool or numbers) as 0/1 bytes in C order: nonzero is set (a cast to 8 bits made 0.5
/// and 256 unset); NaN is InvalidInput naming `what` and the element; types as real_array.
std::vector<std::uint8_t> flags_of(const py::handle& values, const char* what);

/// Clears the array's writeable flag: an in-place change raises ValueError instead of changing a copy or
/// the library's buffer.
inline void make_read_only(py::array& a) {
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
}

/// A read-only H x W array over `data` that keeps `owner` alive (a view: it follows later changes).
template <class T>
py::array view_2d(const T* data, int height, int width, py::handle owner, const py::dtype& dtype = py::dtype::of<T>()) {
  py::array a(dtype, {height, width},
              {static_cast<py::ssize_t>(width * sizeof(T)), static_cast<py::ssize_t>(sizeof(T))}, data, owner);
  make_read_only(a);
  return a;
}

/// A fresh, writable H x W array to copy into.
inline py::array empty_2d(int height, int width, const py::dtype& dtype) {
  return py::array(dtype, {height, width});
}

}  // namespace occ_improve::python
