// The selective sensor's next shot (planner.hpp), the return model (return_model.hpp) and the intrinsics
// of an organized cloud (intrinsics_fit.hpp). Thin: every array is converted once and handed to the
// library, which checks sizes and values itself. Column indices are row-major (v * width + u), as in C++.
#include "arrays.hpp"
#include "bindings.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/sensor/intrinsics_fit.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/planning/return_model.hpp"

#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <sstream>

namespace occ_improve::python {
namespace {

template <class T>
using Array = py::array_t<T, py::array::c_style | py::array::forcecast>;

/// A fresh writable H x W array holding `values` (row-major, as the library's maps).
template <class T>
py::array grid_array(const std::vector<T>& values, int height, int width) {
  Array<T> out({height, width});
  std::memcpy(out.mutable_data(), values.data(), values.size() * sizeof(T));
  return out;
}

/// A 1-D array of `values` (copied).
template <class T>
py::array flat_array(const std::vector<T>& values) {
  Array<T> out(static_cast<py::ssize_t>(values.size()));
  if (!values.empty()) std::memcpy(out.mutable_data(), values.data(), values.size() * sizeof(T));
  return out;
}

/// An array-like of whole numbers in [0, max of T] (counts, column indices) as a vector of T; InvalidInput
/// naming `what`, the element and its value otherwise (a cast would turn -1 into 4294967295 and 1.5 into 1).
template <class T>
std::vector<T> to_whole_numbers(const py::handle& values, const std::string& what) {
  const auto a = c_array_of<double>(real_array(values, what.c_str(), "an array-like of whole numbers", Booleans::refused));
  std::vector<T> out(static_cast<std::size_t>(a.size()));
  const double most = static_cast<double>(std::numeric_limits<T>::max());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double v = a.data()[i];
    if (!(v >= 0 && v <= most && v == std::floor(v))) {
      std::ostringstream m;
      m << what << ": element " << i << " is " << v << " (must be a whole number in [0, " << most << "])";
      throw InvalidInput(m.str());
    }
    out[i] = static_cast<T>(v);
  }
  return out;
}

/// Counts given as a 2-D array must be H x W: a W x H one (indexed [u, v]) has the right size and would be
/// read scrambled. Flat ones are row-major, as documented.
void require_rows_of_the_grid(const py::handle& values, const std::string& what, int width, int height) {
  const py::array a = py::array::ensure(values);
  if (!a || a.ndim() != 2 || (a.shape(0) == height && a.shape(1) == width)) return;
  std::ostringstream m;
  m << what << " is " << a.shape(0) << " x " << a.shape(1) << ": must be height x width = " << height << " x " << width
    << " (row v, column u), or flat";
  throw InvalidInput(m.str());
}

/// An improvement map: a Mapper's own, or an H x W array (copied once into the library's type).
ImprovementMap improvement_from(const py::handle& source) {
  if (py::isinstance<PyMapper>(source)) {
    return with_mapper(source.cast<PyMapper&>(), [](Mapper& mp) { return mp.improvement(); });
  }
  const auto a = c_array_of<float>(real_array(source, "improvement", "an H x W array or a Mapper", Booleans::refused));
  if (a.ndim() != 2) throw InvalidInput("improvement must be an H x W array or a Mapper, got " +
                                        std::to_string(a.ndim()) + " dimensions");
  ImprovementMap map;
  map.height = static_cast<int>(a.shape(0));
  map.width = static_cast<int>(a.shape(1));
  map.value.assign(a.data(), a.data() + a.size());
  // NaN marks a ray that cannot be observed; an infinite improvement is no value (it made expected_gain inf).
  for (std::size_t c = 0; c < map.value.size(); ++c)
    if (std::isinf(map.value[c]))
      throw InvalidInput("improvement: ray " + std::to_string(c) + " (row " + std::to_string(c / static_cast<std::size_t>(map.width)) +
                         ", column " + std::to_string(c % static_cast<std::size_t>(map.width)) +
                         ") is infinite (finite values, or NaN for a ray that cannot be observed)");
  return map;
}

/// ReturnRecord.from_counts: counts as H x W or flat (row-major) array-likes, checked before use.
ReturnRecord record_from_counts(int width, int height, const py::object& asked, const py::object& returned) {
  require_rows_of_the_grid(asked, "asked", width, height);
  require_rows_of_the_grid(returned, "returned", width, height);
  return ReturnRecord::from_counts(width, height, to_whole_numbers<std::uint32_t>(asked, "asked"),
                                   to_whole_numbers<std::uint32_t>(returned, "returned"));
}

/// A record pickled as (width, height, asked, returned) and rebuilt by from_counts: the neighbour sums
/// and totals follow from the counts. A record of no grid (ReturnRecord()) stays one.
py::tuple record_state(const ReturnRecord& r) {
  return py::make_tuple(r.width(), r.height(), flat_array(r.asked()), flat_array(r.returned()));
}
ReturnRecord record_from_state(const py::tuple& state) {
  if (state.size() != 4) throw InvalidInput("a pickled ReturnRecord holds (width, height, asked, returned)");
  const int width = state[0].cast<int>(), height = state[1].cast<int>();
  if (width == 0 && height == 0) return ReturnRecord();
  return record_from_counts(width, height, state[2], state[3]);
}

void bind_return_model(py::module_& m) {
  py::class_<ReturnModelParams> p(m, "ReturnModelParams", "Weight of the neighbourhood prior of the return model.");
  def_value_struct<ReturnModelParams>(p);
  p.def_readwrite("prior_strength_shots", &ReturnModelParams::prior_strength_shots)
      .def("validate", &ReturnModelParams::validate, "Raises InvalidParameter unless finite and > 0.");

  py::class_<ReturnRecord> r(m, "ReturnRecord",
                             "Per ray: the shots that asked for it and those that got a return. Counts are H x W "
                             "uint32 arrays (copies).");
  r.def(py::init<>(), "An empty record of no grid (use for_grid).")
      .def_static("for_grid", &ReturnRecord::for_grid, py::arg("width"), py::arg("height"),
                  "An empty record for width x height columns.")
      .def_static("from_counts", &record_from_counts, py::arg("width"), py::arg("height"), py::arg("asked"),
                  py::arg("returned"),
                  "A record from saved counts (H x W or flat, row-major). Raises InvalidInput for other sizes, "
                  "counts that are not whole numbers >= 0, more returns than asks or more than 2^28 asks of a ray.")
      .def_property_readonly("width", &ReturnRecord::width)
      .def_property_readonly("height", &ReturnRecord::height)
      .def_property_readonly("size", &ReturnRecord::size)
      .def_property_readonly("empty", &ReturnRecord::empty)
      .def_property_readonly("total_asked", &ReturnRecord::total_asked)
      .def_property_readonly("total_returned", &ReturnRecord::total_returned);
  const auto counts = [&r](const char* name, const std::vector<std::uint32_t>& (ReturnRecord::*get)() const,
                           const char* doc) {
    r.def_property_readonly(name, [get](const ReturnRecord& x) { return grid_array((x.*get)(), x.height(), x.width()); },
                            doc);
  };
  counts("asked", &ReturnRecord::asked, "H x W uint32: shots that asked for the ray.");
  counts("returned", &ReturnRecord::returned, "H x W uint32: shots in which the ray returned.");
  counts("asked_nearby", &ReturnRecord::asked_nearby, "H x W uint32: asks summed over the 8 neighbours.");
  counts("returned_nearby", &ReturnRecord::returned_nearby, "H x W uint32: returns summed over the 8 neighbours.");
  r.def("check_matches", &ReturnRecord::check_matches, py::arg("grid_width"), py::arg("grid_height"),
        "Raises InvalidInput naming both sizes unless the record is of this grid.");
  r.def("record_shot", [](ReturnRecord& record, const py::object& columns, const py::object& got_return) {
    record.record_shot(to_whole_numbers<ColumnIndex>(columns, "columns"), flags_of(got_return, "got_return"));
  }, py::arg("columns"), py::arg("got_return"),
        "Adds one shot: got_return[i] (bool) says whether ray columns[i] (row-major index v * width + u) returned. "
        "Checked before anything is counted: InvalidInput for different lengths or a column that is not a whole "
        "number >= 0, InvalidParameter for a column outside the grid.");
  def_fields_repr(r, {"width", "height", "total_asked", "total_returned"});
  def_copy<ReturnRecord>(r);
  r.def(py::pickle(&record_state, &record_from_state));

  m.def("record_return_rate", &record_return_rate, py::arg("record"),
        "Returns / asks over the whole record (1 for an empty record).");
  m.def("return_probability_map", [](const ReturnRecord& record, const ReturnModelParams& params) {
    return grid_array(return_probability_map(record, params), record.height(), record.width());
  }, py::arg("record"), py::arg("params") = ReturnModelParams{},
        "The return probability of every ray, H x W float32 (the Beta-Bernoulli posterior mean).");
}

void bind_plan_request(py::module_& m) {
  py::enum_<ShotShape>(m, "ShotShape", "What a shot takes.")
      .value("rays", ShotShape::rays, "any budget_rays rays, highest score first")
      .value("window", ShotShape::window, "the window of largest summed score (ROI readout)")
      .value("decimation", ShotShape::decimation, "every step-th column and row, at the best offset")
      .value("coarse_to_fine", ShotShape::coarse_to_fine,
             "a coverage pass, then one ray per refinement block (strategy (g); needs a Mapper)");
  py::enum_<RefineBy>(m, "RefineBy", "What ranks coarse_to_fine's refinement blocks.")
      .value("improvement", RefineBy::improvement, "the block's |mean improvement|")
      .value("residual", RefineBy::residual, "the samples' residual from the predictor's local model")
      .value("both", RefineBy::both, "their product")
      .value("triangles", RefineBy::triangles, "the measured samples' triangles by area x non-planarity");
  py::enum_<LocalModel>(m, "LocalModel", "The predictor's local model whose error the residual estimates.")
      .value("constant", LocalModel::constant, "nearest-sample prediction")
      .value("plane", LocalModel::plane, "linear prediction");
  py::class_<PlanRequest> q(m, "PlanRequest", "Budget, shape, re-acquisition share, stop level, candidate mask.");
  def_value_struct<PlanRequest>(q);
  q.def_property("budget_rays", int_field_getter(&PlanRequest::budget_rays),
                 int_field_setter(&PlanRequest::budget_rays, "budget_rays"))
      .def_readwrite("shape", &PlanRequest::shape)
      .def_property("window_width_columns", int_field_getter(&PlanRequest::window_width_columns),
                    int_field_setter(&PlanRequest::window_width_columns, "window_width_columns"))
      .def_property("window_height_columns", int_field_getter(&PlanRequest::window_height_columns),
                    int_field_setter(&PlanRequest::window_height_columns, "window_height_columns"))
      .def_readwrite("negative_share", &PlanRequest::negative_share)
      .def_readwrite("stop_gain_per_ray_below", &PlanRequest::stop_gain_per_ray_below)
      .def_readwrite("stop_view_share", &PlanRequest::stop_view_share)
      .def_readwrite("return_model", &PlanRequest::return_model)
      .def_property("coverage_block_columns", int_field_getter(&PlanRequest::coverage_block_columns),
                    int_field_setter(&PlanRequest::coverage_block_columns, "coverage_block_columns"))
      .def_readwrite("refine_by", &PlanRequest::refine_by)
      .def_readwrite("local_model", &PlanRequest::local_model)
      .def_readwrite("residual_cap_sigmas", &PlanRequest::residual_cap_sigmas)
      .def_property("candidates", [](const PlanRequest& r) -> py::object {
        if (r.candidates.empty()) return py::none();
        return flat_array(r.candidates).attr("astype")("?");
      }, [](PlanRequest& r, const py::object& mask) {
        if (mask.is_none()) {
          r.candidates.clear();
          return;
        }
        std::vector<std::uint8_t> flags = flags_of(mask, "candidates");
        // The request's empty mask means every ray: an empty array given for one would mean that too.
        if (flags.empty()) throw InvalidInput("candidates: an empty mask (give None for every ray)");
        r.candidates = std::move(flags);
      }, "rays shape: which rays the sensor may take, an H x W bool mask (stored flat, row-major; read back as "
         "a 1-D bool array), or None for every ray.")
      .def("validate", &PlanRequest::validate, py::arg("grid_width"), py::arg("grid_height"),
           "Raises InvalidParameter naming the bad value, InvalidInput for a mask of the wrong size.");
}

void bind_shot(py::module_& m) {
  py::class_<Shot> s(m, "Shot", "The next shot (read-only).");
  s.def_property_readonly("columns", [](const Shot& x) { return flat_array(x.columns); },
                          "uint32 row-major ray indices (v, u = divmod(columns, width)): rays shape by rank, then "
                          "the re-acquisitions; other shapes ascending.")
      .def_readonly("expected_gain", &Shot::expected_gain,
                    "Sum of the scores of the rays taken by rank; coarse_to_fine refined by triangles: the rays "
                    "they are expected to bring within 2 sigma (good_rays.hpp).")
      .def_readonly("stop_gain_per_ray", &Shot::stop_gain_per_ray,
                    "What the stop compares with stop_gain_per_ray_below: expected_gain / ranked_rays; refined by "
                    "triangles, the mean score of the view's best stop_view_share of rays.")
      .def_readonly("ranked_rays", &Shot::ranked_rays, "Rays taken by rank (the rest are re-acquisitions).")
      .def_readonly("stop", &Shot::stop, "ranked_rays == 0 or stop_gain_per_ray < stop_gain_per_ray_below.")
      .def_readonly("reason", &Shot::reason)
      .def("__len__", [](const Shot& x) { return x.columns.size(); });
  def_fields_repr(s, {"expected_gain", "stop_gain_per_ray", "ranked_rays", "stop", "reason"});
}

// A PlanMemory with the lock that plan_next_shot holds while the plan (GIL released) updates it.
struct PyPlanMemory {
  PlanMemory memory;
  std::mutex mutex;
  /// What `f` reads of the triangulation, under the lock.
  template <class F>
  auto read(F&& f) {
    const std::lock_guard<std::mutex> lock(mutex);
    return f(memory.triangulation);
  }
};

void bind_planning(py::module_& m) {
  py::class_<PyPlanMemory>(m, "PlanMemory",
                           "What one plan passes to the next within one acquisition (one Mapper, one ReturnRecord): "
                           "the measured samples' triangulation, extended shot by shot instead of rebuilt "
                           "(refine_by triangles). Pass the same one to every plan_next_shot of the acquisition.")
      .def(py::init<>())
      .def_property_readonly(
          "updates", [](PyPlanMemory& m) { return m.read([](const SampleTriangulator& t) { return t.updates(); }); },
          "Triangulation updates so far (one per triangles plan that had rays left to ask).")
      .def_property_readonly(
          "start_overs", [](PyPlanMemory& m) { return m.read([](const SampleTriangulator& t) { return t.start_overs(); }); },
          "Updates that triangulated from scratch: the first, and any after many samples were lost.");
  m.def("plan_next_shot", [](const py::object& improvement, const ReturnRecord& returns, const PlanRequest& request,
                             PyPlanMemory* memory) {
    if (py::isinstance<PyMapper>(improvement))  // the Mapper's own maps and pyramid, read under its lock
      return with_mapper(improvement.cast<PyMapper&>(), [&](Mapper& mapper) {
        if (!memory) return plan_next_shot(mapper, returns, request);
        // Its own lock too, taken after the mapper's: two threads planning on two Mappers may share it.
        std::lock_guard<std::mutex> lock(memory->mutex);
        return plan_next_shot(mapper, returns, request, memory->memory);
      });
    if (memory) throw InvalidParameter("plan_next_shot: memory is kept for a Mapper's plans, not for an improvement array");
    const ImprovementMap map = improvement_from(improvement);
    return run_interruptible([&] { return plan_next_shot(map, returns, request); });
  }, py::arg("improvement"), py::arg("returns"), py::arg("request") = PlanRequest{}, py::arg("memory") = nullptr,
        "The next shot over a Mapper (every shape) or an H x W float32 improvement array (every shape but "
        "coarse_to_fine, which reads the Mapper's multi-scale improvement). returns: "
        "ReturnRecord.for_grid(width, height) when nothing was shot yet. memory: a PlanMemory kept over one "
        "acquisition's shots (Mapper only). Raises as PlanRequest.validate, and InvalidInput when returns is "
        "of another grid.");
  m.def("shot_scores", [](const py::object& improvement, const ReturnRecord& returns, const ReturnModelParams& params) {
    const ImprovementMap map = improvement_from(improvement);
    const std::vector<float> scores = run_interruptible([&] { return shot_scores(map, returns, params); });
    return grid_array(scores, map.height, map.width);
  }, py::arg("improvement"), py::arg("returns"), py::arg("params") = ReturnModelParams{},
        "improvement x return probability, H x W float32: the ranking plan_next_shot uses.");
  m.def("decimation_step", &decimation_step, py::arg("width"), py::arg("height"), py::arg("budget_rays"),
        "The smallest step whose pattern (every step-th column and row) has at most budget_rays rays.");
  m.def("decimation_pattern", [](int width, int height, int step, int offset_x, int offset_y) {
    return flat_array(decimation_pattern(width, height, step, offset_x, offset_y));
  }, py::arg("width"), py::arg("height"), py::arg("step"), py::arg("offset_x"), py::arg("offset_y"),
        "Row-major ray indices (ascending, uint32) of the pattern of `step` at the offset, each in [0, step).");
}

/// An organized cloud (H x W x 3) as the library's fit reads it: the pixel (u, v) at xyz[(v W + u) stride].
/// A cloud the fit refuses gets the Python way round it appended (the library names no way: the tools
/// add their flag where they catch it).
template <class Fit>
IntrinsicsFit fit_organized(const py::object& points, Fit&& fit) {
  const PointsInput in = points_from_array(points);
  const py::array a = py::reinterpret_borrow<py::array>(py::module_::import("numpy").attr("asarray")(points));
  if (a.ndim() != 3) throw InvalidInput("points must be an organized H x W x 3 cloud to fit intrinsics");
  const int height = static_cast<int>(a.shape(0)), width = static_cast<int>(a.shape(1));
  return run_interruptible([&] {
    try {
      return fit(in.span.xyz, width, height, in.span.stride_floats);
    } catch (const InvalidInput& e) {
      throw InvalidInput(std::string(e.what()) + "; if it is a camera image, build the preset from the camera's "
                                                 "own intrinsics instead (read_intrinsics, intrinsics_from_matrix)");
    }
  });
}

void bind_intrinsics_fit(py::module_& m) {
  py::class_<IntrinsicsFit> f(m, "IntrinsicsFit", "Pinhole intrinsics fitted to an organized cloud (read-only).");
  f.def_readonly("intrinsics", &IntrinsicsFit::intrinsics)
      .def_readonly("rms_residual_px", &IntrinsicsFit::rms_residual_px)
      .def_readonly("max_residual_px", &IntrinsicsFit::max_residual_px)
      .def_readonly("points_used", &IntrinsicsFit::points_used);
  def_fields_repr(f, {"intrinsics", "rms_residual_px", "max_residual_px", "points_used"});
  m.attr("MAX_INTRINSICS_FIT_RESIDUAL_PX") = kMaxIntrinsicsFitResidualPx;
  m.def("fit_intrinsics", [](const py::object& points) {
    return fit_organized(points, [](const float* xyz, int w, int h, std::size_t s) { return fit_intrinsics(xyz, w, h, s); });
  }, py::arg("points"),
        "Fits fx, fy, cx, cy to an organized H x W x 3 cloud (NaN / z <= 0 points left out). Raises InvalidInput "
        "when fewer than 100 points are valid or they do not span the image; the fit may be poor (see "
        "rms_residual_px).");
  m.def("fit_intrinsics_checked", [](const py::object& points, double max_rms_px) {
    return fit_organized(points, [max_rms_px](const float* xyz, int w, int h, std::size_t s) {
      return fit_intrinsics_checked(xyz, w, h, s, max_rms_px);
    });
  }, py::arg("points"), py::arg("max_rms_px") = kMaxIntrinsicsFitResidualPx,
        "fit_intrinsics that also raises InvalidInput naming the residual when the RMS exceeds max_rms_px (the "
        "cloud is not a pinhole range image: give the intrinsics instead). max_rms_px must be finite and > 0 "
        "(InvalidParameter otherwise).");
}

}  // namespace

void bind_planner(py::module_& m) {
  bind_return_model(m);
  bind_plan_request(m);
  bind_shot(m);
  bind_planning(m);
  bind_intrinsics_fit(m);
}

}  // namespace occ_improve::python
