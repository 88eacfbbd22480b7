// occ_improve_live: fuse a stream of range frames (OpenNI2 device, .oni recording, PCD folder or
// depth-image sequence) into the occupancy grid (along the sensor's rays) as they arrive, and keep the depth,
// occupancy and improvement maps written to a folder.
#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/grabber_pipeline.hpp"
#include "occ_improve/tools/map_outputs.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/pcl/sequence_sources.hpp"
#include "occ_improve/tools/live_view.hpp"
#include "occ_improve/tools/tool_frame_grabber.hpp"
#include "occ_improve/tools/frame_fusion.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/plan_flags.hpp"
#include "occ_improve/tools/progress.hpp"
#include "occ_improve/tools/signals.hpp"
#include "occ_improve/tools/tool_frames.hpp"
#include "occ_improve/tools/tool_main.hpp"
#include "occ_improve/tools/tool_mask.hpp"
#include "occ_improve/tools/tool_options.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/sim/render.hpp"
#include "occ_improve/planning/return_model.hpp"
#include "occ_improve/sim/virtual_sensor.hpp"
#include "occ_improve/timing.hpp"

#include <pcl/console/print.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cmath>
#include <csignal>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <thread>


namespace {

using namespace occ_improve;
using Pipeline = GrabberPipeline<pcl::PointXYZ>;

const ToolFlags kFlags{
    "occ_improve_live",
    {"SOURCE [options]"},
    "Fuses a stream of range frames into the occupancy grid and writes the maps, the same files as\n"
    "occ_improve_map (depth.png depth_mm.png occupancy.png improvement.png legend.png surface.pcd regions.csv\n"
    "regions.png rays.csv),\n"
    "at the end and every -save_every frames. Give exactly one source: -device, -oni, -pcd_dir, -depth_dir,\n"
    "-simulate or positional inputs (below). With poses, every frame is moved into the FIRST frame's sensor\n"
    "frame (the grid has one viewpoint; with -load, the map's). -simulate -load MAP continues MAP and its\n"
    "return record from the frame's viewpoint. -simulate also writes shots.csv and gain.png (expected gain per\n"
    "shot against rays asked), and with -predicted_depth nearest|linear predicted_depth.png (the map's dense\n"
    "depth from its samples, 16-bit mm, 0 = none within -radius). -view shows the improvement map and the\n"
    "top regions as frames arrive. Ctrl-C stops cleanly and still writes the maps. A file source's frame\n"
    "that cannot be used (unreadable, of another size, empty) is named and skipped: the maps of the others\n"
    "are written, and the tool exits 1.\n",
    joined({output_folder_flag_names(),
            {"-q", "-device", "-oni", "-pcd_dir", "-depth_dir", "-fps", "-drop", "-keep", "-max_frames", "-save_every",
             "-stop_on_signal", "-simulate", "-budget", "-shape", "-refine", "-window",
             "-negative_share", "-stop_gain", "-stop_share", "-max_shots", "-load", "-save", "-threads", "-k",
             "-min_improvement", "-predicted_depth", "-radius", "-view", "-view_screenshot"},
            sensor_flag_names(), camera_flag_names(), {"-no_poses", "-mask"}}),
    {{"-o", "occ_improve_live_out"}},
    {},
    frame_inputs_help()};

// Every write publishes the whole set (and the -save map), so the folder always holds one consistent state
// of the map; a failure anywhere commits nothing.
// What a -save keeps beside the grid: the planner's record (a -simulate run's, a -load map's) and the pose
// of the map's view (a -load map's, else the first posed frame's), so that a later -load continues it.
struct SavedWith {
  ReturnRecord returns;
  std::optional<Eigen::Isometry3d> world_from_map;
};

std::vector<std::string> write_maps(const Mapper& mapper, OutputFolder& out, MapSaveTarget& save,
                                    const RegionOptions& regions, int top_k, const SavedWith& with) {
  const std::vector<std::string> names = write_map_outputs(out, mapper, summarize_map(mapper, regions, top_k), std::nullopt);
  if (save.requested()) save_map(save.staged_path(), mapper.grid(), mapper.model().params(), with.returns, with.world_from_map);
  out.commit();
  save.commit();
  return names;
}

// ---- -simulate FRAME: the selective-acquisition loop against a virtual sensor over a real frame.

struct SimulatedShot {
  std::size_t rays_asked, returns;  ///< this shot's
  std::size_t rays_asked_total;
  double expected_gain;
};

void write_shots_csv(const std::string& path, const std::vector<SimulatedShot>& shots) {
  std::ofstream csv(path);
  csv << "shot,rays_asked,returns,rays_asked_total,expected_gain\n";
  for (std::size_t i = 0; i < shots.size(); ++i)
    csv << i + 1 << ',' << shots[i].rays_asked << ',' << shots[i].returns << ',' << shots[i].rays_asked_total << ','
        << shots[i].expected_gain << '\n';
  if (!csv.flush()) throw IoError("cannot write '" + path + "'");
}

std::size_t returned_this_run(const std::vector<SimulatedShot>& shots) {
  std::size_t returned = 0;
  for (const SimulatedShot& s : shots) returned += s.returns;
  return returned;
}

// One planned shot acquired and inserted; the return record learns which rays stayed silent.
SimulatedShot acquire(const Shot& shot, VirtualSensor& sensor, Mapper& mapper, ReturnRecord& returns,
                      std::size_t asked_before) {
  const std::vector<float> depth = sensor.shoot(shot.columns);  // pixel-native: column index = pixel index
  mapper.insert(PointSpan::from(sensor.points(shot.columns, depth)));
  const std::vector<std::uint8_t> got = VirtualSensor::returned(depth);
  const auto returned = static_cast<std::size_t>(std::count(got.begin(), got.end(), 1));
  returns.record_shot(shot.columns, got);
  return {shot.columns.size(), returned, asked_before + shot.columns.size(), shot.expected_gain};
}

// A simulation continues a -load map's own view: the frame must be of its camera, and of its pose when
// both have one (the virtual sensor acquires from the frame's viewpoint).
void require_simulation_fits_map(const ToolOptions& options, const ToolFrame& frame, const LoadedMap& loaded,
                                 const std::string& load_path) {
  require_frames_fit_loaded_map(loaded.grid.geometry(), frame.camera, load_path);
  if (!options.use_poses || !frame.pose || !loaded.world_from_sensor) return;
  const Eigen::Isometry3d between = loaded.world_from_sensor->inverse() * *frame.pose;
  if (between.translation().norm() > 1e-3 || Eigen::AngleAxisd(between.linear()).angle() > 1e-3)
    throw InvalidInput("-simulate " + frame.name + " is seen from another pose (" + frame.pose_source + ") than the map -load " +
                       load_path + " was saved at: a simulation continues the map's own view");
}

// A scene whose returns all lie outside the depth range gives the map nothing: 92 shots (4.9 frames' worth
// of rays) ran against a scene at 0.30-0.45 m, the map empty and every shot's expected gain the same.
void require_returns_to_acquire(const std::string& name, const GeometryParams& geometry, const std::vector<float>& depth) {
  InsertionReport counts;
  for (const float z : depth) {
    if (!(z > 0.0f)) continue;  // no return (0 or NaN)
    ++counts.points_inserted;
    counts.beyond_depth_range += z >= geometry.depth_max_m;
    counts.nearer_than_depth_range += z < geometry.depth_min_m;
  }
  if (!has_points_in_depth_range(counts))
    throw InvalidInput(nothing_in_depth_range("'" + name + "'", geometry, counts, "nothing to acquire"));
}

int run_simulation(const CommandLine& command_line, const ToolOptions& options, const RegionOptions& regions,
                   OutputFolder& out, MapSaveTarget& save, std::optional<LoadedMap> loaded, const std::string& load_path) {
  const std::string frame_path = *command_line.text("-simulate");
  const int max_shots = *command_line.integer("-max_shots");
  const ToolFrame frame = read_tool_frame(options, single_frame_source(frame_path, "-simulate"));
  SensorPreset preset = options.preset_for_camera(frame.camera);
  if (loaded) {  // the map's grid and model, checked as a preset of the flags would be
    preset.name = "loaded from " + load_path;
    preset.geometry = loaded->grid.geometry().params();
    preset.model = loaded->model;
  }
  if (preset.geometry.angular_binning != AngularBinning::pinhole || !frame.camera || frame.cloud.height <= 1)
    throw InvalidParameter("-simulate " + frame_path + " needs an organized frame and a pixel-native " +
                           (loaded ? "map (-load " + load_path + " is not)" : std::string("preset (kinect_v1)")) +
                           ": the plan's rays are the sensor's pixels");
  if (loaded) require_simulation_fits_map(options, frame, *loaded, load_path);
  // The map's view: a -load map's pose, else the frame's (the simulation acquires from the frame's viewpoint).
  SavedWith with;
  with.world_from_map = loaded && loaded->world_from_sensor ? loaded->world_from_sensor
                        : options.use_poses                 ? frame.pose
                                                            : std::nullopt;
  std::printf("%s\n", describe_camera({frame}).c_str());
  const std::vector<float> scene_depth = depth_of_organized(frame.cloud);
  require_returns_to_acquire(frame.name, preset.geometry, scene_depth);
  VirtualSensor sensor(scene_depth, *frame.camera);
  Mapper mapper = loaded ? Mapper(std::move(loaded->grid), SensorModel(loaded->model)) : Mapper(preset, options.grid);
  const std::string mask_line = apply_tool_mask(command_line, mapper, &frame);
  if (!mask_line.empty()) std::printf("%s\n", mask_line.c_str());
  // A -load map's record: the plan goes on knowing which rays never return.
  ReturnRecord& returns = with.returns;
  returns = loaded ? std::move(loaded->returns) : ReturnRecord::for_grid(mapper.geometry().width(), mapper.geometry().height());
  if (loaded)
    std::printf("continuing the map loaded from %s: %llu rays asked before, %llu returned\n", load_path.c_str(),
                static_cast<unsigned long long>(returns.total_asked()), static_cast<unsigned long long>(returns.total_returned()));
  PlanRequest request = plan_request_from_flags(command_line);
  fit_plan_to_grid(command_line, request, mapper.geometry().width(), mapper.geometry().height());
  std::printf("preset %s, %d rays per shot\n", preset.name.c_str(), request.budget_rays);
  request.candidates = mapper.column_mask();  // rays outside -mask are never asked for
  std::vector<SimulatedShot> shots;
  PlanMemory memory;  // the measured samples' triangulation, extended shot by shot
  std::string why = "reached -max_shots " + std::to_string(max_shots);
  ProgressLine progress(command_line, "shot");
  const auto start = SteadyClock::now();
  try {
    while (static_cast<int>(shots.size()) < max_shots) {
      throw_if_stop_requested();
      const Shot shot = plan_next_shot(mapper, returns, request, memory);
      if (shot.stop) {
        why = "the plan says stop: " + shot.reason;
        break;
      }
      shots.push_back(acquire(shot, sensor, mapper, returns, shots.empty() ? 0 : shots.back().rays_asked_total));
      char line[160];
      std::snprintf(line, sizeof line, "shot %zu: %zu rays asked (%.2f frames), expected gain %.1f", shots.size(),
                    shots.back().rays_asked_total,
                    static_cast<double>(shots.back().rays_asked_total) / static_cast<double>(mapper.geometry().column_count()),
                    shots.back().expected_gain);
      progress.show(line);
    }
  } catch (const Cancelled&) {
    why = "interrupted";  // what was acquired is still written, as a live run's map is
  }
  const int signal = take_stop_request();
  progress.finish();
  write_shots_csv(out.file("shots.csv"), shots);
  std::vector<double> asked, gain;
  for (const SimulatedShot& s : shots) {
    asked.push_back(static_cast<double>(s.rays_asked_total));
    gain.push_back(s.expected_gain);
  }
  if (shots.size() >= 2) write_png(out.file("gain.png"), render_curve(asked, gain));
  const std::string predicted =
      write_predicted_depth(out, mapper, *command_line.text("-predicted_depth"), *command_line.integer("-radius"));
  const std::vector<std::string> names = write_maps(mapper, out, save, regions, options.top_k, with);
  const double seconds = seconds_since(start);
  std::printf("%zu shots, %zu rays asked (%.2f frames), %zu returned, in %.2f s; stopped: %s\n", shots.size(),
              shots.empty() ? 0 : shots.back().rays_asked_total,
              shots.empty() ? 0.0 : static_cast<double>(shots.back().rays_asked_total) / static_cast<double>(mapper.geometry().column_count()),
              returned_this_run(shots), seconds, why.c_str());
  std::printf("wrote %s/: shots.csv%s%s %s\n", out.path().c_str(), shots.size() >= 2 ? " gain.png" : "",
              predicted.empty() ? "" : " predicted_depth.png", join_names(names).c_str());
  if (signal) throw Cancelled(signal);
  return 0;
}

// The stream a run reads, and the sensor preset that fits it.
struct StreamSource {
  std::shared_ptr<pcl::Grabber> grabber;
  FileSequenceGrabber* file_source = nullptr;  ///< the grabber, when it replays files (paced, finite)
  SensorPreset preset;
  std::optional<PinholeIntrinsics> frames_camera;  ///< the frames' camera, where known (a -load map must fit it)
  std::string text, camera;  ///< for the summary
  bool poses_applied = false;  ///< the frames are moved into the first one's view (or a -load map's)
  std::optional<Eigen::Isometry3d> world_from_map;  ///< where the frames' view lies (posed frames), if known
  /// Frames the source skips by design and announces in `text` (a TUM sequence's frames before its ground
  /// truth starts): counted among its errors, but not a failure of the run.
  std::size_t announced_skips = 0;
};

std::string poses_text(bool applied, bool into_loaded_map = false) {
  return !applied ? "no poses" : into_loaded_map ? "poses applied: frames moved into the loaded map's view"
                                                 : "poses applied: map in the first frame's view";
}

// A -load map the frames go into: with poses, they are moved into its view by the pose saved with it.
struct MapView {
  std::string path;
  std::optional<Eigen::Isometry3d> pose;
};

StreamSource open_device(const ToolOptions& options, const std::optional<std::string>& device, const std::string& oni) {
  StreamSource s;
  s.grabber = open_openni2_grabber(device ? *device : oni);
  s.preset = options.preset_for_camera(std::nullopt);
  s.frames_camera = s.preset.camera;  // the device's frames are taken as this camera's
  s.text = device ? "OpenNI2 device " + (device->empty() ? std::string("(first)") : *device) : "recording " + oni;
  s.camera = options.intrinsics ? "camera from " + options.intrinsics_flag
                                : "camera: Kinect v1 defaults fx = fy = 525 (give -intrinsics for another device)";
  return s;
}

StreamSource open_depth_dir(const ToolOptions& options, const std::string& depth_dir, int max_frames, double fps,
                            const std::optional<MapView>& map) {
  DepthSequence sequence = scan_depth_sequence(depth_dir);
  if (max_frames > 0 && sequence.frames.size() > static_cast<std::size_t>(max_frames))
    sequence.frames.resize(static_cast<std::size_t>(max_frames));  // file sources stop exactly there
  const std::optional<PinholeIntrinsics> camera = options.intrinsics ? options.intrinsics : sequence.intrinsics;
  if (!camera) throw InvalidParameter("-depth_dir " + depth_dir + ": no camera-intrinsics.txt there; give -intrinsics or -intrinsics_file");
  DepthSequenceOptions sequence_options;
  sequence_options.fps = static_cast<float>(fps);
  sequence_options.use_poses = options.use_poses;
  sequence_options.encoding = options.depth_encoding;
  if (map) sequence_options.world_from_map = map->pose;
  auto grabber = std::make_shared<DepthSequenceGrabber>(sequence, *camera, sequence_options);
  if (map && grabber->posesApplied() && !map->pose) refuse_posed_frames_into_unposed_map(map->path, depth_dir, "its pose files");
  StreamSource s;
  if (grabber->posesApplied()) s.world_from_map = grabber->worldFromMap();
  s.preset = options.preset_for_camera(camera);
  s.frames_camera = camera;
  s.camera = options.intrinsics ? "camera from " + options.intrinsics_flag : "camera from " + depth_dir + "'s intrinsics file";
  s.text = depth_dir + " (" + std::to_string(sequence.frames.size()) + " depth frames, " +
           poses_text(grabber->posesApplied(), map.has_value()) +
           (grabber->unposedFrames() > 0 ? "; " + std::to_string(grabber->unposedFrames()) + " without a pose skipped" : "") +
           ")";
  s.poses_applied = grabber->posesApplied();
  s.announced_skips = grabber->unposedFrames();
  s.file_source = grabber.get();
  s.grabber = grabber;
  return s;
}

// -pcd_dir's PCD files, or the positional inputs of any kind (expand_input, as every tool reads them).
StreamSource open_files(const ToolOptions& options, const std::string& pcd_dir, int max_frames, double fps,
                        const std::optional<MapView>& map) {
  std::vector<FrameSource> frames;
  if (!pcd_dir.empty()) {
    const PcdSequenceGrabber listing(pcd_dir);
    for (const std::string& file : listing.files()) frames.push_back(FrameSource{file, std::nullopt});
  }
  for (const std::string& input : options.inputs)
    for (FrameSource& frame : expand_input(input)) frames.push_back(std::move(frame));
  if (max_frames > 0 && frames.size() > static_cast<std::size_t>(max_frames))
    frames.resize(static_cast<std::size_t>(max_frames));
  // The first frame's camera (fitted to its organized points unless -intrinsics is given).
  const ToolFrame first = read_tool_frame(options, frames.front());
  const std::string files_text = frames.size() == 1 ? frames.front().path
                                                    : frames.front().path + " and " + std::to_string(frames.size() - 1) + " more";
  const bool posed = first.pose && options.use_poses;
  // The frames, the first too, are moved into the reference's view: a -load map's, else the first frame's.
  const ToolFrame reference = map ? loaded_map_reference(options, first, map->pose, map->path) : frame_header(first);
  auto grabber = std::make_shared<ToolFrameGrabber>(options, reference, std::move(frames), static_cast<float>(fps));
  StreamSource s;
  if (posed) s.world_from_map = first.pose;
  s.preset = options.preset_for_camera(first.camera);
  s.frames_camera = first.camera;
  s.camera = describe_camera({first});
  s.text = (pcd_dir.empty() ? files_text : pcd_dir) + " (" + std::to_string(grabber->frameCount()) + " frames, " +
           poses_text(posed, map.has_value()) + ")";
  s.poses_applied = posed;
  s.file_source = grabber.get();
  s.grabber = grabber;
  return s;
}

// A saved map fixes the geometry and the model; the source's frames must fit it.
std::shared_ptr<Mapper> make_mapper(std::optional<LoadedMap>& loaded, const std::string& load_path,
                                    const ToolOptions& options, StreamSource& source) {
  SensorPreset& preset = source.preset;
  if (!loaded) return std::make_shared<Mapper>(preset, options.grid);
  require_frames_fit_loaded_map(loaded->grid.geometry(), source.frames_camera, load_path);
  auto mapper = std::make_shared<Mapper>(std::move(loaded->grid), SensorModel(loaded->model));
  preset.name = "loaded from " + load_path;
  preset.geometry = mapper->geometry().params();
  preset.model = mapper->model().params();
  return mapper;
}

constexpr const char* kStopSignalReason = "stop signal";
// How long a first Ctrl-C lets the frames in flight finish (a Kinect frame takes 40-100 ms on two cores): the
// follow loop's 200 ms poll plus this keeps the stop within a second.
constexpr std::chrono::milliseconds kFinishInFlight{500};

// ---- -view: the window is opened (its display checked) before any work, and refreshed by follow_stream.

std::unique_ptr<LiveView> open_view(const CommandLine& command_line) {
  if (!command_line.has("-view")) return nullptr;
  if (command_line.has("-simulate")) throw InvalidParameter("-view shows a stream of frames: not with -simulate");
  return std::make_unique<LiveView>("occ_improve_live");
}

// -view_screenshot FILE: an output file as -save is (checked now, written after the maps), never inside the
// -o folder, which a run replaces as a whole.
std::unique_ptr<OutputFile> open_screenshot(const CommandLine& command_line, const OutputFolder& out,
                                            const MapSaveTarget& save) {
  if (!command_line.has("-view_screenshot")) return nullptr;
  const std::string path = *command_line.text("-view_screenshot");
  if (!command_line.has("-view")) throw InvalidParameter("-view_screenshot " + path + " needs -view");
  if (path_is_within(path, out.resolved().string()))
    throw InvalidParameter("-view_screenshot '" + path + "' is inside the -o folder '" + out.path() +
                           "': write it beside the folder");
  if (save.requested()) require_distinct_outputs(save.path(), "-save", path, "-view_screenshot");
  return open_output_file(command_line, "-view_screenshot", is_live_view_screenshot, "a screenshot");
}

// The final map in the window (the maps just written), then its pixels into the screenshot file.
void finish_view(LiveView& view, OutputFile* screenshot, const Mapper& mapper, const std::optional<FrameResult>& last,
                 std::uint64_t processed) {
  view.post(mapper.improvement(), last ? last->top_regions : std::vector<Region>{}, processed);
  if (!screenshot) return;
  if (!view.save_screenshot(screenshot->staged())) {
    pcl::console::print_warn("The window was closed: no screenshot written to %s\n", screenshot->path().c_str());
    return;
  }
  screenshot->commit();
  pcl::console::print_info("Wrote the view to %s\n", screenshot->path().c_str());
}

// When the run ends, besides the source finishing.
struct StreamLimits {
  bool stop_on_signal;
  int max_frames;
};

// The stop signal of a processed frame, as the result callback sets it: follow_stream wakes on it at once
// rather than at its next 200 ms poll, so -stop_on_signal ends the run before the frames after it are
// taken (at 40-50 ms a frame, a poll let ~4 more into the map). With -view the window's own 200 ms
// refresh still paces the loop.
struct StopWake {
  std::atomic<bool> fired{false};
  std::mutex mutex;
  std::condition_variable woken;
  void fire() {
    {
      const std::lock_guard<std::mutex> lock(mutex);
      fired = true;
    }
    woken.notify_all();
  }
  // Waits up to `period`, or less when the signal fires and `stop_on_signal` asks to end on it, or on
  // Ctrl-C: a signal handler cannot notify, so that is polled every 20 ms (at a 200 ms wait, 4-6 frames
  // went into the map after the Ctrl-C).
  void wait(std::chrono::milliseconds period, bool stop_on_signal) {
    const auto until = std::chrono::steady_clock::now() + period;
    std::unique_lock<std::mutex> lock(mutex);
    const auto done = [&] { return (stop_on_signal && fired.load()) || stop_requested() || soft_stop_signal(); };
    while (!done() && std::chrono::steady_clock::now() < until)
      woken.wait_until(lock, std::min(until, std::chrono::steady_clock::now() + std::chrono::milliseconds(20)), done);
  }
};

// Polls the running pipeline, showing its counters (and keeping the -view window live), until the source
// is done or a limit is reached.
const char* follow_stream(Pipeline& pipeline, const StreamSource& source, const StreamLimits& limits,
                          StopWake& stop_wake, ProgressLine& progress, LiveView* view) {
  for (;;) {
    if (!view)
      stop_wake.wait(std::chrono::milliseconds(200), limits.stop_on_signal);
    else if (!view->spin_for(std::chrono::milliseconds(200)))
      return "view window closed";
    const PipelineStatistics s = pipeline.statistics();
    char line[200];
    std::snprintf(line, sizeof line, "frames %llu, processed %llu, dropped %llu, rejected %llu, %.1f frames/s",
                  static_cast<unsigned long long>(s.received), static_cast<unsigned long long>(s.processed),
                  static_cast<unsigned long long>(s.dropped), static_cast<unsigned long long>(s.rejected),
                  s.processed_per_second());
    progress.show(line);
    if (stop_requested() || soft_stop_signal()) return "interrupted";
    if (limits.stop_on_signal && stop_wake.fired) return kStopSignalReason;
    if (limits.max_frames > 0 && s.processed >= static_cast<std::uint64_t>(limits.max_frames)) return "-max_frames reached";
    if (source.file_source && !source.file_source->isRunning() && s.in_flight == 0) return "source finished";
  }
}

// `fired`: the first frame whose stop signal fired (the one that ends a -stop_on_signal run); the frames
// processed after it may have made progress again, so the last frame's signal can read "continue".
void print_stream_summary(const PipelineStatistics& s, bool keeping, const char* stop_reason,
                          const std::optional<FrameResult>& fired, const std::optional<FrameResult>& last) {
  if (fired && std::string(stop_reason) == kStopSignalReason)
    pcl::console::print_info("Stopped: %s (frame %llu: %s)\n", stop_reason,
                             static_cast<unsigned long long>(fired->frame_index + 1), fired->stop.reason.c_str());
  else
    pcl::console::print_info("Stopped: %s\n", stop_reason);
  pcl::console::print_info(
      "Frames: %llu received, %llu processed, %llu dropped, %llu rejected, %llu cut short by the stop, %llu source "
      "errors in %.2f s (%.1f frames/s)\n",
      static_cast<unsigned long long>(s.received), static_cast<unsigned long long>(s.processed),
      static_cast<unsigned long long>(s.dropped), static_cast<unsigned long long>(s.rejected),
      static_cast<unsigned long long>(s.interrupted),
      static_cast<unsigned long long>(s.grabber_errors), s.wall_seconds, s.processed_per_second());
  if (keeping) {
    pcl::console::print_info("Per frame [ms]: convert %.1f, keep %.1f, insert+surface %.1f, improvement %.1f, regions %.1f\n",
                             s.mean_ms(s.convert_ms), s.mean_ms(s.keep_ms), s.mean_ms(s.insert_ms),
                             s.mean_ms(s.improvement_ms), s.mean_ms(s.regions_ms));
    pcl::console::print_info("Points: %llu received, %llu inserted, %llu left out by -keep (invalid and outside the "
                             "view included)\n",
                             static_cast<unsigned long long>(s.points_received),
                             static_cast<unsigned long long>(s.points_received - s.points_not_kept),
                             static_cast<unsigned long long>(s.points_not_kept));
  } else {
    pcl::console::print_info("Per frame [ms]: convert %.1f, insert+surface %.1f, improvement %.1f, regions %.1f\n",
                             s.mean_ms(s.convert_ms), s.mean_ms(s.insert_ms), s.mean_ms(s.improvement_ms),
                             s.mean_ms(s.regions_ms));
  }
  if (!last) return;
  if (fired && std::string(stop_reason) != kStopSignalReason)
    pcl::console::print_info("Stop signal first fired at frame %llu: %s\n",
                             static_cast<unsigned long long>(fired->frame_index + 1), fired->stop.reason.c_str());
  pcl::console::print_info("Stop signal after the last frame (%llu): %s (%s)\n",
                           static_cast<unsigned long long>(last->frame_index + 1), last->stop.stop ? "yes" : "no",
                           last->stop.reason.c_str());
  // u, v: the region's centre column (pixel with the pixel-native presets); the angles are its direction's.
  for (std::size_t i = 0; i < last->top_regions.size(); ++i) {
    const Region& r = last->top_regions[i];
    pcl::console::print_info(
        "  region %zu: improvement %.2f over %zu rays, centre u %d v %d, azimuth %.1f deg, elevation %.1f deg, "
        "depth %.2f m\n",
        i + 1, r.summed_improvement, r.area_columns, r.centre_u, r.centre_v, r.centre_azimuth_rad * 180.0 / M_PI,
        r.centre_elevation_rad * 180.0 / M_PI, r.mean_depth_m);
  }
}

int run(const CommandLine& command_line) {
  const ToolOptions options = parse_tool_options(command_line);
  const std::optional<std::string> device = command_line.has("-device") ? command_line.text("-device").value_or("")
                                                                        : std::optional<std::string>();
  const std::string load_path = command_line.text("-load").value_or("");
  const std::string oni = command_line.text("-oni").value_or("");
  const std::string pcd_dir = command_line.text("-pcd_dir").value_or("");
  const std::string depth_dir = command_line.text("-depth_dir").value_or("");
  const int save_every = *command_line.integer("-save_every");
  const double fps = *command_line.number("-fps");
  if (fps > 0 && fps < kMinimumFps)  // a longer frame period overflows the grabber's clock
    throw InvalidParameter("-fps " + *command_line.text("-fps") + " is invalid: must be 0 (as fast as possible) or at least 0.001");
  const int max_frames = *command_line.integer("-max_frames");
  RegionOptions region_options;
  region_options.min_improvement = static_cast<float>(*command_line.number("-min_improvement"));
  const bool simulate = command_line.has("-simulate");
  const int sources = (device ? 1 : 0) + !oni.empty() + !pcd_dir.empty() + !depth_dir.empty() +
                      !options.inputs.empty() + simulate;
  if (sources != 1)
    throw InvalidParameter("give exactly one source (-device, -oni, -pcd_dir, -depth_dir, input files or -simulate); see -h");
  OutputFolder out = open_output_folder(command_line);
  MapSaveTarget save(command_line, &out);
  if (!simulate && *command_line.text("-predicted_depth") != "none")
    throw InvalidParameter("-predicted_depth is written by -simulate runs only");
  if (simulate && command_line.has("-keep"))
    throw InvalidParameter("-keep thins a stream's frames; -simulate plans its own shots (-budget)");
  for (const char* flag : {"-budget", "-shape", "-refine", "-window", "-negative_share", "-stop_gain", "-stop_share",
                           "-max_shots"})
    warn_if_ignored(command_line, flag, "-simulate", simulate);
  for (const char* flag : {"-fps", "-drop", "-max_frames", "-save_every", "-stop_on_signal"})
    if (simulate && command_line.has(flag))
      std::fprintf(stderr, "warning: %s applies to a stream (-device, -oni, -pcd_dir, -depth_dir, input files), not to "
                           "-simulate: ignored\n", flag);
  warn_if_ignored(command_line, "-radius", "-predicted_depth", *command_line.text("-predicted_depth") != "none");
  const std::unique_ptr<OutputFile> screenshot = open_screenshot(command_line, out, save);
  const std::unique_ptr<LiveView> view = open_view(command_line);
  // Read before the source opens: its pose places the frames in its view, its record is kept by -save.
  std::optional<LoadedMap> loaded;
  if (!load_path.empty()) loaded = load_tool_map(load_path, options);
  if (simulate) return run_simulation(command_line, options, region_options, out, save, std::move(loaded), load_path);
  const std::optional<MapView> map_view =
      loaded ? std::optional<MapView>(MapView{load_path, loaded->world_from_sensor}) : std::nullopt;
  SavedWith saved_with{loaded ? std::move(loaded->returns) : ReturnRecord(), std::nullopt};

  StreamSource source = device || !oni.empty() ? open_device(options, device, oni)
                        : !depth_dir.empty()   ? open_depth_dir(options, depth_dir, max_frames, fps, map_view)
                                               : open_files(options, pcd_dir, max_frames, fps, map_view);
  saved_with.world_from_map = map_view ? map_view->pose : source.world_from_map;  // the map's view
  const InputScope scope(source.text);
  PipelineOptions pipeline_options;
  pipeline_options.insertion.threads = *command_line.integer("-threads");
  pipeline_options.top_regions = static_cast<std::size_t>(options.top_k);
  pipeline_options.regions = region_options;  // the regions shown by -view are regions.csv's
  pipeline_options.backpressure = source.file_source != nullptr && !command_line.has("-drop");
  pipeline_options.keep_fraction = *command_line.number("-keep");
  const std::shared_ptr<Mapper> mapper = make_mapper(loaded, load_path, options, source);
  // A stream has no first frame yet: -mask finite is refused here, a PNG mask applies to every frame.
  const std::string mask_line = apply_tool_mask(command_line, *mapper, nullptr);
  // Before the pipeline, whose end stops the grabber thread that calls it.
  const bool check_scenes = source.file_source && !source.poses_applied && source.file_source->frameCount() > 1;
  UnposedSceneCheck scenes(source.preset.model, check_scenes,
                           "Give their poses (a dataset's pose files, a PCD's VIEWPOINT), or map them one by one "
                           "(occ_improve_map -input_dir DIR -output_dir OUTDIR)");
  std::atomic<bool> check_scene_failed{false};
  Pipeline pipeline(mapper, with_camera(pipeline_options, source.preset));

  // The files' names in the order the pipeline receives them (its frame_index), for the warnings: recorded
  // by a slot connected before the pipeline's, so a name is in before its frame is queued.
  std::mutex names_mutex;
  std::vector<std::string> received_names;
  const boost::signals2::scoped_connection name_connection =
      source.file_source ? source.grabber->registerCallback(std::function<void(const Pipeline::Cloud::ConstPtr&)>(
                               [&](const Pipeline::Cloud::ConstPtr&) {
                                 const std::lock_guard<std::mutex> lock(names_mutex);
                                 received_names.push_back(source.file_source->emittingFrameName());
                               }))
                         : boost::signals2::connection();
  const auto frame_name = [&](std::uint64_t index) {
    const std::lock_guard<std::mutex> lock(names_mutex);
    return index < received_names.size() ? received_names[index] : "frame " + std::to_string(index + 1);
  };
  std::mutex report_mutex;
  std::optional<FrameResult> last, fired;
  InsertionReport points;  // every processed frame's, for the summary's points line
  OutOfViewCheck out_of_view("Map each view by itself (occ_improve_map -save) and merge the maps: occ_to_octomap "
                             "-load MAP -pose P per map");
  StopWake stop_wake;
  std::atomic<int> maps_written{0};
  std::uint64_t frames_seen = 0;  // only touched by the worker
  pipeline.setResultCallback([&](const FrameResult& r) {
    {
      std::lock_guard<std::mutex> lock(report_mutex);
      last = r;
      points += r.report.insertion;
      out_of_view.add(frame_name(r.frame_index), r.report.insertion);
      if (r.stop.stop && !fired) fired = r;
    }
    if (r.stop.stop) stop_wake.fire();
    ++frames_seen;
    if (view) view->post(pipeline.mapper().improvement(), r.top_regions, frames_seen);
    if (save_every > 0 && frames_seen % static_cast<std::uint64_t>(save_every) == 0) {
      write_maps(pipeline.mapper(), out, save, region_options, options.top_k, saved_with);
      ++maps_written;
    }
  });
  ProgressLine progress(command_line, "frame");
  pipeline.setEventCallback([&](const PipelineEvent& e) {
    progress.finish();
    pcl::console::print_warn("%s\n", e.message.c_str());
  });
  if (source.file_source)
    source.file_source->setErrorCallback([&](const std::string& message) { pipeline.reportSourceError(message); });
  pipeline.attach(*source.grabber);
  // Files without poses: frames of other scenes or viewpoints would be fused as one view unnoticed (the other
  // tools warn the same way). On the grabber's thread, as each frame is delivered; an advisory check, so one
  // that cannot run (out of memory) stops checking rather than ending the reading thread.
  std::function<void(const Pipeline::Cloud::ConstPtr&)> check_scene = [&](const Pipeline::Cloud::ConstPtr& cloud) {
    if (check_scene_failed) return;
    try {
      scenes.add(source.file_source->emittingFrameName(), *cloud);
    } catch (const std::exception&) {
      check_scene_failed = true;
    }
  };
  const boost::signals2::scoped_connection scene_connection =
      check_scenes ? source.grabber->registerCallback(check_scene) : boost::signals2::connection();

  const GeometryParams& g = source.preset.geometry;
  pcl::console::print_info("%s\n", source.camera.c_str());
  if (!mask_line.empty()) pcl::console::print_info("%s\n", mask_line.c_str());
  pcl::console::print_info("Source: %s\nPreset: %s (%dx%d rays, %d depth bins, %.2f-%.2f m)\n", source.text.c_str(),
                           source.preset.name.c_str(), g.azimuth_bins, g.elevation_bins, g.depth_bins, g.depth_min_m,
                           g.depth_max_m);
  // A first Ctrl-C lets the frame in flight (and one waiting) finish, so that the map holds whole frames;
  // past kFinishInFlight the stop cancels it (counted as cut short), and a second Ctrl-C at once.
  defer_first_stop_signal();
  pipeline.start();
  const char* stop_reason =
      follow_stream(pipeline, source, {command_line.has("-stop_on_signal"), max_frames}, stop_wake, progress, view.get());
  {
    const CancelAfter cancel_if_slow(soft_stop_signal(), kFinishInFlight);
    pipeline.stop();
  }
  progress.finish();
  for (const std::string& warning : {scenes.warning(), out_of_view.warning()})
    if (!warning.empty()) pcl::console::print_warn("%s\n", warning.c_str());
  const int cancelled = take_stop_request();  // the maps so far are still written below
  const int signal = cancelled ? cancelled : soft_stop_signal();
  const PipelineStatistics statistics = pipeline.statistics();  // final: the pipeline is stopped
  if (statistics.processed == 0 && !signal)
    throw InvalidInput("no frame of " + source.text + " was used (" + std::to_string(statistics.rejected) +
                       " rejected: empty, all NaN or all zero, or of the wrong size; " +
                       std::to_string(statistics.grabber_errors) + " unreadable)");
  const std::vector<std::string> written = write_maps(pipeline.mapper(), out, save, region_options, options.top_k, saved_with);
  if (save.requested()) pcl::console::print_info("Saved the grid to %s\n", save.path().c_str());
  if (view) finish_view(*view, screenshot.get(), pipeline.mapper(), last, statistics.processed);
  print_stream_summary(statistics, pipeline_options.keep_fraction < 1.0, stop_reason, fired, last);
  if (pipeline_options.keep_fraction >= 1.0) pcl::console::print_info("%s\n", describe_points(points).c_str());
  pcl::console::print_info("Wrote %s/: %s (%d intermediate writes)\n", out.path().c_str(), join_names(written).c_str(),
                           maps_written.load());
  // The maps so far are written above: a stream is normally ended by Ctrl-C, and its maps are valid.
  if (signal) throw Cancelled(signal);
  // Files are the user's input, not a live sensor's passing glitch: a frame that could not be used fails the
  // run (as the other tools refuse it), after the maps of the others are written and the warnings above
  // named each one.
  const std::uint64_t unreadable = statistics.grabber_errors - std::min<std::uint64_t>(statistics.grabber_errors, source.announced_skips);
  if (const std::uint64_t unused = statistics.rejected + unreadable; source.file_source && unused > 0)
    throw InvalidInput(std::to_string(unused) + " frame(s) of " + source.text + " could not be used (" +
                       std::to_string(statistics.rejected) + " rejected, " + std::to_string(unreadable) +
                       " skipped by the source: each named above); the maps written hold the other " +
                       std::to_string(statistics.processed));
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return occ_improve::run_tool(argc, argv, kFlags, run); }
