// Where to look next (regions, rays, the stop signal), segmentation and the map images.
#include "arrays.hpp"
#include "bindings.hpp"

#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sim/render.hpp"
#include "occ_improve/segmentation/segmentation.hpp"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <array>

namespace occ_improve::python {

// Region.centre_direction back from a pickle through std::array, not the Eigen caster: GCC 12 gives a
// false maybe-uninitialized warning inside that caster for fixed-size matrices.
template <>
Eigen::Vector3d from_state<Eigen::Vector3d>(const py::handle& value) {
  const auto v = value.cast<std::array<double, 3>>();
  return {v[0], v[1], v[2]};
}

namespace {

py::class_<PyMapper> mapper_class(py::module_& m) { return py::reinterpret_borrow<py::class_<PyMapper>>(m.attr("Mapper")); }

void bind_region_types(py::module_& m) {
  py::class_<RegionOptions> o(m, "RegionOptions", "Which rays form regions (improvement threshold, minimum area).");
  def_value_struct<RegionOptions>(o);
  o.def_readwrite("min_improvement", &RegionOptions::min_improvement)
      .def_property("min_area_columns", int_field_getter(&RegionOptions::min_area_columns),
                    int_field_setter(&RegionOptions::min_area_columns, "min_area_columns"))
      .def("validate", &RegionOptions::validate);
  py::class_<Region> r(m, "Region",
                       "An 8-connected region of high improvement (read-only). Positions are grid coordinates u "
                       "(column) and v (row, grows downwards): image pixels with the pixel-native presets.");
  r.def_readonly("summed_improvement", &Region::summed_improvement)
      .def_readonly("area_columns", &Region::area_columns)
      .def_readonly("peak_improvement", &Region::peak_improvement)
      .def_readonly("centre_u", &Region::centre_u, "The medoid's column: always a ray of the region.")
      .def_readonly("centre_v", &Region::centre_v, "The medoid's row.")
      .def_readonly("peak_u", &Region::peak_u, "Column of the peak (ties as top_rays).")
      .def_readonly("peak_v", &Region::peak_v)
      .def_readonly("min_u", &Region::min_u, "Bounding box, inclusive.")
      .def_readonly("min_v", &Region::min_v)
      .def_readonly("max_u", &Region::max_u)
      .def_readonly("max_v", &Region::max_v)
      .def_readonly("centre_azimuth_rad", &Region::centre_azimuth_rad, "Azimuth of centre_direction (CONVENTIONS 1).")
      .def_readonly("centre_elevation_rad", &Region::centre_elevation_rad,
                    "Elevation of centre_direction (CONVENTIONS 1; y down, so it grows downwards like v).")
      .def_readonly("centre_direction", &Region::centre_direction,
                    "Unit vector through the centre ray, sensor frame, shape (3,).")
      .def_readonly("mean_depth_m", &Region::mean_depth_m, "Over known rays, 0 if none.");
  def_members_pickle<Region>(r, &Region::summed_improvement, &Region::area_columns, &Region::peak_improvement,
                             &Region::peak_u, &Region::peak_v, &Region::centre_u, &Region::centre_v, &Region::min_u,
                             &Region::min_v, &Region::max_u, &Region::max_v, &Region::centre_direction,
                             &Region::centre_azimuth_rad, &Region::centre_elevation_rad, &Region::mean_depth_m);
  def_fields_repr(r, {"summed_improvement", "area_columns", "peak_improvement", "centre_u", "centre_v", "peak_u",
                      "peak_v", "min_u", "min_v", "max_u", "max_v", "centre_direction", "centre_azimuth_rad",
                      "centre_elevation_rad", "mean_depth_m"});
}

void bind_stop_types(py::module_& m) {
  py::class_<StopCriteria> c(m, "StopCriteria", "Absolute thresholds of the stop signal.");
  def_value_struct<StopCriteria>(c);
  c.def_readwrite("total_improvement_below", &StopCriteria::total_improvement_below)
      .def_readwrite("best_region_below", &StopCriteria::best_region_below)
      .def_readwrite("ray_floor", &StopCriteria::ray_floor)
      .def("validate", &StopCriteria::validate);
  py::class_<ProgressCriteria> p(m, "ProgressCriteria", "When a sequence of frames has stopped paying.");
  def_value_struct<ProgressCriteria>(p);
  p.def_readwrite("min_relative_gain", &ProgressCriteria::min_relative_gain)
      .def_property("patience", int_field_getter(&ProgressCriteria::patience),
                    int_field_setter(&ProgressCriteria::patience, "patience"))
      .def("validate", &ProgressCriteria::validate);
  py::class_<StopSignal> s(m, "StopSignal", "Whether to stop acquiring, with the totals and a reason for logs.");
  s.def_readonly("stop", &StopSignal::stop)
      .def_readonly("total_improvement", &StopSignal::total_improvement)
      .def_readonly("best_region_improvement", &StopSignal::best_region_improvement)
      .def_readonly("reason", &StopSignal::reason)
      .def("__bool__", [](const StopSignal& x) { return x.stop; });
  def_fields_repr(s, {"stop", "total_improvement", "best_region_improvement", "reason"});
}

std::vector<Region> mapper_regions(PyMapper& self, const RegionOptions& options) {
  return with_mapper(self, [&](Mapper& mp) {
    return find_regions(mp.geometry(), mp.improvement(), mp.surface(), options);
  });
}

/// top_rays as a structured array (column, azimuth_bin, elevation_bin, improvement, depth_m), best first.
py::array mapper_top_rays(PyMapper& self, int k) {
  const auto rays = with_mapper(self, [&](Mapper& mp) { return top_rays(mp.improvement(), mp.surface(), k); });
  py::array_t<RankedRay> out(static_cast<py::ssize_t>(rays.size()));
  std::copy(rays.begin(), rays.end(), out.mutable_data());
  return out;
}

void bind_ranking(py::module_& m) {
  PYBIND11_NUMPY_DTYPE(RankedRay, column, azimuth_bin, elevation_bin, improvement, depth_m);
  bind_region_types(m);
  bind_stop_types(m);
  auto c = mapper_class(m);
  c.def("regions", &mapper_regions, py::arg("options") = RegionOptions{},
        "8-connected regions of improvement >= options.min_improvement, largest summed improvement first.");
  c.def("top_rays", &mapper_top_rays, py::arg("k"),
        "The k rays of highest improvement, best first, as a structured array with fields column, "
        "azimuth_bin, elevation_bin (int: u and v, the pixel with the pixel-native presets), improvement, "
        "depth_m (float32; depth 0 where unknown). Equal values are ordered as the planner orders them "
        "(spread over the view by a fixed hash of the column), not in scan order.");
  c.def("stop_signal", [](PyMapper& self, const StopCriteria& criteria, const RegionOptions& options) {
    return with_mapper(self, [&](Mapper& mp) {
      return stop_signal(mp.improvement(), find_regions(mp.geometry(), mp.improvement(), mp.surface(), options),
                         criteria);
    });
  }, py::arg("criteria") = StopCriteria{}, py::arg("region_options") = RegionOptions{},
        "Stop when the total improvement or the best region fall below the criteria.");
  py::class_<StopMonitor>(m, "StopMonitor", "The stop signal over a sequence of frames (thresholds or stalled progress).")
      .def(py::init<const StopCriteria&, const ProgressCriteria&>(), py::arg("criteria") = StopCriteria{},
           py::arg("progress") = ProgressCriteria{})
      .def("update", [](StopMonitor& monitor, PyMapper& mapper, std::optional<std::vector<Region>> regions) {
        if (!regions) regions = mapper_regions(mapper, RegionOptions{});
        return with_mapper(mapper, [&](Mapper& mp) { return monitor.update(mp.improvement(), *regions); });
      }, py::arg("mapper"), py::arg("regions") = py::none(),
           "Call once per frame, after inserting it. regions=None: mapper.regions() with default options.")
      .def_property_readonly("stalled_frames", &StopMonitor::stalled_frames);
}

void bind_segmentation_types(py::module_& m) {
  py::class_<SegmentationParams> p(m, "SegmentationParams", "Contour threshold, minimum segment size, dominant plane.");
  def_value_struct<SegmentationParams>(p);
  p.def_readwrite("contour_improvement_below", &SegmentationParams::contour_improvement_below)
      .def_property("min_segment_columns", int_field_getter(&SegmentationParams::min_segment_columns),
                    int_field_setter(&SegmentationParams::min_segment_columns, "min_segment_columns"))
      .def_readwrite("remove_dominant_plane", &SegmentationParams::remove_dominant_plane)
      .def_readwrite("plane_distance_m", &SegmentationParams::plane_distance_m)
      .def_readwrite("plane_distance_per_m2", &SegmentationParams::plane_distance_per_m2)
      .def_property("plane_min_columns", int_field_getter(&SegmentationParams::plane_min_columns),
                    int_field_setter(&SegmentationParams::plane_min_columns, "plane_min_columns"))
      .def_property("plane_ransac_iterations", int_field_getter(&SegmentationParams::plane_ransac_iterations),
                    int_field_setter(&SegmentationParams::plane_ransac_iterations, "plane_ransac_iterations"))
      .def_property("plane_seed", int_field_getter(&SegmentationParams::plane_seed),
                    int_field_setter(&SegmentationParams::plane_seed, "plane_seed"))
      .def_readwrite("split_concave_creases", &SegmentationParams::split_concave_creases)
      .def_readwrite("crease_arm_m", &SegmentationParams::crease_arm_m)
      .def_readwrite("crease_arm_per_m2", &SegmentationParams::crease_arm_per_m2)
      .def_readwrite("crease_smoothing_share", &SegmentationParams::crease_smoothing_share)
      .def_readwrite("crease_min_bend_deg", &SegmentationParams::crease_min_bend_deg)
      .def_readwrite("crease_min_view_angle_deg", &SegmentationParams::crease_min_view_angle_deg)
      .def_readwrite("crease_view_angle_range_m", &SegmentationParams::crease_view_angle_range_m)
      .def_property("crease_max_arm_px", int_field_getter(&SegmentationParams::crease_max_arm_px),
                    int_field_setter(&SegmentationParams::crease_max_arm_px, "crease_max_arm_px"))
      .def_property("threads", int_field_getter(&SegmentationParams::threads),
                    int_field_setter(&SegmentationParams::threads, "threads"))
      .def("validate", &SegmentationParams::validate);
  m.def("segmentation_defaults", py::overload_cast<const SensorPreset&>(&segmentation_defaults), py::arg("preset"),
        "Segmentation parameters scaled for a preset's noise model.");
  py::class_<Segment> s(m, "Segment", "One segment (read-only).");
  s.def_readonly("label", &Segment::label)
      .def_readonly("columns", &Segment::columns)
      .def_readonly("centroid_m", &Segment::centroid_m)
      .def_readonly("mean_depth_m", &Segment::mean_depth_m)
      .def_readonly("plane", &Segment::plane);
  def_fields_repr(s, {"label", "columns", "centroid_m", "mean_depth_m", "plane"});
}

void bind_segmentation_result(py::module_& m) {
  py::class_<Segmentation> r(m, "Segmentation", "Labels per ray; label and contour are read-only views kept alive by it.");
  r.def_property_readonly("label", [](const py::object& self) {
     const auto& s = self.cast<const Segmentation&>();
     return view_2d(s.label.data(), s.height, s.width, self);
   }, "H x W uint32, 0 = no segment; label l is segments[l - 1].")
      .def_property_readonly("contour", [](const py::object& self) {
        const auto& s = self.cast<const Segmentation&>();
        return view_2d(s.contour.data(), s.height, s.width, self, py::dtype("?"));
      }, "H x W bool, True on contour rays.")
      .def_property_readonly("crease", [](const py::object& self) {
        const auto& s = self.cast<const Segmentation&>();
        return view_2d(s.crease.data(), s.height, s.width, self, py::dtype("?"));
      }, "H x W bool, True on concave-crease rays (not contour rays).")
      .def_readonly("segments", &Segmentation::segments, "Largest first.")
      .def_readonly("valid_columns", &Segmentation::valid_columns)
      .def_readonly("contour_columns", &Segmentation::contour_columns)
      .def_readonly("crease_columns", &Segmentation::crease_columns)
      .def_readonly("attached_columns", &Segmentation::attached_columns)
      .def_readonly("plane_columns", &Segmentation::plane_columns);
  def_fields_repr(r, {"valid_columns", "contour_columns", "crease_columns", "attached_columns", "plane_columns"});
  mapper_class(m).def("segment", [](PyMapper& self, const std::optional<SegmentationParams>& params) {
    return with_mapper(self, [&](Mapper& mp) {
      // By default what occ_segment uses for this grid and model.
      return segment_improvement(mp.geometry(), mp.surface(), mp.improvement(),
                                 params ? *params : segmentation_defaults(mp.geometry().params(), mp.model().params()));
    });
  }, py::arg("params") = py::none(),
     "Segments the surface along the improvement map's negative band. params: None = "
     "segmentation_defaults for the Mapper's grid and model, as occ_segment uses them.");
}

/// An Image as an H x W x 3 (or H x W) uint8 array (a copy).
py::array image_array(const Image& image) {
  std::vector<py::ssize_t> shape{image.height, image.width};
  if (image.channels > 1) shape.push_back(image.channels);
  py::array_t<std::uint8_t> out(shape);
  std::copy(image.pixels.begin(), image.pixels.end(), out.mutable_data());
  return out;
}

void bind_render(py::module_& m) {
  mapper_class(m).def("render_improvement", [](PyMapper& self) {
    return image_array(with_mapper(self, [](Mapper& mp) { return render_improvement(mp.improvement()); }));
  }, "The improvement map in the project's colour map (docs/METHOD.md), H x W x 3 uint8.");
  m.def("render_segmentation", [](const Segmentation& s) { return image_array(render_segmentation(s)); },
        py::arg("segmentation"), "Each label's fixed colour, H x W x 3 uint8 (black = no segment).");
  m.def("render_improvement_legend", [] { return image_array(render_improvement_legend()); },
        "The colour bar from -0.4 to 0.4, H x W x 3 uint8.");
}

}  // namespace

void bind_analysis(py::module_& m) {
  bind_ranking(m);
  bind_segmentation_types(m);
  bind_segmentation_result(m);
  bind_render(m);
}

}  // namespace occ_improve::python
