// occ_plan: the next shot of a selective sensor from a saved map or from input frames: which rays to
// acquire (a mask image and a rays CSV), the gain they are expected to bring and whether to stop.
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/tools/map_outputs.hpp"
#include "occ_improve/tools/frame_fusion.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/tools/plan_flags.hpp"
#include "occ_improve/tools/progress.hpp"
#include "occ_improve/tools/tool_frames.hpp"
#include "occ_improve/tools/tool_main.hpp"
#include "occ_improve/tools/tool_mask.hpp"
#include "occ_improve/tools/tool_options.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/sim/render.hpp"
#include "occ_improve/timing.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

using namespace occ_improve;

namespace {

const ToolFlags kFlags{
    "occ_plan",
    {"-load MAP.occmap [plan options] -o OUTDIR", "[options] INPUT... -o OUTDIR", "-sample [options] -o OUTDIR",
     "[options] -input_dir DIR -output_dir OUTDIR   (each frame file of DIR on its own, into OUTDIR/<stem>/)"},
    "Plans the next shot (docs/SELECTIVE.md): rays scored by improvement x return probability (the map's\n"
    "return record; none for frames), coarse-to-fine by default or in one of three other shapes. Writes\n"
    "  OUTDIR/shot_mask.png   grey, one pixel per column (255 = in the shot); with the pixel-native\n"
    "                         kinect_v1 preset it is aligned with the depth image\n"
    "  OUTDIR/shot_rays.csv   the shot's rays: rank, column, azimuth/elevation bin, improvement,\n"
    "                         return probability, score, surface depth, reacquisition\n"
    "  OUTDIR/plan.txt        expected gain, rays, stop decision and its reason (also printed)\n"
    "  OUTDIR/predicted_depth.png  with -predicted_depth nearest|linear: the map's dense depth from its\n"
    "                         samples, 16-bit grey in millimetres (0 = none within -radius)\n",
    joined({output_folder_flag_names(), {"-q", "-load", "-sample", "-budget", "-shape", "-refine", "-window",
                                         "-negative_share", "-stop_gain", "-stop_share", "-predicted_depth", "-radius"},
            sensor_flag_names(), camera_flag_names(), {"-no_poses", "-mask"}, batch_flag_names()}),
    {},
    {},
    frame_inputs_help()};

struct Source {
  std::optional<Mapper> mapper;
  ReturnRecord returns;
  std::string description;
  std::string points;  ///< the frames' points line (describe_points), "" for a loaded map
  std::string mask;  ///< the mask's summary line, "" without -mask
};

Source map_from_frames(const CommandLine& command_line, const ToolOptions& options, bool use_sample,
                       ProgressLine& progress) {
  ToolFrameReader frames(options, use_sample);  // intrinsics from flags, the dataset or fitted; never assumed
  Source source;
  SensorPreset preset;
  const FusedFrames fused = fuse_tool_frames(
      frames, progress,
      [&](const std::optional<ToolFrame>& first) {
        preset = options.preset_for_camera(first ? first->camera : std::nullopt);
        source.mapper.emplace(preset, options.grid);
        source.mask = apply_tool_mask(command_line, *source.mapper, first ? &*first : nullptr);
      },
      [&](const ToolFrame& frame) { return source.mapper->insert(span_of(frame.cloud)).insertion; });
  source.returns = ReturnRecord::for_grid(source.mapper->geometry().width(), source.mapper->geometry().height());
  source.description = (use_sample ? std::string("built-in sample") : std::to_string(fused.frames) + " frame(s)") +
                       ", preset " + preset.name + ", " + fused.camera;
  source.points = describe_points(fused.insertion);
  // A scene nearer than the range's start (or beyond its end) leaves the map without data: the plan asks
  // for everything, as it should, but the user is told why.
  if (!has_points_in_depth_range(fused.insertion))
    std::fprintf(stderr, "warning: %s\n",
                 nothing_in_depth_range(describe_inputs(fused), preset.geometry, fused.insertion,
                                        "the map holds no return, every ray plans as unseen").c_str());
  return source;
}

Source map_from_file(const CommandLine& command_line, const std::string& path, const ToolOptions& options) {
  LoadedMap loaded = load_tool_map(path, options);
  Source source;
  source.mapper.emplace(std::move(loaded.grid), SensorModel(loaded.model));
  source.mask = apply_tool_mask(command_line, *source.mapper, nullptr);
  source.returns = std::move(loaded.returns);
  char record[128];
  std::snprintf(record, sizeof record, " (return record: %llu rays asked, %llu returned, rate %.3f)",
                static_cast<unsigned long long>(source.returns.total_asked()),
                static_cast<unsigned long long>(source.returns.total_returned()), record_return_rate(source.returns));
  source.description = "map " + path + record;
  return source;
}

void write_mask(const std::string& path, const GridGeometry& geometry, const Shot& shot) {
  Image mask{geometry.width(), geometry.height(), 1, std::vector<std::uint8_t>(geometry.column_count(), 0)};
  for (ColumnIndex c : shot.columns) mask.pixels[c] = 255;
  write_png(path, mask);
}

void write_rays(const std::string& path, const Mapper& mapper, const ReturnRecord& returns, const Shot& shot,
                const ReturnModelParams& model) {
  const std::vector<float> p = return_probability_map(returns, model);
  const std::vector<float> score = shot_scores(mapper.improvement(), returns, model);  // what the plan ranked by
  std::ofstream out(path);
  out << "rank,column,azimuth_bin,elevation_bin,improvement,return_probability,score,depth_m,reacquisition\n";
  const GridGeometry& g = mapper.geometry();
  for (std::size_t i = 0; i < shot.columns.size(); ++i) {
    const ColumnIndex c = shot.columns[i];
    const float imp = mapper.improvement().value[c];
    out << i + 1 << ',' << c << ',' << g.azimuth_bin_of(c) << ',' << g.elevation_bin_of(c) << ',' << imp << ',' << p[c]
        << ',' << score[c] << ',' << mapper.surface().depth_m[c] << ',' << (i >= shot.ranked_rays ? 1 : 0) << '\n';
  }
  if (!out.flush()) throw IoError("cannot write '" + path + "'");
}

int run(const CommandLine& command_line) {
  const ToolOptions options = parse_tool_options(command_line);
  const std::string load_path = command_line.text("-load").value_or("");
  const bool use_sample = command_line.has("-sample");
  const int sources = (load_path.empty() ? 0 : 1) + (use_sample ? 1 : 0) + (options.inputs.empty() ? 0 : 1);
  if (sources != 1) throw InvalidParameter("give exactly one of -load MAP, input files, or -sample (see -h)");
  PlanRequest request = plan_request_from_flags(command_line);
  // Fail on an unwritable or foreign output folder before any work (never overwrites what it did not write).
  OutputFolder out = open_output_folder(command_line);

  const auto start = SteadyClock::now();
  ProgressLine progress(command_line, "frame");
  const Source source = load_path.empty() ? map_from_frames(command_line, options, use_sample, progress)
                                          : map_from_file(command_line, load_path, options);
  fit_plan_to_grid(command_line, request, source.mapper->geometry().width(), source.mapper->geometry().height());
  request.candidates = source.mapper->column_mask();  // rays outside -mask are never taken (empty: all)
  const auto planned = SteadyClock::now();
  const Shot shot = plan_next_shot(*source.mapper, source.returns, request);
  const double plan_ms = 1e3 * seconds_since(planned);

  write_mask(out.file("shot_mask.png"), source.mapper->geometry(), shot);
  write_rays(out.file("shot_rays.csv"), *source.mapper, source.returns, shot, request.return_model);
  warn_if_ignored(command_line, "-radius", "-predicted_depth", *command_line.text("-predicted_depth") != "none");
  const std::string predicted =
      write_predicted_depth(out, *source.mapper, *command_line.text("-predicted_depth"), *command_line.integer("-radius"));
  char summary[512];
  std::snprintf(summary, sizeof summary,
                "expected_gain %.6g\nstop_gain_per_ray %.6g\nrays %zu\nranked_rays %zu\nstop %s\nreason %s\n",
                shot.expected_gain, shot.stop_gain_per_ray, shot.columns.size(), shot.ranked_rays, shot.stop ? "yes" : "no",
                shot.reason.c_str());
  std::ofstream plan(out.file("plan.txt"));
  if (!(plan << summary) || !plan.flush()) throw IoError("cannot write '" + out.file("plan.txt") + "'");
  plan.close();
  throw_if_stop_requested();  // before anything is committed: an interrupted run leaves nothing behind
  out.commit();
  if (!source.mask.empty()) std::printf("%s\n", source.mask.c_str());
  std::printf("read %s (%.2f s)\n%s%s%splanned in %.2f ms; wrote %s/: shot_mask.png shot_rays.csv plan.txt%s%s\n",
              source.description.c_str(), std::chrono::duration<double>(planned - start).count(), source.points.c_str(),
              source.points.empty() ? "" : "\n", summary, plan_ms,
              out.path().c_str(), predicted.empty() ? "" : " ", predicted.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return run_tool(argc, argv, kFlags, run); }
