#include "occ_improve/pcl/sequence_sources.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"

#include <pcl/common/transforms.h>
#include <pcl/io/openni2_grabber.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

namespace occ_improve {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------------
// FileSequenceGrabber

FileSequenceGrabber::FileSequenceGrabber(std::size_t frame_count, float fps)
    : frame_count_(frame_count), fps_(fps), frame_signal_(createSignal<FrameSignal>()) {
  detail::require_parameter(std::isfinite(fps) && (fps == 0.0f || (fps >= kMinimumFps && fps <= 1e6f)), "fps", fps,
                            "0 (as fast as possible) or in [0.001, 1e6]");
}

FileSequenceGrabber::~FileSequenceGrabber() noexcept { stop(); }

void FileSequenceGrabber::setErrorCallback(ErrorCallback callback) {
  std::lock_guard<std::mutex> lock(mutex_);
  on_error_ = std::move(callback);
}

void FileSequenceGrabber::start() {
  stop();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_requested_ = false;
  }
  emitted_ = 0;
  errors_ = 0;
  running_ = true;
  thread_ = std::thread([this] { run(); });
}

void FileSequenceGrabber::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_requested_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  running_ = false;
}

bool FileSequenceGrabber::isRunning() const { return running_; }

void FileSequenceGrabber::waitUntilDone() {
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait(lock, [this] { return !running_ || stop_requested_; });
}

void FileSequenceGrabber::run() {
  using Clock = std::chrono::steady_clock;
  const auto period = fps_ > 0.0f ? std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / fps_))
                                  : Clock::duration::zero();
  auto next_frame_time = Clock::now();
  for (std::size_t i = 0; i < frame_count_; ++i) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (wake_.wait_until(lock, next_frame_time, [this] { return stop_requested_; })) break;
    }
    next_frame_time += period;
    Cloud::Ptr cloud;
    try {
      cloud = loadFrame(i);
    } catch (const Cancelled&) {
      break;  // the user's stop, met inside a read (PCL's readers are waited for with polls): not a bad file
    } catch (const std::exception& e) {
      ++errors_;
      ErrorCallback on_error;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        on_error = on_error_;
      }
      if (on_error)
        on_error(std::string(getName()) + ": file " + std::to_string(i + 1) + " of " + std::to_string(frame_count_) +
                 " skipped: " + e.what());
      continue;
    }
    emitting_ = i;
    if (frame_signal_->num_slots() > 0) (*frame_signal_)(cloud);
    ++emitted_;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    running_ = false;
  }
  wake_.notify_all();
}

// ---------------------------------------------------------------------------------------------------
// PcdSequenceGrabber

namespace {

std::vector<std::string> files_in(const std::string& directory, const std::vector<std::string>& extensions) {
  std::error_code ec;
  fs::directory_iterator it(directory, ec);
  if (ec) throw IoError("cannot read folder '" + directory + "': " + ec.message());
  std::vector<std::string> files;
  for (const auto& entry : it) {
    if (!entry.is_regular_file()) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (std::find(extensions.begin(), extensions.end(), ext) != extensions.end()) files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::string> require_files(std::vector<std::string> files, const std::string& what) {
  if (files.empty()) throw InvalidInput("no " + what + " found");
  return files;
}

}  // namespace

PcdSequenceGrabber::PcdSequenceGrabber(const std::string& directory, float fps)
    : PcdSequenceGrabber(require_files(files_in(directory, {".pcd"}), ".pcd file in '" + directory + "'"), fps) {}

PcdSequenceGrabber::PcdSequenceGrabber(std::vector<std::string> files, float fps)
    : FileSequenceGrabber(files.size(), fps), files_(require_files(std::move(files), "PCD file in the list")) {}

FileSequenceGrabber::Cloud::Ptr PcdSequenceGrabber::loadFrame(std::size_t index) {
  LoadedFrame frame = load_pcd_frame(files_[index]);
  return Cloud::Ptr(new Cloud(std::move(frame.cloud)));
}

// ---------------------------------------------------------------------------------------------------
// Depth sequences

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}


/// "timestamp value..." lines, comments (#) and blank lines skipped, trailing white space (a Windows line
/// end's '\r' kept the file names "1.png\r": "unsupported depth image type '.png'") dropped.
std::vector<std::pair<double, std::string>> timestamped_lines(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot open '" + path.string() + "'");
  std::vector<std::pair<double, std::string>> lines;
  std::string line;
  while (std::getline(in, line)) {
    line.erase(line.find_last_not_of(" \t\r") + 1);  // npos + 1 = 0: a blank line becomes empty
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double t = 0;
    std::string rest;
    if (!(fields >> t)) throw FormatError("'" + path.string() + "': line without a timestamp: " + line);
    std::getline(fields >> std::ws, rest);
    lines.emplace_back(t, rest);
  }
  return lines;
}

DepthSequence scan_tum(const fs::path& directory) {
  DepthSequence sequence;
  sequence.encoding = DepthEncoding::tum_5000;
  std::map<double, Eigen::Isometry3d> poses;
  if (fs::exists(directory / "groundtruth.txt")) {
    for (const auto& [t, rest] : timestamped_lines(directory / "groundtruth.txt")) {
      std::istringstream fields(rest);
      double tx, ty, tz, qx, qy, qz, qw;
      // A zero quaternion would normalise to NaN and carry NaN into every point.
      if (!(fields >> tx >> ty >> tz >> qx >> qy >> qz >> qw) || !Eigen::Vector3d(tx, ty, tz).allFinite() ||
          !(Eigen::Vector4d(qx, qy, qz, qw).norm() > 1e-6) || !Eigen::Vector4d(qx, qy, qz, qw).allFinite())
        throw FormatError("'" + (directory / "groundtruth.txt").string() + "': bad pose line at t = " + std::to_string(t));
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      pose.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
      pose.translation() = Eigen::Vector3d(tx, ty, tz);
      poses.emplace(t, pose);
    }
  }
  constexpr double kMaxPoseGapSeconds = 0.02;
  for (const auto& [t, file] : timestamped_lines(directory / "depth.txt")) {
    DepthSequenceFrame frame;
    frame.depth_path = (directory / file).string();
    if (!poses.empty()) {
      auto after = poses.lower_bound(t);
      auto best = after;
      if (after == poses.end() || (after != poses.begin() && t - std::prev(after)->first < after->first - t))
        best = std::prev(after);
      if (std::abs(best->first - t) <= kMaxPoseGapSeconds) frame.camera_to_world = best->second;
    }
    sequence.frames.push_back(std::move(frame));
  }
  return sequence;
}

}  // namespace

namespace {

// 7-Scenes frames among `images` (name order), each with its pose file when there is one.
std::vector<DepthSequenceFrame> seven_scenes_frames(const std::vector<std::string>& images) {
  std::vector<DepthSequenceFrame> frames;
  for (const std::string& path : images) {
    if (!ends_with(path, ".depth.png")) continue;
    DepthSequenceFrame frame;
    frame.depth_path = path;
    const std::string pose_path = pose_file_for(path);
    if (fs::exists(pose_path)) frame.camera_to_world = read_pose_matrix_file(pose_path);
    frames.push_back(std::move(frame));
  }
  return frames;
}

// A 7-Scenes scene folder holds no frame itself but seq-NN/ subfolders of frames whose poses share the
// scene's world frame: their frames in folder then name order, as occ_improve_map reads such a folder.
// Empty when no subfolder holds 7-Scenes frames.
DepthSequence scene_folder_sequence(const fs::path& directory) {
  std::error_code ec;
  std::vector<fs::path> subfolders;
  for (fs::directory_iterator it(directory, ec), end; it != end && !ec; it.increment(ec))
    if (it->is_directory(ec)) subfolders.push_back(it->path());
  if (ec) throw IoError("cannot read folder '" + directory.string() + "': " + ec.message());
  std::sort(subfolders.begin(), subfolders.end());
  DepthSequence sequence;
  sequence.encoding = DepthEncoding::millimetres;
  std::string camera_folder;
  for (const fs::path& folder : subfolders) {
    std::vector<DepthSequenceFrame> frames = seven_scenes_frames(files_in(folder.string(), {".png"}));
    if (frames.empty()) continue;
    const std::optional<PinholeIntrinsics> camera = intrinsics_beside(folder, frames.front().depth_path);
    if (camera_folder.empty()) {
      sequence.intrinsics = camera;
      camera_folder = folder.string();
    } else if (camera != sequence.intrinsics) {
      throw InvalidInput("'" + folder.string() + "' and '" + camera_folder +
                         "' have different camera-intrinsics.txt: give one of them as the sequence");
    }
    std::move(frames.begin(), frames.end(), std::back_inserter(sequence.frames));
  }
  return sequence;
}

}  // namespace

DepthSequence scan_depth_sequence(const std::string& directory_name) {
  const fs::path directory(directory_name);
  if (fs::exists(directory / "depth.txt")) {
    DepthSequence sequence = scan_tum(directory);
    if (sequence.frames.empty()) throw InvalidInput("'" + (directory / "depth.txt").string() + "' lists no frame");
    return sequence;
  }
  DepthSequence sequence;
  const std::vector<std::string> images = files_in(directory_name, {".png", ".pgm", ".tif", ".tiff"});
  sequence.frames = seven_scenes_frames(images);
  if (!sequence.frames.empty()) {
    sequence.encoding = DepthEncoding::millimetres;
    sequence.intrinsics = intrinsics_beside(directory, sequence.frames.front().depth_path);
  } else if (images.empty()) {
    sequence = scene_folder_sequence(directory);
  } else {
    const bool some_named_depth = std::any_of(images.begin(), images.end(), is_named_depth);
    for (const std::string& path : images)
      if (!some_named_depth || is_named_depth(path)) sequence.frames.push_back({path, std::nullopt});
  }
  if (sequence.frames.empty())
    throw InvalidInput("no depth image (.png/.pgm/.tif/.tiff) found in '" + directory_name +
                       "' (nor 7-Scenes frames in its subfolders)");
  return sequence;
}

DepthSequenceGrabber::DepthSequenceGrabber(DepthSequence sequence, const PinholeIntrinsics& intrinsics,
                                           const DepthSequenceOptions& options)
    : FileSequenceGrabber(sequence.frames.size(), options.fps),
      sequence_(std::move(sequence)),
      intrinsics_(intrinsics),
      encoding_(options.encoding ? options.encoding : sequence_.encoding) {
  if (sequence_.frames.empty()) throw InvalidParameter("depth sequence: no frames");
  intrinsics_.validate();
  // Poses are used when some frame has one (TUM's ground truth often starts after the first depth frames):
  // the map is the first posed frame's view, and a frame without a pose is skipped and counted (loadFrame),
  // since its points cannot be put in that view.
  const auto posed = std::find_if(sequence_.frames.begin(), sequence_.frames.end(),
                                  [](const DepthSequenceFrame& f) { return f.camera_to_world.has_value(); });
  use_poses_ = options.use_poses && posed != sequence_.frames.end();
  if (use_poses_) world_to_first_ = options.world_from_map ? options.world_from_map->inverse() : posed->camera_to_world->inverse();
}

std::size_t DepthSequenceGrabber::unposedFrames() const {
  if (!use_poses_) return 0;
  return static_cast<std::size_t>(std::count_if(sequence_.frames.begin(), sequence_.frames.end(),
                                                [](const DepthSequenceFrame& f) { return !f.camera_to_world; }));
}

FileSequenceGrabber::Cloud::Ptr DepthSequenceGrabber::loadFrame(std::size_t index) {
  const DepthSequenceFrame& frame = sequence_.frames[index];
  if (use_poses_ && !frame.camera_to_world)
    throw InvalidInput("'" + frame.depth_path + "' has no pose while the sequence's others have: skipped (-no_poses "
                       "uses every frame, without poses)");
  LoadedFrame loaded = load_depth_frame(frame.depth_path, intrinsics_, encoding_);
  Cloud::Ptr cloud(new Cloud);
  if (use_poses_) {
    const Eigen::Isometry3d to_first = world_to_first_ * *frame.camera_to_world;
    pcl::transformPointCloud(loaded.cloud, *cloud, to_first.matrix().cast<float>());
  } else {
    *cloud = std::move(loaded.cloud);
  }
  return cloud;
}

// ---------------------------------------------------------------------------------------------------
// OpenNI2

namespace {

/// The innermost description of a PCL exception ("<function> in <file> @ <line> : <description>", nested
/// for re-thrown errors), without source locations and on one line, for "error: ..." output.
std::string one_line(const pcl::PCLException& e) {
  std::string text;
  for (const char c : std::string(e.detailedMessage())) {
    const bool space = c == '\n' || c == '\t' || c == '\r' || c == ' ';
    if (!space)
      text += c;
    else if (!text.empty() && text.back() != ' ')
      text += ' ';
  }
  const std::size_t last_location = text.rfind(" : ");
  if (last_location != std::string::npos) text = text.substr(last_location + 3);
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

}  // namespace

std::shared_ptr<pcl::Grabber> open_openni2_grabber(const std::string& device_or_oni) {
  const bool is_file = ends_with(device_or_oni, ".oni") || ends_with(device_or_oni, ".ONI");
  if (is_file && !fs::exists(device_or_oni)) throw IoError("OpenNI2 recording '" + device_or_oni + "' does not exist");
  try {
    return std::make_shared<pcl::io::OpenNI2Grabber>(device_or_oni);
  } catch (const pcl::IOException& e) {
    const std::string what = one_line(e);
    if (what.find("No devices connected") != std::string::npos)
      throw IoError("no OpenNI2 device connected (plug in a Kinect/Xtion, or replay a recording with -oni FILE)");
    throw IoError("cannot open OpenNI2 " + std::string(is_file ? "recording '" : "device '") + device_or_oni +
                  "': " + what);
  } catch (const pcl::PCLException& e) {
    throw IoError("cannot open OpenNI2 " + std::string(is_file ? "recording '" : "device '") + device_or_oni +
                  "': " + one_line(e));
  }
}

}  // namespace occ_improve
