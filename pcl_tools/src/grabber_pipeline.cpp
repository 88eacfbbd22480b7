#include "occ_improve/pcl/grabber_pipeline.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/planning/point_selection.hpp"
#include "occ_improve/timing.hpp"

#include <algorithm>

namespace occ_improve {

namespace {

double ms_since(double start_seconds) { return (now_seconds() - start_seconds) * 1e3; }

}  // namespace

void PipelineOptions::validate() const {
  regions.validate();
  stop.validate();
  progress.validate();
  detail::require_parameter(insertion.threads >= 0, "insertion.threads", insertion.threads, ">= 0");
  detail::require_parameter(keep_fraction > 0.0 && keep_fraction <= 1.0, "keep_fraction", keep_fraction, "in (0, 1]");
  detail::require_parameter((expected_width == 0) == (expected_height == 0), "expected_width",
                            expected_width, "0 exactly when expected_height is 0");
}

namespace detail {

PipelineEngine::PipelineEngine(std::shared_ptr<Mapper> mapper, const PipelineOptions& options)
    : mapper_(std::move(mapper)), options_(options), stop_monitor_(options.stop, options.progress) {
  if (!mapper_) throw InvalidParameter("GrabberPipeline: mapper is null");
  options_.validate();
}

PipelineEngine::~PipelineEngine() { stopWorker(); }

void PipelineEngine::startWorker() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (running_) return;
  stopping_ = false;
  running_ = true;
  started_at_ = now_seconds();
  stopped_at_ = 0;
  worker_ = std::thread([this] { run(); });
}

void PipelineEngine::stopWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!running_) return;
    stopping_ = true;
  }
  work_ready_.notify_all();
  slot_free_.notify_all();
  worker_.join();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    running_ = false;
    stopped_at_ = now_seconds();
  }
  slot_free_.notify_all();
}

void PipelineEngine::push(ErasedFrame frame) noexcept {
  std::unique_lock<std::mutex> lock(mutex_);
  const std::uint64_t index = stats_.received++;
  if (!running_ || stopping_) {
    // Delivered after stop() began: nothing will process it.
    ++stats_.dropped;
    return;
  }
  if (options_.backpressure) slot_free_.wait(lock, [this] { return !slot_ || stopping_; });
  if (slot_) {
    ++stats_.dropped;  // the newest frame wins
  } else {
    ++stats_.in_flight;
  }
  slot_ = std::move(frame);
  slot_index_ = index;
  lock.unlock();
  work_ready_.notify_one();
}

void PipelineEngine::reportGrabberError(const std::string& message) noexcept {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.grabber_errors;
  }
  emit({PipelineEvent::Kind::grabber_error, 0, message});
}

void PipelineEngine::waitIdle() {
  std::unique_lock<std::mutex> lock(mutex_);
  slot_free_.wait(lock, [this] { return (!slot_ && !busy_) || !running_; });
}

PipelineStatistics PipelineEngine::statistics() const {
  std::lock_guard<std::mutex> lock(mutex_);
  PipelineStatistics s = stats_;
  if (started_at_ > 0) s.wall_seconds = (running_ ? now_seconds() : stopped_at_) - started_at_;
  return s;
}

void PipelineEngine::emit(const PipelineEvent& event) noexcept {
  if (!on_event) return;
  try {
    on_event(event);
  } catch (...) {
    // A failing observer must not stop the pipeline; the event was already counted.
  }
}

void PipelineEngine::reject(std::uint64_t index, const std::string& message) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.rejected;
  }
  // Counted from 1 in the message, as the summary counts frames received (index counts from 0).
  emit({PipelineEvent::Kind::rejected_frame, index,
        "received frame " + std::to_string(index + 1) + " rejected: " + message});
}

void PipelineEngine::run() {
  for (;;) {
    ErasedFrame frame;
    std::uint64_t index = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_ready_.wait(lock, [this] { return slot_ || stopping_; });
      if (!slot_) break;  // stopping and nothing left
      frame = std::move(*slot_);
      index = slot_index_;
      slot_.reset();
      busy_ = true;
    }
    slot_free_.notify_all();
    process(frame, index);
    frame = {};  // release the cloud before reporting idle
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
      --stats_.in_flight;
    }
    slot_free_.notify_all();
  }
}

void PipelineEngine::process(ErasedFrame& frame, std::uint64_t index) {
  const double t0 = now_seconds();
  if (frame.points.count == 0) return reject(index, "empty frame");
  if (valid_point_count(frame.points) == 0)
    return reject(index, "no valid point (" + std::to_string(frame.points.count) + " points, all NaN, infinite or at the origin)");
  const bool organized = frame.height > 1;
  if (options_.require_organized && !organized)
    return reject(index, "unorganized frame (" + std::to_string(frame.points.count) +
                             " points) but the sensor model needs an organized image");
  if (organized && options_.expected_width != 0 &&
      (frame.width != options_.expected_width || frame.height != options_.expected_height))
    return reject(index, "organized " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                             " frame does not match the sensor model's " + std::to_string(options_.expected_width) +
                             "x" + std::to_string(options_.expected_height) + " camera");
  if (stream_width_ == 0) {
    stream_width_ = frame.width;
    stream_height_ = frame.height;
  } else if (frame.width != stream_width_ || frame.height != stream_height_) {
    return reject(index, "size changed mid-stream: " + std::to_string(frame.width) + "x" +
                             std::to_string(frame.height) + " after " + std::to_string(stream_width_) + "x" +
                             std::to_string(stream_height_));
  }
  const double convert_ms = ms_since(t0);

  FrameResult result;
  result.frame_index = index;
  double keep_ms = 0;
  std::size_t inserted_points = frame.points.count;
  const char* stage = "the mapper refused it: ";
  try {
    PointSpan points = frame.points;
    if (options_.keep_fraction < 1.0) {
      stage = "choosing the kept points failed: ";
      const double t_keep = now_seconds();
      points = kept_share(points);
      inserted_points = points.count;
      keep_ms = ms_since(t_keep);
      stage = "the mapper refused it: ";
    }
    result.report = mapper_->insert(points, options_.insertion);
  } catch (const Cancelled&) {  // the user's stop, not a bad frame: counted apart, no warning
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.interrupted;
    return;
  } catch (const std::exception& e) {
    return reject(index, std::string(stage) + e.what());
  }
  const double t_regions = now_seconds();
  std::vector<Region> regions = find_regions(mapper_->geometry(), mapper_->improvement(), mapper_->surface(),
                                             options_.regions);
  result.stop = stop_monitor_.update(mapper_->improvement(), regions);
  regions.resize(std::min(regions.size(), options_.top_regions));
  result.top_regions = std::move(regions);
  const double regions_ms = ms_since(t_regions);
  result.seconds = now_seconds() - t0;

  const double t_callback = now_seconds();
  if (on_result) {
    try {
      on_result(result);
    } catch (const Cancelled&) {
      // A stop during an intermediate write: the final write after stop() publishes the map.
    } catch (const std::exception& e) {
      emit({PipelineEvent::Kind::grabber_error, index, std::string("result callback threw: ") + e.what()});
    }
  }
  const double callback_ms = ms_since(t_callback);

  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.processed;
  stats_.points_received += frame.points.count;
  stats_.points_not_kept += frame.points.count - inserted_points;
  stats_.convert_ms += convert_ms;
  stats_.keep_ms += keep_ms;
  stats_.insert_ms += result.report.insertion.seconds * 1e3;
  stats_.improvement_ms += result.report.improvement_seconds * 1e3;
  stats_.regions_ms += regions_ms;
  stats_.callback_ms += callback_ms;
}

PointSpan PipelineEngine::kept_share(PointSpan points) {
  Mapper& m = *mapper_;
  const MapView map{m.geometry(), m.surface(), m.improvement(), m.pyramid()};
  const std::vector<std::uint64_t> kept =
      keep_points_by_map(points_on_rays(points, m.geometry()), KeepAmount::fraction(options_.keep_fraction), map);
  kept_points_.clear();
  for (const std::uint64_t i : kept) {
    const float* p = points.xyz + i * points.stride_floats;
    kept_points_.emplace_back(p[0], p[1], p[2]);
  }
  return PointSpan::from(kept_points_);
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------------

PipelineOptions with_camera(PipelineOptions options, const SensorPreset& preset) {
  if (preset.camera) {
    options.expected_width = static_cast<std::uint32_t>(preset.camera->width);
    options.expected_height = static_cast<std::uint32_t>(preset.camera->height);
  }
  return options;
}

template <typename PointT>
GrabberPipeline<PointT>::GrabberPipeline(const SensorPreset& preset, const GridOptions& grid_options,
                                         PipelineOptions options)
    : engine_(std::make_shared<Mapper>(preset, grid_options), with_camera(std::move(options), preset)) {}

template <typename PointT>
GrabberPipeline<PointT>::GrabberPipeline(std::shared_ptr<Mapper> mapper, const PipelineOptions& options)
    : engine_(std::move(mapper), options) {}

template <typename PointT>
GrabberPipeline<PointT>::~GrabberPipeline() {
  stop();
  connection_.disconnect();
}

template <typename PointT>
void GrabberPipeline<PointT>::attach(pcl::Grabber& grabber) {
  using Signal = void(const typename Cloud::ConstPtr&);
  if (running_) throw InvalidInput("GrabberPipeline::attach: stop the pipeline first");
  if (!grabber.providesCallback<Signal>())
    throw InvalidInput("grabber '" + grabber.getName() + "' does not deliver clouds of this point type");
  connection_.disconnect();
  std::function<Signal> callback = [this](const typename Cloud::ConstPtr& cloud) { pushFrame(cloud); };
  connection_ = grabber.registerCallback(callback);
  grabber_ = &grabber;
}

template <typename PointT>
void GrabberPipeline<PointT>::setResultCallback(ResultCallback callback) {
  engine_.on_result = std::move(callback);
}

template <typename PointT>
void GrabberPipeline<PointT>::setEventCallback(EventCallback callback) {
  engine_.on_event = std::move(callback);
}

template <typename PointT>
void GrabberPipeline<PointT>::start() {
  if (running_) return;
  engine_.startWorker();
  running_ = true;
  if (!grabber_) return;
  try {
    grabber_->start();
  } catch (const std::exception& e) {
    const std::string message = "grabber '" + grabber_->getName() + "' failed to start: " + e.what();
    engine_.reportGrabberError(message);
    stop();
    throw IoError(message);
  }
}

template <typename PointT>
void GrabberPipeline<PointT>::stop() {
  if (!running_) return;
  if (grabber_) {
    try {
      if (grabber_->isRunning()) grabber_->stop();
    } catch (const std::exception& e) {
      engine_.reportGrabberError("grabber '" + grabber_->getName() + "' failed to stop: " + e.what());
    }
  }
  engine_.stopWorker();
  running_ = false;
}

template <typename PointT>
void GrabberPipeline<PointT>::pushFrame(const typename Cloud::ConstPtr& cloud) {
  detail::ErasedFrame frame;
  if (cloud) {
    frame.points = span_of(*cloud);
    frame.width = cloud->width;
    frame.height = cloud->height;
    frame.owner = cloud;
  }
  engine_.push(std::move(frame));
}

template class GrabberPipeline<pcl::PointXYZ>;
template class GrabberPipeline<pcl::PointXYZI>;
template class GrabberPipeline<pcl::PointXYZRGB>;
template class GrabberPipeline<pcl::PointXYZRGBA>;
template class GrabberPipeline<pcl::PointXYZL>;

}  // namespace occ_improve
