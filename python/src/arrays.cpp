#include "arrays.hpp"

#include "occ_improve/errors.hpp"

#include <cmath>
#include <sstream>
#include <string>

namespace occ_improve::python {
namespace {

std::string shape_text(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

/// The only element layout the library reads in place: 4-byte floats, native byte order, aligned.
bool is_native_float32(const py::array& a) {
  const bool aligned = (py::detail::array_proxy(a.ptr())->flags & py::detail::npy_api::NPY_ARRAY_ALIGNED_) != 0;
  return a.dtype().kind() == 'f' && a.itemsize() == 4 && a.dtype().attr("isnative").cast<bool>() && aligned;
}

/// The constant distance in floats between consecutive points, 0 when there is none the library can use.
/// The leading axes are folded into one run of points: each must continue where the ones inside it end
/// (true for C order and for slices like cloud[:, :, :3] of an H x W x 4 array).
std::size_t point_stride_floats(const py::array& a) {
  const py::ssize_t f = static_cast<py::ssize_t>(sizeof(float));
  if (a.strides(a.ndim() - 1) != f) return 0;
  py::ssize_t count = 1, stride = 3 * f;  // the run folded so far
  for (py::ssize_t axis = a.ndim() - 2; axis >= 0; --axis) {
    if (a.shape(axis) == 1) continue;
    if (count == 1) {
      stride = a.strides(axis);
    } else if (a.strides(axis) != count * stride) {
      return 0;
    }
    count *= a.shape(axis);
  }
  if (stride < 3 * f || stride % f != 0) return 0;  // overlapping, reversed or misaligned points
  return static_cast<std::size_t>(stride / f);
}

/// Where a ragged nested sequence first breaks: "row 0 has 3 values, row 1 has 2", empty when its rows
/// all have one length (the break is deeper, or it is not a sequence of sequences).
std::string ragged_rows_text(const py::handle& object) {
  if (!py::isinstance<py::sequence>(object) || py::isinstance<py::str>(object)) return "";
  const auto rows = py::reinterpret_borrow<py::sequence>(object);
  const auto length = [](const py::handle& row) -> py::ssize_t {
    const bool nested = py::isinstance<py::sequence>(row) && !py::isinstance<py::str>(row);
    return nested ? static_cast<py::ssize_t>(py::len(row)) : -1;
  };
  const auto describe = [](py::ssize_t i, py::ssize_t n) {
    if (n < 0) return "row " + std::to_string(i) + " is a single value";
    return "row " + std::to_string(i) + " has " + std::to_string(n) + (n == 1 ? " value" : " values");
  };
  const py::ssize_t count = static_cast<py::ssize_t>(py::len(rows));
  for (py::ssize_t i = 1; i < count; ++i)
    if (length(rows[i]) != length(rows[0])) return describe(0, length(rows[0])) + ", " + describe(i, length(rows[i]));
  return "";
}

/// Any array-like (nested lists too) as an ndarray, without a copy when it already is one. A nested
/// sequence numpy cannot make an array of (rows of different lengths) is InvalidInput naming `expected`.
py::array as_array(const py::handle& object, const char* what, const char* expected) {
  if (py::isinstance<py::array>(object)) return py::reinterpret_borrow<py::array>(object);
  try {
    return py::module_::import("numpy").attr("asarray")(object);
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_ValueError)) throw;
    const std::string rows = ragged_rows_text(object);
    const std::string given = rows.empty() ? "a sequence numpy cannot make one array of (" + std::string(py::str(e.value()))
                                           : "a ragged nested sequence (" + rows;
    throw InvalidInput(std::string(what) + " must be " + expected + ", got " + given + ")");
  }
}

}  // namespace

py::array real_array(const py::handle& object, const char* what, const char* expected, Booleans booleans) {
  const py::array a = as_array(object, what, expected);
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u' && !(kind == 'b' && booleans == Booleans::taken))
    throw py::type_error(std::string(what) + " must be a real numeric array" +
                         (booleans == Booleans::taken ? " or booleans" : "") + ", got dtype " +
                         std::string(py::str(a.dtype())));
  return a;
}

std::vector<std::uint8_t> flags_of(const py::handle& values, const char* what) {
  const auto a = c_array_of<double>(real_array(values, what, "an array-like of flags", Booleans::taken));
  std::vector<std::uint8_t> out(static_cast<std::size_t>(a.size()));
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double v = a.data()[i];
    if (std::isnan(v))
      throw InvalidInput(std::string(what) + ": element " + std::to_string(i) + " is NaN (flags are 0 or nonzero)");
    out[i] = v != 0 ? 1 : 0;
  }
  return out;
}

PointsInput points_from_array(const py::handle& object) {
  static const char* const expected = "an N x 3 or H x W x 3 array of x, y, z";
  const py::array points = real_array(object, "points", expected, Booleans::refused);
  const bool shaped = (points.ndim() == 2 || points.ndim() == 3) && points.shape(points.ndim() - 1) == 3;
  if (!shaped) throw InvalidInput(std::string("points must be ") + expected + ", got shape " + shape_text(points));
  PointsInput in;
  in.span.count = static_cast<std::size_t>(points.size() / 3);
  const std::size_t stride = is_native_float32(points) ? point_stride_floats(points) : 0;
  if (in.span.count == 0) return in;
  if (stride != 0) {
    in.keep = points;
    in.span.xyz = static_cast<const float*>(points.data());
    in.span.stride_floats = stride;
    return in;
  }
  auto converted = c_array_of<float>(points);
  in.span.xyz = converted.data();
  in.keep = std::move(converted);
  in.copied = true;
  return in;
}

DepthInput depth_from_array(const py::handle& object, const PinholeIntrinsics& intrinsics) {
  const py::array depth = real_array(object, "depth", "an H x W array of depths", Booleans::refused);
  if (depth.ndim() != 2 || depth.shape(0) != intrinsics.height || depth.shape(1) != intrinsics.width) {
    throw InvalidInput("depth must be an H x W array matching the intrinsics (" + std::to_string(intrinsics.height) +
                       ", " + std::to_string(intrinsics.width) + "), got shape " + shape_text(depth));
  }
  DepthInput in;
  in.pixels = static_cast<std::size_t>(depth.size());
  const bool readable = is_native_float32(depth) && (depth.flags() & py::array::c_style);
  const py::array converted = readable ? depth : c_array_of<float>(depth);
  in.depth = static_cast<const float*>(converted.data());
  in.keep = std::move(converted);
  in.copied = !readable;
  return in;
}

}  // namespace occ_improve::python
