#pragma once
// A grabber-fed mapping pipeline: attach to any pcl::Grabber, and every frame the grabber delivers is
// handed to one worker thread that inserts it through a Mapper (insertion + incremental surface +
// improvement), ranks regions and evaluates the stop signal, then reports the result.
//
// Threading: the grabber's callback only puts the frame into a one-frame mailbox. When the worker is
// still busy and a frame is waiting, the newest frame replaces it and the replaced one is counted as
// dropped (a live sensor must never be blocked). With `backpressure` the callback instead waits for the
// worker (file replay: every frame processed, none dropped).
//
// Bad frames (empty, organized with another size than the sensor model's camera, unorganized when
// organization is required, a size different from the stream's first accepted frame, or a frame the
// mapper refuses) are counted as rejected and reported; the pipeline keeps running.
// Once stopped: received = processed + dropped + rejected.
//
// The Mapper is read and written by the worker only while the pipeline runs: read it from the result
// callback (which runs on the worker) or after stop(). Callbacks must not call stop() (it joins the
// worker they run on); set a flag and stop from another thread instead.
#include "occ_improve/mapper.hpp"
#include "occ_improve/planning/ranking.hpp"

#include <pcl/io/grabber.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace occ_improve {

struct PipelineOptions {
  InsertionOptions insertion;     ///< threads of the insertion
  RegionOptions regions;          ///< what counts as a region of interest
  std::size_t top_regions = 5;    ///< regions kept in each FrameResult (best first)
  StopCriteria stop;              ///< when to signal "enough"
  ProgressCriteria progress;      ///< ... or when frames stop paying (StopMonitor)
  /// In (0, 1]: insert only this share of each frame's points on an observable ray, chosen against the
  /// map before the frame goes in (keep_points_by_map, point_selection.hpp: selective sensing, which over
  /// a posed sequence builds a better map than pcl::RandomSample of as many; docs/SELECTIVE.md). 1: every
  /// point. The rest is counted (PipelineStatistics::points_not_kept).
  double keep_fraction = 1.0;
  bool backpressure = false;      ///< true: the grabber waits for the worker instead of dropping frames
  bool require_organized = false; ///< reject unorganized frames
  /// Expected organized size (0 = any); set from the preset's camera by the preset constructor.
  std::uint32_t expected_width = 0, expected_height = 0;
  void validate() const;          ///< throws InvalidParameter
};

/// The options with expected_width/height set from the preset's camera (unchanged without a camera), so
/// frames of another size are rejected instead of mapped through the wrong rays.
PipelineOptions with_camera(PipelineOptions options, const SensorPreset& preset);


/// What the worker did with one frame.
struct FrameResult {
  std::uint64_t frame_index = 0;  ///< 0-based index among frames received
  MapperReport report;
  std::vector<Region> top_regions;
  StopSignal stop{false, 0.0, 0.0, ""};
  double seconds = 0.0;           ///< convert + insert + surface + improvement + regions
};

/// A frame the pipeline could not use, or a grabber failure.
struct PipelineEvent {
  enum class Kind { rejected_frame, grabber_error };
  Kind kind;
  std::uint64_t frame_index;  ///< for rejected frames; 0 for grabber errors
  std::string message;
};

struct PipelineStatistics {
  std::uint64_t received = 0;   ///< frames delivered by the grabber
  std::uint64_t processed = 0;  ///< frames inserted
  std::uint64_t dropped = 0;    ///< replaced by a newer frame before the worker took them
  std::uint64_t rejected = 0;   ///< bad frames (see the header comment)
  std::uint64_t interrupted = 0;  ///< frames a stop request (Ctrl-C) cut short: partly inserted, or not at all (during keep_fraction's choice)
  std::uint64_t grabber_errors = 0;  ///< start/stop failures and errors reported by the source
  /// Points of processed frames: all of them (valid or not), and those not inserted because of
  /// keep_fraction (points without a ray included: with keep_fraction < 1 only the kept points reach the
  /// mapper, whose report then counts no invalid point).
  std::uint64_t points_received = 0, points_not_kept = 0;
  std::uint64_t in_flight = 0;  ///< waiting or being processed (0 once stopped)
  /// Summed milliseconds over processed frames, per stage (insert_ms includes the surface update).
  double convert_ms = 0, keep_ms = 0, insert_ms = 0, improvement_ms = 0, regions_ms = 0, callback_ms = 0;
  double wall_seconds = 0;      ///< from start() to stop() (or to now while running)
  double processed_per_second() const { return wall_seconds > 0 ? static_cast<double>(processed) / wall_seconds : 0.0; }
  double mean_ms(double total_ms) const { return processed > 0 ? total_ms / static_cast<double>(processed) : 0.0; }
};

namespace detail {

/// A frame whose type is erased: its points as a span, kept alive by `owner`.
struct ErasedFrame {
  std::shared_ptr<const void> owner;
  PointSpan points;
  std::uint32_t width = 0, height = 0;  ///< height 1 = unorganized
};

/// The non-template engine: mailbox, worker thread, validation, mapping, statistics.
class PipelineEngine {
public:
  PipelineEngine(std::shared_ptr<Mapper> mapper, const PipelineOptions& options);
  ~PipelineEngine();
  PipelineEngine(const PipelineEngine&) = delete;
  PipelineEngine& operator=(const PipelineEngine&) = delete;

  void startWorker();
  /// Processes what is in the mailbox, then joins the worker.
  void stopWorker();
  /// Called from the grabber's thread; never throws.
  void push(ErasedFrame frame) noexcept;
  void reportGrabberError(const std::string& message) noexcept;
  void waitIdle();

  std::function<void(const FrameResult&)> on_result;
  std::function<void(const PipelineEvent&)> on_event;

  PipelineStatistics statistics() const;
  Mapper& mapper() { return *mapper_; }
  const std::shared_ptr<Mapper>& sharedMapper() const { return mapper_; }

private:
  void run();
  void process(ErasedFrame& frame, std::uint64_t index);
  /// The frame's points keep_fraction keeps, chosen by the map (in kept_points_).
  PointSpan kept_share(PointSpan points);
  void reject(std::uint64_t index, const std::string& message);
  void emit(const PipelineEvent& event) noexcept;

  std::shared_ptr<Mapper> mapper_;
  PipelineOptions options_;
  StopMonitor stop_monitor_;  ///< worker thread only
  mutable std::mutex mutex_;
  std::condition_variable work_ready_, slot_free_;
  std::optional<ErasedFrame> slot_;
  std::uint64_t slot_index_ = 0;
  bool busy_ = false, stopping_ = false, running_ = false;
  std::thread worker_;
  PipelineStatistics stats_;
  std::vector<Eigen::Vector3f> kept_points_;  ///< worker thread only: the frame's kept points
  std::uint32_t stream_width_ = 0, stream_height_ = 0;  ///< fixed by the first accepted frame
  double started_at_ = 0, stopped_at_ = 0;
};

}  // namespace detail

/// Pipeline for clouds of PointT (any PCL type starting with x, y, z floats). Explicitly instantiated
/// for PointXYZ, PointXYZI, PointXYZRGB, PointXYZRGBA and PointXYZL.
template <typename PointT>
class GrabberPipeline {
public:
  using Cloud = pcl::PointCloud<PointT>;
  using ResultCallback = std::function<void(const FrameResult&)>;
  using EventCallback = std::function<void(const PipelineEvent&)>;

  /// Own mapper for the preset; frames must be organized like the preset's camera when it has one.
  explicit GrabberPipeline(const SensorPreset& preset, const GridOptions& grid_options = {},
                           PipelineOptions options = {});
  /// Shares the caller's mapper (options.expected_width/height as given).
  GrabberPipeline(std::shared_ptr<Mapper> mapper, const PipelineOptions& options = {});
  ~GrabberPipeline();
  GrabberPipeline(const GrabberPipeline&) = delete;
  GrabberPipeline& operator=(const GrabberPipeline&) = delete;

  /// Registers the frame callback on the grabber (before start()); the grabber must outlive the
  /// pipeline's running period (start() .. stop()). Throws InvalidInput when the grabber
  /// does not provide void(const pcl::PointCloud<PointT>::ConstPtr&) or the pipeline is running.
  void attach(pcl::Grabber& grabber);
  /// Callbacks run on the worker thread; set them before start().
  void setResultCallback(ResultCallback callback);
  void setEventCallback(EventCallback callback);

  /// Starts the worker, then the grabber. A grabber whose start() throws is counted, reported and the
  /// pipeline stopped again; start() then throws IoError naming the grabber.
  void start();
  /// Stops the grabber (failures counted and reported), processes the pending frame, joins the worker,
  /// disconnects from the grabber. Idempotent; called by the destructor.
  void stop();
  bool isRunning() const { return running_; }
  /// Blocks until the mailbox is empty and the worker idle.
  void waitIdle() { engine_.waitIdle(); }

  /// Feeds one frame as the grabber would (from any thread; also used by tests and the sources).
  void pushFrame(const typename Cloud::ConstPtr& cloud);
  /// Counts and reports a failure of the frame source (e.g. a file sequence's unreadable frame).
  void reportSourceError(const std::string& message) { engine_.reportGrabberError(message); }

  PipelineStatistics statistics() const { return engine_.statistics(); }
  /// See the header comment for when it is safe to read.
  const Mapper& mapper() const { return *engine_.sharedMapper(); }
  std::shared_ptr<Mapper> sharedMapper() const { return engine_.sharedMapper(); }

private:
  detail::PipelineEngine engine_;
  pcl::Grabber* grabber_ = nullptr;
  boost::signals2::connection connection_;
  bool running_ = false;
};

}  // namespace occ_improve
