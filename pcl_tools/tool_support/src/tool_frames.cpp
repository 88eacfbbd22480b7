#include "occ_improve/tools/tool_frames.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/sensor/intrinsics_fit.hpp"
#include "occ_improve/timing.hpp"
#include "occ_improve/tools/input_scope.hpp"

#include <pcl/common/transforms.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>
#include <sstream>

namespace occ_improve {

namespace {

// An organized cloud is one camera image: a camera of another size would put its pixels on the wrong rays
// (or outside the grid), so it is refused as a depth image of the wrong size is.
void require_camera_fits(const pcl::PointCloud<pcl::PointXYZ>& cloud, const std::optional<PinholeIntrinsics>& camera,
                         const std::string& path, const std::string& camera_source) {
  if (!camera || cloud.height <= 1) return;
  if (static_cast<int>(cloud.width) == camera->width && static_cast<int>(cloud.height) == camera->height) return;
  std::ostringstream m;
  m << "cloud '" << path << "' is " << cloud.width << " x " << cloud.height << " but the camera (" << camera_source
    << ") is " << camera->width << " x " << camera->height << ": give the cloud's own intrinsics (FX,FY,CX,CY,"
    << cloud.width << "," << cloud.height << ")";
  throw InvalidInput(m.str());
}

// A guessed encoding that puts most of an image beyond the grid is likely the wrong one (a TUM-scaled
// image of values that are not multiples of 5 reads as millimetres: 5 x too far). Said, not refused: a
// scene may lie far.
void warn_if_mostly_beyond_range(const LoadedFrame& loaded, const std::string& path, double depth_max_m) {
  constexpr std::size_t kEvery = 16;  // a median for a warning: every 16th point is plenty, and cheap per frame
  std::vector<float> z;
  for (std::size_t i = 0; i < loaded.cloud.size(); i += kEvery)
    if (const float d = loaded.cloud[i].z; std::isfinite(d) && d > 0) z.push_back(d);
  if (z.empty()) return;
  std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
  if (!(z[z.size() / 2] > depth_max_m)) return;
  std::fprintf(stderr,
               "warning: '%s' read as %s puts its median depth at %.2f m, beyond the grid's %.2f m: if its values "
               "are in another unit, give -depth_encoding\n",
               path.c_str(), depth_encoding_name(*loaded.encoding), z[z.size() / 2], depth_max_m);
}

// The unit check's median from at most ~kUnitSamples points, evenly spread (a frame's 307 200 ranges and
// their selection took ~3 ms of the reading thread, beside the insertion, for a median 4096 points give
// as well); a smaller cloud is judged whole.
constexpr std::size_t kUnitSamples = 4096;
PointSpan spread_sample(PointSpan points) {
  const std::size_t every = std::max<std::size_t>(1, points.count / kUnitSamples);
  return {points.xyz, (points.count + every - 1) / every, points.stride_floats * every};
}

}  // namespace

ToolFrame load_tool_frame(const ToolOptions& options, const FrameSource& source, const ToolFrame* first) {
  ToolFrame frame;
  std::optional<PinholeIntrinsics> camera = options.intrinsics ? options.intrinsics : source.intrinsics;
  frame.camera_source = options.intrinsics ? options.intrinsics_flag : source.intrinsics ? "the dataset's camera-intrinsics.txt" : "";
  if (!camera && is_depth_image_path(source.path))
    throw InvalidParameter("'" + source.path + "' is a depth image and no intrinsics were found for it: give "
                           "-intrinsics FX,FY,CX,CY[,W,H] or -intrinsics_file PATH");
  LoadedFrame loaded = [&] {
    try {
      return load_frame(source.path, camera, options.depth_encoding);
    } catch (const InvalidInput& e) {  // a size mismatch: say whose the camera is
      if (frame.camera_source.empty()) throw;
      throw InvalidInput(std::string(e.what()) + " (intrinsics from " + frame.camera_source + ")");
    }
  }();
  require_valid_points(span_of(loaded.cloud), source.path);
  const bool encoding_guessed = loaded.encoding && !options.depth_encoding;
  if (encoding_guessed)  // its own warning
    warn_if_mostly_beyond_range(loaded, source.path, options.preset.geometry.depth_max_m);
  require_camera_fits(loaded.cloud, camera, source.path, frame.camera_source);
  if (loaded.viewpoint && options.use_poses) {
    // PCL's VIEWPOINT: the points are in the cloud's frame, the sensor at the viewpoint; the grid is the
    // sensor's, so the points go into the sensor frame. -no_poses ignores it, as every other pose: the
    // points are then taken as written in the sensor frame (a cloud whose VIEWPOINT is wrong stays usable).
    pcl::transformPointCloud(loaded.cloud, loaded.cloud, loaded.viewpoint->inverse().matrix().cast<float>());
    frame.pose = loaded.viewpoint;
    frame.pose_source = "VIEWPOINT of " + source.path;
    frame.file_from_sensor = loaded.viewpoint;
  } else if (source.pose) {
    frame.pose = source.pose;
    frame.pose_source = source.pose_source;
  }
  // A cloud saved in millimetres was mapped "beyond the depth range" without a word (and from ~340 m on,
  // the returns' sigma reached back into the grid as a phantom wall at its end). Judged in the sensor frame:
  // a VIEWPOINT cloud's points lie far from its own origin.
  if (!encoding_guessed)
    require_points_in_metres(spread_sample(span_of(loaded.cloud)), source.path, options.preset.geometry,
                             loaded.encoding ? "image" : "cloud",
                             loaded.encoding ? ": give the right -depth_encoding"
                                             : ": the tools read clouds in metres (a scene that far needs a larger -depth_max)");
  frame.name = source.path;
  if (loaded.encoding) frame.name += std::string(" (depth encoding ") + depth_encoding_name(*loaded.encoding) + ")";
  if (!camera && options.preset_needs_camera() && loaded.cloud.height <= 1) {
    if (!first || !first->camera)
      throw InvalidInput("'" + source.path + "' is not organized, so its camera cannot be fitted; preset " +
                         options.preset_name + " needs one: give -intrinsics (or -preset kinect_v1_paper)");
    camera = first->camera;  // its points are projected through it: an unorganized cloud fits any camera
    frame.camera_source = "that of " + first->name;
  }
  if (!camera && options.preset_needs_camera()) {
    IntrinsicsFit fit;
    try {
      fit = estimate_intrinsics_fit(loaded.cloud, kMaxIntrinsicsFitResidualPx);
    } catch (const InvalidInput& e) {  // the fit knows the points, not the file
      throw InvalidInput("'" + source.path + "': " + e.what() + "; give -intrinsics if it is a camera image");
    }
    camera = fit.intrinsics;
    std::ostringstream why;
    why << "fitted to " << source.path << ", RMS residual " << fit.rms_residual_px << " px over " << fit.points_used
        << " points";
    frame.camera_source = why.str();
  }
  frame.camera = camera;
  frame.cloud = std::move(loaded.cloud);
  frame.colour = std::move(loaded.colour);
  return frame;
}

ToolFrame read_tool_frame(const ToolOptions& options, const FrameSource& source, const ToolFrame* first) {
  throw_if_stop_requested();
  const InputScope scope(source.path);
  return load_tool_frame(options, source, first);
}

ToolFrame sample_tool_frame() {
  const sample::SampleFrame scene = sample::generate_scene();
  return {"built-in sample", organized_cloud(scene.points(), scene.intrinsics.width, scene.intrinsics.height),
          scene.intrinsics, "the built-in sample's camera", std::nullopt};
}

ToolFrameReader::ToolFrameReader(const ToolOptions& options, bool use_sample)
    : options_(options), use_sample_(use_sample) {
  if (use_sample && !options.inputs.empty()) throw InvalidParameter("give either input files or -sample, not both");
  if (use_sample && options.intrinsics)  // the sample is rendered through its own camera: the flag would be ignored
    throw InvalidParameter(options.intrinsics_flag + " with -sample: the built-in sample has its own camera");
  for (const std::string& input : options.inputs) {
    const InputScope scope(input);
    for (FrameSource& source : expand_input(input)) sources_.push_back(std::move(source));
  }
}

std::optional<ToolFrame> ToolFrameReader::next() {
  const double start = now_seconds();
  std::optional<ToolFrame> frame = read_next();
  read_seconds_ += now_seconds() - start;
  return frame;
}

std::optional<ToolFrame> ToolFrameReader::read_next() {
  if (next_ == count()) return std::nullopt;
  if (use_sample_) {
    ++next_;
    return sample_tool_frame();
  }
  ToolFrame frame = read_tool_frame(options_, sources_[next_++], first_ ? &*first_ : nullptr);
  if (first_) {
    require_same_camera(*first_, frame);
    move_into_first_frame(options_, *first_, frame);
  } else if (map_path_) {  // the first frame too goes into the map's view, and the later ones where it went
    first_ = loaded_map_reference(options_, frame, map_pose_, *map_path_);
    move_into_first_frame(options_, *first_, frame);
  } else {
    first_ = frame_header(frame);
  }
  return frame;
}

bool ToolFrameReader::moved_into_loaded_map() const {
  return map_path_ && first_ && first_->pose && options_.use_poses;
}

void ToolFrameReader::into_loaded_map(const std::optional<Eigen::Isometry3d>& map_pose, const std::string& map_path) {
  map_path_ = map_path;
  map_pose_ = map_pose;
}

// Moved into the first frame's view instead, the new frames landed where the map's own view was assumed to
// be: a 7-Scenes chain was off by more than 20 mm on 68 % of its pixels, without a word.
ToolFrame loaded_map_reference(const ToolOptions& options, const ToolFrame& first,
                               const std::optional<Eigen::Isometry3d>& map_pose, const std::string& map_path) {
  ToolFrame reference = frame_header(first);
  if (!options.use_poses || !first.pose) return reference;  // frames without poses are taken in the map's view
  if (!map_pose) refuse_posed_frames_into_unposed_map(map_path, first.name, first.pose_source);
  reference.pose = map_pose;
  reference.pose_source = "the pose saved with " + map_path;
  return reference;
}

void refuse_posed_frames_into_unposed_map(const std::string& map_path, const std::string& frame,
                                          const std::string& pose_source) {
  throw InvalidInput("-load " + map_path + " holds no pose (saved from frames without poses, or by a build before map "
                     "format 5), so '" + frame + "' cannot be placed in its view by its pose (" + pose_source +
                     "): give -no_poses if the frames are in the map's sensor frame already");
}

std::optional<Eigen::Isometry3d> ToolFrameReader::first_pose() const {
  if (map_path_) return map_pose_;  // the frames are in the map's view: moved there by their poses, or taken so
  if (!first_ || !options_.use_poses) return std::nullopt;
  return first_->pose;
}

ToolFrame frame_header(const ToolFrame& frame) {
  return ToolFrame{frame.name, {}, frame.camera, frame.camera_source, std::nullopt, frame.pose, frame.pose_source,
                   frame.file_from_sensor};
}

void move_into_first_frame(const ToolOptions& options, const ToolFrame& first, ToolFrame& frame) {
  if (!options.use_poses || (!first.pose && !frame.pose)) return;
  if (!first.pose || !frame.pose) {
    const std::string& unposed = frame.pose ? first.name : frame.name;
    const bool pcd = unposed.size() > 4 && unposed.compare(unposed.size() - 4, 4, ".pcd") == 0;
    throw InvalidInput("'" + unposed + "' has no pose while '" + (frame.pose ? frame.name : first.name) +
                       "' has one (" + (frame.pose ? frame.pose_source : first.pose_source) + ")" +
                       (pcd ? " (a PCD's VIEWPOINT at the identity is read as none: old PCL grabbers wrote it "
                              "for every cloud)" : "") +
                       ": give every frame a pose, or -no_poses to take every frame from the first's viewpoint");
  }
  const Eigen::Isometry3d into_first = first.pose->inverse() * *frame.pose;
  pcl::transformPointCloud(frame.cloud, frame.cloud, into_first.matrix().cast<float>());
}

void require_same_camera(const ToolFrame& first, const ToolFrame& frame) {
  if (first.camera && frame.camera && !same_camera(*first.camera, *frame.camera))
    throw InvalidInput("'" + frame.name + "' was taken with another camera than '" + first.name + "' (" +
                       describe_camera({frame}) + " against " + describe_camera({first}) +
                       "): the frames of one map share one viewpoint and camera; give -intrinsics to force one");
}

std::vector<ToolFrame> read_tool_frames(const ToolOptions& options) {
  ToolFrameReader reader(options);
  std::vector<ToolFrame> frames;
  while (std::optional<ToolFrame> frame = reader.next()) frames.push_back(std::move(*frame));
  return frames;
}

std::string describe_camera(const std::vector<ToolFrame>& frames) {
  for (const ToolFrame& f : frames) {
    if (!f.camera) continue;
    return "camera " + camera_text(*f.camera) + " (" + f.camera_source + ")";
  }
  return "no camera (the preset's grid does not depend on one)";
}

std::string frame_inputs_help(bool fuses_frames, bool adds_to_loaded_map) {
  const std::string kinds = R"(  FILE.pcd / FILE.ply       a cloud with x y z in metres, optical frame (z forward, y down); with a
                            camera preset its intrinsics are fitted to its organized points (an
                            unorganized cloud after the first frame takes the first frame's camera)
  FILE.png/.pgm/.tif/.tiff  16-bit depth image, back-projected through -intrinsics or its dataset's file
  FOLDER                    a dataset folder: 7-Scenes/3DMatch/SUN3D (*.depth.png, camera-intrinsics.txt,
                            *.pose.txt) or PCL's image-grabber layout (*_depth.tiff)
)";
  if (!fuses_frames) return kinds + "  One frame (a FOLDER with -input_dir: each of its frames by itself).\n";
  const std::string fused = "  Frames are fused in order; with poses every frame is moved into the first frame's sensor frame";
  if (!adds_to_loaded_map) return kinds + fused + ".\n";
  return kinds + fused + "\n  (with -load, into the map's, by the pose saved with it).\n";
}

}  // namespace occ_improve
