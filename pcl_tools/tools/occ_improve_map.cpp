// occ_improve_map: fuse one or more range frames taken from one viewpoint into the occupancy
// grid and write where one more measurement would teach the most: depth, occupancy and improvement
// images, the per-ray results as an organized PCD, and the ranked regions worth re-acquiring.
#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/map_io.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/pcl/map_cloud.hpp"
#include "occ_improve/pcl/tool_options.hpp"
#include "occ_improve/ranking.hpp"
#include "occ_improve/render.hpp"
#include "occ_improve/sample_scene.hpp"

#include <pcl/console/parse.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

using namespace occ_improve;

namespace {

constexpr double kRadToDeg = 57.29577951308232;

void print_usage(const char* program) {
  std::cout << "Usage: " << program << " [options] INPUT... -o OUTDIR\n"
            << "       " << program << " -sample -o OUTDIR\n\n"
            << "Fuses the input frames (one viewpoint, in order) into an occupancy grid along the sensor's rays\n"
            << "and writes the\n"
            << "improvement map (where one more measurement would change the map most) to OUTDIR:\n"
            << "  depth.png occupancy.png improvement.png legend.png  the maps as images (pixel-native presets:\n"
            << "                pixel-aligned with the input depth image; grey = columns no pixel can see)\n"
            << "  overlay.png   the improvement colours over the frame's colour (PCDs with rgb/rgba)\n"
            << "  surface.pcd   organized PointImprovement cloud (x y z surface_depth probability improvement)\n"
            << "  regions.csv   the K best connected regions, ranked by summed improvement\n"
            << "  rays.csv      the K best single rays\n\n"
            << "Tool options:\n"
            << usage_output_folder("occ_improve_out")
            << "  -sample                   use the built-in generated Kinect-like frame instead of input files\n"
            << "  -load MAP.occmap          start from a saved grid (same viewpoint); it carries its own preset,\n"
            << "                            so preset flags are ignored; input frames are fused on top of it\n"
            << "  -save MAP.occmap          save the resulting grid (written atomically)\n"
            << "  -threads N                worker threads (default 0: all cores)\n"
            << "  -min_improvement V        a region's rays have improvement >= V (default 0.2: above\n"
            << "                            a ray seen once, below no data)\n\n"
            << usage_common();
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}


void write_regions_csv(const std::string& path, const std::vector<Region>& regions) {
  std::ofstream out(path);
  if (!out) throw IoError("cannot write '" + path + "'");
  out << "rank,summed_improvement,area_columns,peak_improvement,centroid_azimuth_deg,centroid_elevation_deg,"
         "direction_x,direction_y,direction_z,mean_depth_m\n";
  char line[512];
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const Region& r = regions[i];
    std::snprintf(line, sizeof line, "%zu,%.6f,%zu,%.6f,%.4f,%.4f,%.6f,%.6f,%.6f,%.4f\n", i + 1,
                  r.summed_improvement, r.area_columns, static_cast<double>(r.peak_improvement),
                  r.centroid_azimuth_rad * kRadToDeg, r.centroid_elevation_rad * kRadToDeg, r.centroid_direction.x(),
                  r.centroid_direction.y(), r.centroid_direction.z(), r.mean_depth_m);
    out << line;
  }
  if (!out.flush()) throw IoError("cannot write '" + path + "'");
}

void write_rays_csv(const std::string& path, const SphericalGeometry& geometry, const std::vector<RankedRay>& rays) {
  std::ofstream out(path);
  if (!out) throw IoError("cannot write '" + path + "'");
  out << "rank,improvement,azimuth_bin,elevation_bin,azimuth_deg,elevation_deg,depth_m\n";
  char line[256];
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RankedRay& r = rays[i];
    std::snprintf(line, sizeof line, "%zu,%.6f,%d,%d,%.4f,%.4f,%.4f\n", i + 1, static_cast<double>(r.improvement),
                  r.azimuth_bin, r.elevation_bin, geometry.azimuth().centre(r.azimuth_bin) * kRadToDeg,
                  geometry.elevation().centre(r.elevation_bin) * kRadToDeg, static_cast<double>(r.depth_m));
    out << line;
  }
  if (!out.flush()) throw IoError("cannot write '" + path + "'");
}

void print_points(const InsertionReport& in) {
  std::printf("points: %zu read, %zu used, %zu skipped invalid, %zu skipped outside the field of view; "
              "%zu used beyond the depth range (free space only)\n",
              in.points_received, in.points_inserted, in.skipped_invalid, in.skipped_outside_fov,
              in.beyond_depth_range);
}

std::vector<ToolFrame> sample_frames() {
  const sample::SampleFrame scene = sample::generate_scene();
  std::vector<ToolFrame> frames;
  frames.push_back({"built-in sample", organized_cloud(scene.points(), scene.intrinsics.width, scene.intrinsics.height),
                    scene.intrinsics, "the built-in sample's camera", std::nullopt});
  return frames;
}

// Every frame of the inputs, in order (read_tool_frames: cameras never assumed, frames without a valid
// point refused before any work).
std::vector<ToolFrame> read_frames(const ToolOptions& options) {
  try {
    return read_tool_frames(options);
  } catch (const Interrupted&) {
    std::printf("interrupted while reading the inputs; nothing written\n");
    throw;
  }
}

MapperReport insert_frames(Mapper& mapper, const std::vector<ToolFrame>& frames, const InsertionOptions& insertion) {
  MapperReport total;
  std::size_t inserted = 0;
  try {
    for (const ToolFrame& frame : frames) {
      throw_if_interrupted();
      InputScope scope(frame.name);
      const MapperReport r = mapper.insert(span_of(frame.cloud), insertion);
      total.insertion += r.insertion;
      total.improvement_seconds += r.improvement_seconds;
      ++inserted;
    }
  } catch (const Interrupted&) {
    std::printf("inserted %zu of %zu frame(s) before the interruption; nothing written\n", inserted, frames.size());
    print_points(total.insertion);
    throw;
  }
  return total;
}

int run(int argc, char** argv) {
  ToolSpec spec;
  spec.value_flags = {"-o", "-threads", "-min_improvement", "-load", "-save"};
  spec.switches = {"-sample", "-overwrite"};
  const ToolOptions options = parse_tool_options(argc, argv, spec);
  const bool use_sample = pcl::console::find_switch(argc, argv, "-sample");
  std::string load_path, save_path;
  pcl::console::parse_argument(argc, argv, "-load", load_path);
  pcl::console::parse_argument(argc, argv, "-save", save_path);
  InsertionOptions insertion;
  if (std::string text; pcl::console::parse_argument(argc, argv, "-threads", text) >= 0) {
    char* end = nullptr;
    const long threads = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || threads < 0 || threads > 1024)
      throw InvalidParameter("-threads " + text + " is invalid: must be an integer in [0, 1024]");
    insertion.threads = static_cast<int>(threads);
  }
  RegionOptions region_options;
  if (std::string text; pcl::console::parse_argument(argc, argv, "-min_improvement", text) >= 0) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || !std::isfinite(v))
      throw InvalidParameter("-min_improvement " + text + " is invalid: must be a finite number");
    region_options.min_improvement = static_cast<float>(v);
  }
  if (use_sample && !options.inputs.empty()) throw InvalidParameter("give either input files or -sample, not both");
  if (!use_sample && options.inputs.empty() && load_path.empty())
    throw InvalidParameter("no input: give PCD / depth image files or a dataset folder, -sample or -load (see -h)");

  // Fail on an unwritable or foreign output folder before any work.
  OutputFolder staging = open_output_folder(argc, argv, "occ_improve_map", "occ_improve_out");

  // Read.
  auto start = std::chrono::steady_clock::now();
  const std::vector<ToolFrame> frames = use_sample ? sample_frames() : read_frames(options);
  const double read_seconds = seconds_since(start);

  SensorPreset preset = options.preset_for_camera(frames.empty() ? std::nullopt : frames.front().camera);
  Mapper mapper = [&] {
    if (load_path.empty()) return Mapper(preset, options.grid);
    LoadedMap loaded = load_map(load_path, options.grid.memory_cap_bytes);
    preset.name = "loaded from " + load_path;
    preset.geometry = loaded.grid.geometry().params();
    preset.model = loaded.model;
    return Mapper(std::move(loaded.grid), SensorModel(loaded.model));
  }();

  // Insert (insertion with the surface kept current, then the incremental improvement; timed by the mapper).
  const MapperReport total = insert_frames(mapper, frames, insertion);
  if (!frames.empty() && total.insertion.points_inserted == 0)
    throw InvalidInput("no point of the input lies inside the grid's field of view (preset " + preset.name + ")");

  // Rank.
  start = std::chrono::steady_clock::now();
  const std::vector<Region> all_regions =
      find_regions(mapper.geometry(), mapper.improvement(), mapper.surface(), region_options);
  const std::vector<RankedRay> rays = top_rays(mapper.improvement(), mapper.surface(), options.top_k);
  const StopSignal stop = stop_signal(mapper.improvement(), all_regions);
  const std::vector<Region> regions(
      all_regions.begin(), all_regions.begin() + static_cast<std::ptrdiff_t>(std::min<std::size_t>(
                                                     all_regions.size(), static_cast<std::size_t>(options.top_k))));
  const double ranking_seconds = seconds_since(start);

  // Write into the staging folder, then move it into place.
  start = std::chrono::steady_clock::now();
  write_png(staging.file("depth.png"), render_depth(mapper.surface(), mapper.geometry().depth().max()));
  write_png(staging.file("occupancy.png"), render_occupancy(mapper.surface()));
  write_png(staging.file("improvement.png"), render_improvement(mapper.improvement()));
  write_png(staging.file("legend.png"), render_improvement_legend());
  // With a pixel-native grid (whose size is the frame's) the map is pixel-aligned with the registered colour.
  const bool overlay = !frames.empty() && frames.front().colour && mapper.geometry().binning() == AngularBinning::pinhole;
  if (overlay) write_png(staging.file("overlay.png"), render_overlay(mapper.improvement(), *frames.front().colour));
  save_improvement_cloud(staging.file("surface.pcd"),
                         to_improvement_cloud(mapper.geometry(), mapper.surface(), mapper.improvement()));
  write_regions_csv(staging.file("regions.csv"), regions);
  write_rays_csv(staging.file("rays.csv"), mapper.geometry(), rays);
  throw_if_interrupted();  // before anything is committed: an interrupted run leaves nothing behind
  staging.commit();
  if (!save_path.empty()) save_map(save_path, mapper.grid(), mapper.model().params());
  const double write_seconds = seconds_since(start);

  // Summary.
  const InsertionReport& in = total.insertion;
  const GeometryParams& g = preset.geometry;
  std::printf("preset %s: %s binning, %d x %d x %d bins, depth %.2f-%.2f m, %s mode\n", preset.name.c_str(),
              to_string(g.angular_binning), g.azimuth_bins, g.elevation_bins, g.depth_bins, g.depth_min_m, g.depth_max_m,
              options.grid.mode == UpdateMode::clamped ? "clamped" : "exact");
  std::printf("%s\n", describe_camera(frames).c_str());
  for (const ToolFrame& f : frames) std::printf("read %s: %zu points\n", f.name.c_str(), f.cloud.size());
  print_points(in);
  std::printf("time [s]: read %.3f, insert+surface %.3f, improvement %.3f, ranking %.3f, write %.3f\n",
              read_seconds, in.seconds, total.improvement_seconds, ranking_seconds,
              write_seconds);
  std::printf("top %zu of %zu regions (improvement >= %.3g, >= %zu rays):\n", regions.size(), all_regions.size(),
              static_cast<double>(region_options.min_improvement), region_options.min_area_columns);
  std::printf("  rank  summed  area   peak  azimuth  elevation  depth\n");
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const Region& r = regions[i];
    std::printf("  %4zu %7.2f %5zu %6.3f %7.2fd %9.2fd %5.2fm\n", i + 1, r.summed_improvement, r.area_columns,
                static_cast<double>(r.peak_improvement), r.centroid_azimuth_rad * kRadToDeg,
                r.centroid_elevation_rad * kRadToDeg, r.mean_depth_m);
  }
  if (!rays.empty())
    std::printf("best ray: azimuth bin %d, elevation bin %d, improvement %.3f, surface depth %.2f m\n",
                rays.front().azimuth_bin, rays.front().elevation_bin, static_cast<double>(rays.front().improvement),
                static_cast<double>(rays.front().depth_m));
  std::printf("stop: %s (%s)\n", stop.stop ? "yes" : "no", stop.reason.c_str());
  std::printf("wrote %s/: depth.png occupancy.png improvement.png legend.png%s surface.pcd regions.csv rays.csv\n",
              staging.path().c_str(), overlay ? " overlay.png" : "");
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return occ_improve::run_tool(argc, argv, print_usage, run); }
