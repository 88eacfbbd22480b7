#include "occ_improve/pcl/tool_options.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"

#include <pcl/console/parse.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <new>
#include <sstream>

namespace occ_improve {

namespace {

const std::vector<std::string> kCommonValueFlags = {
    "-preset", "-sigma_depth", "-sigma_depth_quadratic", "-sigma_angle", "-support_k", "-depth_bins",
    "-depth_max", "-fov", "-k", "-mode", "-clamp", "-intrinsics", "-intrinsics_file", "-depth_encoding"};
const std::vector<std::string> kCommonSwitches = {"-h", "--help"};
constexpr double kPi = 3.14159265358979323846;

bool contains(const std::vector<std::string>& list, const std::string& s) {
  return std::find(list.begin(), list.end(), s) != list.end();
}

[[noreturn]] void bad_flag(const std::string& flag, const std::string& value, const std::string& requirement) {
  throw InvalidParameter(flag + " " + value + " is invalid: must be " + requirement);
}

// A negative number ("-0.5") is a value, not a flag.
bool looks_like_flag(const std::string& arg) {
  if (arg.size() < 2 || arg[0] != '-') return false;
  char* end = nullptr;
  std::strtod(arg.c_str(), &end);
  return *end != '\0';
}

double to_double(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v)) bad_flag(flag, text, "a finite number");
  return v;
}

int to_int(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || v < -2147483647L || v > 2147483647L)
    bad_flag(flag, text, "an integer");
  return static_cast<int>(v);
}

std::vector<double> to_doubles(const std::string& flag, const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(to_double(flag, item));
  return values;
}

// The value of a flag given once; nullopt when absent.
std::optional<std::string> value_of(int argc, const char* const* argv, const char* flag) {
  std::string value;
  if (pcl::console::parse_argument(argc, argv, flag, value) < 0) return std::nullopt;
  return value;
}

std::optional<double> positive_double(int argc, const char* const* argv, const char* flag) {
  const auto text = value_of(argc, argv, flag);
  if (!text) return std::nullopt;
  const double v = to_double(flag, *text);
  if (!(v > 0)) bad_flag(flag, *text, "> 0");
  return v;
}

std::optional<double> non_negative_double(int argc, const char* const* argv, const char* flag) {
  const auto text = value_of(argc, argv, flag);
  if (!text) return std::nullopt;
  const double v = to_double(flag, *text);
  if (v < 0) bad_flag(flag, *text, ">= 0");
  return v;
}

PinholeIntrinsics intrinsics_from_list(const std::string& text) {
  const std::vector<double> v = to_doubles("-intrinsics", text);
  if (v.size() != 4 && v.size() != 6) bad_flag("-intrinsics", text, "fx,fy,cx,cy or fx,fy,cx,cy,width,height");
  PinholeIntrinsics k;
  k.fx = v[0];
  k.fy = v[1];
  k.cx = v[2];
  k.cy = v[3];
  if (v.size() == 6) {
    if (v[4] != std::floor(v[4]) || v[5] != std::floor(v[5]) || v[4] < 1 || v[5] < 1 || v[4] > 65536 || v[5] > 65536)
      bad_flag("-intrinsics", text, "a whole width and height in [1, 65536]");
    k.width = static_cast<int>(v[4]);
    k.height = static_cast<int>(v[5]);
  }
  try {
    k.validate();
  } catch (const InvalidParameter& e) {
    throw InvalidParameter(std::string("-intrinsics ") + text + ": " + e.what());
  }
  return k;
}

void check_arguments(int argc, const char* const* argv, const ToolSpec& spec, std::vector<std::string>& inputs) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (!looks_like_flag(arg)) {
      inputs.push_back(arg);
      continue;
    }
    if (contains(kCommonValueFlags, arg) || contains(spec.value_flags, arg)) {
      if (i + 1 >= argc) throw InvalidParameter(arg + " needs a value");
      ++i;
      continue;
    }
    if (contains(kCommonSwitches, arg) || contains(spec.switches, arg)) continue;
    throw InvalidParameter("unknown option " + arg + " (see -h)");
  }
}

}  // namespace

bool help_requested(int argc, const char* const* argv) {
  return pcl::console::find_switch(argc, argv, "-h") ||
         pcl::console::find_switch(argc, argv, "--help");
}

SensorPreset apply_overrides(SensorPreset p, const PresetOverrides& o) {
  if (o.sigma_depth_m) p.model.sigma_depth_m = *o.sigma_depth_m;
  if (o.sigma_depth_per_m2) p.model.sigma_depth_per_m2 = *o.sigma_depth_per_m2;
  if (o.sigma_angle_rad) {
    p.model.sigma_azimuth_rad = p.model.sigma_elevation_rad = *o.sigma_angle_rad;
    // The pixel-native binning's sigmas are in pixels: the same angle at the image centre.
    if (p.camera) {
      p.model.sigma_u_px = std::tan(*o.sigma_angle_rad) * p.camera->fx;
      p.model.sigma_v_px = std::tan(*o.sigma_angle_rad) * p.camera->fy;
    }
  }
  if ((o.fov_horizontal_deg || o.fov_vertical_deg) && p.geometry.angular_binning == AngularBinning::pinhole)
    throw InvalidParameter("-fov applies to spherical grids; preset " + p.name +
                           " has one column per camera pixel (its field of view is the image's)");
  if (o.support_k) p.model.support_k = *o.support_k;
  if (o.depth_bins) p.geometry.depth_bins = *o.depth_bins;
  if (o.depth_max_m) p.geometry.depth_max_m = *o.depth_max_m;
  if (o.fov_horizontal_deg) {
    const double half = *o.fov_horizontal_deg * kPi / 360.0;
    p.geometry.azimuth_min_rad = -half;
    p.geometry.azimuth_max_rad = half;
  }
  if (o.fov_vertical_deg) {
    const double half = *o.fov_vertical_deg * kPi / 360.0;
    p.geometry.elevation_min_rad = -half;
    p.geometry.elevation_max_rad = half;
  }
  // The overrides are validated together with the preset: a depth_max below the preset's depth_min,
  // for example, only shows here. The message names the field; say which flags set it.
  try {
    p.geometry.validate();
    p.model.validate();
  } catch (const InvalidParameter& e) {
    throw InvalidParameter(std::string(e.what()) + " (after -preset " + p.name + " and the overrides)");
  }
  return p;
}

SensorPreset ToolOptions::preset_for_camera(const std::optional<PinholeIntrinsics>& camera) const {
  if (intrinsics || !camera || !preset.camera) return preset;
  return apply_overrides(preset_by_name(preset_name, *camera), overrides);
}

namespace {

bool is_depth_image(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".png" || ext == ".pgm";
}

bool same_camera(const PinholeIntrinsics& a, const PinholeIntrinsics& b) {
  // Fitted cameras of one sensor agree to ~1e-4 px; a principal point half a pixel off (319.5 against 320,
  // both common) moves every pixel-native column by half its width.
  constexpr double kTolerancePx = 0.05;
  return a.width == b.width && a.height == b.height && std::abs(a.fx - b.fx) <= kTolerancePx &&
         std::abs(a.fy - b.fy) <= kTolerancePx && std::abs(a.cx - b.cx) <= kTolerancePx &&
         std::abs(a.cy - b.cy) <= kTolerancePx;
}

}  // namespace

ToolFrame read_tool_frame(const ToolOptions& options, const FrameSource& source) {
  throw_if_interrupted();
  const InputScope scope(source.path);
  ToolFrame frame;
  std::optional<PinholeIntrinsics> camera = options.intrinsics ? options.intrinsics : source.intrinsics;
  frame.camera_source = options.intrinsics ? options.intrinsics_flag : source.intrinsics ? "the dataset's camera-intrinsics.txt" : "";
  if (!camera && is_depth_image(source.path))
    throw InvalidParameter("'" + source.path + "' is a depth image and no intrinsics were found for it: give "
                           "-intrinsics FX,FY,CX,CY[,W,H] or -intrinsics_file PATH");
  LoadedFrame loaded = load_frame(source.path, camera, options.depth_encoding);
  require_valid_points(span_of(loaded.cloud), source.path);
  frame.name = source.path;
  if (loaded.encoding) frame.name += std::string(" (depth encoding ") + depth_encoding_name(*loaded.encoding) + ")";
  if (!camera && options.preset_needs_camera()) {
    if (loaded.cloud.height <= 1)
      throw InvalidInput("'" + source.path + "' is not organized, so its camera cannot be fitted; preset " +
                         options.preset_name + " needs one: give -intrinsics (or -preset kinect_v1_paper)");
    const IntrinsicsFit fit = estimate_intrinsics_fit(loaded.cloud, kMaxIntrinsicsFitResidualPx);
    camera = fit.intrinsics;
    std::ostringstream why;
    why << "fitted to " << source.path << ", RMS residual " << fit.rms_residual_px << " px over " << fit.points_used
        << " points";
    frame.camera_source = why.str();
  }
  frame.camera = camera;
  frame.cloud = std::move(loaded.cloud);
  frame.colour = std::move(loaded.colour);
  return frame;
}

std::vector<ToolFrame> read_tool_frames(const ToolOptions& options) {
  std::vector<ToolFrame> frames;
  for (const std::string& input : options.inputs) {
    const InputScope scope(input);
    for (const FrameSource& source : expand_input(input)) {
      frames.push_back(read_tool_frame(options, source));
      const ToolFrame &first = frames.front(), &last = frames.back();
      if (first.camera && last.camera && !same_camera(*first.camera, *last.camera))
        throw InvalidInput("'" + source.path + "' was taken with another camera than '" + first.name +
                           "' (" + describe_camera({last}) + " against " + describe_camera({first}) +
                           "): the frames of one map share one viewpoint and camera; give -intrinsics to force one");
    }
  }
  return frames;
}

std::string describe_camera(const std::vector<ToolFrame>& frames) {
  for (const ToolFrame& f : frames) {
    if (!f.camera) continue;
    const PinholeIntrinsics& k = *f.camera;
    char text[160];
    std::snprintf(text, sizeof text, "camera fx=%.2f fy=%.2f cx=%.2f cy=%.2f %dx%d", k.fx, k.fy, k.cx, k.cy, k.width,
                  k.height);
    return std::string(text) + " (" + f.camera_source + ")";
  }
  return "no camera (the preset's grid does not depend on one)";
}

ToolOptions parse_tool_options(int argc, const char* const* argv, const ToolSpec& spec) {
  ToolOptions t;
  check_arguments(argc, argv, spec, t.inputs);

  t.preset_name = value_of(argc, argv, "-preset").value_or(spec.default_preset);
  if (!contains(preset_names(), t.preset_name)) {
    std::string known;
    for (const auto& n : preset_names()) known += (known.empty() ? "" : ", ") + n;
    bad_flag("-preset", t.preset_name, "one of " + known);
  }

  const auto intrinsics_list = value_of(argc, argv, "-intrinsics");
  const auto intrinsics_file = value_of(argc, argv, "-intrinsics_file");
  if (intrinsics_list && intrinsics_file) throw InvalidParameter("give -intrinsics or -intrinsics_file, not both");
  if (intrinsics_list) {
    t.intrinsics = intrinsics_from_list(*intrinsics_list);
    t.intrinsics_flag = "-intrinsics";
  }
  if (intrinsics_file) {
    t.intrinsics = read_intrinsics_file(*intrinsics_file);
    t.intrinsics_flag = "-intrinsics_file " + *intrinsics_file;
  }

  if (const auto e = value_of(argc, argv, "-depth_encoding")) {
    try {
      t.depth_encoding = parse_depth_encoding(*e);
    } catch (const InvalidParameter&) {
      bad_flag("-depth_encoding", *e, "one of mm, tum, sun, nyu");
    }
  }

  PresetOverrides& o = t.overrides;
  o.sigma_depth_m = non_negative_double(argc, argv, "-sigma_depth");
  o.sigma_depth_per_m2 = non_negative_double(argc, argv, "-sigma_depth_quadratic");
  o.sigma_angle_rad = positive_double(argc, argv, "-sigma_angle");
  o.support_k = positive_double(argc, argv, "-support_k");
  o.depth_max_m = positive_double(argc, argv, "-depth_max");
  if (const auto text = value_of(argc, argv, "-depth_bins")) {
    o.depth_bins = to_int("-depth_bins", *text);
    if (*o.depth_bins < 1) bad_flag("-depth_bins", *text, ">= 1");
  }
  if (const auto text = value_of(argc, argv, "-fov")) {
    const std::vector<double> fov = to_doubles("-fov", *text);
    if (fov.size() != 2 || !(fov[0] > 0 && fov[0] < 360) || !(fov[1] > 0 && fov[1] < 180))
      bad_flag("-fov", *text, "h,v in degrees with 0 < h < 360 and 0 < v < 180");
    o.fov_horizontal_deg = fov[0];
    o.fov_vertical_deg = fov[1];
  }

  t.preset = apply_overrides(t.intrinsics ? preset_by_name(t.preset_name, *t.intrinsics) : preset_by_name(t.preset_name), o);

  if (const auto mode = value_of(argc, argv, "-mode")) {
    if (*mode == "clamped")
      t.grid.mode = UpdateMode::clamped;
    else if (*mode == "exact")
      t.grid.mode = UpdateMode::exact;
    else
      bad_flag("-mode", *mode, "clamped or exact");
  }
  if (const auto clamp = value_of(argc, argv, "-clamp")) {
    if (*clamp == "octomap") {
      const UpdateMode mode = t.grid.mode;
      t.grid = GridOptions::octomap_clamping();
      t.grid.mode = mode;
    } else if (*clamp != "paper") {
      bad_flag("-clamp", *clamp, "octomap or paper");
    }
  }

  try {
    require_within_memory_cap(t.preset.geometry, t.grid.memory_cap_bytes);
  } catch (const ResourceLimit& e) {
    throw ResourceLimit(std::string(e.what()) + " (after -preset " + t.preset_name + " and -depth_bins/-fov)");
  }

  t.top_k = spec.default_top_k;
  if (const auto text = value_of(argc, argv, "-k")) {
    t.top_k = to_int("-k", *text);
    if (t.top_k <= 0) bad_flag("-k", *text, "> 0");
  }
  return t;
}

OutputFolder open_output_folder(int argc, const char* const* argv, const std::string& tool,
                                const std::string& fallback) {
  std::string folder = fallback;
  pcl::console::parse_argument(argc, argv, "-o", folder);
  if (folder.empty()) throw InvalidParameter("-o needs a folder name");
  return OutputFolder(folder, tool, pcl::console::find_switch(argc, argv, "-overwrite"));
}

std::string usage_output_folder(const std::string& fallback) {
  return "  -o OUTDIR                 output folder" + (fallback.empty() ? std::string(" (required)") : " (default " + fallback + ")") +
         "; written in a staging folder\n"
         "                            and moved into place at the end. A folder that holds files this tool did\n"
         "                            not write (marker " + kOutputMarkerName + ") is refused\n"
         "  -overwrite                write into such a folder anyway: files of the same names are replaced,\n"
         "                            nothing else is touched\n";
}

std::string usage_common() {
  return R"(Sensor and grid:
  -preset NAME              kinect_v1 (default: one column per camera pixel, depth along z, 2048
                            inverse-depth bins 0.5-8 m, sigma_z = 1.425e-3 z^2), kinect_v1_paper (the
                            paper: 640x480x512 spherical bins, 57x43 deg, 0-5 m, constant sigmas) or
                            kinect_v1_spherical (kinect_v1's depth model over spherical bins)
  -sigma_depth M            constant depth sigma [m]
  -sigma_depth_quadratic C  depth sigma term growing with rho^2 [1/m] (sigma = sigma_depth + C rho^2)
  -sigma_angle RAD          angular sigma [rad] (pixel-native grids: the same angle in pixels at the centre)
  -support_k K              region of support in standard deviations (default 2)
  -depth_bins N             number of depth bins
  -depth_max M              far end of the depth range [m]
  -fov H,V                  field of view centred on the optical axis [deg] (spherical grids only)
  -mode clamped|exact       clamp the log-odds after each update (default) or sum them as eq. 2 does
  -clamp paper|octomap      clamping thresholds: 0.001/0.999 (default) or OctoMap's 0.1192/0.971
  -k K                      how many top rays/regions to report (K > 0)
Inputs (positional, fused in order, all from the same viewpoint):
  FILE.pcd                  any PCD with x y z fields, metres, optical frame; with a camera preset its
                            intrinsics are fitted to its organized points unless -intrinsics is given
  FILE.png / FILE.pgm       16-bit depth image, back-projected through -intrinsics or the dataset's file
  FOLDER                    a 3DMatch/SUN3D/7-Scenes folder: its *.depth.png frames and camera-intrinsics.txt
  -intrinsics FX,FY,CX,CY[,W,H]  depth camera intrinsics [pixels] (default size 640x480)
  -intrinsics_file PATH     "fx fy cx cy [w h]" or a 3x3 matrix (camera-intrinsics.txt)
  -depth_encoding E         mm (millimetres), tum (1/5000 m), sun (SUN RGB-D bit-rotated mm),
                            nyu (raw Kinect disparity); default: guessed per file from its values
  -h                        this help
)";
}

namespace {

volatile std::sig_atomic_t g_stop_signal = 0;
extern "C" void record_stop_signal(int signal) { g_stop_signal = signal; }

void install_stop_signals() {
  struct sigaction action {};
  action.sa_handler = record_stop_signal;
  action.sa_flags = SA_RESETHAND;  // a second Ctrl-C kills at once; the next run removes what is left
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

std::string& current_input() {
  static std::string input;
  return input;
}
// The innermost input whose scope an exception left: recorded while unwinding, read by run_tool.
std::string& failed_input() {
  static std::string input;
  return input;
}

// One line on stderr: the message, and the input being worked on when the message does not name it.
int report_failure(const std::string& message) {
  std::string line = message;
  std::replace(line.begin(), line.end(), '\n', ' ');
  const std::string& input = failed_input();
  if (!input.empty() && line.find(input) == std::string::npos) line += " (input '" + input + "')";
  std::fprintf(stderr, "error: %s\n", line.c_str());
  return 1;
}

}  // namespace

InputScope::InputScope(const std::string& input) : previous_(current_input()), uncaught_(std::uncaught_exceptions()) {
  current_input() = input;
}

InputScope::~InputScope() {
  if (std::uncaught_exceptions() > uncaught_ && failed_input().empty()) failed_input() = current_input();
  current_input() = previous_;
}

Interrupted::Interrupted(int signal)
    : std::runtime_error(std::string("interrupted by ") + (signal == SIGTERM ? "SIGTERM" : "SIGINT")), signal_(signal) {}

int stop_signal_received() { return static_cast<int>(g_stop_signal); }

void throw_if_interrupted() {
  if (const int signal = stop_signal_received()) throw Interrupted(signal);
}

int run_tool(int argc, char** argv, void (*print_usage)(const char* program), int (*run)(int argc, char** argv)) {
  if (help_requested(argc, argv)) {
    print_usage(argv[0]);
    return 0;
  }
  install_stop_signals();
  try {
    return run(argc, argv);
  } catch (const Interrupted& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 128 + e.signal();
  } catch (const std::bad_alloc&) {
    return report_failure("out of memory (std::bad_alloc)");
  } catch (const std::exception& e) {
    return report_failure(e.what());
  } catch (...) {
    return report_failure("unknown exception");
  }
}

}  // namespace occ_improve
