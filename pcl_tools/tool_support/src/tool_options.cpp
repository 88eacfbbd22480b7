#include "occ_improve/tools/tool_options.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/tools/batch.hpp"
#include "occ_improve/tools/output_files.hpp"

#include <pcl/common/transforms.h>
#include <pcl/console/print.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <new>
#include <sstream>

namespace occ_improve {

namespace {

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void bad_flag(const std::string& flag, const std::string& value, const std::string& requirement) {
  throw InvalidParameter(flag + " " + value + " is invalid: must be " + requirement);
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

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
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

SensorPreset apply_overrides(SensorPreset p, const PresetOverrides& o) {
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
    p.model.validate_for(p.geometry);
  } catch (const InvalidParameter& e) {
    throw InvalidParameter(std::string(e.what()) + " (after -preset " + p.name + describe_overrides(o) + ")");
  }
  return p;
}

SensorPreset ToolOptions::preset_for_camera(const std::optional<PinholeIntrinsics>& camera) const {
  if (intrinsics || !camera || !preset.camera) return preset;
  return apply_overrides(preset_by_name(preset_name, *camera), overrides);
}

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

}  // namespace

ToolFrame load_tool_frame(const ToolOptions& options, const FrameSource& source) {
  ToolFrame frame;
  std::optional<PinholeIntrinsics> camera = options.intrinsics ? options.intrinsics : source.intrinsics;
  frame.camera_source = options.intrinsics ? options.intrinsics_flag : source.intrinsics ? "the dataset's camera-intrinsics.txt" : "";
  if (!camera && is_depth_image_path(source.path))
    throw InvalidParameter("'" + source.path + "' is a depth image and no intrinsics were found for it: give "
                           "-intrinsics FX,FY,CX,CY[,W,H] or -intrinsics_file PATH");
  LoadedFrame loaded = load_frame(source.path, camera, options.depth_encoding);
  require_valid_points(span_of(loaded.cloud), source.path);
  require_camera_fits(loaded.cloud, camera, source.path, frame.camera_source);
  if (loaded.viewpoint) {
    // PCL's VIEWPOINT: the points are in the cloud's frame, the sensor at the viewpoint; the grid is the
    // sensor's, so the points go into the sensor frame whether or not poses are used to fuse frames.
    pcl::transformPointCloud(loaded.cloud, loaded.cloud, loaded.viewpoint->inverse().matrix().cast<float>());
    frame.pose = loaded.viewpoint;
    frame.pose_source = "VIEWPOINT of " + source.path;
  } else if (source.pose) {
    frame.pose = source.pose;
    frame.pose_source = source.pose_source;
  }
  frame.name = source.path;
  if (loaded.encoding) frame.name += std::string(" (depth encoding ") + depth_encoding_name(*loaded.encoding) + ")";
  if (!camera && options.preset_needs_camera()) {
    if (loaded.cloud.height <= 1)
      throw InvalidInput("'" + source.path + "' is not organized, so its camera cannot be fitted; preset " +
                         options.preset_name + " needs one: give -intrinsics (or -preset kinect_v1_paper)");
    const IntrinsicsFit fit = estimate_intrinsics_fit(loaded.cloud, kMaxIntrinsicsFitResidualPx);
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

ToolFrame read_tool_frame(const ToolOptions& options, const FrameSource& source) {
  throw_if_stop_requested();
  const InputScope scope(source.path);
  return load_tool_frame(options, source);
}

ToolFrame sample_tool_frame() {
  const sample::SampleFrame scene = sample::generate_scene();
  return {"built-in sample", organized_cloud(scene.points(), scene.intrinsics.width, scene.intrinsics.height),
          scene.intrinsics, "the built-in sample's camera", std::nullopt};
}

ToolFrameReader::ToolFrameReader(const ToolOptions& options, bool use_sample)
    : options_(options), use_sample_(use_sample) {
  if (use_sample && !options.inputs.empty()) throw InvalidParameter("give either input files or -sample, not both");
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
  ToolFrame frame = read_tool_frame(options_, sources_[next_++]);
  if (first_) {
    require_same_camera(*first_, frame);
    move_into_first_frame(options_, *first_, frame);
  } else {
    first_ = frame_header(frame);
  }
  return frame;
}

std::optional<Eigen::Isometry3d> ToolFrameReader::first_pose() const {
  if (!first_ || !options_.use_poses) return std::nullopt;
  return first_->pose;
}

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

// Collects the frames that disagree with the first one (frame_depth_agreement) when no poses place them, and
// warns once at the end: fusing different scenes as one view makes a map of neither.
class SceneCheck {
public:
  SceneCheck(const SensorModelParams& model, bool poses_applied) : model_(model), active_(!poses_applied) {}
  void add(const ToolFrame& frame) {
    if (!active_ || frame.cloud.height <= 1) return;
    if (!first_) {
      first_ = frame.cloud;
      first_name_ = frame.name;
      return;
    }
    const FrameDepthAgreement a = frame_depth_agreement(*first_, frame.cloud, model_);
    if (a.co_valid < 1000 || a.disagreeing_share() <= kDifferentSceneShare) return;
    names_.push_back(frame.name);
    worst_share_ = std::max(worst_share_, a.disagreeing_share());
  }
  void warn_if_needed() const {
    if (names_.empty()) return;
    std::fprintf(stderr,
                 "warning: %zu frame(s) fused without poses disagree in depth with the first frame '%s' on up to "
                 "%.0f%% of their common valid pixels (beyond 3 sigma; the first such frame: '%s'): different scenes "
                 "or viewpoints? Give their poses, or map them one by one (-input_dir DIR -output_dir OUTDIR)\n",
                 names_.size(), first_name_.c_str(), 100.0 * worst_share_, names_.front().c_str());
  }

private:
  SensorModelParams model_;
  bool active_;
  std::optional<pcl::PointCloud<pcl::PointXYZ>> first_;
  std::string first_name_;
  std::vector<std::string> names_;
  double worst_share_ = 0;
};

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
    prepare(frame);
  } catch (const ResourceLimit& e) {
    throw ResourceLimit("'" + (frame ? frame->name : std::string("sample")) + "': " + e.what() + ";" +
                        memory_cap_hint(true));
  }
  // Poses move every frame into the first one's view; without them, frames of other scenes go unnoticed.
  SceneCheck scenes(frames.options().preset.model, frames.options().use_poses && frame && frame->pose);
  try {
    for (; frame; frame = frames.next()) {
      throw_if_stop_requested();
      const InputScope scope(frame->name);
      scenes.add(*frame);
      fused.insertion += insert(*frame);
      fused.frame_lines.push_back("read " + frame->name + ": " + std::to_string(frame->cloud.size()) + " points");
      progress.update(++fused.frames, frames.count(), fused.insertion.points_received);
    }
  } catch (const Cancelled&) {
    progress.finish();
    std::printf("inserted %zu of %zu frame(s) before the interruption; nothing written\n%s\n", fused.frames,
                frames.count(), describe_points(fused.insertion).c_str());
    throw;
  }
  progress.finish();
  scenes.warn_if_needed();
  fused.first_pose = frames.first_pose();
  fused.poses = fused.first_pose ? "poses applied: every frame moved into the first frame's sensor frame" : "no poses";
  if (fused.frames > 0 && fused.insertion.points_inserted == 0)
    throw InvalidInput("no point of the input lies inside the grid's field of view");
  return fused;
}

std::optional<PixelMask> read_tool_mask(const CommandLine& command_line, const ToolFrame* first) {
  if (!command_line.declares("-mask") || !command_line.has("-mask")) return std::nullopt;
  const std::string value = *command_line.text("-mask");
  if (value != "finite") {
    try {
      return read_mask_png(value);
    } catch (const std::exception& e) {
      throw InvalidParameter("-mask " + value + ": " + e.what());
    }
  }
  if (!first) throw InvalidParameter("-mask finite needs an input frame (it is the first frame's valid pixels)");
  const auto& cloud = first->cloud;
  if (cloud.height <= 1)
    throw InvalidParameter("-mask finite: '" + first->name + "' is not organized, so its points name no pixel");
  return finite_pixel_mask(span_of(cloud), static_cast<int>(cloud.width), static_cast<int>(cloud.height));
}

namespace {
// Runs `use` on the mask, naming -mask and its source in a refusal (the core's message names sizes only).
template <typename Use>
auto with_mask_named(const CommandLine& command_line, Use use) {
  try {
    return use();
  } catch (const InvalidInput& e) {
    throw InvalidParameter("-mask " + *command_line.text("-mask") + ": " + e.what());
  } catch (const InvalidParameter& e) {
    const std::string what = e.what();
    if (what.rfind("-mask", 0) == 0) throw;
    throw InvalidParameter("-mask " + *command_line.text("-mask") + ": " + what);
  }
}
}  // namespace

std::string apply_tool_mask(const CommandLine& command_line, Mapper& mapper, const ToolFrame* first) {
  return with_mask_named(command_line, [&] {
    const std::optional<PixelMask> mask = read_tool_mask(command_line, first);
    if (!mask) return std::string();
    mapper.set_mask(*mask);
    return "mask " + *command_line.text("-mask") + ": " + std::to_string(mask->valid_count()) + " of " +
           std::to_string(mask->valid.size()) + " pixels valid";
  });
}

std::vector<std::uint8_t> tool_mask_columns(const CommandLine& command_line, const GridGeometry& geometry,
                                            const PixelMask& mask) {
  return with_mask_named(command_line, [&] { return mask_columns(geometry, mask); });
}

std::string describe_points(const InsertionReport& in) {
  char line[400];
  std::snprintf(line, sizeof line,
                "points: %zu read, %zu used, %zu skipped invalid, %zu skipped outside the field of view; "
                "%zu used beyond the depth range (free space only)",
                in.points_received, in.points_inserted, in.skipped_invalid, in.skipped_outside_fov,
                in.beyond_depth_range);
  return line;
}

ToolFrame frame_header(const ToolFrame& frame) {
  return ToolFrame{frame.name, {}, frame.camera, frame.camera_source, std::nullopt, frame.pose, frame.pose_source};
}

void move_into_first_frame(const ToolOptions& options, const ToolFrame& first, ToolFrame& frame) {
  if (!options.use_poses || (!first.pose && !frame.pose)) return;
  if (!first.pose || !frame.pose)
    throw InvalidInput("'" + (frame.pose ? first.name : frame.name) + "' has no pose while '" +
                       (frame.pose ? frame.name : first.name) + "' has one (" +
                       (frame.pose ? frame.pose_source : first.pose_source) +
                       "): give every frame a pose, or -no_poses to take every frame from the first's viewpoint");
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

  t.preset = apply_overrides(t.intrinsics ? preset_by_name(t.preset_name, *t.intrinsics) : preset_by_name(t.preset_name), o);

  if (declared_text(c, "-mode") == std::string("exact")) t.grid.mode = UpdateMode::exact;
  if (declared_text(c, "-clamp") == std::string("octomap")) {
    const UpdateMode mode = t.grid.mode;
    t.grid = GridOptions::octomap_clamping();
    t.grid.mode = mode;
  }

  if (const auto gib = declared_number(c, "-memory_cap"))
    t.grid.memory_cap_bytes = static_cast<std::size_t>(std::min(*gib * double(1 << 30), 1e18));
  try {
    require_within_memory_cap(t.preset.geometry, t.grid.memory_cap_bytes);
  } catch (const ResourceLimit& e) {
    throw ResourceLimit(std::string(e.what()) + " (after -preset " + t.preset_name + " and -depth_bins/-fov;" +
                        memory_cap_hint(true) + ")");
  }
  if (const auto k = declared_number(c, "-k")) t.top_k = static_cast<int>(*k);
  t.use_poses = !(c.declares("-no_poses") && c.has("-no_poses"));
  return t;
}

std::string memory_cap_hint(bool with_depth_bins) {
  return with_depth_bins ? " raise the cap with -memory_cap GIB, or lower -depth_bins" : " raise the cap with -memory_cap GIB";
}

LoadedMap load_tool_map(const std::string& path, const ToolOptions& options) {
  try {
    return load_map(path, options.grid.memory_cap_bytes);
  } catch (const ResourceLimit& e) {
    throw ResourceLimit(std::string(e.what()) + ";" + memory_cap_hint(false));  // the map fixes its own bins
  }
}

void create_parent_folders(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).lexically_normal().parent_path();
  std::error_code ec;
  if (!parent.empty() && !std::filesystem::exists(parent, ec)) std::filesystem::create_directories(parent, ec);
}

void apply_segmentation_flags(const CommandLine& c, SegmentationParams& params) {
  if (c.declares("-contour") && c.has("-contour"))
    params.contour_improvement_below = static_cast<float>(*c.number("-contour"));
  if (c.declares("-min_segment")) params.min_segment_columns = static_cast<std::size_t>(*c.integer("-min_segment"));
  if (c.declares("-plane_distance") && c.has("-plane_distance")) params.plane_distance_m = *c.number("-plane_distance");
  if (c.declares("-no_plane") && c.has("-no_plane")) params.remove_dominant_plane = false;
  if (c.declares("-no_crease") && c.has("-no_crease")) params.split_concave_creases = false;
  params.validate();
}

OutputFolder open_output_folder(const CommandLine& c) {
  const auto folder = c.text("-o");
  if (!folder) throw InvalidParameter("-o OUTDIR is required (see -h)");
  create_parent_folders(*folder);  // the folder itself is staged and moved into place
  return OutputFolder(*folder, c.tool().tool, c.has("-overwrite"), run_inputs(c));
}

std::string frame_inputs_help() {
  return R"(  FILE.pcd / FILE.ply       a cloud with x y z in metres, optical frame (z forward, y down); with a
                            camera preset its intrinsics are fitted to its organized points
  FILE.png/.pgm/.tif/.tiff  16-bit depth image, back-projected through -intrinsics or its dataset's file
  FOLDER                    a dataset folder: 7-Scenes/3DMatch/SUN3D (*.depth.png, camera-intrinsics.txt,
                            *.pose.txt) or PCL's image-grabber layout (*_depth.tiff)
  Frames are fused in order; with poses every frame is moved into the first frame's sensor frame.
)";
}

namespace {

extern "C" void record_stop_signal(int signal) { request_stop(signal); }

void install_stop_signals() {
  struct sigaction action {};
  action.sa_handler = record_stop_signal;
  action.sa_flags = SA_RESETHAND;  // a second Ctrl-C kills at once; the next run removes what is left
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

std::string& current_input() {
  static std::string input;
  return input;
}
// The innermost input whose scope an exception left: recorded while unwinding, read by run_tool.
std::string& failed_input() {
  static std::string input;
  return input;
}

// One line on stderr: the message, and the input being worked on when the message does not name it.
int report_failure(const std::string& message) {
  std::fprintf(stderr, "%s\n", failure_line(message).c_str());
  return 1;
}

}  // namespace

std::string failure_line(const std::string& message) {
  std::string line = message;
  std::replace(line.begin(), line.end(), '\n', ' ');
  const std::string& input = failed_input();
  if (!input.empty() && line.find(input) == std::string::npos) line += " (input '" + input + "')";
  failed_input().clear();
  return "error: " + line;
}

InputScope::InputScope(const std::string& input) : previous_(current_input()), uncaught_(std::uncaught_exceptions()) {
  current_input() = input;
}

InputScope::~InputScope() {
  if (std::uncaught_exceptions() > uncaught_ && failed_input().empty()) failed_input() = current_input();
  current_input() = previous_;
}

int take_stop_request() {
  const int signal = stop_requested();
  clear_stop_request();
  return signal;
}

namespace {

bool help_requested(int argc, const char* const* argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "-h") == 0 || std::strcmp(argv[i], "-help") == 0 || std::strcmp(argv[i], "--help") == 0)
      return true;
  return false;
}

}  // namespace

int run_tool(int argc, char** argv, const ToolFlags& flags, int (*run)(const CommandLine& command_line)) {
  const std::string program = std::filesystem::path(argv[0]).filename().string();
  if (help_requested(argc, argv) || argc < 2) {
    std::fputs(usage_text(flags, program).c_str(), argc < 2 ? stderr : stdout);
    return argc < 2 ? 1 : 0;
  }
  install_stop_signals();
  try {
    const CommandLine command_line = parse_command_line(flags, argc, argv);
    if (command_line.has("-v")) {
      pcl::console::setVerbosityLevel(pcl::console::L_DEBUG);
      std::fprintf(stderr, "%s with:\n%s", program.c_str(), resolved_flags(command_line).c_str());
    }
    const int code = batch_requested(command_line) ? run_batch(command_line, run) : run(command_line);
    // A signal that came too late for any poll (during the final renames, say) still ends in 128 + signal,
    // as the README promises; the run had finished, so what it wrote is in place.
    if (const int signal = stop_requested()) {
      std::fprintf(stderr, "%s after the run had finished (its outputs are committed)\n", Cancelled(signal).what());
      return 128 + signal;
    }
    return code;
  } catch (const Cancelled& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 128 + e.reason();
  } catch (const std::bad_alloc&) {
    return report_failure("out of memory (std::bad_alloc)");
  } catch (const std::exception& e) {
    return report_failure(e.what());
  } catch (...) {
    return report_failure("unknown exception");
  }
}

ProgressLine::ProgressLine(const CommandLine& c, std::string unit)
    : shown_(isatty(fileno(stderr)) != 0 && !(c.declares("-q") && c.has("-q"))),
      unit_(std::move(unit)),
      start_seconds_(now_seconds()) {}

ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::show(const std::string& text) {
  if (!shown_) return;
  const double now = now_seconds();
  if (last_draw_seconds_ >= 0 && now - last_draw_seconds_ < 0.1) return;
  last_draw_seconds_ = now;
  std::fprintf(stderr, "\r\033[K%s", text.c_str());  // erase to the end of the line, then draw
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressLine::update(std::size_t done, std::size_t total, std::size_t points) {
  if (!shown_) return;
  const double elapsed = now_seconds() - start_seconds_;
  const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  std::ostringstream line;
  line.setf(std::ios::fixed);
  line.precision(1);
  line << unit_ << ' ' << done;
  if (total) line << '/' << total;
  if (points) line << ", " << static_cast<double>(points) / 1e6 << "M points";
  if (done) line << ", " << rate << ' ' << unit_ << "s/s";
  if (total && done && done < total) line << ", " << static_cast<double>(total - done) / rate << " s left";
  show(line.str());
}

void ProgressLine::finish() {
  if (!drawn_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
  drawn_ = false;
}

PlanRequest plan_request_from_flags(const CommandLine& command_line) {
  PlanRequest request;
  request.budget_rays = *command_line.integer("-budget");
  const std::string shape = *command_line.text("-shape");
  request.shape = shape == "window"       ? ShotShape::window
                  : shape == "decimation" ? ShotShape::decimation
                  : shape == "rays"       ? ShotShape::rays
                                          : ShotShape::coarse_to_fine;
  const std::string refine = *command_line.text("-refine");
  request.refine_by = refine == "improvement" ? RefineBy::improvement
                      : refine == "both"      ? RefineBy::both
                                              : RefineBy::residual;
  const std::string window = *command_line.text("-window");
  const auto x = window.find('x');
  try {
    std::size_t used_w = 0, used_h = 0;
    if (x == std::string::npos) throw std::invalid_argument("no x");
    request.window_width_columns = std::stoi(window.substr(0, x), &used_w);
    request.window_height_columns = std::stoi(window.substr(x + 1), &used_h);
    if (used_w != x || used_h != window.size() - x - 1 || request.window_width_columns < 1 ||
        request.window_height_columns < 1)
      throw std::invalid_argument("not whole");
  } catch (const std::logic_error&) {
    throw InvalidParameter("-window " + window + " is invalid: must be WIDTHxHEIGHT in columns >= 1, e.g. 64x48");
  }
  request.negative_share = *command_line.number("-negative_share");
  request.stop_gain_per_ray_below = *command_line.number("-stop_gain");
  return request;
}

}  // namespace occ_improve
