#pragma once
// The sensor preset, grid options, camera and inputs the occ_improve tools build from their common flags
// (flags.hpp's sensor_flag_names() and camera_flag_names()), with a preset's overrides.
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/tools/flags.hpp"

#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// The overrides given on the command line, applied on top of a preset (unset = keep the preset's).
struct PresetOverrides {
  std::optional<double> sigma_depth_m, sigma_depth_per_m2, sigma_angle_rad, support_k;
  std::optional<int> depth_bins;
  std::optional<double> depth_max_m;
  std::optional<double> fov_horizontal_deg, fov_vertical_deg;
};

struct ToolOptions {
  std::string preset_name;
  PresetOverrides overrides;
  /// The named preset (built from `intrinsics` when it is camera-based) + overrides. A camera-based preset
  /// without -intrinsics has Kinect v1's nominal camera here and its camera-dependent checks (sigmas in
  /// pixels, the memory cap) wait for the inputs' camera: preset_for_camera does them.
  SensorPreset preset;
  GridOptions grid;
  std::optional<PinholeIntrinsics> intrinsics;  ///< from -intrinsics or -intrinsics_file
  std::string intrinsics_flag;                  ///< "-intrinsics" or "-intrinsics_file PATH", for messages
  std::optional<DepthEncoding> depth_encoding;  ///< unset: chosen per file (see frame_io.hpp)
  int top_k = 10;
  bool use_poses = true;            ///< false with -no_poses: every frame taken from the first's viewpoint
  std::vector<std::string> inputs;  ///< positional arguments, in command-line order

  /// The preset again for a camera found with the input (e.g. a folder's camera-intrinsics.txt, a fitted
  /// cloud) when no intrinsics were given on the command line; overrides are re-applied and checked for
  /// that camera, the memory cap too (a 320 x 240 camera's grid is a quarter of the nominal one's). Without
  /// a camera, the preset as parsed, checked (a device's frames are taken as the nominal camera's). Paper
  /// presets ignore it.
  SensorPreset preset_for_camera(const std::optional<PinholeIntrinsics>& camera) const;
  /// Whether the preset is built from a camera (kinect_v1, kinect_v1_spherical), so frames need one.
  bool preset_needs_camera() const { return preset.camera.has_value(); }
};

/// The sensor preset, grid options, camera and inputs from a parsed command line (the flags of
/// sensor_flag_names() and camera_flag_names() the tool declares; the others keep their defaults).
/// Throws InvalidParameter naming the flag when flags conflict or the preset they build is invalid,
/// IoError/FormatError for an unreadable -intrinsics_file.
ToolOptions parse_tool_options(const CommandLine& command_line);

/// Applies overrides to a preset and validates the result (InvalidParameter naming the flag); with
/// `camera_checks` false, only what does not depend on the camera (its geometry).
SensorPreset apply_overrides(SensorPreset preset, const PresetOverrides& overrides, bool camera_checks = true);

/// load_map under the tool's cap; a ResourceLimit says how to raise it (-memory_cap).
LoadedMap load_tool_map(const std::string& path, const ToolOptions& options);

/// Throws InvalidParameter naming -load PATH and both cameras when frames of `camera` (if known) are not
/// of the camera the loaded grid was built for (require_grid_camera): their points would fall in other
/// columns, or outside the field of view, without a word.
void require_frames_fit_loaded_map(const GridGeometry& loaded, const std::optional<PinholeIntrinsics>& camera,
                                   const std::string& path);

/// " raise the cap with -memory_cap GIB[, or lower -depth_bins]": the end of a tool's ResourceLimit message.
std::string memory_cap_hint(bool with_depth_bins);

}  // namespace occ_improve
