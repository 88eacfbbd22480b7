// occ_to_octomap: convert an occupancy grid, saved by save_map or built from range frames, into
// an OctoMap file (.bt maximum likelihood, .ot full log-odds) at a chosen resolution, seen from a pose.
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/octomap/export.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/tools/frame_fusion.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/progress.hpp"
#include "occ_improve/tools/signals.hpp"
#include "occ_improve/tools/tool_frames.hpp"
#include "occ_improve/tools/tool_main.hpp"
#include "occ_improve/tools/tool_mask.hpp"
#include "occ_improve/tools/tool_options.hpp"
#include "occ_improve/timing.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

using namespace occ_improve;

namespace {

const ToolFlags kFlags{
    "occ_to_octomap",
    {"-load MAP.occmap [-pose P] [-load MAP2 -pose P2 ...] [options] -o OUT.bt|OUT.ot",
     "[options] INPUT... -o OUT.bt|OUT.ot", "-sample [options] -o OUT.bt|OUT.ot"},
    "Writes the occupancy grid as an OctoMap OcTree: a leaf is occupied when any occupied grid voxel\n"
    "reaches into it (it takes their largest log-odds), free when free space crosses it as OctoMap marks\n"
    "free a leaf a ray crosses (-free crossed: its centre or a corner lies in free space, and no return's\n"
    "surface; -free wholly: all of it), unknown otherwise.\n"
    ".bt = maximum likelihood, .ot = full log-odds (both with OctoMap's own writers). The tree is in a\n"
    "world frame: -pose, else the pose saved with a -load map (a -save of posed frames), else the first\n"
    "frame's pose when the inputs have poses (a 7-Scenes folder), else -frame.\n"
    "Neither format stores the clamping thresholds (the tree in memory has the grid's; a reader of the\n"
    "file gets OctoMap's defaults) nor the sensor model; keep the .occmap (-save) for those.\n"
    "Repeat -load (each with its own -pose, in order, or each saved with its pose) to merge maps taken\n"
    "from several poses: log-odds\n"
    "are added, then clamped.\n"
    "The tree's worst case is capped too: at 2 GiB unless -memory_cap is given (then by it).\n",
    joined({{"-o", "-overwrite", "-q", "-load", "-pose", "-sample", "-save", "-resolution", "-frame", "-free"}, sensor_flag_names(),
            camera_flag_names(), {"-no_poses", "-mask"}}),
    {},
    {"-load", "-pose"},
    frame_inputs_help(true, false)};

// world <- optical for -frame z_up: the optical z (forward) is world x, x (right) is -y, y (down) is -z.
Eigen::Isometry3d z_up_from_optical() {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return pose;
}

Eigen::Isometry3d parse_pose(const std::string& text) {
  const std::vector<double> v = parse_number_list("-pose", text);
  if (v.size() != 7) throw InvalidParameter("-pose " + text + " is invalid: needs 7 numbers x,y,z,qx,qy,qz,qw");
  Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  if (std::abs(q.norm() - 1.0) > 1e-3)
    throw InvalidParameter("-pose " + text + " is invalid: the quaternion's norm is " + std::to_string(q.norm()) +
                           ", must be 1 (a rotation)");
  q.normalize();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  pose.linear() = q.toRotationMatrix();
  return pose;
}

struct Source {
  std::optional<ColumnGrid> grid;
  SensorModelParams model;
  std::string description;
  InsertionReport insertion;
  std::optional<Eigen::Isometry3d> world_from_grid;  ///< the first frame's pose (posed frames), a map's saved pose
};

Source build_from_frames(const CommandLine& command_line, const ToolOptions& options, bool use_sample,
                         ProgressLine& progress) {
  ToolFrameReader frames(options, use_sample);
  Source source;
  SensorPreset preset;
  std::optional<SensorModel> model;
  std::vector<std::uint8_t> mask_columns;  // -mask: the points outside it are left out (empty: none)
  std::vector<float> kept;
  std::size_t masked = 0;
  const FusedFrames fused = fuse_tool_frames(
      frames, progress,
      [&](const std::optional<ToolFrame>& first) {
        preset = options.preset_for_camera(first ? first->camera : std::nullopt);
        source.model = preset.model;
        source.grid.emplace(GridGeometry(preset.geometry), options.grid);
        model.emplace(preset.model);
        const ToolFrame* first_frame = first ? &*first : nullptr;
        if (const std::optional<PixelMask> mask = read_tool_mask(command_line, first_frame))
          mask_columns = tool_mask_columns(command_line, source.grid->geometry(), *mask);
      },
      [&](const ToolFrame& frame) {
        if (mask_columns.empty()) return insert_points(*source.grid, *model, span_of(frame.cloud));
        masked += drop_masked_points(source.grid->geometry(), mask_columns, span_of(frame.cloud), kept);
        return insert_points(*source.grid, *model, PointSpan{kept.data(), kept.size() / 3, 3});
      });
  source.insertion = fused.insertion;
  source.world_from_grid = fused.first_pose;
  source.description = (use_sample ? std::string("built-in sample frame") : std::to_string(fused.frames) + " frame(s)") +
                       ", preset " + preset.name + ", " + fused.camera + ", " + fused.poses;
  if (!mask_columns.empty())
    source.description += "; -mask " + *command_line.text("-mask") + ": " + std::to_string(masked) +
                          " valid points outside it left out";
  return source;
}

// The -pose values, one per map, or none (checked before any work).
std::vector<Eigen::Isometry3d> parse_poses(const CommandLine& command_line, std::size_t maps) {
  const std::vector<std::string> texts = command_line.values("-pose");
  if (!texts.empty() && texts.size() != maps)
    throw InvalidParameter("give one -pose per map (" + std::to_string(maps) + " map(s), " +
                           std::to_string(texts.size()) + " poses)");
  std::vector<Eigen::Isometry3d> poses;
  for (const std::string& text : texts) poses.push_back(parse_pose(text));
  return poses;
}

// world <- grid per source: -pose, else the grid's own pose (a map saved with one; the first frame's for
// posed input frames), else -frame's for a single source; maps merged without either are refused.
std::vector<Eigen::Isometry3d> source_poses(const CommandLine& command_line, std::vector<Eigen::Isometry3d> given,
                                            const std::vector<Source>& grids) {
  if (!given.empty()) return given;
  for (std::size_t i = 0; i < grids.size(); ++i) {
    if (grids[i].world_from_grid) {
      given.push_back(*grids[i].world_from_grid);
    } else if (grids.size() > 1) {
      throw InvalidParameter("merging " + std::to_string(grids.size()) + " maps needs one -pose per -load: " +
                             grids[i].description + " was saved without its pose");
    } else {
      given.push_back(*command_line.text("-frame") == "z_up" ? z_up_from_optical() : Eigen::Isometry3d::Identity());
    }
  }
  return given;
}

Source load_saved_map(const std::string& path, const ToolOptions& options) {
  throw_if_stop_requested();
  const InputScope scope(path);
  LoadedMap loaded = load_tool_map(path, options);
  Source source;
  source.grid.emplace(std::move(loaded.grid));
  source.model = loaded.model;
  source.world_from_grid = loaded.world_from_sensor;
  source.description = "map " + path;
  return source;
}

// Every grid into the tree at its pose; the first map set the tree's clamping, the others merge into it.
OctomapExportReport export_grids(const std::vector<Source>& grids, const std::vector<Eigen::Isometry3d>& poses,
                                 const OctomapExportOptions& options, octomap::OcTree& tree) {
  OctomapExportReport report;
  for (std::size_t i = 0; i < grids.size(); ++i) {
    OctomapExportReport r;
    try {
      r = add_to_octree(tree, *grids[i].grid, poses[i], options);
    } catch (const ResourceLimit& e) {
      throw ResourceLimit(std::string(e.what()) + ", or raise the cap with -memory_cap GIB");
    }
    report.occupied_written += r.occupied_written;
    report.free_written += r.free_written;
    report.left_unknown += r.left_unknown;
    report.seconds += r.seconds;
  }
  return report;
}

// "84.1 MB", or "45.2 kB" below a megabyte (a 45 kB tree read "0.0 MB").
std::string size_text(double bytes) {
  char text[32];
  const bool kilobytes = bytes < 999.95e3;  // what rounds to 1000.0 kB reads 1.0 MB
  std::snprintf(text, sizeof text, kilobytes ? "%.1f kB" : "%.1f MB", kilobytes ? bytes / 1e3 : bytes / 1e6);
  return text;
}

int run(const CommandLine& command_line) {
  const ToolOptions options = parse_tool_options(command_line);
  const std::string output = command_line.text("-o").value_or("");
  const std::vector<std::string> load_paths = command_line.values("-load");
  const bool use_sample = command_line.has("-sample");
  if (output.empty()) throw InvalidParameter("-o OUT.bt|OUT.ot is required (see -h)");
  require_octomap_output_path(output);
  const double resolution = *command_line.number("-resolution");
  const int sources = (load_paths.empty() ? 0 : 1) + (use_sample ? 1 : 0) + (options.inputs.empty() ? 0 : 1);
  if (sources != 1) throw InvalidParameter("give exactly one of -load MAP, input files, or -sample (see -h)");
  if (!load_paths.empty() && command_line.has("-save"))
    throw InvalidParameter("-save only applies to a grid built from frames");
  // Both outputs are checked (never an input, never a foreign file) before any work, committed after it.
  MapSaveTarget save(command_line, nullptr);
  if (save.requested()) require_distinct_outputs(save.path(), "-save", output, "-o");
  const auto tree_file = open_output_file(command_line, "-o", is_octomap_file, "an OctoMap file");
  const std::vector<Eigen::Isometry3d> given_poses = parse_poses(command_line, std::max<std::size_t>(load_paths.size(), 1));
  const PresetOverrides& o = options.overrides;
  const bool preset_flags = command_line.has("-preset") || o.sigma_depth_m ||
                            o.sigma_depth_per_m2 || o.sigma_angle_rad || o.support_k || o.depth_bins ||
                            o.depth_max_m || o.fov_horizontal_deg || o.fov_vertical_deg;
  if (!load_paths.empty() && preset_flags)
    std::cerr << "warning: preset flags are ignored with -load: a saved map carries its own geometry and model\n";

  // Every source is read before the first export, so a bad map fails before any work.
  if (!load_paths.empty() && command_line.has("-mask"))
    throw InvalidParameter("-mask applies to input frames; a saved map (-load) is exported as it is");
  auto start = SteadyClock::now();
  std::vector<Source> grids;
  const LeftToExitOnStop<std::vector<Source>> grids_left_on_stop(grids);
  for (const std::string& path : load_paths) grids.push_back(load_saved_map(path, options));
  ProgressLine progress(command_line, "frame");
  if (load_paths.empty()) grids.push_back(build_from_frames(command_line, options, use_sample, progress));
  const std::vector<Eigen::Isometry3d> poses = source_poses(command_line, given_poses, grids);
  for (Source& source : grids)  // where each tree went: the summary says which pose placed it
    source.description += command_line.has("-pose")  ? " (at -pose)"
                          : !source.world_from_grid ? " (in -frame " + *command_line.text("-frame") + ")"
                          : load_paths.empty()      ? " (at the first frame's pose)"
                                                    : " (at the pose saved with it)";
  if (command_line.has("-frame") && (command_line.has("-pose") || grids.front().world_from_grid))
    std::fprintf(stderr, "warning: -frame applies without poses: ignored (the tree is placed by %s)\n",
                 command_line.has("-pose") ? "-pose" : "the poses");
  const double read_seconds = seconds_since(start);

  double save_seconds = 0;
  if (save.requested()) {
    start = SteadyClock::now();
    // Where the grid's sensor frame lies in the frames' world (their first pose): what places frames added
    // after a -load. -pose places the tree only, so it is saved for frames without poses alone (a -pose
    // saved over posed frames put the next frames 0.9 m and 40 deg off); never -frame's, a display
    // convention rather than where the sensor was.
    const std::optional<Eigen::Isometry3d> pose =
        grids.front().world_from_grid ? grids.front().world_from_grid
        : command_line.has("-pose")   ? std::optional<Eigen::Isometry3d>(poses.front())
                                      : std::nullopt;
    save_map(save.staged_path(), *grids.front().grid, grids.front().model, ReturnRecord(), pose);
    save_seconds = seconds_since(start);
  }

  // -memory_cap bounds the tree too when given (the export's own default cap is 2 GiB).
  OctomapExportOptions export_options;
  if (command_line.has("-memory_cap")) export_options.memory_cap_bytes = options.grid.memory_cap_bytes;
  export_options.free_leaves = *command_line.text("-free") == "wholly" ? FreeLeafRule::wholly_free : FreeLeafRule::crossed;
  std::unique_ptr<octomap::OcTree> tree = make_octree(*grids.front().grid, resolution, export_options);
  const LeftToExitOnStop<std::unique_ptr<octomap::OcTree>> tree_left_on_stop(tree);
  const OctomapExportReport report = export_grids(grids, poses, export_options, *tree);
  throw_if_stop_requested();  // before the output is written: an interrupted run leaves nothing behind
  start = SteadyClock::now();
  write_octree(*tree, tree_file->staged());
  throw_if_stop_requested();
  save.commit();
  tree_file->commit();
  const double write_seconds = seconds_since(start);

  for (const Source& source : grids) {
    const ColumnGrid& grid = *source.grid;
    const GeometryParams& g = grid.geometry().params();
    std::printf("read %s: %d x %d x %d bins, %zu touched columns, %s mode\n", source.description.c_str(),
                g.azimuth_bins, g.elevation_bins, g.depth_bins, grid.touched_column_count(),
                grid.clamped() ? "clamped" : "exact");
    if (source.insertion.points_received) std::printf("%s\n", describe_points(source.insertion).c_str());
  }
  if (save.requested()) std::printf("saved map %s\n", save.path().c_str());
  std::printf("OcTree at %.4g m: %zu occupied and %zu free leaf updates, %zu left unknown; %zu leaves, %s\n",
              resolution, report.occupied_written, report.free_written, report.left_unknown,
              tree->getNumLeafNodes(), size_text(static_cast<double>(tree->memoryUsage())).c_str());
  std::printf("wrote %s (%s)\n", output.c_str(), size_text(static_cast<double>(std::filesystem::file_size(output))).c_str());
  std::printf("time [s]: read %.3f, save %.3f, export %.3f, write %.3f\n", read_seconds, save_seconds,
              report.seconds, write_seconds);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return occ_improve::run_tool(argc, argv, kFlags, run); }
