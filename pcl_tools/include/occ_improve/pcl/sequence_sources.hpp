#pragma once
// Frame sources for the grabber pipeline. Each is a pcl::Grabber, so the pipeline (and any PCL code)
// attaches to them exactly as to a live camera, through the signal
//   void(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr&).
//  - PcdSequenceGrabber: the .pcd files of a folder (or a list), in name order.
//  - DepthSequenceGrabber: 16-bit depth images with intrinsics and optional camera-to-world poses
//    (7-Scenes `frame-NNNNNN.depth.png` + `.pose.txt` + `camera-intrinsics.txt`, or TUM RGB-D
//    `depth.txt` + `groundtruth.txt`).
//  - open_openni2_grabber(): a live OpenNI2 device or an .oni recording, with "no device" turned into
//    an occ_improve::IoError.
//
// Poses: the grid is single-viewpoint (one sensor origin). With poses, every frame's points are
// transformed into the FIRST frame's sensor frame (p_first = T_first^-1 * T_i * p) before they are
// emitted, so the map is built in the first frame's view; the emitted cloud keeps the frame's image
// layout (organized width x height) but its points are no longer in that frame's own optical frame.
//
// Files are read on the source's own thread, at `fps` frames per second or as fast as possible
// (fps = 0). A file that cannot be read is skipped, counted (errors()) and reported through the error
// callback; the sequence goes on.
#include "occ_improve/pcl/frame_io.hpp"

#include <pcl/io/grabber.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace occ_improve {

/// The slowest replay rate a file source takes [frames/s]: one frame per 1000 s (a longer period
/// overflows the clock's duration type).
constexpr double kMinimumFps = 1e-3;

/// Common machinery of the file sequences: the reading thread, pacing, counting, clean stop.
class FileSequenceGrabber : public pcl::Grabber {
public:
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;
  using FrameSignal = void(const Cloud::ConstPtr&);
  using ErrorCallback = std::function<void(const std::string& message)>;

  /// Derived classes call stop() in their own destructor (the thread calls their loadFrame).
  ~FileSequenceGrabber() noexcept override;

  /// Starts (or restarts from the first frame) the reading thread.
  void start() override;
  /// Stops and joins the reading thread; a frame being read is finished first. Idempotent.
  void stop() override;
  bool isRunning() const override;
  float getFramesPerSecond() const override { return fps_; }

  /// Blocks until every frame has been emitted (or stop() was called). Returns at once when not started.
  void waitUntilDone();

  std::size_t frameCount() const { return frame_count_; }
  std::size_t framesEmitted() const { return emitted_; }
  std::size_t errors() const { return errors_; }
  /// Called from the reading thread for each file that cannot be read.
  void setErrorCallback(ErrorCallback callback);
  /// Inside a frame's callback (on the reading thread): the file the frame was read from.
  std::string emittingFrameName() const { return frameName(emitting_); }

protected:
  /// fps = 0: as fast as possible; fps < 0 throws InvalidParameter.
  FileSequenceGrabber(std::size_t frame_count, float fps);
  /// The i-th frame (may throw any occ_improve::Error; the frame is then skipped and counted).
  virtual Cloud::Ptr loadFrame(std::size_t index) = 0;
  /// The i-th frame's file.
  virtual std::string frameName(std::size_t index) const = 0;

private:
  void run();

  std::size_t frame_count_;
  float fps_;
  boost::signals2::signal<FrameSignal>* frame_signal_;
  ErrorCallback on_error_;
  std::thread thread_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_requested_ = false;
  std::atomic<bool> running_{false};
  std::atomic<std::size_t> emitted_{0}, errors_{0};
  std::size_t emitting_ = 0;  ///< the frame being emitted (reading thread only)
};

/// The .pcd files of a folder in name order (non-.pcd files are ignored), or an explicit list.
/// Throws IoError when the folder cannot be read, InvalidInput when it holds no .pcd file.
class PcdSequenceGrabber : public FileSequenceGrabber {
public:
  explicit PcdSequenceGrabber(const std::string& directory, float fps = 0.0f);
  PcdSequenceGrabber(std::vector<std::string> files, float fps);
  ~PcdSequenceGrabber() noexcept override { stop(); }
  std::string getName() const override { return "PcdSequenceGrabber"; }
  const std::vector<std::string>& files() const { return files_; }

protected:
  Cloud::Ptr loadFrame(std::size_t index) override;
  std::string frameName(std::size_t index) const override { return files_[index]; }

private:
  std::vector<std::string> files_;
};

/// One depth frame of a sequence: its file and, when known, its camera-to-world pose.
struct DepthSequenceFrame {
  std::string depth_path;
  std::optional<Eigen::Isometry3d> camera_to_world;
};

/// A depth-image sequence as found on disk.
struct DepthSequence {
  std::vector<DepthSequenceFrame> frames;
  std::optional<PinholeIntrinsics> intrinsics;  ///< from the layout's own file, when it has one
  std::optional<DepthEncoding> encoding;  ///< the layout's encoding; unset: guessed per file (frame_io)
};

/// Recognises the layout of `directory`:
///  - 7-Scenes: `frame-NNNNNN.depth.png` (mm), poses from `frame-NNNNNN.pose.txt` (4x4 camera-to-world)
///    when present; intrinsics from `camera-intrinsics.txt` in the folder or its parent; a scene folder
///    without frames of its own reads its subfolders' (seq-01/, seq-02/, ... in name order: 7-Scenes'
///    poses share the scene's world frame), all of one camera (else InvalidInput);
///  - TUM RGB-D: `depth.txt` ("timestamp depth/file.png" lines, 1/5000 m), poses from `groundtruth.txt`
///    ("t tx ty tz qx qy qz qw", nearest timestamp within 20 ms) when present;
///  - otherwise every .png/.pgm/.tif/.tiff in name order (only those with "depth" in their name when some
///    have it, so colour images beside them are left out: PCL's grabber layout `*_depth.tiff` with
///    `*_rgb.tiff`), no poses, encoding guessed per file.
/// Throws IoError when unreadable, InvalidInput when no depth image is found, FormatError on a bad pose.
DepthSequence scan_depth_sequence(const std::string& directory);

struct DepthSequenceOptions {
  float fps = 0.0f;                 ///< 0: as fast as possible
  bool use_poses = true;            ///< transform into the first frame's sensor frame when poses exist
  /// With poses: the sensor frame the frames are moved into, camera-to-world (a loaded map's pose); unset:
  /// the first posed frame's.
  std::optional<Eigen::Isometry3d> world_from_map;
  std::optional<DepthEncoding> encoding;  ///< overrides the layout's encoding
};

/// Emits back-projected depth images (organized width x height, NaN where no return), transformed
/// into the first frame's sensor frame when poses are used (see the header comment).
class DepthSequenceGrabber : public FileSequenceGrabber {
public:
  /// Throws InvalidParameter when the sequence has no frames or the intrinsics are invalid.
  DepthSequenceGrabber(DepthSequence sequence, const PinholeIntrinsics& intrinsics,
                       const DepthSequenceOptions& options = {});
  ~DepthSequenceGrabber() noexcept override { stop(); }
  std::string getName() const override { return "DepthSequenceGrabber"; }
  const DepthSequence& sequence() const { return sequence_; }
  /// True when frames are transformed by their poses.
  bool posesApplied() const { return use_poses_; }
  /// The camera-to-world of the frame they are moved into (posesApplied only): the options' world_from_map,
  /// else the first posed frame's.
  Eigen::Isometry3d worldFromMap() const { return world_to_first_.inverse(); }
  /// Frames skipped for want of a pose while others have one (0 without poses).
  std::size_t unposedFrames() const;

protected:
  Cloud::Ptr loadFrame(std::size_t index) override;
  std::string frameName(std::size_t index) const override { return sequence_.frames[index].depth_path; }

private:
  DepthSequence sequence_;
  PinholeIntrinsics intrinsics_;
  std::optional<DepthEncoding> encoding_;
  bool use_poses_ = false;
  Eigen::Isometry3d world_to_first_ = Eigen::Isometry3d::Identity();
};

/// Opens an OpenNI2 device ("" = the first one, or a device URI) or an .oni recording (a path ending in
/// .oni). Throws IoError "no OpenNI2 device connected" when no device is present, IoError naming the
/// file or URI for any other failure. The grabber emits pcl::PointXYZ clouds (among others).
std::shared_ptr<pcl::Grabber> open_openni2_grabber(const std::string& device_or_oni = "");

}  // namespace occ_improve
