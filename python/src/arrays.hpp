#pragma once
// numpy <-> library buffers. Inputs are read in place where the library can read the layout (float32,
// native byte order, xyz contiguous, one constant positive stride between points); anything else is
// converted once to a float32 C-contiguous copy, kept alive beside the span that reads it.
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

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

/// A read-only H x W array over `data` that keeps `owner` alive (a view: it follows later changes).
template <class T>
py::array view_2d(const T* data, int height, int width, py::handle owner, const py::dtype& dtype = py::dtype::of<T>()) {
  py::array a(dtype, {height, width},
              {static_cast<py::ssize_t>(width * sizeof(T)), static_cast<py::ssize_t>(sizeof(T))}, data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

/// A fresh, writable H x W array to copy into.
inline py::array empty_2d(int height, int width, const py::dtype& dtype) {
  return py::array(dtype, {height, width});
}

}  // namespace occ_improve::python
