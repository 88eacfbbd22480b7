#include "occ_improve/tools/frame_fusion.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/tools/input_scope.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace occ_improve {

FrameDepthAgreement frame_depth_agreement(const pcl::PointCloud<pcl::PointXYZ>& first, const pcl::PointCloud<pcl::PointXYZ>& frame,
                               const SensorModelParams& model, double k_sigma) {
  FrameDepthAgreement a;
  if (first.height <= 1 || frame.width != first.width || frame.height != first.height) return a;
  for (std::size_t i = 0; i < first.size(); ++i) {
    const pcl::PointXYZ &p = first[i], &q = frame[i];
    if (!is_valid_point(p.x, p.y, p.z) || !is_valid_point(q.x, q.y, q.z)) continue;
    ++a.co_valid;
    const double z = p.z;
    const double sigma = std::max(model.sigma_depth_floor_m, model.sigma_depth_m + model.sigma_depth_per_m2 * z * z);
    a.disagreeing += std::abs(static_cast<double>(q.z) - z) > k_sigma * sigma;
  }
  return a;
}

namespace {
// Fewer pixels valid in both frames say nothing about whether they show one scene.
constexpr std::size_t kMinCoValid = 1000;
}  // namespace

void FlaggedFrames::add(const std::string& name, double share) {
  if (count++ == 0) first = name;
  worst_share = std::max(worst_share, share);
}

UnposedSceneCheck::UnposedSceneCheck(const SensorModelParams& model, bool active, std::string advice)
    : model_(model), active_(active), advice_(std::move(advice)) {}

void UnposedSceneCheck::add(const std::string& name, const pcl::PointCloud<pcl::PointXYZ>& cloud) {
  if (!active_ || cloud.height <= 1) return;
  if (!first_) {
    // A first frame without returns (all NaN: a frame the insertion refuses) would leave nothing to compare.
    const auto valid = std::count_if(cloud.begin(), cloud.end(), [](const pcl::PointXYZ& p) { return is_valid_point(p.x, p.y, p.z); });
    if (valid < static_cast<std::ptrdiff_t>(kMinCoValid)) return;
    first_ = cloud;
    first_name_ = name;
    return;
  }
  const FrameDepthAgreement a = frame_depth_agreement(*first_, cloud, model_);
  if (a.co_valid < kMinCoValid || a.disagreeing_share() <= kDifferentSceneShare) return;
  flagged_.add(name, a.disagreeing_share());
}

std::string UnposedSceneCheck::warning() const {
  if (flagged_.count == 0) return "";
  char line[1024];
  std::snprintf(line, sizeof line,
                "warning: %zu frame(s) fused without poses disagree in depth with the first frame '%s' on up to %.0f%% "
                "of their common valid pixels (beyond 3 sigma; the first such frame: '%s'): different scenes or "
                "viewpoints? %s",
                flagged_.count, first_name_.c_str(), 100.0 * flagged_.worst_share, flagged_.first.c_str(), advice_.c_str());
  return line;
}

void OutOfViewCheck::add(const std::string& name, const InsertionReport& report) {
  const std::size_t valid = report.points_received - report.skipped_invalid;
  if (valid == 0) return;
  const double share = static_cast<double>(report.skipped_outside_fov) / static_cast<double>(valid);
  if (share > kMostlyOutOfViewShare) flagged_.add(name, share);
}

std::string OutOfViewCheck::warning() const {
  if (flagged_.count == 0) return "";
  char line[1024];
  std::snprintf(line, sizeof line,
                "warning: %zu frame(s) have up to %.0f%% of their valid points outside the grid's field of view (the "
                "first frame's, or a -load map's; the first such frame: '%s'); they were skipped and counted: other "
                "viewpoints? %s",
                flagged_.count, 100.0 * flagged_.worst_share, flagged_.first.c_str(), advice_.c_str());
  return line;
}

namespace {

// Why no point of the frames was inserted, naming them: the mask, or the field of view.
std::string nothing_inserted(const FusedFrames& fused) {
  const InsertionReport& in = fused.insertion;
  const std::string inputs = describe_inputs(fused);
  const std::size_t valid = in.points_received - in.skipped_invalid;
  if (in.skipped_masked > 0 && in.skipped_outside_fov == 0)
    return "-mask leaves out all " + std::to_string(valid) + " valid points of " + inputs;
  return "no point of " + inputs + " lies inside the grid's field of view (" + std::to_string(in.skipped_outside_fov) +
         " of its " + std::to_string(valid) + " valid points behind the camera or beside the image" +
         (in.skipped_masked > 0 ? ", the other " + std::to_string(in.skipped_masked) + " outside -mask)" : ")");
}

}  // namespace

FusedFrames fuse_tool_frames(ToolFrameReader& frames, ProgressLine& progress,
                             const std::function<void(const std::optional<ToolFrame>& first)>& prepare,
                             const std::function<InsertionReport(const ToolFrame& frame)>& insert) {
  FusedFrames fused;
  std::optional<ToolFrame> frame = frames.next();
  if (frame) {
    fused.camera = describe_camera({*frame});
    fused.colour = frame->colour;
  }
  try {  // the first frame's camera sizes the grid: a grid beyond the cap is refused naming the frame
    prepare(frame);  // (the preset's cap check, preset_for_camera, says how to raise the cap)
  } catch (const ResourceLimit& e) {
    throw ResourceLimit("'" + (frame ? frame->name : std::string("sample")) + "': " + e.what());
  }
  // Poses move every frame into the first one's view; without them, frames of other scenes go unnoticed.
  const bool poses_applied = frames.options().use_poses && frame && frame->pose;
  UnposedSceneCheck scenes(frames.options().preset.model, !poses_applied && frames.count() > 1,
                           "Give their poses, or map them one by one (-input_dir DIR -output_dir OUTDIR)");
  OutOfViewCheck out_of_view("Map each view by itself (-save) and merge the maps: occ_to_octomap -load MAP -pose P "
                             "per map");
  try {
    for (; frame; frame = frames.next()) {
      throw_if_stop_requested();
      const InputScope scope(frame->name);
      scenes.add(frame->name, frame->cloud);
      const InsertionReport inserted = insert(*frame);
      out_of_view.add(frame->name, inserted);
      fused.insertion += inserted;
      fused.frame_lines.push_back("read " + frame->name + ": " + std::to_string(frame->cloud.size()) + " points");
      if (fused.frames == 0) fused.first_name = frame->name;
      progress.update(++fused.frames, frames.count(), fused.insertion.points_received);
    }
  } catch (const Cancelled&) {
    progress.finish();
    // The frame being inserted when the stop came is not counted: its report never came back.
    std::printf("inserted %zu of %zu frame(s) before the interruption; nothing written\nof those frames' %s\n",
                fused.frames, frames.count(), describe_points(fused.insertion).c_str());
    throw;
  }
  progress.finish();
  for (const std::string& warning : {scenes.warning(), out_of_view.warning()})
    if (!warning.empty()) std::fprintf(stderr, "%s\n", warning.c_str());
  fused.first_pose = frames.first_pose();
  fused.poses = frames.moved_into_loaded_map() ? "poses applied: every frame moved into the loaded map's sensor frame"
                : fused.first_pose && !frames.loads_map() ? "poses applied: every frame moved into the first frame's sensor frame"
                                                          : "no poses";
  if (fused.frames > 0 && fused.insertion.points_inserted == 0) throw InvalidInput(nothing_inserted(fused));
  return fused;
}

std::string describe_points(const InsertionReport& in) {
  char line[400];
  std::snprintf(line, sizeof line,
                "points: %zu read, %zu used, %zu skipped invalid, %zu skipped outside the field of view; "
                "%zu used beyond the depth range (free space only), %zu used nearer than its start (in front of "
                "the grid)",
                in.points_received, in.points_inserted, in.skipped_invalid, in.skipped_outside_fov,
                in.beyond_depth_range, in.nearer_than_depth_range);
  if (in.skipped_masked > 0) return line + std::string("; ") + std::to_string(in.skipped_masked) + " skipped outside -mask";
  return line;
}

bool has_points_in_depth_range(const InsertionReport& in) {
  return in.points_inserted == 0 || in.points_inserted > in.beyond_depth_range + in.nearer_than_depth_range;
}

std::string describe_inputs(const FusedFrames& fused) {
  return fused.frames == 1 ? "'" + fused.first_name + "'"
                           : std::to_string(fused.frames) + " frames from '" + fused.first_name + "'";
}

std::string nothing_in_depth_range(const std::string& inputs, const GeometryParams& g, const InsertionReport& in,
                                   const std::string& consequence) {
  char range[64];
  std::snprintf(range, sizeof range, "%.2f-%.2f m", g.depth_min_m, g.depth_max_m);
  // Only the far end is a flag: the start is the sensor's own (a Kinect returns nothing nearer).
  const std::string hint = in.beyond_depth_range > 0 ? "; -depth_max sets its far end" : "; its start is the preset's";
  return "no point of " + inputs + " lies in the depth range " + range + " (" + std::to_string(in.beyond_depth_range) +
         " beyond it, " + std::to_string(in.nearer_than_depth_range) + " nearer than its start): " + consequence + hint;
}

}  // namespace occ_improve
