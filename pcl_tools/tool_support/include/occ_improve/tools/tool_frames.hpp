#pragma once
// The frames of a tool's inputs: read one at a time under the tools' rules (a camera is never assumed;
// one viewpoint, one camera), moved into the first frame's sensor frame by their poses.
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/tools/tool_options.hpp"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

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
  /// A PCD's VIEWPOINT the points were moved out of (into the sensor frame): what takes outputs made of the
  /// points (occ_segment's labels.pcd) back into the frame the file holds them in. Unset otherwise.
  std::optional<Eigen::Isometry3d> file_from_sensor{};
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
  /// The grid's sensor frame in the world: the loaded map's pose when the frames go into a loaded map
  /// (into_loaded_map; unset when it has none), else, once the first frame is read, its camera-to-world
  /// when poses are applied.
  std::optional<Eigen::Isometry3d> first_pose() const;
  /// The frames go into a map loaded from `map_path` (call before the first next()): with poses, every
  /// frame, the first too, is moved into the map's sensor frame by `map_pose`; a posed first frame and a
  /// map without a pose (saved from frames without poses, or before map format 5) are refused (InvalidInput
  /// naming both and -no_poses), since the map's view in the world is unknown. Frames without poses are
  /// taken in the map's view, as before.
  void into_loaded_map(const std::optional<Eigen::Isometry3d>& map_pose, const std::string& map_path);
  /// Whether the frames were moved into a loaded map's sensor frame by its pose.
  bool moved_into_loaded_map() const;
  /// Whether into_loaded_map was called.
  bool loads_map() const { return map_path_.has_value(); }
  const ToolOptions& options() const { return options_; }

private:
  std::optional<ToolFrame> read_next();

  const ToolOptions& options_;
  bool use_sample_;
  std::vector<FrameSource> sources_;
  std::size_t next_ = 0;
  double read_seconds_ = 0;
  std::optional<ToolFrame> first_;  ///< its name and camera (the cloud is not kept)
  std::optional<std::string> map_path_;          ///< into_loaded_map's
  std::optional<Eigen::Isometry3d> map_pose_;    ///< into_loaded_map's
};

/// The built-in generated Kinect-like frame (samples/scene) as a tool frame, with its camera.
ToolFrame sample_tool_frame();

/// Moves `frame` into the sensor frame of `first` by their poses (first^-1 * frame), when poses are used
/// and `first` has one; refuses a frame without a pose then, and a posed frame after an unposed first.
void move_into_first_frame(const ToolOptions& options, const ToolFrame& first, ToolFrame& frame);

/// The reference the frames of a -load run are moved into (move_into_first_frame): `first`'s header, its
/// pose the map's when poses apply and `first` has one (refused when the map has none, below); frames
/// without poses are taken in the map's view as they are.
ToolFrame loaded_map_reference(const ToolOptions& options, const ToolFrame& first,
                               const std::optional<Eigen::Isometry3d>& map_pose, const std::string& map_path);

/// InvalidInput for posed frames going into a map loaded from `map_path` that holds no pose (saved from
/// frames without poses, or before map format 5): where its view lies in the world is unknown, so the
/// frames cannot be placed in it by their poses; names the frame, its pose's source and -no_poses.
[[noreturn]] void refuse_posed_frames_into_unposed_map(const std::string& map_path, const std::string& frame,
                                                       const std::string& pose_source);

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
/// refused when a poor fit, naming -intrinsics). An unorganized cloud fits no camera: after a first frame
/// (`first`, whose camera the sequence's frames share) it takes that frame's camera, else it is refused
/// naming -intrinsics. A frame without a valid point is refused (require_valid_points). Checks for a stop
/// signal first and names the input for run_tool's error line (InputScope).
ToolFrame read_tool_frame(const ToolOptions& options, const FrameSource& source, const ToolFrame* first = nullptr);
/// The same without the stop check and the InputScope, for a reading thread (a grabber's).
ToolFrame load_tool_frame(const ToolOptions& options, const FrameSource& source, const ToolFrame* first = nullptr);

/// "camera fx=.. fy=.. cx=.. cy=.. WxH (source)", or the note that the preset needs none.
std::string describe_camera(const std::vector<ToolFrame>& frames);

/// -h text of the positional frame inputs every frame-reading tool takes (`fuses_frames`: several are fused,
/// else the tool takes one; `adds_to_loaded_map`: frames may follow a -load).
std::string frame_inputs_help(bool fuses_frames = true, bool adds_to_loaded_map = true);

}  // namespace occ_improve
