// occ_improve_map: fuse one or more range frames taken from one viewpoint into the occupancy
// grid and write where one more measurement would teach the most: depth, occupancy and improvement
// images, the per-ray results as an organized PCD, and the ranked regions worth re-acquiring.
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/tools/map_outputs.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/tools/frame_fusion.hpp"
#include "occ_improve/tools/progress.hpp"
#include "occ_improve/tools/tool_frames.hpp"
#include "occ_improve/tools/tool_main.hpp"
#include "occ_improve/tools/tool_mask.hpp"
#include "occ_improve/tools/tool_options.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sim/render.hpp"
#include "occ_improve/timing.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

using namespace occ_improve;

namespace {

constexpr double kRadToDeg = 57.29577951308232;

const ToolFlags kFlags{
    "occ_improve_map",
    {"[options] INPUT... -o OUTDIR", "-sample -o OUTDIR", "-load MAP.occmap [INPUT...] -o OUTDIR",
     "[options] -input_dir DIR -output_dir OUTDIR   (each frame file of DIR on its own, into OUTDIR/<stem>/)"},
    "Fuses the input frames (one viewpoint, in order) into an occupancy grid along the sensor's rays and\n"
    "writes the improvement map (where one more measurement would change the map most) to OUTDIR:\n"
    "  depth.png occupancy.png improvement.png legend.png  the maps as images (pixel-native presets:\n"
    "                pixel-aligned with the input depth image; grey = columns no pixel can see)\n"
    "  depth_mm.png  the surface depth as 16-bit millimetres (0 = unknown)\n"
    "  overlay.png   the improvement colours over the frame's colour (inputs with colour)\n"
    "  surface.pcd   organized PointImprovement cloud (x y z surface_depth probability improvement)\n"
    "  regions.csv   the K best connected regions, ranked by summed improvement\n"
    "  regions.png   16-bit region ids per ray: regions.csv's rank, 0 = none\n"
    "  rays.csv      the K best single rays\n"
    "README.md \"Output files\" lists every column.\n",
    joined({output_folder_flag_names(), {"-q", "-sample", "-load", "-save", "-threads", "-k", "-min_improvement"},
            sensor_flag_names(), camera_flag_names(), {"-no_poses", "-mask"}, batch_flag_names()}),
    {{"-o", "occ_improve_out"}},
    {},
    frame_inputs_help()};

int run(const CommandLine& command_line) {
  const ToolOptions options = parse_tool_options(command_line);
  const bool use_sample = command_line.has("-sample");
  const std::string load_path = command_line.text("-load").value_or("");
  InsertionOptions insertion;
  insertion.threads = *command_line.integer("-threads");
  RegionOptions region_options;
  region_options.min_improvement = static_cast<float>(*command_line.number("-min_improvement"));
  if (!use_sample && options.inputs.empty() && load_path.empty())
    throw InvalidParameter("no input: give PCD / depth image files or a dataset folder, -sample or -load (see -h)");

  // Fail on an unwritable or foreign output folder, or a -save that may not be replaced, before any work.
  OutputFolder staging = open_output_folder(command_line);
  MapSaveTarget save(command_line, &staging);

  // The first frame sets the camera, so the grid; the others are read and inserted one by one (insertion
  // with the surface kept current, then the incremental improvement; timed by the mapper).
  ToolFrameReader frames(options, use_sample);
  // A loaded map is read before the frames: its pose places them in its view (and its record is kept).
  std::optional<LoadedMap> loaded;
  if (!load_path.empty()) {
    loaded = load_tool_map(load_path, options);
    frames.into_loaded_map(loaded->world_from_sensor, load_path);
  }
  ReturnRecord returns = loaded ? std::move(loaded->returns) : ReturnRecord();
  ProgressLine progress(command_line, "frame");
  SensorPreset preset;
  std::optional<Mapper> mapper;
  double improvement_seconds = 0;
  std::string mask_line;
  std::size_t points_masked = 0;
  const FusedFrames fused = fuse_tool_frames(
      frames, progress,
      [&](const std::optional<ToolFrame>& first) {
        preset = options.preset_for_camera(first ? first->camera : std::nullopt);
        if (!loaded) {
          mapper.emplace(preset, options.grid);
        } else {
          preset.name = "loaded from " + load_path;
          preset.geometry = loaded->grid.geometry().params();
          preset.model = loaded->model;
          mapper.emplace(std::move(loaded->grid), SensorModel(loaded->model));
          require_frames_fit_loaded_map(mapper->geometry(), first ? first->camera : std::nullopt, load_path);
        }
        mask_line = apply_tool_mask(command_line, *mapper, first ? &*first : nullptr);
      },
      [&](const ToolFrame& frame) {
        const MapperReport r = mapper->insert(span_of(frame.cloud), insertion);
        improvement_seconds += r.improvement_seconds;
        points_masked += r.points_masked;
        return r.insertion;
      });

  // Rank.
  auto start = SteadyClock::now();
  const MapSummary summary = summarize_map(*mapper, region_options, options.top_k);
  const double ranking_seconds = seconds_since(start);

  // Write into the staging folder, then move it into place.
  start = SteadyClock::now();
  const std::vector<std::string> written =
      write_map_outputs(staging, *mapper, summary, fused.colour);
  // With the planner's record a -load brought and the pose of the map's view (frames.first_pose()).
  if (save.requested()) save_map(save.staged_path(), mapper->grid(), mapper->model().params(), returns, frames.first_pose());
  throw_if_stop_requested();  // before anything is committed: an interrupted run leaves nothing behind
  staging.commit();
  save.commit();
  const double write_seconds = seconds_since(start);
  const std::vector<Region>& regions = summary.regions;
  const std::vector<RankedRay>& rays = summary.rays;

  // Summary.
  const InsertionReport& in = fused.insertion;
  const GeometryParams& g = preset.geometry;
  std::printf("preset %s: %s binning, %d x %d x %d bins, depth %.2f-%.2f m, %s mode\n", preset.name.c_str(),
              to_string(g.angular_binning), g.azimuth_bins, g.elevation_bins, g.depth_bins, g.depth_min_m, g.depth_max_m,
              mapper->grid().clamped() ? "clamped" : "exact");  // a loaded map keeps its own mode
  std::printf("%s\n", fused.frames ? fused.camera.c_str() : "no frame (the loaded map only)");
  for (const std::string& line : fused.frame_lines) std::printf("%s\n", line.c_str());
  if (fused.frames > 0) std::printf("%s\n", fused.poses.c_str());
  std::printf("%s\n", describe_points(in).c_str());
  if (!mask_line.empty()) std::printf("%s; %zu valid points outside it left out\n", mask_line.c_str(), points_masked);
  std::printf("time [s]: read %.3f, insert+surface %.3f, improvement %.3f, ranking %.3f, write %.3f\n",
              frames.read_seconds(), in.seconds, improvement_seconds, ranking_seconds,
              write_seconds);
  std::printf("top %zu of %zu regions (improvement >= %.3g, >= %zu rays):\n", regions.size(), summary.all_regions.size(),
              static_cast<double>(region_options.min_improvement), region_options.min_area_columns);
  // u, v: the region's centre column (pixel with the pixel-native presets); the angles are its direction's.
  std::printf("  rank  summed  area   peak  centre u,v   azimuth  elevation  depth\n");
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const Region& r = regions[i];
    std::printf("  %4zu %7.2f %5zu %6.3f  %4d,%-4d %7.2fd %9.2fd %5.2fm\n", i + 1, r.summed_improvement, r.area_columns,
                static_cast<double>(r.peak_improvement), r.centre_u, r.centre_v, r.centre_azimuth_rad * kRadToDeg,
                r.centre_elevation_rad * kRadToDeg, r.mean_depth_m);
  }
  if (!rays.empty())
    std::printf("best ray: column u %d, row v %d, improvement %.3f, surface depth %.2f m\n", rays.front().azimuth_bin,
                rays.front().elevation_bin, static_cast<double>(rays.front().improvement),
                static_cast<double>(rays.front().depth_m));
  std::printf("stop: %s (%s)\n", summary.stop.stop ? "yes" : "no", summary.stop.reason.c_str());
  std::printf("wrote %s/: %s\n", staging.path().c_str(), join_names(written).c_str());
  if (save.requested()) std::printf("saved map %s\n", save.path().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return occ_improve::run_tool(argc, argv, kFlags, run); }
