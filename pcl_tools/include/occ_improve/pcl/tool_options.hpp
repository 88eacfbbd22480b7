#pragma once
// The command-line flags every occ_improve tool shares (sensor preset and its overrides, update mode,
// camera intrinsics, depth encoding, input files), parsed once in the style of PCL's tools
// (pcl::console::parse_argument / find_switch). Every bad flag throws InvalidParameter naming the flag.
#include "occ_improve/atomic_file.hpp"
#include "occ_improve/grid.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/presets.hpp"

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace occ_improve {

/// What a tool adds to the common flags.
struct ToolSpec {
  std::string default_preset = "kinect_v1";  ///< the real-use, pixel-native preset in every tool
  int default_top_k = 10;
  /// The tool's own flags that take a value (e.g. "-o"), so their values are not taken as inputs.
  std::vector<std::string> value_flags;
  /// The tool's own switches (e.g. "-sample"). Any other "-name" argument is an unknown flag (error).
  std::vector<std::string> switches;
};

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
  SensorPreset preset;  ///< the named preset (built from `intrinsics` when it is camera-based) + overrides
  GridOptions grid;
  std::optional<PinholeIntrinsics> intrinsics;  ///< from -intrinsics or -intrinsics_file
  std::string intrinsics_flag;                  ///< "-intrinsics" or "-intrinsics_file PATH", for messages
  std::optional<DepthEncoding> depth_encoding;  ///< unset: chosen per file (see frame_io.hpp)
  int top_k = 10;
  std::vector<std::string> inputs;  ///< positional arguments, in command-line order

  /// The preset again for a camera found with the input (e.g. a folder's camera-intrinsics.txt) when no
  /// intrinsics were given on the command line; overrides are re-applied. Paper presets ignore it.
  SensorPreset preset_for_camera(const std::optional<PinholeIntrinsics>& camera) const;
  /// Whether the preset is built from a camera (kinect_v1, kinect_v1_spherical), so frames need one.
  bool preset_needs_camera() const { return preset.camera.has_value(); }
};

/// One input frame of a tool, with the camera it is seen through and where that camera came from.
struct ToolFrame {
  std::string name;  ///< the file, with its depth encoding for depth images
  pcl::PointCloud<pcl::PointXYZ> cloud;
  std::optional<PinholeIntrinsics> camera;
  std::string camera_source;  ///< "-intrinsics", "camera-intrinsics.txt ...", "fitted to the cloud, ..."
  std::optional<Image> colour;  ///< registered colour (organized PCDs with rgb/rgba)
};

/// Reads every input (expand_input: files and dataset folders, in order). Intrinsics are never assumed:
/// a depth image is back-projected through -intrinsics/-intrinsics_file or its dataset's intrinsics
/// file, and refused without either; a PCD's camera, when the preset needs one and none was given, is
/// fitted to its organized points (estimate_intrinsics; refused when unorganized or a poor fit, naming
/// -intrinsics). A frame without a valid point is refused (require_valid_points), frames seen through
/// different cameras too: one viewpoint, one camera. Checks for a stop signal between frames and names
/// the input being read for run_tool's error line (InputScope).
std::vector<ToolFrame> read_tool_frames(const ToolOptions& options);
/// One frame by the same rules.
ToolFrame read_tool_frame(const ToolOptions& options, const FrameSource& source);

/// "camera fx=.. fy=.. cx=.. cy=.. WxH (source)", or the note that the preset needs none.
std::string describe_camera(const std::vector<ToolFrame>& frames);

/// True when -h or --help is among the arguments.
bool help_requested(int argc, const char* const* argv);

/// The shared main() of the command-line tools: prints usage on -h/--help (exit 0), otherwise installs
/// the stop-signal handlers and runs `run`. Any exception, std::bad_alloc and non-standard ones included,
/// becomes ONE line "error: ..." on stderr naming the input being worked on (InputScope) and exit code 1;
/// Interrupted becomes "interrupted by SIG..." and exit code 128 + the signal number.
int run_tool(int argc, char** argv, void (*print_usage)(const char* program), int (*run)(int argc, char** argv));

/// Names the input a tool is working on while it lives, so that run_tool's error line names it even for
/// a failure whose message does not (std::bad_alloc). Nested scopes name the innermost input.
class InputScope {
public:
  explicit InputScope(const std::string& input);
  InputScope(const InputScope&) = delete;
  InputScope& operator=(const InputScope&) = delete;
  ~InputScope();

private:
  std::string previous_;
  int uncaught_;
};

/// A tool stopped by SIGINT or SIGTERM. Not an occ_improve::Error: nothing is wrong with the input.
class Interrupted : public std::runtime_error {
public:
  explicit Interrupted(int signal);
  int signal() const { return signal_; }

private:
  int signal_;
};

/// The first SIGINT/SIGTERM received since run_tool installed its handlers, or 0. The handlers only
/// record the signal (so that the tool can stop between steps, remove its staging files and print what
/// it did); they reset themselves, so a second signal ends the process at once.
int stop_signal_received();

/// Throws Interrupted when a stop signal was received; tools call it between steps (frames, files).
void throw_if_interrupted();

/// Parses the common flags. Throws InvalidParameter naming the flag on any bad value or unknown flag,
/// IoError/FormatError for an unreadable -intrinsics_file.
ToolOptions parse_tool_options(int argc, const char* const* argv, const ToolSpec& spec = {});

/// Applies overrides to a preset and validates the result (InvalidParameter naming the flag).
SensorPreset apply_overrides(SensorPreset preset, const PresetOverrides& overrides);

/// The output folder named by -o (else `fallback`) for `tool`, refused when it already holds files the
/// tool did not write unless -overwrite is among the arguments (see OutputFolder). The tool lists "-o" in
/// its value flags and "-overwrite" in its switches.
OutputFolder open_output_folder(int argc, const char* const* argv, const std::string& tool,
                                const std::string& fallback);

/// Usage text of -o and -overwrite, for a tool's -h.
std::string usage_output_folder(const std::string& fallback);

/// Usage text of the common flags, for a tool's -h.
std::string usage_common();

}  // namespace occ_improve
