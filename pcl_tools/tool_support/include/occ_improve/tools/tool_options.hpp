#pragma once
// What the occ_improve tools share beyond their flag table (flags.hpp): the sensor preset and grid built
// from the common flags, the frames read from the inputs, the output folder, the progress line, and the
// main() that turns every failure into one error line.
#include "occ_improve/cancel.hpp"
#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/grid/mask.hpp"
#include "occ_improve/tools/flags.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/segmentation/segmentation.hpp"

#include <Eigen/Geometry>

#include <functional>
#include <optional>
#include <stdexcept>
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
  SensorPreset preset;  ///< the named preset (built from `intrinsics` when it is camera-based) + overrides
  GridOptions grid;
  std::optional<PinholeIntrinsics> intrinsics;  ///< from -intrinsics or -intrinsics_file
  std::string intrinsics_flag;                  ///< "-intrinsics" or "-intrinsics_file PATH", for messages
  std::optional<DepthEncoding> depth_encoding;  ///< unset: chosen per file (see frame_io.hpp)
  int top_k = 10;
  bool use_poses = true;            ///< false with -no_poses: every frame taken from the first's viewpoint
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
  /// Camera-to-world of the frame: its dataset's pose file, or a PCD's VIEWPOINT (whose points are then
  /// moved into the sensor frame as they are read, as PCL defines the viewpoint). Unset without either.
  std::optional<Eigen::Isometry3d> pose{};
  std::string pose_source{};  ///< "frame-000150.pose.txt", "VIEWPOINT of FILE.pcd"
};

/// The frames of a tool's inputs (or the built-in sample, for -sample), read one at a time so that a long
/// sequence is never all in memory. Every input is expanded at construction (expand_input: files and
/// dataset folders, in order; IoError for a missing one). Each frame follows read_tool_frame's rules, and
/// a frame seen through another camera than the first is refused: one viewpoint, one camera. With poses
/// (and not -no_poses), every frame is moved into the first frame's sensor frame (the grid has one
/// viewpoint, the first's); a frame without a pose among posed frames is refused, naming -no_poses.
class ToolFrameReader {
public:
  explicit ToolFrameReader(const ToolOptions& options, bool use_sample = false);
  /// How many frames there are.
  std::size_t count() const { return use_sample_ ? 1 : sources_.size(); }
  /// The next frame, or nullopt after the last.
  std::optional<ToolFrame> next();
  /// Time spent reading so far [s].
  double read_seconds() const { return read_seconds_; }
  /// The first frame's camera-to-world when poses are applied (the grid's frame in the world), once read.
  std::optional<Eigen::Isometry3d> first_pose() const;
  const ToolOptions& options() const { return options_; }

private:
  std::optional<ToolFrame> read_next();

  const ToolOptions& options_;
  bool use_sample_;
  std::vector<FrameSource> sources_;
  std::size_t next_ = 0;
  double read_seconds_ = 0;
  std::optional<ToolFrame> first_;  ///< its name and camera (the cloud is not kept)
};

/// The built-in generated Kinect-like frame (samples/scene) as a tool frame, with its camera.
ToolFrame sample_tool_frame();

/// Moves `frame` into the sensor frame of `first` by their poses (first^-1 * frame), when poses are used
/// and `first` has one; refuses a frame without a pose then, and a posed frame after an unposed first.
void move_into_first_frame(const ToolOptions& options, const ToolFrame& first, ToolFrame& frame);

/// The frame's name, camera and pose without its points and colour: what the checks against a first frame
/// (require_same_camera, move_into_first_frame) keep of it.
ToolFrame frame_header(const ToolFrame& frame);

/// Refuses (InvalidInput naming both) a frame seen through another camera than the first frame's: the
/// frames of one map share one viewpoint and camera.
void require_same_camera(const ToolFrame& first, const ToolFrame& frame);

/// Every frame of the inputs at once (ToolFrameReader), for tools that need them together.
std::vector<ToolFrame> read_tool_frames(const ToolOptions& options);
/// One frame: a depth image is back-projected through -intrinsics/-intrinsics_file or its dataset's
/// intrinsics file and refused without either (intrinsics are never assumed); a cloud's camera, when the
/// preset needs one and none was given, is fitted to its organized points (estimate_intrinsics_fit;
/// refused when unorganized or a poor fit, naming -intrinsics). A frame without a valid point is refused
/// (require_valid_points). Checks for a stop signal first and names the input for run_tool's error line
/// (InputScope).
ToolFrame read_tool_frame(const ToolOptions& options, const FrameSource& source);
/// The same without the stop check and the InputScope, for a reading thread (a grabber's).
ToolFrame load_tool_frame(const ToolOptions& options, const FrameSource& source);

/// "camera fx=.. fy=.. cx=.. cy=.. WxH (source)", or the note that the preset needs none.
std::string describe_camera(const std::vector<ToolFrame>& frames);

/// The shared main() of the command-line tools: prints usage_text on -h/-help/--help (exit 0) and on no
/// argument at all (exit 1), otherwise parses the command line against `flags`, installs the stop-signal
/// handlers and runs `run`. Any exception, a refused flag, std::bad_alloc and non-standard ones included,
/// becomes ONE line "error: ..." on stderr naming the input being worked on (InputScope) and exit code 1;
/// Cancelled becomes "interrupted by SIG..." and exit code 128 + the signal number.
int run_tool(int argc, char** argv, const ToolFlags& flags, int (*run)(const CommandLine& command_line));

/// The one error line of a failure ("error: MESSAGE"), naming the input whose InputScope the exception
/// left when MESSAGE does not; that input is then forgotten (a batch goes on to the next file).
std::string failure_line(const std::string& message);

/// -h text of the positional frame inputs every frame-reading tool takes.
std::string frame_inputs_help();

/// A progress line on stderr for work that runs over about a second ("frame 12/50, 3.1M points,
/// 4.2 frames/s, 9 s left"). Shown only when stderr is a terminal and -q was not given (silent in logs and
/// pipes); redrawn at most ten times a second; erased by finish() or the destructor, so the summary that
/// follows starts on a clean line.
class ProgressLine {
public:
  /// `unit` names what is counted: "frame", "shot", "cloud".
  ProgressLine(const CommandLine& command_line, std::string unit);
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;
  ~ProgressLine();

  bool shown() const { return shown_; }
  /// `done` of `total` units (total 0: unknown) and the points handled so far; rate and time left follow.
  void update(std::size_t done, std::size_t total, std::size_t points = 0);
  /// A line of the tool's own making (a live stream's counters).
  void show(const std::string& text);
  void finish();

private:
  bool shown_;
  bool drawn_ = false;
  std::string unit_;
  double start_seconds_, last_draw_seconds_ = -1.0;
};

/// How two organized frames of one view agree in depth: of the pixels valid in both (`co_valid`), those
/// whose z differ by more than k sigma (`disagreeing`), sigma the preset's depth noise at the first frame's
/// z (SensorModelParams: max(floor, sigma_depth_m + sigma_depth_per_m2 z^2)). Frames of one scene from one
/// viewpoint disagree only at depth edges and in noise (a few per cent of the pixels at k = 3); frames of
/// different scenes or viewpoints on most pixels.
struct FrameDepthAgreement {
  std::size_t co_valid = 0, disagreeing = 0;
  double disagreeing_share() const { return co_valid ? static_cast<double>(disagreeing) / co_valid : 0.0; }
};
/// The fusion's test (fuse_tool_frames): k = 3. Both frames must be organized and of one size (else all 0).
FrameDepthAgreement frame_depth_agreement(const pcl::PointCloud<pcl::PointXYZ>& first, const pcl::PointCloud<pcl::PointXYZ>& frame,
                               const SensorModelParams& model, double k_sigma = 3.0);
/// Above this share of disagreeing co-valid pixels (over at least 1000 of them) fuse_tool_frames warns.
inline constexpr double kDifferentSceneShare = 0.5;

/// What fuse_tool_frames did, for a tool's summary.
struct FusedFrames {
  InsertionReport insertion;
  std::size_t frames = 0;
  std::optional<Eigen::Isometry3d> first_pose;  ///< the grid's frame in the world (poses applied), if any
  std::string poses;                     ///< "poses applied: ..." or "no poses", for the summary
  std::string camera;                    ///< describe_camera of the first frame
  std::optional<Image> colour;           ///< the first frame's colour
  std::vector<std::string> frame_lines;  ///< "read NAME: N points" per frame
};

/// Reads every frame (ToolFrameReader), calls `prepare` with the first one (its camera sets the grid), then
/// `insert` on each, one frame in memory at a time, with the progress line. Frames fused without poses
/// are compared with the first (frame_depth_agreement); when some disagree on more than kDifferentSceneShare of
/// their co-valid pixels, one warning line on stderr names them: different scenes fused as one view. Refuses a run whose points all
/// miss the grid. Cancelled: prints how many frames were inserted ("nothing written") and rethrows.
FusedFrames fuse_tool_frames(ToolFrameReader& frames, ProgressLine& progress,
                             const std::function<void(const std::optional<ToolFrame>& first)>& prepare,
                             const std::function<InsertionReport(const ToolFrame& frame)>& insert);

/// The -mask of a frame-reading tool (nullopt without it): the PNG (read_mask_png), or for "finite" the
/// valid pixels of `first`, which must be an organized frame of its camera's size. Refusals are one line
/// naming -mask and the file.
std::optional<PixelMask> read_tool_mask(const CommandLine& command_line, const ToolFrame* first);
/// read_tool_mask set on the mapper (Mapper::set_mask); refusals (another size than the camera, a grid
/// without a camera) name -mask and the file. Returns the summary line ("mask FILE: N of M pixels valid"),
/// "" without -mask.
std::string apply_tool_mask(const CommandLine& command_line, Mapper& mapper, const ToolFrame* first);
/// mask_columns(geometry, mask) with refusals naming -mask and the file: for a tool that checks the mask
/// before its mapper exists (occ_segment) or fills a grid itself (occ_to_octomap).
std::vector<std::uint8_t> tool_mask_columns(const CommandLine& command_line, const GridGeometry& geometry,
                                            const PixelMask& mask);

/// The points line of a tool's summary: read, used, skipped and beyond the depth range.
std::string describe_points(const InsertionReport& report);


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

// Stopping on SIGINT/SIGTERM: run_tool's handlers call the library's request_stop(signal) (cancel.hpp),
// so the library's long loops and the tools' own (frames, files, shots; throw_if_stop_requested) stop
// within milliseconds with Cancelled, which run_tool reports as "interrupted by SIG..." and exit code
// 128 + the signal. stop_requested() is the signal received, or 0. The handlers reset themselves, so a
// second signal ends the process at once.

/// For a tool that still writes what it has after a stop (occ_improve_live): the signal received, or 0,
/// and the request withdrawn so that the writing is not cancelled too; the tool then ends with
/// throw Cancelled(signal). The frame or shot in flight when the signal came is left partly inserted.
int take_stop_request();

/// The sensor preset, grid options, camera and inputs from a parsed command line (the flags of
/// sensor_flag_names() and camera_flag_names() the tool declares; the others keep their defaults).
/// Throws InvalidParameter naming the flag when flags conflict or the preset they build is invalid,
/// IoError/FormatError for an unreadable -intrinsics_file.
ToolOptions parse_tool_options(const CommandLine& command_line);

/// load_map under the tool's cap; a ResourceLimit says how to raise it (-memory_cap).
LoadedMap load_tool_map(const std::string& path, const ToolOptions& options);

/// " raise the cap with -memory_cap GIB[, or lower -depth_bins]": the end of a tool's ResourceLimit message.
std::string memory_cap_hint(bool with_depth_bins);

/// Applies overrides to a preset and validates the result (InvalidParameter naming the flag).
SensorPreset apply_overrides(SensorPreset preset, const PresetOverrides& overrides);

/// -contour, -min_segment, -plane_distance and -no_plane, those the tool declares and the user gave (or, for
/// -min_segment, its table default), over a preset's segmentation defaults (segmentation_defaults).
void apply_segmentation_flags(const CommandLine& command_line, SegmentationParams& params);

/// Creates the missing folders above `path` (like mkdir -p of its parent); an output file or folder whose
/// parent cannot be created then fails to write with the writer's own message naming it.
void create_parent_folders(const std::string& path);

/// The output folder named by -o (or the tool's default for it; InvalidParameter when it has none), its
/// missing parents created; refused when it already holds files the tool did not write unless -overwrite
/// was given (see OutputFolder).
OutputFolder open_output_folder(const CommandLine& command_line);

/// The plan flags -budget, -shape, -refine, -window, -negative_share, -stop_gain as a PlanRequest (one
/// reading for occ_plan and occ_improve_live -simulate). InvalidParameter naming a malformed -window.
PlanRequest plan_request_from_flags(const CommandLine& command_line);

}  // namespace occ_improve
