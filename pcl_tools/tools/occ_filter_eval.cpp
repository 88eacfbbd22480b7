// occ_filter_eval: selective acquisition in a PCL pipeline. Over a posed depth sequence, ImprovementFilter
// keeping a fraction of each frame (chosen against the map before the frame is inserted) against
// pcl::RandomSample and pcl::VoxelGrid keeping as many points; each map is scored against the map from all
// points (filter_eval.hpp, docs/SELECTIVE.md "The same question in a PCL pipeline").
#include "occ_improve/errors.hpp"
#include "occ_improve/eval/filter_eval.hpp"
#include "occ_improve/pcl/tool_options.hpp"

#include <pcl/console/parse.h>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

using namespace occ_improve;

namespace {

void print_usage(const char* program) {
  std::cout << "Usage: " << program << " SEQUENCE_FOLDER [options]\n\n"
            << "A posed depth sequence (7-Scenes or TUM RGB-D layout, see sequence_sources.hpp), every frame put\n"
            << "in the first frame's view. Reference: the map from all points. For each fraction, four runs\n"
            << "from an empty map keep that share of each frame: ImprovementFilter (top fraction, chosen against\n"
            << "the run's map before the frame is inserted), the same on the frame's points in a seeded random\n"
            << "order (improvement_shuffled: ties go to random points, not the top rows), pcl::RandomSample (as\n"
            << "many points, seeded) and pcl::VoxelGrid (leaf bisected to about as many). After each frame:\n"
            << "points kept so far and the quality = share of the reference's surface columns whose predicted\n"
            << "depth lies within 2 sigma(z); columns = distinct rays a frame's kept points fall in.\n"
            << "Writes OUT/filter.csv (strategy,fraction,frame,asked,kept,columns,points,leaf_m,quality).\n\n"
            << usage_output_folder("out/filter")
            << "  -fractions LIST   shares of each frame to keep (default 0.05,0.2)\n"
            << "  -frames N         the first N frames only (default 0: all)\n"
            << "  -radius R         predict_depth radius in columns (default 16)\n"
            << "  -seed N           RandomSample's seed (default 1)\n\n"
            << usage_common();
}

std::vector<double> parse_fractions(int argc, char** argv) {
  std::string text = "0.05,0.2";
  pcl::console::parse_argument(argc, argv, "-fractions", text);
  std::vector<double> fractions;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    try {
      fractions.push_back(std::stod(item));
    } catch (const std::logic_error&) {
      throw InvalidParameter("-fractions " + text + " is invalid: '" + item + "' is not a number");
    }
    detail::require_parameter(fractions.back() > 0 && fractions.back() <= 1, "-fractions", fractions.back(), "in (0, 1]");
  }
  if (fractions.empty()) throw InvalidParameter("-fractions is empty: give e.g. 0.05,0.2");
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

int run(int argc, char** argv) {
  ToolSpec spec;
  spec.value_flags = {"-o", "-fractions", "-frames", "-radius", "-seed"};
  spec.switches = {"-overwrite"};
  const ToolOptions options = parse_tool_options(argc, argv, spec);
  const std::vector<double> fractions = parse_fractions(argc, argv);
  int max_frames = 0, seed = 1;
  FilterEvalOptions eval;
  pcl::console::parse_argument(argc, argv, "-frames", max_frames);
  pcl::console::parse_argument(argc, argv, "-radius", eval.radius_columns);
  pcl::console::parse_argument(argc, argv, "-seed", seed);
  detail::require_parameter(max_frames >= 0, "-frames", max_frames, ">= 0");
  detail::require_parameter(eval.radius_columns >= 0, "-radius", eval.radius_columns, ">= 0");
  detail::require_parameter(seed >= 0, "-seed", seed, ">= 0");
  eval.seed = static_cast<std::uint32_t>(seed);
  OutputFolder out = open_output_folder(argc, argv, "occ_filter_eval", "out/filter");

  const EvalSetup s = setup(options);
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
      throw_if_interrupted();
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

int main(int argc, char** argv) { return run_tool(argc, argv, print_usage, run); }
