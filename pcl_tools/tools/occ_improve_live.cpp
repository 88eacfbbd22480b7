// occ_improve_live: fuse a stream of range frames (OpenNI2 device, .oni recording, PCD folder or
// depth-image sequence) into the occupancy grid (along the sensor's rays) as they arrive, and keep the depth,
// occupancy and improvement maps written to a folder.
#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/map_io.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/grabber_pipeline.hpp"
#include "occ_improve/pcl/sequence_sources.hpp"
#include "occ_improve/pcl/tool_options.hpp"
#include "occ_improve/planner.hpp"
#include "occ_improve/render.hpp"
#include "occ_improve/return_model.hpp"
#include "occ_improve/virtual_sensor.hpp"

#include <pcl/console/parse.h>
#include <pcl/console/print.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <thread>

#include <unistd.h>

namespace {

using namespace occ_improve;
using Pipeline = GrabberPipeline<pcl::PointXYZ>;

void print_usage(const char* program) {
  std::cout << "Usage: " << program << " <source> [options]\n"
            << "Fuses a stream of range frames into the occupancy grid and writes the maps.\n\n"
            << "Source (exactly one):\n"
            << "  -device [URI]             live OpenNI2 device (first one found, or its URI)\n"
            << "  -oni FILE                 OpenNI2 recording\n"
            << "  -pcd_dir DIR              the .pcd files of a folder, in name order\n"
            << "  -depth_dir DIR            depth-image sequence: 7-Scenes (frame-*.depth.png, .pose.txt,\n"
            << "                            camera-intrinsics.txt), TUM RGB-D (depth.txt, groundtruth.txt) or\n"
            << "                            a folder of 16-bit PNG/PGM; needs intrinsics unless the folder has them\n"
            << "  FILE.pcd ...              positional PCD files, in order\n"
            << "  -simulate FRAME           the closed loop of docs/SELECTIVE.md against a virtual Kinect v1 over\n"
            << "                            one real frame (organized PCD or depth image): plan a shot, acquire its\n"
            << "                            rays (axial noise, disparity quantisation, no return where the frame\n"
            << "                            has none), insert, learn which rays never return, until the plan says\n"
            << "                            stop; writes shots.csv and gain.png (expected gain per shot against\n"
            << "                            rays asked) with the maps. Pixel-native presets only.\n"
            << "  -budget N                 -simulate: rays per shot (default 4096)\n"
            << "  -max_shots N              -simulate: stop after N shots at the latest (default 1000)\n"
            << "With poses, every frame is moved into the FIRST frame's sensor frame (the grid has one\n"
            << "viewpoint).\n\n"
            << "Pipeline:\n"
            << usage_output_folder("occ_improve_live_out")
            << "  -save_every N             also write the maps every N processed frames (default 0: at the end)\n"
            << "  -load MAP.occmap          continue a saved grid from the same viewpoint (it carries its own\n"
            << "                            preset; preset flags are ignored; poses are relative to this run's first frame)\n"
            << "  -save MAP.occmap          save the grid at the end (and with the maps every -save_every frames)\n"
            << "  -fps F                    file sources: frames per second (default 0: as fast as possible)\n"
            << "  -threads N                insertion threads (default 0: all cores)\n"
            << "  -drop                     file sources: newest frame wins like a live sensor (default: every\n"
            << "                            frame is processed)\n"
            << "  -no_poses                 ignore the sequence's poses\n"
            << "  -stop_on_signal           stop once the improvement stop signal fires\n"
            << "  -max_frames N             file sources: only the first N frames; live: stop after N processed\n"
            << "Ctrl-C stops cleanly and still writes the maps.\n\n"
            << usage_common();
}

/// The argument vector without "-device [URI]", which tool_options does not know; returns the URI
/// (empty for the first device) when -device was given.
std::optional<std::string> take_device_flag(std::vector<const char*>& args) {
  for (std::size_t i = 1; i < args.size(); ++i) {
    if (std::string(args[i]) != "-device") continue;
    std::string uri;
    std::size_t erase = 1;
    if (i + 1 < args.size() && args[i + 1][0] != '-') {
      uri = args[i + 1];
      erase = 2;
    }
    args.erase(args.begin() + static_cast<std::ptrdiff_t>(i), args.begin() + static_cast<std::ptrdiff_t>(i + erase));
    return uri;
  }
  return std::nullopt;
}

// Every write publishes the whole set, so the folder always holds one consistent state of the map.
void write_maps(const Mapper& mapper, OutputFolder& out, double depth_max_m) {
  write_png(out.file("depth.png"), render_depth(mapper.surface(), depth_max_m));
  write_png(out.file("occupancy.png"), render_occupancy(mapper.surface()));
  write_png(out.file("improvement.png"), render_improvement(mapper.improvement()));
  write_png(out.file("improvement_legend.png"), render_improvement_legend());
  out.commit();
}

template <typename T>
T parse_number(int argc, const char* const* argv, const char* flag, T fallback, T minimum) {
  T value = fallback;
  if (pcl::console::parse_argument(argc, argv, flag, value) >= 0 && value < minimum)
    throw InvalidParameter(std::string(flag) + " " + std::to_string(value) + " is invalid: must be >= " +
                           std::to_string(minimum));
  return value;
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

// One planned shot acquired and inserted; the return record learns which rays stayed silent.
SimulatedShot acquire(const Shot& shot, VirtualSensor& sensor, Mapper& mapper, ReturnRecord& returns,
                      std::size_t asked_before) {
  const std::vector<float> depth = sensor.shoot(shot.columns);  // pixel-native: column index = pixel index
  mapper.insert(PointSpan::from(sensor.points(shot.columns, depth)));
  std::vector<std::uint8_t> got(depth.size());
  std::size_t returned = 0;
  for (std::size_t i = 0; i < depth.size(); ++i) returned += got[i] = depth[i] > 0.0f;
  returns.record_shot(shot.columns, got);
  return {shot.columns.size(), returned, asked_before + shot.columns.size(), shot.expected_gain};
}

int run_simulation(const ToolOptions& options, const std::string& frame_path, int budget, int max_shots,
                   OutputFolder& out) {
  const ToolFrame frame = read_tool_frame(options, FrameSource{frame_path, std::nullopt});
  const SensorPreset preset = options.preset_for_camera(frame.camera);
  if (preset.geometry.angular_binning != AngularBinning::pinhole || !frame.camera || frame.cloud.height <= 1)
    throw InvalidParameter("-simulate " + frame_path + " needs an organized frame and a pixel-native preset "
                           "(kinect_v1): the plan's rays are the sensor's pixels");
  std::printf("%s\npreset %s, %d rays per shot\n", describe_camera({frame}).c_str(), preset.name.c_str(), budget);
  VirtualSensor sensor(depth_of_organized(frame.cloud), *frame.camera);
  Mapper mapper(preset, options.grid);
  ReturnRecord returns = ReturnRecord::for_grid(mapper.geometry().width(), mapper.geometry().height());
  PlanRequest request;
  request.budget_rays = budget;
  std::vector<SimulatedShot> shots;
  std::string why = "reached -max_shots " + std::to_string(max_shots);
  const bool terminal = isatty(fileno(stdout)) != 0;
  const auto start = std::chrono::steady_clock::now();
  try {
    while (static_cast<int>(shots.size()) < max_shots) {
      throw_if_interrupted();
      const Shot shot = plan_next_shot(mapper.improvement(), returns, request);
      if (shot.stop) {
        why = "the plan says stop: " + shot.reason;
        break;
      }
      shots.push_back(acquire(shot, sensor, mapper, returns, shots.empty() ? 0 : shots.back().rays_asked_total));
      if (terminal)
        std::printf("\rshot %zu: %zu rays asked (%.2f frames), expected gain %.1f   ", shots.size(),
                    shots.back().rays_asked_total,
                    static_cast<double>(shots.back().rays_asked_total) / static_cast<double>(mapper.geometry().column_count()),
                    shots.back().expected_gain),
            std::fflush(stdout);
    }
  } catch (const Interrupted&) {
    why = "interrupted";  // what was acquired is still written, as a live run's map is
  }
  if (terminal) std::printf("\n");
  write_shots_csv(out.file("shots.csv"), shots);
  std::vector<double> asked, gain;
  for (const SimulatedShot& s : shots) {
    asked.push_back(static_cast<double>(s.rays_asked_total));
    gain.push_back(s.expected_gain);
  }
  if (shots.size() >= 2) write_png(out.file("gain.png"), render_curve(asked, gain));
  write_maps(mapper, out, preset.geometry.depth_max_m);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%zu shots, %zu rays asked (%.2f frames), %zu returned, in %.2f s; stopped: %s\n", shots.size(),
              shots.empty() ? 0 : shots.back().rays_asked_total,
              shots.empty() ? 0.0 : static_cast<double>(shots.back().rays_asked_total) / static_cast<double>(mapper.geometry().column_count()),
              returns.total_returned(), seconds, why.c_str());
  std::printf("wrote %s/: shots.csv%s depth.png occupancy.png improvement.png improvement_legend.png\n",
              out.path().c_str(), shots.size() >= 2 ? " gain.png" : "");
  return why == "interrupted" ? 128 + SIGINT : 0;
}

int run(int argc, const char* const* argv_in) {
  std::vector<const char*> args(argv_in, argv_in + argc);
  const std::optional<std::string> device = take_device_flag(args);
  const int n = static_cast<int>(args.size());
  const char* const* argv = args.data();

  ToolSpec spec;
  spec.default_preset = "kinect_v1";
  spec.value_flags = {"-oni",     "-pcd_dir",    "-depth_dir", "-o",   "-save_every",
                      "-fps",     "-threads",    "-max_frames", "-load", "-save",
                      "-simulate", "-budget",    "-max_shots"};
  spec.switches = {"-drop", "-no_poses", "-stop_on_signal", "-overwrite"};
  const ToolOptions options = parse_tool_options(n, argv, spec);

  std::string oni, pcd_dir, depth_dir, load_path, save_path;
  pcl::console::parse_argument(n, argv, "-load", load_path);
  pcl::console::parse_argument(n, argv, "-save", save_path);
  pcl::console::parse_argument(n, argv, "-oni", oni);
  pcl::console::parse_argument(n, argv, "-pcd_dir", pcd_dir);
  pcl::console::parse_argument(n, argv, "-depth_dir", depth_dir);
  const int save_every = parse_number(n, argv, "-save_every", 0, 0);
  const float fps = parse_number(n, argv, "-fps", 0.0f, 0.0f);
  const int threads = parse_number(n, argv, "-threads", 0, 0);
  const int max_frames = parse_number(n, argv, "-max_frames", 0, 0);
  const bool drop = pcl::console::find_switch(n, argv, "-drop");
  const bool stop_on_signal = pcl::console::find_switch(n, argv, "-stop_on_signal");

  std::string simulate;
  pcl::console::parse_argument(n, argv, "-simulate", simulate);
  const int budget = parse_number(n, argv, "-budget", 4096, 1);
  const int max_shots = parse_number(n, argv, "-max_shots", 1000, 1);
  const int sources = (device ? 1 : 0) + !oni.empty() + !pcd_dir.empty() + !depth_dir.empty() +
                      !options.inputs.empty() + !simulate.empty();
  if (sources != 1)
    throw InvalidParameter("give exactly one source (-device, -oni, -pcd_dir, -depth_dir, PCD files or -simulate); see -h");
  OutputFolder out = open_output_folder(n, argv, "occ_improve_live", "occ_improve_live_out");
  if (!simulate.empty()) return run_simulation(options, simulate, budget, max_shots, out);

  // The source, and the sensor preset that fits it.
  std::shared_ptr<pcl::Grabber> grabber;
  FileSequenceGrabber* file_source = nullptr;
  SensorPreset preset = options.preset;
  std::string source_text, camera_text;
  if (device || !oni.empty()) {
    grabber = open_openni2_grabber(device ? *device : oni);
    source_text = device ? "OpenNI2 device " + (device->empty() ? std::string("(first)") : *device) : "recording " + oni;
    camera_text = options.intrinsics ? "camera from " + options.intrinsics_flag
                                     : "camera: Kinect v1 defaults fx = fy = 525 (give -intrinsics for another device)";
  } else if (!depth_dir.empty()) {
    DepthSequence sequence = scan_depth_sequence(depth_dir);
    if (max_frames > 0 && sequence.frames.size() > static_cast<std::size_t>(max_frames))
      sequence.frames.resize(static_cast<std::size_t>(max_frames));  // file sources stop exactly there
    const std::optional<PinholeIntrinsics> camera = options.intrinsics ? options.intrinsics : sequence.intrinsics;
    if (!camera) throw InvalidParameter("-depth_dir " + depth_dir + ": no camera-intrinsics.txt there; give -intrinsics or -intrinsics_file");
    if (!options.intrinsics) preset = options.preset_for_camera(camera);
    camera_text = options.intrinsics ? "camera from " + options.intrinsics_flag : "camera from " + depth_dir + "'s intrinsics file";
    DepthSequenceOptions sequence_options;
    sequence_options.fps = fps;
    sequence_options.use_poses = !pcl::console::find_switch(n, argv, "-no_poses");
    sequence_options.encoding = options.depth_encoding;
    auto source = std::make_shared<DepthSequenceGrabber>(sequence, *camera, sequence_options);
    source_text = depth_dir + " (" + std::to_string(sequence.frames.size()) + " depth frames, " +
                  (source->posesApplied() ? "poses applied: map in the first frame's view" : "no poses") + ")";
    file_source = source.get();
    grabber = source;
  } else {
    std::vector<std::string> files = pcd_dir.empty() ? options.inputs : PcdSequenceGrabber(pcd_dir).files();
    if (max_frames > 0 && files.size() > static_cast<std::size_t>(max_frames))
      files.resize(static_cast<std::size_t>(max_frames));
    if (files.empty()) throw InvalidInput("no PCD files to replay");
    // The first frame's camera (fitted to its organized points unless -intrinsics is given).
    const ToolFrame first = read_tool_frame(options, FrameSource{files.front(), std::nullopt});
    preset = options.preset_for_camera(first.camera);
    camera_text = describe_camera({first});
    auto source = std::make_shared<PcdSequenceGrabber>(files, fps);
    const std::string files_text = files.empty() ? std::string("no PCD file")
                                   : files.size() == 1 ? files.front()
                                                       : files.front() + " and " + std::to_string(files.size() - 1) + " more";
    source_text = (pcd_dir.empty() ? files_text : pcd_dir) + " (" + std::to_string(source->frameCount()) + " frames)";
    file_source = source.get();
    grabber = source;
  }

  const InputScope scope(source_text);
  PipelineOptions pipeline_options;
  pipeline_options.insertion.threads = threads;
  pipeline_options.top_regions = static_cast<std::size_t>(options.top_k);
  pipeline_options.backpressure = file_source != nullptr && !drop;
  // A saved map fixes the geometry and the model; the source's frames must fit it.
  std::shared_ptr<Mapper> mapper;
  if (!load_path.empty()) {
    LoadedMap loaded = load_map(load_path, options.grid.memory_cap_bytes);
    mapper = std::make_shared<Mapper>(std::move(loaded.grid), SensorModel(loaded.model));
    preset.name = "loaded from " + load_path;
    preset.geometry = mapper->geometry().params();
    preset.model = mapper->model().params();
  } else {
    mapper = std::make_shared<Mapper>(preset, options.grid);
  }
  Pipeline pipeline(mapper, with_camera(pipeline_options, preset));
  const double depth_max_m = preset.geometry.depth_max_m;
  const auto save_grid = [&] {
    if (!save_path.empty()) save_map(save_path, pipeline.mapper().grid(), pipeline.mapper().model().params());
  };

  std::mutex report_mutex;
  FrameResult last;
  bool have_result = false;
  std::atomic<bool> stop_signalled{false};
  std::atomic<int> maps_written{0};
  std::uint64_t frames_seen = 0;  // only touched by the worker
  pipeline.setResultCallback([&](const FrameResult& r) {
    {
      std::lock_guard<std::mutex> lock(report_mutex);
      last = r;
      have_result = true;
    }
    if (r.stop.stop) stop_signalled = true;
    if (save_every > 0 && ++frames_seen % static_cast<std::uint64_t>(save_every) == 0) {
      write_maps(pipeline.mapper(), out, depth_max_m);
      save_grid();
      ++maps_written;
    }
  });
  pipeline.setEventCallback([](const PipelineEvent& e) { pcl::console::print_warn("\n%s\n", e.message.c_str()); });
  if (file_source)
    file_source->setErrorCallback([&](const std::string& message) { pipeline.reportSourceError(message); });
  pipeline.attach(*grabber);

  pcl::console::print_info("%s\n", camera_text.c_str());
  pcl::console::print_info("Source: %s\nPreset: %s (%dx%d rays, %d depth bins, 0-%.1f m)\n", source_text.c_str(),
                           preset.name.c_str(), preset.geometry.azimuth_bins, preset.geometry.elevation_bins,
                           preset.geometry.depth_bins, depth_max_m);
  pipeline.start();
  const char* stop_reason = "source finished";
  // On a terminal the progress line rewrites itself; in a log, one line every 5 s.
  const bool terminal = isatty(fileno(stderr)) != 0;
  const int ticks_per_line = terminal ? 1 : 25;
  for (int tick = 1;; ++tick) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const PipelineStatistics s = pipeline.statistics();
    if (tick % ticks_per_line == 0)
      std::fprintf(stderr, "%sframes %llu  processed %llu  dropped %llu  rejected %llu  %.1f fps   %s",
                   terminal ? "\r" : "", static_cast<unsigned long long>(s.received),
                   static_cast<unsigned long long>(s.processed), static_cast<unsigned long long>(s.dropped),
                   static_cast<unsigned long long>(s.rejected), s.processed_per_second(), terminal ? "" : "\n");
    if (stop_signal_received()) { stop_reason = "interrupted"; break; }
    if (stop_on_signal && stop_signalled) { stop_reason = "stop signal"; break; }
    if (max_frames > 0 && s.processed >= static_cast<std::uint64_t>(max_frames)) { stop_reason = "-max_frames reached"; break; }
    if (file_source && !file_source->isRunning() && s.in_flight == 0) break;
  }
  pipeline.stop();
  if (terminal) std::fprintf(stderr, "\n");
  if (const PipelineStatistics s = pipeline.statistics(); s.processed == 0 && !stop_signal_received())
    throw InvalidInput("no frame of " + source_text + " was used (" + std::to_string(s.rejected) +
                       " rejected: empty, all NaN or all zero, or of the wrong size; " +
                       std::to_string(s.grabber_errors) + " unreadable)");
  write_maps(pipeline.mapper(), out, depth_max_m);
  save_grid();
  if (!save_path.empty()) pcl::console::print_info("Saved the grid to %s\n", save_path.c_str());

  const PipelineStatistics s = pipeline.statistics();
  pcl::console::print_info("Stopped: %s\n", stop_reason);
  pcl::console::print_info(
      "Frames: %llu received, %llu processed, %llu dropped, %llu rejected, %llu source errors in %.2f s "
      "(%.1f frames/s)\n",
      static_cast<unsigned long long>(s.received), static_cast<unsigned long long>(s.processed),
      static_cast<unsigned long long>(s.dropped), static_cast<unsigned long long>(s.rejected),
      static_cast<unsigned long long>(s.grabber_errors), s.wall_seconds, s.processed_per_second());
  pcl::console::print_info("Per frame [ms]: convert %.1f, insert+surface %.1f, improvement %.1f, regions %.1f\n",
                           s.mean_ms(s.convert_ms), s.mean_ms(s.insert_ms),
                           s.mean_ms(s.improvement_ms), s.mean_ms(s.regions_ms));
  if (have_result) {
    pcl::console::print_info("Stop signal: %s (%s)\n", last.stop.stop ? "yes" : "no", last.stop.reason.c_str());
    for (std::size_t i = 0; i < last.top_regions.size(); ++i) {
      const Region& r = last.top_regions[i];
      pcl::console::print_info("  region %zu: improvement %.2f over %zu rays, azimuth %.1f deg, elevation %.1f deg, depth %.2f m\n",
                               i + 1, r.summed_improvement, r.area_columns, r.centroid_azimuth_rad * 180.0 / M_PI,
                               r.centroid_elevation_rad * 180.0 / M_PI, r.mean_depth_m);
    }
  }
  pcl::console::print_info("Wrote %s/{depth,occupancy,improvement,improvement_legend}.png (%d intermediate writes)\n",
                           out.path().c_str(), maps_written.load());
  // The maps so far are written above: a stream is normally ended by Ctrl-C, and its maps are valid.
  if (const int signal = stop_signal_received()) throw Interrupted(signal);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return occ_improve::run_tool(argc, argv, print_usage, [](int n, char** v) { return run(n, v); });
}
