// The Mapper: insertion of points and depth images (GIL released), and its maps as numpy arrays.
#include "arrays.hpp"
#include "bindings.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/grid/mask.hpp"
#include "occ_improve/integrate/point_units.hpp"
#include "occ_improve/planning/point_selection.hpp"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <vector>

namespace occ_improve::python {
namespace {

void bind_reports(py::module_& m) {
  py::class_<InsertionReport> r(m, "InsertionReport",
                                "What happened to every point: received = inserted + skipped_invalid + skipped_outside_fov + skipped_masked.");
  r.def_readonly("points_received", &InsertionReport::points_received)
      .def_readonly("points_inserted", &InsertionReport::points_inserted)
      .def_readonly("skipped_invalid", &InsertionReport::skipped_invalid, "NaN/Inf coordinate or no return")
      .def_readonly("skipped_outside_fov", &InsertionReport::skipped_outside_fov)
      .def_readonly("skipped_masked", &InsertionReport::skipped_masked, "valid, on a ray the Mapper's mask leaves out")
      .def_readonly("beyond_depth_range", &InsertionReport::beyond_depth_range, "inserted; only their free space counts")
      .def_readonly("nearer_than_depth_range", &InsertionReport::nearer_than_depth_range,
                    "inserted nearer than the depth range's start: in front of the grid, little or nothing kept")
      .def_readonly("column_updates", &InsertionReport::column_updates)
      .def_readonly("seconds", &InsertionReport::seconds);
  def_fields_repr(r, {"points_received", "points_inserted", "skipped_invalid", "skipped_outside_fov", "skipped_masked",
                      "beyond_depth_range", "nearer_than_depth_range", "column_updates", "seconds"});
  py::class_<MapperReport> mr(m, "MapperReport", "One Mapper.insert: the insertion and the improvement update.");
  mr.def_readonly("insertion", &MapperReport::insertion)
      .def_readonly("improvement_seconds", &MapperReport::improvement_seconds)
      .def_readonly("surface_columns_changed", &MapperReport::surface_columns_changed)
      .def_readonly("rays_recomputed", &MapperReport::rays_recomputed)
      .def_readonly("points_masked", &MapperReport::points_masked, "valid points outside the mask, left out");
  def_fields_repr(mr, {"insertion", "improvement_seconds", "surface_columns_changed", "rays_recomputed",
                       "points_masked"});
}

InsertionOptions insertion_options(const py::object& threads) {
  InsertionOptions options;
  options.threads = int_for_field<int>(threads, "threads");  // 2**40 too is InvalidParameter naming threads
  options.validate();  // before any work: a bad count is the caller's mistake, not a failure halfway
  return options;
}

/// An H x W array (bool or numbers, nonzero = valid) as the library's mask over the camera's pixels.
PixelMask pixel_mask_from(const py::handle& mask) {
  const py::array a = real_array(mask, "mask", "an H x W array of flags", Booleans::taken);
  if (a.ndim() != 2)
    throw InvalidInput("mask must be an H x W array, got " + std::to_string(a.ndim()) + " dimensions");
  PixelMask out{static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)), flags_of(a, "mask")};
  out.validate();
  return out;
}

/// insert_depth: refuses a scale under which the image's median depth is a unit mistake.
void require_plausible_scale(const float* raw, std::size_t pixels, double scale, const GeometryParams& g) {
  const std::optional<UnitMistake> mistake = unit_mistake(std::vector<float>(raw, raw + pixels), scale, g);
  if (!mistake) return;
  std::ostringstream m;
  m << "scale = " << scale << " puts the median depth of this image at " << mistake->outside(g)
    << ": the image looks like " << mistake->likely.name << ": pass scale=" << mistake->likely.scale;
  throw InvalidParameter(m.str());
}

/// insert: refuses points whose median range is a unit mistake (points are in metres; a cloud in
/// millimetres took 100 times as long to insert, every point beyond the range, and left the map free).
void require_plausible_ranges(PointSpan points, const GeometryParams& g) {
  const std::optional<UnitMistake> mistake = point_unit_mistake(points, g);
  if (!mistake) return;
  throw InvalidParameter(mistake->about_points(g) + ": pass them in metres (a scene that far needs a larger depth_max_m)");
}

/// Mapper::insert, through set_mask first when a mask is given (None: the mask in place, if any).
MapperReport insert_masked(Mapper& m, PointSpan points, const InsertionOptions& options,
                           const std::optional<PixelMask>& mask) {
  return mask ? m.insert(points, options, *mask) : m.insert(points, options);
}

std::optional<PixelMask> optional_mask(const py::object& mask) {
  if (mask.is_none()) return std::nullopt;
  return pixel_mask_from(mask);
}

MapperReport insert_points_array(PyMapper& self, const py::object& points, const py::object& threads,
                                  const py::object& mask) {
  const InsertionOptions options = insertion_options(threads);
  const std::optional<PixelMask> pixels = optional_mask(mask);
  const PointsInput in = points_from_array(points);  // with the GIL: it may ask numpy for a copy
  return with_mapper(self, [&](Mapper& m) {
    require_plausible_ranges(in.span, m.geometry().params());
    return insert_masked(m, in.span, options, pixels);
  });
}

MapperReport insert_depth_array(PyMapper& self, const py::object& depth, const PinholeIntrinsics& intrinsics,
                                double scale, const py::object& threads, const py::object& mask) {
  occ_improve::detail::require_parameter(std::isfinite(scale) && scale > 0, "scale", scale, "finite and > 0");
  const InsertionOptions options = insertion_options(threads);
  // The camera first: an image of another camera's size is better explained by the camera than the shape.
  require_grid_camera(self.mapper.geometry(), intrinsics);
  const DepthInput in = depth_from_array(depth, intrinsics);
  const std::optional<PixelMask> pixels = optional_mask(mask);
  return with_mapper(self, [&](Mapper& m) {
    require_plausible_scale(in.depth, in.pixels, scale, m.geometry().params());
    // Scaling happens here, without the GIL; the back-projection is the library's own.
    std::vector<float> scaled;
    const float* metres = in.depth;
    if (scale != 1.0) {
      scaled.assign(in.depth, in.depth + in.pixels);
      for (float& d : scaled) d = static_cast<float>(d * scale);
      metres = scaled.data();
    }
    const auto points = depth_image_to_points(DepthImage{metres, in.pixels, intrinsics});
    return insert_masked(m, PointSpan::from(points), options, pixels);
  });
}

template <class T>
using MapGetter = const std::vector<T>& (*)(const Mapper&);

/// A map of the Mapper as an H x W array: a copy, or a read-only view that keeps the Mapper alive.
template <class T>
py::array map_array(const py::object& owner, bool copy, MapGetter<T> get, const py::dtype& dtype) {
  PyMapper& self = owner.cast<PyMapper&>();
  const int h = self.mapper.geometry().height(), w = self.mapper.geometry().width();  // fixed for its life
  if (!copy) return view_2d<T>(get(self.mapper).data(), h, w, owner, dtype);
  py::array out = empty_2d(h, w, dtype);  // allocated with the GIL, filled without it
  T* dst = static_cast<T*>(out.mutable_data());
  with_mapper(self, [&](Mapper& m) {
    const std::vector<T>& src = get(m);
    std::copy(src.begin(), src.end(), dst);
  });
  return out;
}

template <class T>
void def_map_output(py::class_<PyMapper>& c, const char* name, MapGetter<T> get, const std::string& what,
                    const py::dtype& dtype = py::dtype::of<T>()) {
  static const std::string note =
      " H x W (row = elevation bin, column = azimuth bin). copy=True (default): a new array. copy=False: a "
      "read-only view of the Mapper's own buffer, valid as long as the view exists (it keeps the Mapper "
      "alive) and updated in place by later inserts (do not read it while another thread inserts).";
  c.def(name, [get, dtype](const py::object& self, bool copy) { return map_array<T>(self, copy, get, dtype); },
        py::arg("copy") = true, (what + note).c_str());
}

void bind_map_outputs(py::class_<PyMapper>& c) {
  def_map_output<float>(c, "depth", [](const Mapper& m) -> const auto& { return m.surface().depth_m; },
                        "Surface depth in metres (0 where unknown), float32.");
  def_map_output<float>(c, "probability", [](const Mapper& m) -> const auto& { return m.surface().probability; },
                        "Occupancy probability of the surface voxel, float32.");
  // The flags are 0/1 bytes, so numpy's 1-byte bool can view them directly.
  def_map_output<std::uint8_t>(c, "unknown", [](const Mapper& m) -> const auto& { return m.surface().unknown; },
                               "True where the ray was never updated, bool.", py::dtype("?"));
  def_map_output<std::int32_t>(c, "surface_bin", [](const Mapper& m) -> const auto& { return m.surface().bin; },
                               "Surface depth bin, int32 (-1 unknown, depth_bins when all bins are equal).");
  def_map_output<float>(c, "improvement", [](const Mapper& m) -> const auto& { return m.improvement().value; },
                        "Expected improvement per ray (eqs. 3-4), float32.");
}

void bind_mapper_mask(py::class_<PyMapper>& c) {
  c.def("set_mask", [](PyMapper& self, const py::object& mask) {
    const PixelMask m = pixel_mask_from(mask);
    with_mapper(self, [&](Mapper& mp) { mp.set_mask(m); });
  }, py::arg("mask"),
        "A validity / region-of-interest mask over the camera's pixels (H x W, nonzero = valid) for every later "
        "insert: points outside are left out and counted (MapperReport.points_masked), the improvement there is "
        "NaN (never ranked, in a region or planned). Raises InvalidInput for another size than the camera's, "
        "InvalidParameter for a preset without a camera (set_column_mask takes one flag per column).");
  c.def("set_column_mask", [](PyMapper& self, const py::object& mask) {
    const PixelMask m = pixel_mask_from(mask);
    const GridGeometry& g = self.mapper.geometry();
    require_shape("column mask", m.shape(), "the grid", ColumnShape::of_grid(g.width(), g.height()));
    with_mapper(self, [&](Mapper& mp) { mp.set_column_mask(m.valid); });
  }, py::arg("mask"),
        "The same mask given per column of the grid (H x W = elevation bins x azimuth bins, nonzero = inside), for "
        "any preset, those without a camera too (the paper preset, lidar_rings: a vehicle's own body, a blind "
        "sector). Raises InvalidInput for another shape than the grid's.");
  c.def("clear_mask", [](PyMapper& self) { with_mapper(self, [](Mapper& mp) { mp.clear_mask(); }); },
        "Removes the mask: every column is observable again.");
  c.def_property_readonly("column_mask", [](PyMapper& self) -> py::object {
    const std::vector<std::uint8_t> columns =
        with_mapper(self, [](Mapper& mp) { return mp.column_mask(); });
    if (columns.empty()) return py::none();
    py::array_t<bool> out({self.mapper.geometry().height(), self.mapper.geometry().width()});
    std::copy(columns.begin(), columns.end(), out.mutable_data());
    return std::move(out);
  }, "H x W bool, True where a column is inside the mask; None without a mask.");
}

void bind_mapper_insertion(py::class_<PyMapper>& c) {
  c.def(py::init([](const SensorPreset& preset, const GridOptions& options) {
          return std::make_unique<PyMapper>(Mapper(preset, options));
        }),
        py::arg("preset"), py::arg("options") = GridOptions{});
  c.def("insert", &insert_points_array, py::arg("points"), py::arg("threads") = 0, py::arg("mask") = py::none(),
        "Inserts points in the sensor frame (metres): an N x 3 or H x W x 3 array. float32 arrays whose points "
        "lie at one constant stride (C order, or slices like cloud[..., :3]) are read in place; other dtypes "
        "and layouts are converted to a float32 copy first. NaN/Inf/zero points are skipped and counted. "
        "threads: 0 = all cores, at most 1024 (InvalidParameter otherwise). mask: as set_mask, for this and later "
        "inserts (None: keep the mask in place). Raises InvalidParameter when the points' median range lies "
        "outside the depth range while millimetres would not. Releases the GIL.");
  c.def("insert_depth", &insert_depth_array, py::arg("depth"), py::arg("intrinsics"), py::arg("scale") = 1.0,
        py::arg("threads") = 0, py::arg("mask") = py::none(),
        "Inserts an H x W depth image (z-depth; value * scale = metres, 0 or NaN = no return) through its "
        "intrinsics. A C-contiguous float32 image is read in place; others (e.g. uint16 millimetres with "
        "scale=0.001) are converted first. Raises InvalidParameter for a scale under which the median return lies "
        "outside the depth range while millimetres or metres would not, and for intrinsics of another camera "
        "than the preset's. mask: as in insert. Releases the GIL.");
}

/// Mapper.keep_points: the point numbers (ascending) to keep by the map (point_selection.hpp).
py::array_t<std::int64_t> keep_points_array(PyMapper& self, const py::object& points, std::optional<std::int64_t> count,
                                            std::optional<double> fraction) {
  if (count.has_value() == fraction.has_value())
    throw InvalidParameter("keep_points: give exactly one of count and fraction");
  if (count) occ_improve::detail::require_parameter(*count >= 0, "count", static_cast<double>(*count), ">= 0");
  const KeepAmount amount =
      count ? KeepAmount::count(static_cast<std::size_t>(*count)) : KeepAmount::fraction(*fraction);
  const PointsInput in = points_from_array(points);  // with the GIL: it may ask numpy for a copy
  const std::vector<std::uint64_t> kept = with_mapper(self, [&](Mapper& m) {  // ascending
    const MapView map{m.geometry(), m.surface(), m.improvement(), m.pyramid()};
    return keep_points_by_map(points_on_rays(in.span, m.geometry()), amount, map);
  });
  py::array_t<std::int64_t> out(static_cast<py::ssize_t>(kept.size()));
  std::copy(kept.begin(), kept.end(), out.mutable_data());
  return out;
}

void bind_mapper_selection(py::class_<PyMapper>& c) {
  c.def("keep_points", &keep_points_array, py::arg("points"), py::arg("count") = py::none(),
        py::arg("fraction") = py::none(),
        "Which points of a frame to keep by the map (selective sensing; the order of ImprovementFilter's top "
        "modes, docs/SELECTIVE.md): their numbers in `points` (the row of an N x 3 array; of an H x W x 3 image, "
        "v * W + u, the row of points.reshape(-1, 3)), ascending, as an int64 array. Give exactly one of count (at most that many) and fraction (of the points "
        "on an observable ray, in [0, 1]). A jittered grid at the scale of the sampling; in each cell a ray that "
        "already holds a depth sample first (the rays beside it are predicted from it), then the highest "
        "improvement. Points without a ray (NaN, outside the field of view) or on a masked ray are never kept. "
        "Choose before inserting the frame, then insert points.reshape(-1, 3)[kept]. Releases the GIL.");
}

void bind_mapper_properties(py::class_<PyMapper>& c) {
  // Geometry, model and options never change after construction: read without the lock.
  c.def_property_readonly("width", [](PyMapper& s) { return s.mapper.geometry().width(); }, "Azimuth bins.");
  c.def_property_readonly("height", [](PyMapper& s) { return s.mapper.geometry().height(); }, "Elevation bins.");
  c.def_property_readonly("geometry", [](PyMapper& s) { return s.mapper.geometry().params(); }, "GeometryParams (a copy).");
  c.def_property_readonly("model", [](PyMapper& s) { return s.mapper.model().params(); }, "SensorModelParams (a copy).");
  c.def_property_readonly("options", [](PyMapper& s) { return s.mapper.grid().options(); }, "GridOptions (a copy).");
  c.def("memory_bytes", [](PyMapper& s) { return with_mapper(s, [](Mapper& mp) { return mp.grid().memory_bytes(); }); },
        "Heap bytes held by the grid's store.");
  c.def("touched_columns", [](PyMapper& s) {
    return with_mapper(s, [](Mapper& mp) { return mp.grid().touched_column_count(); });
  }, "Rays that hold any data.");
  // pickle's default said only "cannot pickle 'Mapper' object"; copying a grid of gigabytes by accident
  // is no better: the way to keep or move a map is its file.
  c.def("__reduce__", [](const py::object&) -> py::object {
    throw py::type_error("Mapper cannot be pickled or copied (it holds the whole grid): use Mapper.save(path) "
                         "and load_map(path)");
  }, "Raises TypeError: a Mapper is kept or moved through its file (save, load_map).");
  c.def("__repr__", [](PyMapper& s) {
    const GridGeometry& g = s.mapper.geometry();
    return "Mapper(" + std::to_string(g.width()) + " x " + std::to_string(g.height()) + " x " +
           std::to_string(g.depth().bins()) + ")";
  });
}

void require_bins(const GridGeometry& g, int azimuth_bin, int elevation_bin) {
  occ_improve::detail::require_parameter(azimuth_bin >= 0 && azimuth_bin < g.width(), "azimuth_bin", azimuth_bin,
                                         "inside [0, width)");
  occ_improve::detail::require_parameter(elevation_bin >= 0 && elevation_bin < g.height(), "elevation_bin",
                                         elevation_bin, "inside [0, height)");
}

void bind_mapper_rays(py::class_<PyMapper>& c) {
  c.def("ray_improvement", [](PyMapper& s, int azimuth_bin, int elevation_bin) {
    require_bins(s.mapper.geometry(), azimuth_bin, elevation_bin);
    return with_mapper(s, [&](Mapper& mp) {
      // A ray the map holds no value for (masked, or outside the sensor's view) has none here either: it
      // gave eq. 4's value (0.324, -1.18) where improvement() holds NaN.
      const std::size_t c = static_cast<std::size_t>(elevation_bin) * static_cast<std::size_t>(mp.geometry().width()) +
                            static_cast<std::size_t>(azimuth_bin);
      if (std::isnan(mp.improvement().value[c])) return std::numeric_limits<double>::quiet_NaN();
      return ray_improvement(mp.geometry(), mp.model(), mp.surface(), azimuth_bin, elevation_bin);
    });
  }, py::arg("azimuth_bin"), py::arg("elevation_bin"),
        "Eqs. 3-4 for one ray, recomputed from the surface (double precision; the map holds the float value); "
        "NaN where the map holds NaN (a masked ray, or one outside the sensor's view).");
  c.def("direction", [](PyMapper& s, int azimuth_bin, int elevation_bin) {
    require_bins(s.mapper.geometry(), azimuth_bin, elevation_bin);
    return Eigen::Vector3d(s.mapper.geometry().direction(azimuth_bin, elevation_bin));
  }, py::arg("azimuth_bin"), py::arg("elevation_bin"), "Unit direction (sensor frame) through a ray's centre.");
  c.def("locate", [](PyMapper& s, const std::array<double, 3>& p) -> std::optional<std::pair<int, int>> {
    // std::array, not Eigen: GCC 12 gives a false maybe-uninitialized warning in pybind11's Eigen caster.
    const GridGeometry& g = s.mapper.geometry();
    ColumnIndex c = 0;
    if (!g.column_of(p[0], p[1], p[2], c)) return std::nullopt;
    return std::make_pair(g.azimuth_bin_of(c), g.elevation_bin_of(c));
  }, py::arg("point"), "(azimuth_bin, elevation_bin) of the ray through a sensor-frame point, None outside the field of view.");
}

void bind_mapper_class(py::module_& m) {
  py::class_<PyMapper> c(m, "Mapper",
                         "A spherical grid with its sensor model, surface and improvement map, kept up to date "
                         "together. Methods release the GIL; calls on one Mapper from several threads are serialised.");
  bind_mapper_insertion(c);
  bind_mapper_mask(c);
  bind_map_outputs(c);
  bind_mapper_properties(c);
  bind_mapper_rays(c);
  bind_mapper_selection(c);
}

}  // namespace

void bind_mapper(py::module_& m) {
  bind_reports(m);
  bind_mapper_class(m);
}

}  // namespace occ_improve::python
