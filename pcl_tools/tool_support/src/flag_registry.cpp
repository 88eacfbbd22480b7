#include "occ_improve/tools/flag_registry.hpp"

#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <limits>
#include <stdexcept>

namespace occ_improve {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

FlagSpec switch_flag(std::string name, std::string group, std::string help) {
  FlagSpec f;
  f.name = std::move(name);
  f.group = std::move(group);
  f.help = std::move(help);
  return f;
}

FlagSpec value_flag(std::string name, FlagKind kind, std::string value_name, std::string group, std::string help,
                    std::string default_value, std::string default_note = "") {
  FlagSpec f = switch_flag(std::move(name), std::move(group), std::move(help));
  f.kind = kind;
  f.value_name = std::move(value_name);
  f.default_value = std::move(default_value);
  f.default_note = std::move(default_note);
  return f;
}

FlagSpec bounded(FlagSpec f, double minimum, double maximum = kInf, bool minimum_exclusive = false,
                 bool maximum_exclusive = false) {
  f.minimum = minimum;
  f.maximum = maximum;
  f.minimum_exclusive = minimum_exclusive;
  f.maximum_exclusive = maximum_exclusive;
  return f;
}

FlagSpec with_note(FlagSpec f, std::string default_note) {
  f.default_note = std::move(default_note);
  return f;
}

FlagSpec choice(std::string name, std::vector<std::string> choices, std::string group, std::string help,
                std::string default_value) {
  std::string value_name;
  for (const std::string& c : choices) value_name += (value_name.empty() ? "" : "|") + c;
  FlagSpec f = value_flag(std::move(name), FlagKind::choice, value_name, std::move(group), std::move(help),
                          std::move(default_value));
  f.choices = std::move(choices);
  return f;
}

const char* const kInput = "Input";
const char* const kSensor = "Sensor and grid";
const char* const kMap = "Map";
const char* const kOutput = "Output";
const char* const kStream = "Stream source";
const char* const kPlan = "Shot planning";
const char* const kOctomap = "OctoMap";
const char* const kSegmentation = "Segmentation";
const char* const kPcl = "PCL's segmentation (the comparison)";
const char* const kEvaluation = "Evaluation";
const char* const kGeneral = "General";
const char* const kBatch = "Batch (one output folder per input file)";

std::vector<FlagSpec> input_flags() {
  using K = FlagKind;
  return {
      value_flag("-intrinsics", K::text, "FX,FY,CX,CY[,W,H]", kInput,
                 "depth camera intrinsics [pixels]; the size defaults to 640x480", "",
                 "the dataset's camera-intrinsics.txt, else fitted to an organized cloud; never assumed"),
      value_flag("-intrinsics_file", K::text, "PATH", kInput,
                 "intrinsics from \"fx fy cx cy [w h]\" or a 3x3 matrix (camera-intrinsics.txt)", "",
                 "as -intrinsics"),
      with_note(choice("-depth_encoding", {"mm", "tum", "sun", "nyu"}, kInput,
                       "16-bit depth units: millimetres, TUM's 1/5000 m, SUN RGB-D's bit-rotated mm, NYU's raw\n"
                       "disparity", ""),
                "guessed per file from its values"),
      switch_flag("-no_poses", kInput,
                  "ignore the frames' poses (.pose.txt, groundtruth.txt, a PCD's VIEWPOINT); by default every\n"
                  "frame is moved into the first frame's sensor frame (with -load, the map's)"),
      switch_flag("-sample", kInput, "use the built-in generated Kinect-like frame instead of input files"),
      value_flag("-mask", K::text, "PNG|finite", kInput,
                 "validity / region-of-interest mask over the camera's pixels: an 8- or 16-bit grey PNG of the\n"
                 "camera's size, nonzero = valid. Rays outside it are not observable: their points are left\n"
                 "out, they are never ranked, in a region or planned, and drawn grey. finite: the first\n"
                 "frame's valid pixels (for clouds cropped to NaN, as mOSD's; on a raw frame it also hides the\n"
                 "holes and shadows the map is there to find)",
                 "", "none: every ray"),
  };
}

std::vector<FlagSpec> sensor_flags() {
  using K = FlagKind;
  return {
      choice("-preset", preset_names(), kSensor,
             "kinect_v1: one column per camera pixel, depth along z, 2048 inverse-depth bins 0.5-8 m,\n"
             "sigma_z = 1.425e-3 z^2; kinect_v1_paper: the paper's 640x480x512 spherical bins, 57x43 deg,\n"
             "0-5 m, constant sigmas; kinect_v1_spherical: kinect_v1's depth model over spherical bins",
             "kinect_v1"),
      bounded(value_flag("-sigma_depth", K::number, "M", kSensor, "constant depth sigma [m]", "", "the preset's"), 0),
      bounded(value_flag("-sigma_depth_quadratic", K::number, "C", kSensor,
                         "depth sigma term growing with rho^2 [1/m] (sigma = sigma_depth + C rho^2)", "",
                         "the preset's"),
              0),
      bounded(value_flag("-sigma_angle", K::number, "RAD", kSensor,
                         "angular sigma [rad] (pixel-native grids: the same angle in pixels at the centre);\n"
                         "at most 4 bin widths, and support_k x sigma at most 8 (docs/METHOD.md)",
                         "",
                         "the preset's"),
              0, kInf, true),
      bounded(value_flag("-support_k", K::number, "K", kSensor, "region of support in standard deviations", "",
                         "the preset's, 2"),
              0, kInf, true),
      bounded(value_flag("-depth_bins", K::integer, "N", kSensor, "number of depth bins", "", "the preset's"), 1),
      bounded(value_flag("-depth_max", K::number, "M", kSensor, "far end of the depth range [m]", "", "the preset's"),
              0, kInf, true),
      value_flag("-fov", K::text, "H,V", kSensor, "field of view centred on the optical axis [deg], spherical grids only",
                 "", "the preset's"),
      choice("-mode", {"clamped", "exact"}, kSensor,
             "clamp the log-odds after each update, or sum them as eq. 2 does", "clamped"),
      choice("-clamp", {"paper", "octomap"}, kSensor,
             "clamping thresholds: 0.001/0.999, or OctoMap's 0.1192/0.971", "paper"),
      bounded(value_flag("-memory_cap", K::number, "GIB", kSensor,
                         "refuse a grid or map whose worst case (voxels, per-column maps, per-bin tables)\n"
                         "exceeds this [GiB]",
                         "", "half of the physical memory"),
              0, kInf, true),
  };
}

std::vector<FlagSpec> map_and_output_flags() {
  using K = FlagKind;
  return {
      value_flag("-load", K::text, "MAP.occmap", kMap,
                 "start from a saved grid; it carries its own preset, so preset flags are ignored. Frames\n"
                 "with poses are moved into its view by the pose saved with it (a -save of posed frames);\n"
                 "a map without one takes frames without poses (or -no_poses) only", "", "none: an empty grid"),
      value_flag("-save", K::text, "MAP.occmap", kMap, "save the resulting grid (written atomically, after the other outputs); an existing file\n"
                 "is replaced only when it is an occ_improve map (or with -overwrite), never an input", "", "not saved"),
      bounded(value_flag("-threads", K::integer, "N", kMap, "insertion threads; 0: all cores", "0"), 0,
              InsertionOptions::kMaxThreads),
      bounded(value_flag("-k", K::integer, "K", kMap, "how many top rays and regions to report", "10"), 1),
      value_flag("-min_improvement", K::number, "V", kMap,
                 "a region's rays have improvement >= V (0.2: above a ray seen once, below no data)", "0.2"),
      value_flag("-o", K::text, "OUT", kOutput,
                 "where the output goes: a folder, created with its parents (occ_to_octomap: a .bt/.ot\n"
                 "file; a failed run removes the parents it created). Written in a staging folder and moved\n"
                 "into place at the end; a folder holding files\n"
                 "this tool did not write (marker " + std::string(kOutputMarkerName) + ") is refused",
                 "", "required"),
      switch_flag("-overwrite", kOutput,
                  "write into such a folder anyway: files of the same names are replaced, nothing else is touched;\n"
                  "also replace an output file (-save, occ_to_octomap -o) that occ_improve did not write (an\n"
                  "input of the run is never replaced)"),
      switch_flag("-q", kOutput, "no progress line (it is only shown when stderr is a terminal)"),
      value_flag("-input_dir", K::text, "DIR", kBatch,
                 "batch mode, as PCL's tools: every frame file in DIR (.pcd .ply .png .pgm .tif .tiff; not its\n"
                 "subfolders) is processed on its own, into OUTDIR/<file stem>/ (-output_dir); instead of\n"
                 "positional inputs and -o. Files that fail are named and counted, the run goes on and exits 1",
                 "", "none: the inputs are fused"),
      value_flag("-output_dir", K::text, "OUTDIR", kBatch,
                 "with -input_dir: where the per-file output folders go (never inside DIR); each follows -o's\n"
                 "rules (a folder this tool did not write is refused before any work, unless -overwrite)",
                 "", "required with -input_dir"),
  };
}

std::vector<FlagSpec> stream_flags() {
  using K = FlagKind;
  FlagSpec device = value_flag("-device", K::text, "[URI]", kStream, "live OpenNI2 device: the first one found, or its URI",
                               "", "none");
  device.optional_value = true;
  return {
      device,
      value_flag("-oni", K::text, "FILE", kStream, "OpenNI2 recording", "", "none"),
      value_flag("-pcd_dir", K::text, "DIR", kStream, "the .pcd files of a folder, in name order", "", "none"),
      value_flag("-depth_dir", K::text, "DIR", kStream,
                 "depth-image sequence: 7-Scenes (frame-*.depth.png, .pose.txt, camera-intrinsics.txt;\n"
                 "a scene folder reads its seq-*/ subfolders in turn), TUM RGB-D (depth.txt,\n"
                 "groundtruth.txt) or a folder of 16-bit PNG/PGM/TIFF (PCL's grabber layout: *_depth.tiff)",
                 "", "none"),
      bounded(value_flag("-fps", K::number, "F", kStream,
                         "file sources: frames per second, 0 (as fast as possible) or at least 0.001", "0"),
              0, 1000),
      switch_flag("-drop", kStream,
                  "file sources: the newest frame wins, like a live sensor (default: every frame is processed)"),
      bounded(value_flag("-keep", K::number, "F", kStream,
                         "insert only this share of each frame, chosen by the map before the frame goes in\n"
                         "(selective sensing, docs/SELECTIVE.md); the rest is counted in the summary", "1"),
              0, 1, true),
      bounded(value_flag("-max_frames", K::integer, "N", kStream,
                         "only the first N frames (live: stop after N processed); 0: all", "0"),
              0),
      bounded(value_flag("-save_every", K::integer, "N", kStream, "also write the maps every N processed frames; 0: at the end",
                         "0"),
              0),
      switch_flag("-stop_on_signal", kStream,
                  "stop once the improvement stop signal fires (frames already taken in are finished)"),
      value_flag("-simulate", K::text, "FRAME", kStream,
                 "the closed loop of docs/SELECTIVE.md against a virtual Kinect v1 over one real frame\n"
                 "(organized PCD or depth image): plan a shot, acquire its rays, insert, learn which rays\n"
                 "never return, until the plan says stop. Pixel-native presets only", "", "none"),
      bounded(value_flag("-max_shots", K::integer, "N", kStream, "-simulate: stop after N shots at the latest", "1000"), 1),
      switch_flag("-view", kStream,
                  "show the improvement map and the top regions' boxes in a window as frames arrive (PCL's\n"
                  "ImageViewer; needs an X display, headless: xvfb-run -a). Closing the window ends the run"),
      value_flag("-view_screenshot", K::text, "FILE", kStream,
                 "-view: at the end, write the window's pixels to FILE (PNG), beside the -o folder", "", "none"),
  };
}

std::vector<FlagSpec> plan_and_octomap_flags() {
  using K = FlagKind;
  return {
      bounded(value_flag("-budget", K::integer, "N", kPlan, "rays per shot", "4096", "4096, or every ray of a smaller grid"), 1),
      choice("-shape", {"coarse_to_fine", "rays", "window", "decimation"}, kPlan,
             "shot shape: coarse-to-fine (a coverage pass, then one ray per block by the multi-scale\n"
             "improvement and the predictor's residual; docs/SELECTIVE.md), the best single rays, the best\n"
             "WxH window, or every n-th column and row", "coarse_to_fine"),
      choice("-refine", {"triangles", "residual", "both", "improvement"}, kPlan,
             "coarse_to_fine: what ranks the refinement (the measured samples' triangles by area x\n"
             "non-planarity, the best with -predicted_depth linear; or blocks by the predictor's residual,\n"
             "x the improvement, or the improvement alone)", "triangles"),
      value_flag("-window", K::text, "WxH", kPlan, "window shape in columns; its area <= the budget", "64x64"),
      bounded(value_flag("-negative_share", K::number, "S", kPlan, "-shape rays: share of a shot re-acquiring negative rays", "0"), 0,
              1, false, true),
      bounded(value_flag("-stop_gain", K::number, "G", kPlan, "stop below G expected gain per ray", "0.1"), 0),
      bounded(value_flag("-stop_share", K::number, "S", kPlan,
                         "-refine triangles: the stop reads the mean score of the view's best share S of rays", "0.2"),
              0, 1, true, false),
      choice("-predicted_depth", {"none", "nearest", "linear"}, kPlan,
             "also write predicted_depth.png: the map's dense depth from its samples (16-bit mm) by this rule "
             "(docs/SELECTIVE.md \"Predicted depth\"; radius: -radius)",
             "none"),
      bounded(value_flag("-resolution", K::number, "R", kOctomap, "OcTree leaf size [m]", "0.02"), 0, kInf, true),
      value_flag("-pose", K::text, "x,y,z,qx,qy,qz,qw", kOctomap,
                 "sensor pose in the world (world <- optical sensor frame, unit quaternion); one per -load", "",
                 "the pose saved with the map (-save of a posed run), the first frame's pose when the input\n"
                 "has poses, else from -frame"),
      choice("-frame", {"z_up", "optical"}, kOctomap,
             "world frame without poses: z_up puts the sensor at the origin looking along x with z up\n"
             "(ROS, octovis); optical keeps the camera's z forward, y down", "z_up"),
      choice("-free", {"crossed", "wholly"}, kOctomap,
             "free leaves: crossed = free space crosses the leaf (its centre or a corner is free), as OctoMap marks\n"
             "a leaf a ray crosses; wholly = the leaf lies wholly in free space (a leaf with unknown space stays\n"
             "unknown: at 10 cm about two thirds of OctoMap's free leaves)", "crossed"),
  };
}

std::vector<FlagSpec> segmentation_and_evaluation_flags() {
  using K = FlagKind;
  return {
      bounded(value_flag("-contour", K::number, "V", kSegmentation, "contour rays have improvement < V", "",
                         "the preset's: -0.02, -0.01 for a constant depth sigma (kinect_v1_paper)"),
              // Held as a float (-1e300 became -inf, refused naming the library's field); improvements are of
              // order 1, so any bound far below them does.
              -1e30, 0, false, true),
      bounded(value_flag("-min_segment", K::integer, "N", kSegmentation,
                         "smaller regions are attached to a neighbour; islands between holes, which have\n"
                         "none, stay segments [rays]", "200"),
              1),
      switch_flag("-no_plane", kSegmentation,
                  "keep the dominant plane (table, floor); by default it is taken out first, as PCL does"),
      switch_flag("-no_crease", kSegmentation,
                  "cut along the improvement contours only, not along concave creases of the surface"),
      bounded(value_flag("-plane_distance", K::number, "D", kSegmentation, "plane inlier band [m]; it widens with range as the depth noise (2.5 sigma)", "",
                         "0.006 pixel-native, 0.01 spherical"),
              0, kInf, true),
      bounded(value_flag("-pcl_min_inliers", K::integer, "N", kPcl, "OrganizedMultiPlaneSegmentation min inliers", "3000"),
              1),
      bounded(value_flag("-pcl_distance", K::number, "D", kPcl, "EuclideanClusterComparator threshold [m]", "0.005"), 0,
              kInf, true),
      bounded(value_flag("-pcl_min_cluster", K::integer, "N", kPcl, "smallest cluster kept [points]", "500"), 1),
      value_flag("-budgets", K::text, "LIST", kEvaluation, "rays per shot as shares of the image, in (0, 1]",
                 "0.01,0.05,0.2"),
      value_flag("-strategies", K::text, "LIST", kEvaluation,
                 "strategies besides a_full: all, or a comma-separated list of their names", "all"),
      value_flag("-predictors", K::text, "LIST", kEvaluation,
                 "predict_depth rules scoring every strategy: nearest, linear or both", "nearest,linear"),
      value_flag("-fractions", K::text, "LIST", kEvaluation, "shares of each frame to keep, in (0, 1]", "0.05,0.2"),
      bounded(value_flag("-frames", K::number, "N", kEvaluation, "points acquired per run, in full frames", "5"), 0, kInf,
              true),
      bounded(value_flag("-radius", K::integer, "R", kEvaluation, "predict_depth radius [columns]", "16"), 0),
      bounded(value_flag("-seed", K::integer, "N", kEvaluation, "seed of the run's random choices (noise, order)", "1"),
              0),
  };
}

std::vector<FlagSpec> build_registry() {
  std::vector<FlagSpec> all;
  for (auto part : {input_flags(), sensor_flags(), map_and_output_flags(), stream_flags(), plan_and_octomap_flags(),
                    segmentation_and_evaluation_flags()})
    all.insert(all.end(), part.begin(), part.end());
  all.push_back(switch_flag("-h", kGeneral, "this help"));
  all.push_back(switch_flag("-help", kGeneral, "this help"));
  all.push_back(switch_flag("--help", kGeneral, "this help"));
  all.push_back(switch_flag("-v", kGeneral,
                            "verbose: every flag's value (defaults included) on stderr first, and PCL's own\n"
                            "messages at debug level (pcl::console::L_DEBUG), as PCL's tools take -v"));
  return all;
}

}  // namespace

const std::vector<FlagSpec>& flag_registry() {
  static const std::vector<FlagSpec> registry = build_registry();
  return registry;
}

const FlagSpec& flag_spec(const std::string& name) {
  for (const FlagSpec& f : flag_registry())
    if (f.name == name) return f;
  throw std::logic_error("flag " + name + " is not in the flag registry");
}

std::vector<std::string> sensor_flag_names() {
  return {"-preset", "-sigma_depth", "-sigma_depth_quadratic", "-sigma_angle", "-support_k",
          "-depth_bins", "-depth_max", "-fov", "-mode", "-clamp", "-memory_cap"};
}

std::vector<std::string> camera_flag_names() { return {"-intrinsics", "-intrinsics_file", "-depth_encoding"}; }

std::vector<std::string> output_folder_flag_names() { return {"-o", "-overwrite"}; }

std::vector<std::string> batch_flag_names() { return {"-input_dir", "-output_dir"}; }

std::vector<std::string> joined(std::initializer_list<std::vector<std::string>> lists) {
  std::vector<std::string> all;
  for (const auto& list : lists) all.insert(all.end(), list.begin(), list.end());
  return all;
}

}  // namespace occ_improve
