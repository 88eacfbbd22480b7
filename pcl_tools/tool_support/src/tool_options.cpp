#include "occ_improve/tools/tool_options.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/depth_binning.hpp"
#include "occ_improve/tools/flag_registry.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace occ_improve {

namespace {

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void bad_flag(const std::string& flag, const std::string& value, const std::string& requirement) {
  throw InvalidParameter(flag + " " + value + " is invalid: must be " + requirement);
}

// Depth bins wider than the depth noise sigma(z) (-depth_bins lowered for a large camera, or a small
// constant -sigma_depth): a surface crossing a bin boundary spreads its return over two bins and keeps a
// lower peak probability than one at a bin's centre, so a flat surface shows stripes of higher
// improvement along such crossings (a 1-3 m ramp gave 38 regions at 1024 bins, none at the default 2048,
// where bins are 0.64 sigma wide). One line on stderr saying where, when a bin is wider than one sigma.
void warn_if_depth_bins_wider_than_sigma(const SensorPreset& preset) {
  const GeometryParams& g = preset.geometry;
  const DepthAxis axis(g.depth_binning, g.depth_min_m, g.depth_max_m, g.depth_bins);
  const SensorModel model(preset.model);
  double widest = 0, at_m = 0;
  for (const double centre : axis.centres()) {
    const double width_in_sigmas = axis.width_at(centre) / model.sigma_depth_at(centre);
    if (width_in_sigmas > widest) {
      widest = width_in_sigmas;
      at_m = centre;
    }
  }
  if (widest <= 1.0) return;
  std::fprintf(stderr,
               "warning: depth bins up to %.1f sigma wide (%.1f mm at %.2f m, sigma %.1f mm): flat surfaces will show "
               "stripes of higher improvement where they cross bin boundaries (and occ_segment cuts them into bands "
               "there); give more -depth_bins or a larger -sigma_depth\n",
               widest, 1000.0 * axis.width_at(at_m), at_m, 1000.0 * model.sigma_depth_at(at_m));
}

// With -load the map's own grid and sensor model are used: the flags that would shape another (given by
// habit, or to change the map) were ignored without a word. (-preset and the camera flags may still serve
// to read frames added to the map; -memory_cap bounds the load.)
void warn_of_flags_a_loaded_map_overrides(const CommandLine& c) {
  std::string ignored;
  for (const std::string& flag : sensor_flag_names())
    if (flag != "-preset" && flag != "-memory_cap" && c.declares(flag) && c.has(flag))
      ignored += (ignored.empty() ? "" : ", ") + flag;
  if (!ignored.empty())
    std::fprintf(stderr, "warning: -load uses the map's own grid and sensor model: %s ignored\n", ignored.c_str());
}

PinholeIntrinsics intrinsics_from_list(const std::string& text) {
  const std::vector<double> v = parse_number_list("-intrinsics", text);
  if (v.size() != 4 && v.size() != 6) bad_flag("-intrinsics", text, "fx,fy,cx,cy or fx,fy,cx,cy,width,height");
  PinholeIntrinsics k;
  k.fx = v[0];
  k.fy = v[1];
  k.cx = v[2];
  k.cy = v[3];
  if (v.size() == 6) {
    if (v[4] != std::floor(v[4]) || v[5] != std::floor(v[5]) || v[4] < 1 || v[5] < 1 || v[4] > 65536 || v[5] > 65536)
      bad_flag("-intrinsics", text, "a whole width and height in [1, 65536]");
    k.width = static_cast<int>(v[4]);
    k.height = static_cast<int>(v[5]);
  }
  try {
    k.validate();
  } catch (const InvalidParameter& e) {
    throw InvalidParameter(std::string("-intrinsics ") + text + ": " + e.what());
  }
  return k;
}

// The value of a flag when the tool declares it and it was given or has a default.
std::optional<std::string> declared_text(const CommandLine& c, const std::string& flag) {
  return c.declares(flag) ? c.text(flag) : std::nullopt;
}
std::optional<double> declared_number(const CommandLine& c, const std::string& flag) {
  return c.declares(flag) ? c.number(flag) : std::nullopt;
}

// " and -sigma_angle 3.2 -support_k 2": the flags a preset's validation error may come from.
std::string describe_overrides(const PresetOverrides& o) {
  std::ostringstream s;
  const auto add = [&](const char* flag, const auto& value) {
    if (value) s << ' ' << flag << ' ' << *value;
  };
  add("-sigma_depth", o.sigma_depth_m);
  add("-sigma_depth_quadratic", o.sigma_depth_per_m2);
  add("-sigma_angle", o.sigma_angle_rad);
  add("-support_k", o.support_k);
  add("-depth_bins", o.depth_bins);
  add("-depth_max", o.depth_max_m);
  add("-fov", o.fov_horizontal_deg);
  return s.str().empty() ? std::string() : " and" + s.str();
}

}  // namespace

SensorPreset apply_overrides(SensorPreset p, const PresetOverrides& o, bool camera_checks) {
  if (o.sigma_depth_m) p.model.sigma_depth_m = *o.sigma_depth_m;
  if (o.sigma_depth_per_m2) p.model.sigma_depth_per_m2 = *o.sigma_depth_per_m2;
  if (o.sigma_angle_rad) {
    // tan() below wraps past pi/2 (3.2 rad became 30 px, pi nearly 0 px): an angular sigma is far below that.
    if (!(*o.sigma_angle_rad < kPi / 2))
      bad_flag("-sigma_angle", std::to_string(*o.sigma_angle_rad), "below pi/2 rad (an angle from the optical axis)");
    p.model.sigma_azimuth_rad = p.model.sigma_elevation_rad = *o.sigma_angle_rad;
    // The pixel-native binning's sigmas are in pixels: the same angle at the image centre.
    if (p.camera) {
      p.model.sigma_u_px = std::tan(*o.sigma_angle_rad) * p.camera->fx;
      p.model.sigma_v_px = std::tan(*o.sigma_angle_rad) * p.camera->fy;
    }
  }
  if ((o.fov_horizontal_deg || o.fov_vertical_deg) && p.geometry.angular_binning == AngularBinning::pinhole)
    throw InvalidParameter("-fov applies to spherical grids; preset " + p.name +
                           " has one column per camera pixel (its field of view is the image's)");
  if (o.support_k) p.model.support_k = *o.support_k;
  if (o.depth_bins) p.geometry.depth_bins = *o.depth_bins;
  if (o.depth_max_m) p.geometry.depth_max_m = *o.depth_max_m;
  if (o.fov_horizontal_deg) {
    const double half = *o.fov_horizontal_deg * kPi / 360.0;
    p.geometry.azimuth_min_rad = -half;
    p.geometry.azimuth_max_rad = half;
  }
  if (o.fov_vertical_deg) {
    const double half = *o.fov_vertical_deg * kPi / 360.0;
    p.geometry.elevation_min_rad = -half;
    p.geometry.elevation_max_rad = half;
  }
  // The overrides are validated together with the preset: a depth_max below the preset's depth_min,
  // for example, only shows here. The message names the field; say which flags set it.
  try {
    p.geometry.validate();
    if (camera_checks) p.model.validate_for(p.geometry);
  } catch (const InvalidParameter& e) {
    throw InvalidParameter(std::string(e.what()) + " (after -preset " + p.name + describe_overrides(o) + ")");
  }
  return p;
}

namespace {

// The grid's worst case against the cap, before any grid exists (-depth_bins 1e8 took 3.1 GB before the
// cap's error), naming the flags that size it.
void require_tool_grid_within_cap(const SensorPreset& preset, const GridOptions& grid, const std::string& preset_name) {
  try {
    require_within_memory_cap(preset.geometry, grid.memory_cap_bytes);
  } catch (const ResourceLimit& e) {
    throw ResourceLimit(std::string(e.what()) + " (after -preset " + preset_name + " and -depth_bins/-fov;" +
                        memory_cap_hint(true) + ")");
  }
}

// Before the inputs give the camera (and so the columns), the depth axis alone: one column's worst case, a
// lower bound of the grid's, against the cap, before anything is built per depth bin (-depth_bins 1e9
// without -intrinsics took 24 GB before the cap's error, until the kernel killed the tool).
void require_depth_axis_within_cap(const SensorPreset& preset, const GridOptions& grid, const std::string& preset_name) {
  SensorPreset one_column = preset;
  one_column.geometry.azimuth_bins = one_column.geometry.elevation_bins = 1;
  try {
    require_tool_grid_within_cap(one_column, grid, preset_name);
  } catch (const ResourceLimit& e) {
    throw ResourceLimit("the depth axis alone (one column of the grid, whose camera the inputs give): " + std::string(e.what()));
  }
}

}  // namespace

SensorPreset ToolOptions::preset_for_camera(const std::optional<PinholeIntrinsics>& camera) const {
  if (intrinsics || !preset.camera) return preset;  // checked while parsing
  const SensorPreset p = apply_overrides(camera ? preset_by_name(preset_name, *camera) : preset, overrides);
  require_tool_grid_within_cap(p, grid, preset_name);
  return p;
}

ToolOptions parse_tool_options(const CommandLine& c) {
  ToolOptions t;
  t.inputs = c.positionals();
  t.preset_name = declared_text(c, "-preset").value_or("kinect_v1");

  const auto intrinsics_list = declared_text(c, "-intrinsics");
  const auto intrinsics_file = declared_text(c, "-intrinsics_file");
  if (intrinsics_list && intrinsics_file) throw InvalidParameter("give -intrinsics or -intrinsics_file, not both");
  if (intrinsics_list) {
    t.intrinsics = intrinsics_from_list(*intrinsics_list);
    t.intrinsics_flag = "-intrinsics";
  }
  if (intrinsics_file) {
    t.intrinsics = read_intrinsics_file(*intrinsics_file);
    t.intrinsics_flag = "-intrinsics_file " + *intrinsics_file;
  }
  if (const auto e = declared_text(c, "-depth_encoding")) t.depth_encoding = parse_depth_encoding(*e);

  PresetOverrides& o = t.overrides;
  o.sigma_depth_m = declared_number(c, "-sigma_depth");
  o.sigma_depth_per_m2 = declared_number(c, "-sigma_depth_quadratic");
  o.sigma_angle_rad = declared_number(c, "-sigma_angle");
  o.support_k = declared_number(c, "-support_k");
  o.depth_max_m = declared_number(c, "-depth_max");
  if (const auto bins = declared_number(c, "-depth_bins")) o.depth_bins = static_cast<int>(*bins);
  if (const auto text = declared_text(c, "-fov")) {
    const std::vector<double> fov = parse_number_list("-fov", *text);
    if (fov.size() != 2 || !(fov[0] > 0 && fov[0] < 360) || !(fov[1] > 0 && fov[1] < 180))
      bad_flag("-fov", *text, "h,v in degrees with 0 < h < 360 and 0 < v < 180");
    o.fov_horizontal_deg = fov[0];
    o.fov_vertical_deg = fov[1];
  }

  const SensorPreset named = t.intrinsics ? preset_by_name(t.preset_name, *t.intrinsics) : preset_by_name(t.preset_name);
  const bool camera_known = t.intrinsics || !named.camera;  // else the inputs' camera, found later
  t.preset = apply_overrides(named, o, camera_known);

  if (declared_text(c, "-mode") == std::string("exact")) t.grid.mode = UpdateMode::exact;
  if (declared_text(c, "-clamp") == std::string("octomap")) {
    const UpdateMode mode = t.grid.mode;
    t.grid = GridOptions::octomap_clamping();
    t.grid.mode = mode;
  }

  if (const auto gib = declared_number(c, "-memory_cap"))
    t.grid.memory_cap_bytes = static_cast<std::size_t>(std::min(*gib * double(1 << 30), 1e18));
  if (camera_known)
    require_tool_grid_within_cap(t.preset, t.grid, t.preset_name);
  else
    require_depth_axis_within_cap(t.preset, t.grid, t.preset_name);
  // A loaded map brings its own bins and model: the preset of the flags is not the grid then.
  if (!(c.declares("-load") && c.has("-load")))
    warn_if_depth_bins_wider_than_sigma(t.preset);
  else
    warn_of_flags_a_loaded_map_overrides(c);
  if (const auto k = declared_number(c, "-k")) t.top_k = static_cast<int>(*k);
  t.use_poses = !(c.declares("-no_poses") && c.has("-no_poses"));
  return t;
}

std::string memory_cap_hint(bool with_depth_bins) {
  return with_depth_bins ? " raise the cap with -memory_cap GIB, or lower -depth_bins" : " raise the cap with -memory_cap GIB";
}

void require_frames_fit_loaded_map(const GridGeometry& loaded, const std::optional<PinholeIntrinsics>& camera,
                                   const std::string& path) {
  if (!camera) return;
  try {
    require_grid_camera(loaded, *camera);
  } catch (const InvalidParameter& e) {
    throw InvalidParameter("-load " + path + ": the frames are not of the map's camera: " + e.what());
  }
}

LoadedMap load_tool_map(const std::string& path, const ToolOptions& options) {
  try {
    return load_map(path, options.grid.memory_cap_bytes);
  } catch (const ResourceLimit& e) {
    throw ResourceLimit(std::string(e.what()) + ";" + memory_cap_hint(false));  // the map fixes its own bins
  }
}

}  // namespace occ_improve
