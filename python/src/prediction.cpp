// A dense depth from sparse samples (depth_prediction.hpp): from a sparse depth image without a map, and
// from a Mapper's surface.
#include "arrays.hpp"
#include "bindings.hpp"

#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/errors.hpp"

#include <pybind11/stl.h>

#include <algorithm>
#include <string>

namespace occ_improve::python {
namespace {

/// (depth_m float32 H x W, distance int32 H x W) copied out of a prediction.
py::tuple to_arrays(const PredictedDepth& p) {
  py::array depth = empty_2d(p.height, p.width, py::dtype::of<float>());
  py::array distance = empty_2d(p.height, p.width, py::dtype::of<std::int32_t>());
  std::copy(p.depth_m.begin(), p.depth_m.end(), static_cast<float*>(depth.mutable_data()));
  std::copy(p.distance.begin(), p.distance.end(), static_cast<std::int32_t*>(distance.mutable_data()));
  return py::make_tuple(depth, distance);
}

py::tuple predict_from_image(const py::handle& sparse, const SensorModelParams& model, const DepthPredictionParams& params) {
  const auto image = c_array_of<float>(real_array(sparse, "sparse_depth", "an H x W array of depths", Booleans::refused));
  if (image.ndim() != 2)
    throw InvalidInput("predict_dense_depth: sparse_depth has " + std::to_string(image.ndim()) +
                       " dimensions, not 2 (H x W)");
  const int h = static_cast<int>(image.shape(0)), w = static_cast<int>(image.shape(1));
  const std::vector<float> values(image.data(), image.data() + image.size());
  const SensorModel sensor(model);
  const PredictedDepth p = run_interruptible([&] { return predict_dense_depth(values, w, h, sensor, params); });
  return to_arrays(p);
}

}  // namespace

void bind_prediction(py::module_& m) {
  py::enum_<DepthPredictionRule>(m, "DepthPredictionRule", "How a dense depth is predicted from sparse samples.")
      .value("nearest", DepthPredictionRule::nearest, "the nearest sample's depth (chessboard distance)")
      .value("linear", DepthPredictionRule::linear,
             "linear in inverse depth over the samples' Delaunay triangles, never across a depth discontinuity");
  py::class_<DepthPredictionParams> p(m, "DepthPredictionParams",
                                      "Rule, radius [columns] and discontinuity test [sigma(z)] of a depth prediction.");
  def_value_struct<DepthPredictionParams>(p);
  p.def_property("radius_columns", int_field_getter(&DepthPredictionParams::radius_columns),
                 int_field_setter(&DepthPredictionParams::radius_columns, "radius_columns"))
      .def_readwrite("rule", &DepthPredictionParams::rule)
      .def_readwrite("discontinuity_sigmas", &DepthPredictionParams::discontinuity_sigmas)
      .def("validate", &DepthPredictionParams::validate);
  m.def("predict_dense_depth", &predict_from_image, py::arg("sparse_depth"), py::arg("model"),
        py::arg("params") = DepthPredictionParams{},
        "A dense depth from a sparse H x W depth image in metres (0 or NaN: no sample). Returns (depth_m "
        "float32 H x W, 0 where no sample lies within the radius; distance int32 H x W, chessboard distance "
        "to the nearest sample, -1 where none). model gives sigma(z) for the linear rule's discontinuity "
        "test. Raises InvalidParameter / InvalidInput naming the bad value or pixel.");
  py::reinterpret_borrow<py::class_<PyMapper>>(m.attr("Mapper"))
      .def(
          "predict_depth",
          [](PyMapper& self, const DepthPredictionParams& params) {
            const PredictedDepth p = with_mapper(self, [&](Mapper& mapper) {
              return predict_depth(mapper.surface(), mapper.model(), params);
            });
            return to_arrays(p);
          },
          py::arg("params") = DepthPredictionParams{},
          "The map's dense predicted depth from its surface samples (known, P > 0.5): (depth_m float32, "
          "distance int32), each H x W, as predict_dense_depth.");
}

}  // namespace occ_improve::python
