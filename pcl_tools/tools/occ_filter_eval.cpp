// occ_filter_eval: selective acquisition in a PCL pipeline. Over a posed depth sequence, ImprovementFilter
// keeping a fraction of each frame (chosen against the map before the frame is inserted) against
// pcl::RandomSample and pcl::VoxelGrid keeping as many points; each map is scored against the map from all
// points (filter_eval.hpp, docs/SELECTIVE.md "The same question in a PCL pipeline").
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/eval/filter_eval.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/tools/tool_main.hpp"
#include "occ_improve/tools/tool_options.hpp"


#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

using namespace occ_improve;

namespace {

const ToolFlags kFlags{
    "occ_filter_eval",
    {"SEQUENCE_FOLDER [options]"},
    "A posed depth sequence (7-Scenes or TUM RGB-D layout, see sequence_sources.hpp), every frame put in the\n"
    "first frame's view. Reference: the map from all points. For each fraction, four runs from an empty\n"
    "map keep that share of each frame: ImprovementFilter (top fraction, chosen against the run's map\n"
    "before the frame is inserted), the same on the frame's points in a seeded random order\n"
    "(improvement_shuffled: ties go to random points, not the top rows), pcl::RandomSample (as many\n"
    "points, seeded) and pcl::VoxelGrid (leaf bisected to about as many). After each frame: points kept\n"
    "so far and the quality = share of the reference's surface columns whose predicted depth lies within\n"
    "2 sigma(z); columns = distinct rays a frame's kept points fall in.\n"
    "Writes OUTDIR/filter.csv (strategy,fraction,frame,asked,kept,columns,points,leaf_m,quality).\n",
    joined({output_folder_flag_names(), {"-fractions", "-max_frames", "-radius", "-seed"}, sensor_flag_names(),
            {"-intrinsics", "-intrinsics_file"}}),  // the sequence's layout fixes its depth encoding
    {{"-o", "out/filter"}},
    {},
    "  SEQUENCE_FOLDER           7-Scenes (frame-*.depth.png + .pose.txt; a scene folder reads its seq-*/\n"
    "                            subfolders in turn) or TUM RGB-D (depth.txt, groundtruth.txt) folder\n"};

std::vector<double> parse_fractions(const CommandLine& command_line) {
  const std::string text = *command_line.text("-fractions");
  const std::vector<double> fractions = parse_number_list("-fractions", text);
  for (double f : fractions)
    if (!(f > 0 && f <= 1)) throw InvalidParameter("-fractions " + text + " is invalid: every share must be in (0, 1]");
  return fractions;
}

struct EvalSetup {
  std::string folder;
  SensorPreset preset;
  PinholeIntrinsics intrinsics;
  DepthSequence sequence;
};

EvalSetup setup(const ToolOptions& options) {
  if (options.inputs.size() != 1) throw InvalidParameter("give exactly one sequence folder (see -h)");
  EvalSetup s{options.inputs.front(), {}, {}, scan_depth_sequence(options.inputs.front())};
  const std::optional<PinholeIntrinsics> camera = options.intrinsics ? options.intrinsics : s.sequence.intrinsics;
  if (!camera) throw InvalidInput(s.folder + " has no camera-intrinsics.txt: give -intrinsics or -intrinsics_file");
  s.intrinsics = *camera;
  s.preset = options.preset_for_camera(camera);
  return s;
}

void write_steps(std::ostream& csv, KeepStrategy strategy, double fraction, const std::vector<FilterStep>& steps) {
  for (const FilterStep& s : steps)
    csv << keep_strategy_name(strategy) << ',' << fraction << ',' << s.frame << ',' << s.asked << ',' << s.kept << ','
        << s.columns << ',' << s.points << ',' << s.leaf_m << ',' << s.quality << '\n';
}

int run(const CommandLine& command_line) {
  const ToolOptions options = parse_tool_options(command_line);
  const std::vector<double> fractions = parse_fractions(command_line);
  const int max_frames = *command_line.integer("-max_frames");
  FilterEvalOptions eval;
  eval.radius_columns = *command_line.integer("-radius");
  eval.seed = static_cast<std::uint32_t>(*command_line.integer("-seed"));
  OutputFolder out = open_output_folder(command_line);

  const EvalSetup s = setup(options);
  const InputScope scope(s.folder);  // an error (no poses, an unreadable frame) names the folder given
  const Frames frames = read_posed_frames(s.sequence, s.intrinsics, Mapper(s.preset).geometry(),
                                          static_cast<std::size_t>(max_frames));
  const Mapper reference = map_of_all_points(frames, s.preset);
  std::fprintf(stderr, "%s: %zu frames, preset %s; reference: all points\n", s.folder.c_str(), frames.size(),
               s.preset.name.c_str());
  std::ofstream csv(out.file("filter.csv"));
  csv << "strategy,fraction,frame,asked,kept,columns,points,leaf_m,quality\n";
  for (double fraction : fractions)
    for (KeepStrategy strategy : {KeepStrategy::improvement, KeepStrategy::improvement_shuffled, KeepStrategy::random_sample,
                                  KeepStrategy::voxel_grid}) {
      throw_if_stop_requested();
      const std::vector<FilterStep> steps = run_keep_strategy(strategy, fraction, frames, s.preset, reference, eval);
      write_steps(csv, strategy, fraction, steps);
      std::printf("%-20s %.2f: %zu points, quality %.4f\n", keep_strategy_name(strategy), fraction,
                  steps.back().points, steps.back().quality);
    }
  if (!csv.flush()) throw IoError("cannot write '" + out.file("filter.csv") + "'");
  csv.close();
  out.commit();
  std::printf("wrote %s/filter.csv\n", out.path().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return run_tool(argc, argv, kFlags, run); }
