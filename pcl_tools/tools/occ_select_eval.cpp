// occ_select_eval: does following the improvement map build a better map per point acquired than
// sampling uniformly? The flags, the scenes and the output folder; the evaluation (strategies (a)-(g) of
// docs/SELECTIVE.md against a virtual selective sensor) is occ_improve/eval/select_eval.hpp.
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/eval/select_eval.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/tools/tool_frames.hpp"
#include "occ_improve/tools/tool_main.hpp"
#include "occ_improve/tools/tool_options.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <fstream>
#include <string>
#include <vector>

namespace {

using namespace occ_improve;

const ToolFlags kFlags{
    "occ_select_eval",
    {"SCENE... [options]"},
    "For each scene and budget, strategies (a) full frames, (b) uniform random without replacement,\n"
    "(c) regular decimation, (d) improvement-guided, (e) (d) + return model, (f) (e) + re-acquisition of\n"
    "negative rays, (g) coarse-to-fine (coverage pass, then one ray per block by the multi-scale improvement x\n"
    "the predictor's residual; g_improvement / g_residual: by one of them; g_triangles: by the samples'\n"
    "triangles) acquire from a virtual Kinect v1 (virtual_sensor.hpp), each scored with every -predictors rule\n"
    "(runs of the linear one are named <strategy>_linear). o_oracle, run only when named, is a reference\n"
    "that reads the scene (after (g)'s first shot, the unasked rays whose prediction is wrong, worst first).\n"
    "Quality = share of\n"
    "scene-return rays whose predicted depth lies within 2 sigma(z) = 2 x 1.425e-3 z^2 of the scene's.\n"
    "Writes OUTDIR/<scene>.csv per scene and OUTDIR/summary.csv.\n",
    joined({output_folder_flag_names(), {"-budgets", "-frames", "-negative_share", "-radius", "-seed", "-strategies", "-predictors"},
            camera_flag_names()}),
    {{"-o", "out/select"}, {"-negative_share", "0.1"}},
    {},
    "  sample                    the built-in scene, noise-free\n"
    "  FILE.pcd / FILE.ply       an organized cloud (intrinsics fitted to it unless -intrinsics)\n"
    "  depth image or FOLDER     16-bit depth with its dataset's camera-intrinsics.txt or -intrinsics; the\n"
    "                            first frame of a folder\n"};

// A scene's name, which names its CSV (OUTDIR/<name>.csv): the file's or folder's name to its first dot.
std::string scene_name(const std::string& input) {
  if (input == "sample") return input;
  std::filesystem::path path(input);
  if (path.filename().empty()) path = path.parent_path();  // a folder given as "frames/"
  const std::string name = path.filename().string();
  return name.substr(0, name.find('.'));
}

// Every scene writes its own CSV: two scenes of one name (d1/scene.pcd, d2/scene.pcd), or one named like
// the summary, would replace each other's results.
void require_distinct_scene_names(const std::vector<std::string>& scenes) {
  std::map<std::string, std::string> input_of;
  for (const std::string& input : scenes) {
    const std::string name = scene_name(input);
    if (name.empty() || name == "summary")
      throw InvalidParameter("scene '" + input + "' would write '" + name + ".csv': rename it");
    const auto [first, fresh] = input_of.emplace(name, input);
    if (!fresh)
      throw InvalidParameter("scenes '" + first->second + "' and '" + input + "' would both write " + name +
                             ".csv: give the scenes distinct file names");
  }
}

SelectScene load_scene(const std::string& input, const ToolOptions& options) {
  SelectScene s;
  s.name = scene_name(input);
  if (input == "sample") {
    sample::SceneOptions clean;
    clean.noise = clean.quantise = false;
    const sample::SampleFrame f = sample::generate_scene(clean);
    return {"sample", f.depth_m, f.intrinsics};
  }
  // The tools' frame rules: intrinsics from -intrinsics, the dataset or fitted to the cloud; never assumed.
  const ToolFrame frame = read_tool_frame(options, single_frame_source(input, "a scene"));
  if (!frame.cloud.isOrganized() || frame.cloud.height <= 1 || !frame.camera)
    throw InvalidInput(input + ": not an organized frame");
  s.intrinsics = *frame.camera;
  s.depth_m = depth_of_organized(frame.cloud);
  return s;
}

// One scene's CSV in the output folder, its rows from the evaluation.
std::vector<SelectSummaryRow> evaluate_scene(const SelectScene& scene, const SelectEvalOptions& options,
                                             OutputFolder& out) {
  const std::string path = out.file(scene.name + ".csv");
  std::ofstream csv(path);
  if (!csv) throw IoError("cannot write " + path);
  return evaluate_select_scene(scene, options, csv);
}

SelectEvalOptions parse_options(const CommandLine& command_line) {
  SelectEvalOptions o;
  o.budgets = parse_number_list("-budgets", *command_line.text("-budgets"));
  for (std::size_t i = 0; i < o.budgets.size(); ++i) {
    const double b = o.budgets[i];
    if (!(b > 0 && b <= 1)) throw InvalidParameter("-budgets " + *command_line.text("-budgets") + " is invalid: every share must be in (0, 1]");
    // A repeated share ran the same runs twice, their rows repeated in the CSVs.
    if (std::find(o.budgets.begin(), o.budgets.begin() + static_cast<std::ptrdiff_t>(i), b) != o.budgets.begin() + static_cast<std::ptrdiff_t>(i))
      throw InvalidParameter("-budgets " + *command_line.text("-budgets") + " is invalid: a share is repeated");
  }
  o.frames = *command_line.number("-frames");
  o.share = *command_line.number("-negative_share");
  o.radius = *command_line.integer("-radius");
  o.seed = static_cast<std::uint64_t>(*command_line.integer("-seed"));
  o.strategies = select_strategies_by_names(*command_line.text("-strategies"));
  o.predictors = select_predictors_by_names(*command_line.text("-predictors"));
  return o;
}

int run(const CommandLine& command_line) {
  const SelectEvalOptions o = parse_options(command_line);
  const ToolOptions frame_options = parse_tool_options(command_line);
  const std::vector<std::string>& scenes = command_line.positionals();
  if (scenes.empty()) throw InvalidParameter("no scene given (see -h)");
  require_distinct_scene_names(scenes);
  OutputFolder out = open_output_folder(command_line);
  std::vector<SelectSummaryRow> all;
  for (const std::string& input : scenes) {
    throw_if_stop_requested();
    const InputScope scope(input);
    const SelectScene scene = load_scene(input, frame_options);
    std::fprintf(stderr, "%s: %d x %d, fx %.1f\n", scene.name.c_str(), scene.intrinsics.width, scene.intrinsics.height,
                 scene.intrinsics.fx);
    const std::vector<SelectSummaryRow> rows = evaluate_scene(scene, o, out);
    all.insert(all.end(), rows.begin(), rows.end());
  }
  write_select_summary(all, out.file("summary.csv"));
  out.commit();
  std::printf("wrote %s/summary.csv and one CSV per scene\n", out.path().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return run_tool(argc, argv, kFlags, run); }
