#pragma once
// Fusing a tool's frames into one grid: one frame in memory at a time, with the progress line, and a
// warning when frames fused without poses look like different scenes.
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "occ_improve/tools/progress.hpp"
#include "occ_improve/tools/tool_frames.hpp"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

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

/// The frames a check flags: how many, the first of them, and the largest share (of pixels or points)
/// that flagged one.
struct FlaggedFrames {
  std::size_t count = 0;
  std::string first;
  double worst_share = 0;
  void add(const std::string& name, double share);
};

/// Frames fused without poses, each compared with the first (frame_depth_agreement): warning() is one line
/// naming those that disagree on more than kDifferentSceneShare of at least 1000 co-valid pixels (different
/// scenes or viewpoints fused as one view make a map of neither), empty when none do. Inactive (with poses
/// applied, or a single frame) it checks nothing and keeps no copy of the first frame. `advice` ends the
/// warning (what the tool's user can do).
class UnposedSceneCheck {
public:
  UnposedSceneCheck(const SensorModelParams& model, bool active, std::string advice);
  void add(const std::string& name, const pcl::PointCloud<pcl::PointXYZ>& cloud);
  std::string warning() const;

private:
  SensorModelParams model_;
  bool active_;
  std::string advice_;
  std::optional<pcl::PointCloud<pcl::PointXYZ>> first_;
  std::string first_name_;
  FlaggedFrames flagged_;
};

/// Frames whose valid points fall largely outside the grid's field of view: the grid has the first frame's
/// viewpoint, so a frame placed by its pose far from it (another view of the scene) is mostly skipped, each
/// point counted. warning() is one line naming the first such frame (over kMostlyOutOfViewShare of its
/// valid points outside), empty when none is.
class OutOfViewCheck {
public:
  explicit OutOfViewCheck(std::string advice) : advice_(std::move(advice)) {}
  void add(const std::string& name, const InsertionReport& report);
  std::string warning() const;

private:
  std::string advice_;
  FlaggedFrames flagged_;
};
/// Above this share of a frame's valid points outside the view OutOfViewCheck warns.
inline constexpr double kMostlyOutOfViewShare = 0.25;

/// What fuse_tool_frames did, for a tool's summary.
struct FusedFrames {
  InsertionReport insertion;
  std::size_t frames = 0;
  std::optional<Eigen::Isometry3d> first_pose;  ///< the grid's frame in the world (poses applied), if any
  std::string poses;                     ///< "poses applied: ..." or "no poses", for the summary
  std::string camera;                    ///< describe_camera of the first frame
  std::optional<Image> colour;           ///< the first frame's colour
  std::vector<std::string> frame_lines;  ///< "read NAME: N points" per frame
  std::string first_name;                ///< the first frame's name (errors name the input)
};

/// Reads every frame (ToolFrameReader), calls `prepare` with the first one (its camera sets the grid), then
/// `insert` on each, one frame in memory at a time, with the progress line. Frames fused without poses
/// are compared with the first (frame_depth_agreement); when some disagree on more than kDifferentSceneShare of
/// their co-valid pixels, one warning line on stderr names them: different scenes fused as one view. Refuses a run whose points all
/// miss the grid. Cancelled: prints how many frames were inserted ("nothing written") and rethrows.
FusedFrames fuse_tool_frames(ToolFrameReader& frames, ProgressLine& progress,
                             const std::function<void(const std::optional<ToolFrame>& first)>& prepare,
                             const std::function<InsertionReport(const ToolFrame& frame)>& insert);

/// The points line of a tool's summary: read, used, skipped and beyond the depth range.
std::string describe_points(const InsertionReport& report);

/// Whether some valid point lies inside the depth range (a return the grid holds); true without valid points.
bool has_points_in_depth_range(const InsertionReport& report);
/// "no point of INPUTS lies in the depth range 0.50-8.00 m (N beyond it, M nearer than its start): CONSEQUENCE;
/// -depth_max sets its far end" (all nearer: "; its start is the preset's"): what a tool says (an error or
/// a warning, its own) when has_points_in_depth_range is false. `inputs` is quoted by the caller:
/// "'far.pcd'", describe_inputs(fused).
std::string nothing_in_depth_range(const std::string& inputs, const GeometryParams& geometry, const InsertionReport& report,
                                   const std::string& consequence);
/// "'NAME'" for one frame, "N frames from 'NAME'" for more: the inputs of a fused run, as messages name them.
std::string describe_inputs(const FusedFrames& fused);

}  // namespace occ_improve
