// Presets, geometry and sensor-model parameters, grid options: plain structs with keyword constructors.
#include "bindings.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/camera_matrix.hpp"
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cstring>

namespace occ_improve::python {
namespace {

void bind_intrinsics(py::module_& m) {
  py::class_<PinholeIntrinsics> k(m, "PinholeIntrinsics", "A pinhole depth camera (pixels; u right, v down).");
  def_value_struct<PinholeIntrinsics>(k);
  k.def_readwrite("fx", &PinholeIntrinsics::fx)
      .def_readwrite("fy", &PinholeIntrinsics::fy)
      .def_readwrite("cx", &PinholeIntrinsics::cx)
      .def_readwrite("cy", &PinholeIntrinsics::cy)
      .def_property("width", int_field_getter(&PinholeIntrinsics::width),
                    int_field_setter(&PinholeIntrinsics::width, "width"))
      .def_property("height", int_field_getter(&PinholeIntrinsics::height),
                    int_field_setter(&PinholeIntrinsics::height, "height"))
      .def("validate", &PinholeIntrinsics::validate, "Raises InvalidParameter naming the first bad field.");
  m.def("kinect_v1_intrinsics", &kinect_v1_intrinsics, "Kinect v1 as OpenNI reports it (fx = fy = 525).");
  m.def("_intrinsics_from_matrix", &intrinsics_from_matrix, py::arg("k_row_major"), py::arg("width"), py::arg("height"),
        "The library's rule for a camera matrix (frames.intrinsics_from_matrix takes any array).");
}

void bind_geometry_params(py::module_& m) {
  // Depth binnings too are named by their tags; DepthBinning holds the built-in ones.
  struct DepthBinningTags {};
  py::class_<DepthBinningTags>(m, "DepthBinning",
                               "The built-in depth binnings' tags (GeometryParams.depth_binning is the tag).")
      .def_property_readonly_static("uniform", [](py::object) { return DepthBinning::uniform; })
      .def_property_readonly_static("inverse_depth", [](py::object) { return DepthBinning::inverse_depth; });
  m.def("registered_depth_binnings", &registered_depth_binnings, "The tags depth_binning may name.");
  // Binnings are named by their registered tags (strings); AngularBinning holds the built-in ones.
  struct AngularBinningTags {};
  py::class_<AngularBinningTags>(m, "AngularBinning",
                                 "The built-in binnings' tags (GeometryParams.angular_binning is the tag).")
      .def_property_readonly_static("spherical", [](py::object) { return AngularBinning::spherical; })
      .def_property_readonly_static("pinhole", [](py::object) { return AngularBinning::pinhole; })
      .def_property_readonly_static("lidar_rings", [](py::object) { return AngularBinning::lidar_rings; });
  m.def("registered_angular_binnings", &registered_angular_binnings, "The tags angular_binning may name.");
  py::class_<GeometryParams> g(m, "GeometryParams",
                               "The grid's binning, bins and ranges (radians or pixels, metres).");
  def_value_struct<GeometryParams>(g);
  g.def_readwrite("angular_binning", &GeometryParams::angular_binning)
      .def_readwrite("camera", &GeometryParams::camera,
                     "pinhole: the camera whose pixels are the columns; spherical: marks observable columns, or None.")
      .def_property("azimuth_bins", int_field_getter(&GeometryParams::azimuth_bins),
                    int_field_setter(&GeometryParams::azimuth_bins, "azimuth_bins"))
      .def_property("elevation_bins", int_field_getter(&GeometryParams::elevation_bins),
                    int_field_setter(&GeometryParams::elevation_bins, "elevation_bins"))
      .def_property("depth_bins", int_field_getter(&GeometryParams::depth_bins),
                    int_field_setter(&GeometryParams::depth_bins, "depth_bins"))
      .def_readwrite("azimuth_min_rad", &GeometryParams::azimuth_min_rad)
      .def_readwrite("azimuth_max_rad", &GeometryParams::azimuth_max_rad)
      .def_readwrite("elevation_min_rad", &GeometryParams::elevation_min_rad)
      .def_readwrite("elevation_max_rad", &GeometryParams::elevation_max_rad)
      .def_readwrite("row_elevations_rad", &GeometryParams::row_elevations_rad,
                     "lidar_rings: each ring's elevation (y down), rows top to bottom; [] otherwise.")
      .def_readwrite("depth_binning", &GeometryParams::depth_binning)
      .def_readwrite("depth_min_m", &GeometryParams::depth_min_m)
      .def_readwrite("depth_max_m", &GeometryParams::depth_max_m)
      .def("validate", &GeometryParams::validate, "Raises InvalidParameter naming the first bad field.");
}

void bind_model_params(py::module_& m) {
  py::class_<SensorModelParams> s(m, "SensorModelParams",
                                  "Eq. 1's noise model: sigma_rho = max(floor, sigma_depth_m + sigma_depth_per_m2 rho^2).");
  def_value_struct<SensorModelParams>(s);
  s.def_readwrite("sigma_azimuth_rad", &SensorModelParams::sigma_azimuth_rad)
      .def_readwrite("sigma_elevation_rad", &SensorModelParams::sigma_elevation_rad)
      .def_readwrite("sigma_u_px", &SensorModelParams::sigma_u_px)
      .def_readwrite("sigma_v_px", &SensorModelParams::sigma_v_px)
      .def_readwrite("sigma_depth_m", &SensorModelParams::sigma_depth_m)
      .def_readwrite("sigma_depth_per_m2", &SensorModelParams::sigma_depth_per_m2)
      .def_readwrite("sigma_depth_floor_m", &SensorModelParams::sigma_depth_floor_m)
      .def_readwrite("support_k", &SensorModelParams::support_k)
      .def("validate", &SensorModelParams::validate, "Raises InvalidParameter naming the first bad field.");
}

/// preset_by_name(name) for a preset that does not depend on a camera; a camera preset is refused
/// rather than built for the nominal Kinect v1 as the C++ overload does.
SensorPreset preset_by_name_without_camera(const std::string& name) {
  SensorPreset preset = preset_by_name(name);  // unknown names raise here, listing the known ones
  if (preset.camera)
    throw InvalidParameter("preset '" + name + "' is built from the depth camera's intrinsics: call preset_by_name('" +
                           name + "', intrinsics) (kinect_v1_intrinsics() for OpenNI's nominal Kinect v1)");
  return preset;
}

void bind_preset(py::module_& m) {
  py::class_<SensorPreset> p(m, "SensorPreset", "A grid geometry and a sensor model that belong together.");
  def_value_struct<SensorPreset>(p);
  p.def_readwrite("name", &SensorPreset::name)
      .def_readwrite("geometry", &SensorPreset::geometry)
      .def_readwrite("model", &SensorPreset::model)
      .def_readwrite("camera", &SensorPreset::camera, "The intrinsics it was built from, or None.");

  py::class_<PinholePresetOptions> o(m, "PinholePresetOptions", "Depth axis and noise for preset_from_pinhole.");
  def_value_struct<PinholePresetOptions>(o);
  o.def_readwrite("angular_binning", &PinholePresetOptions::angular_binning)
      .def_property("depth_bins", int_field_getter(&PinholePresetOptions::depth_bins),
                    int_field_setter(&PinholePresetOptions::depth_bins, "depth_bins"))
      .def_readwrite("depth_binning", &PinholePresetOptions::depth_binning)
      .def_readwrite("depth_min_m", &PinholePresetOptions::depth_min_m)
      .def_readwrite("depth_max_m", &PinholePresetOptions::depth_max_m)
      .def_readwrite("sigma_depth_m", &PinholePresetOptions::sigma_depth_m)
      .def_readwrite("sigma_depth_per_m2", &PinholePresetOptions::sigma_depth_per_m2)
      .def_readwrite("sigma_depth_floor_m", &PinholePresetOptions::sigma_depth_floor_m)
      .def_readwrite("support_k", &PinholePresetOptions::support_k);

  py::class_<LidarRingsOptions> l(m, "LidarRingsOptions", "A spinning LiDAR's rings, azimuth steps, depth and noise.");
  def_value_struct<LidarRingsOptions>(l);
  l.def_readwrite("ring_elevations_deg", &LidarRingsOptions::ring_elevations_deg)
      .def_property("azimuth_steps", int_field_getter(&LidarRingsOptions::azimuth_steps),
                    int_field_setter(&LidarRingsOptions::azimuth_steps, "azimuth_steps"))
      .def_readwrite("azimuth_min_deg", &LidarRingsOptions::azimuth_min_deg)
      .def_readwrite("azimuth_max_deg", &LidarRingsOptions::azimuth_max_deg)
      .def_property("depth_bins", int_field_getter(&LidarRingsOptions::depth_bins),
                    int_field_setter(&LidarRingsOptions::depth_bins, "depth_bins"))
      .def_readwrite("depth_binning", &LidarRingsOptions::depth_binning)
      .def_readwrite("depth_min_m", &LidarRingsOptions::depth_min_m)
      .def_readwrite("depth_max_m", &LidarRingsOptions::depth_max_m)
      .def_readwrite("sigma_range_m", &LidarRingsOptions::sigma_range_m)
      .def_readwrite("sigma_azimuth_rad", &LidarRingsOptions::sigma_azimuth_rad)
      .def_readwrite("sigma_elevation_rad", &LidarRingsOptions::sigma_elevation_rad)
      .def_readwrite("support_k", &LidarRingsOptions::support_k);
  m.def("lidar_rings", &lidar_rings, py::arg("options") = LidarRingsOptions{}, py::arg("name") = "lidar_rings",
        "A spinning LiDAR's range image (lidar_rings binning); the default options are a Velodyne VLP-16.");

  m.def("kinect_v1_paper", &kinect_v1_paper, "The paper's set-up: 640 x 480 x 512 bins, 57 x 43 deg, [0, 5 m).");
  // The camera presets take the camera's intrinsics, never a default: a grid built for another camera
  // puts every pixel in the wrong column. kinect_v1_intrinsics() asks for OpenNI's values explicitly.
  m.def("kinect_v1", &kinect_v1, py::arg("intrinsics"),
        "For real use (the default): one column per pixel of the camera, depth along z, inverse-depth bins "
        "over [0.5 m, 8 m]. intrinsics: the depth camera's (read_intrinsics, or kinect_v1_intrinsics() for "
        "OpenNI's nominal Kinect v1).");
  m.def("kinect_v1_spherical", &kinect_v1_spherical, py::arg("intrinsics"),
        "kinect_v1's depth model over spherical bins spanning the image (columns outside it not observable).");
  m.def("preset_from_pinhole", &preset_from_pinhole, py::arg("intrinsics"),
        py::arg("options") = PinholePresetOptions{}, py::arg("name") = "pinhole",
        "A preset for any pinhole depth camera: one column per pixel over the image's angular extent.");
  m.def("preset_by_name", &preset_by_name_without_camera, py::arg("name"),
        "'kinect_v1_paper' (the camera presets need intrinsics: preset_by_name(name, intrinsics)); raises "
        "InvalidParameter listing the known names.");
  m.def("preset_by_name", py::overload_cast<const std::string&, const PinholeIntrinsics&>(&preset_by_name),
        py::arg("name"), py::arg("intrinsics"), "The named preset for this camera (kinect_v1_paper ignores it).");
  m.def("preset_names", &preset_names, "The names preset_by_name accepts.");
}

void bind_grid_options(py::module_& m) {
  py::enum_<UpdateMode>(m, "UpdateMode", "How log-odds are accumulated.")
      .value("clamped", UpdateMode::clamped, "clamped after each update, as OctoMap does (default)")
      .value("exact", UpdateMode::exact, "eq. 2 exactly, no bounds");
  py::class_<GridOptions> g(m, "GridOptions", "Update mode, clamping probabilities and the memory cap.");
  def_value_struct<GridOptions>(g);
  g.def_readwrite("mode", &GridOptions::mode)
      .def_readwrite("probability_min", &GridOptions::probability_min)
      .def_readwrite("probability_max", &GridOptions::probability_max)
      .def_property("memory_cap_bytes", int_field_getter(&GridOptions::memory_cap_bytes),
                    int_field_setter(&GridOptions::memory_cap_bytes, "memory_cap_bytes"))
      .def("validate", &GridOptions::validate, "Raises InvalidParameter naming the first bad field.")
      .def_static("octomap_clamping", &GridOptions::octomap_clamping, "OctoMap's clamping (0.1192 / 0.971).");
}

/// The built-in sample frame as (depth H x W float32 metres, intrinsics); 0 = no return.
py::tuple sample_depth(std::uint32_t seed, bool noise, bool quantise, bool projector_shadow) {
  sample::SceneOptions options;
  options.seed = seed;
  options.noise = noise;
  options.quantise = quantise;
  options.projector_shadow = projector_shadow;
  const sample::SampleFrame frame = sample::generate_scene(options);
  py::array_t<float> depth({frame.intrinsics.height, frame.intrinsics.width});
  std::memcpy(depth.mutable_data(), frame.depth_m.data(), frame.depth_m.size() * sizeof(float));
  return py::make_tuple(depth, frame.intrinsics);
}

}  // namespace

void bind_presets(py::module_& m) {
  bind_intrinsics(m);
  bind_geometry_params(m);
  bind_model_params(m);
  bind_preset(m);
  bind_grid_options(m);
  m.def("sample_depth", &sample_depth, py::arg("seed") = 1, py::arg("noise") = true, py::arg("quantise") = true,
        py::arg("projector_shadow") = true,
        "The built-in Kinect-like sample frame (floor, wall, recess, box, pole, shadows, dark poster): "
        "(depth, intrinsics), depth an H x W float32 array of z-depth in metres, 0 = no return.");
}

}  // namespace occ_improve::python
