// occ_select_eval: does following the improvement map build a better map per point acquired than
// sampling uniformly? Strategies (a)-(f) of docs/SELECTIVE.md run against a virtual selective sensor
// over real frames; the map's predicted depth is scored against the scene's depth (not improvement).
#include "occ_improve/cancel.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/tools/tool_frames.hpp"
#include "occ_improve/tools/tool_main.hpp"
#include "occ_improve/tools/tool_options.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/sim/virtual_sensor.hpp"


#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
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
    "the predictor's residual; g_improvement / g_residual: by one of them) acquire from a virtual Kinect v1,\n"
    "each scored with every -predictors rule (runs of the linear one are named <strategy>_linear) (virtual_sensor.hpp); quality = share of\n"
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

struct Scene {
  std::string name;
  std::vector<float> depth_m;  ///< z per pixel, 0 = no return
  PinholeIntrinsics intrinsics;
};

Scene load_scene(const std::string& input, const ToolOptions& options) {
  Scene s;
  s.name = std::filesystem::path(input).stem().string();
  if (input == "sample") {
    sample::SceneOptions clean;
    clean.noise = clean.quantise = false;
    const sample::SampleFrame f = sample::generate_scene(clean);
    return {"sample", f.depth_m, f.intrinsics};
  }
  // The tools' frame rules: intrinsics from -intrinsics, the dataset or fitted to the cloud; never assumed.
  const ToolFrame frame = read_tool_frame(options, expand_input(input).front());
  if (!frame.cloud.isOrganized() || frame.cloud.height <= 1 || !frame.camera)
    throw InvalidInput(input + ": not an organized frame");
  s.intrinsics = *frame.camera;
  s.depth_m = depth_of_organized(frame.cloud);
  if (s.name.find('.') != std::string::npos) s.name = s.name.substr(0, s.name.find('.'));
  return s;
}

constexpr std::size_t kReferenceFrames = 5;  ///< the target's "quality of 5 full frames"

enum Strategy { full, uniform, decimation, guided, guided_returns, guided_reacquire, coarse_both, coarse_improvement, coarse_residual };
const char* const kStrategyNames[] = {"a_full",      "b_uniform",       "c_decimation",
                                      "d_guided",    "e_returns",       "f_reacquire",
                                      "g_coarse_to_fine", "g_improvement", "g_residual"};
constexpr Strategy kCompared[] = {uniform, decimation, guided, guided_returns, guided_reacquire,
                                  coarse_both, coarse_improvement, coarse_residual};

bool is_coarse_to_fine(Strategy s) { return s == coarse_both || s == coarse_improvement || s == coarse_residual; }

struct Options {
  std::vector<double> budgets;
  double frames = 5, share = 0.1;
  int radius = 16;
  std::uint64_t seed = 1;
  std::vector<Strategy> strategies;  ///< besides (a), which is always run (the reference)
  std::vector<DepthPredictionRule> predictors;
};

/// A run's name: the strategy's, with "_linear" for the linear predictor (the prefix b_, c_, ... stays).
std::string run_name(Strategy s, DepthPredictionRule rule) {
  return std::string(kStrategyNames[s]) + (rule == DepthPredictionRule::linear ? "_linear" : "");
}

struct Quality {
  double within = 0, coverage = 0, mean_abs_error_m = 0;
  std::size_t good = 0;
};

/// How the grid's columns meet the scene's pixels: the column holding each pixel's centre ray and the
/// pixel holding each column's centre ray (-1 where none: a column no pixel sees is not observable).
/// With the pixel-native kinect_v1 both are the identity.
struct PixelColumns {
  std::vector<std::int64_t> column_of_pixel, pixel_of_column;
  std::vector<std::uint8_t> observable;  ///< per column: observable by the grid and by a pixel
};

PixelColumns pixel_columns(const GridGeometry& g, const PinholeIntrinsics& k) {
  PixelColumns m;
  const auto pixels = static_cast<std::size_t>(k.width) * static_cast<std::size_t>(k.height);
  m.column_of_pixel.assign(pixels, -1);
  for (std::size_t p = 0; p < pixels; ++p) {
    ColumnIndex c;
    const double u = static_cast<double>(p % static_cast<std::size_t>(k.width)), v = static_cast<double>(p / static_cast<std::size_t>(k.width));
    if (g.column_of((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0, c)) m.column_of_pixel[p] = c;
  }
  m.pixel_of_column.assign(g.column_count(), -1);
  m.observable.assign(g.column_count(), 0);
  for (ColumnIndex c = 0; c < g.column_count(); ++c) {
    const Eigen::Vector3d d = g.direction(g.azimuth_bin_of(c), g.elevation_bin_of(c));
    if (d.z() <= 0 || !g.observable(c)) continue;
    const long u = std::lround(k.fx * d.x() / d.z() + k.cx), v = std::lround(k.fy * d.y() / d.z() + k.cy);
    if (u < 0 || v < 0 || u >= k.width || v >= k.height) continue;
    m.pixel_of_column[c] = v * k.width + u;
    m.observable[c] = 1;
  }
  return m;
}

/// The metric: for every scene pixel with a return, the map's z there (the surface sample of the
/// pixel's column, else predict_depth) within 2 sigma(z) = 2 x 1.425e-3 z^2 of the scene's z.
Quality map_quality(const Mapper& mapper, const Scene& scene, const PixelColumns& map, int radius,
                    DepthPredictionRule rule) {
  DepthPredictionParams params;
  params.radius_columns = radius;
  params.rule = rule;
  const PredictedDepth predicted = predict_depth(mapper.surface(), mapper.model(), params);
  const GridGeometry& g = mapper.geometry();
  Quality q;
  std::size_t returns = 0, covered = 0;
  double abs_error = 0;
  for (std::size_t p = 0; p < scene.depth_m.size(); ++p) {
    const double z = scene.depth_m[p];
    if (z <= 0) continue;
    ++returns;
    const std::int64_t c = map.column_of_pixel[p];
    if (c < 0 || predicted.distance[static_cast<std::size_t>(c)] < 0) continue;
    ++covered;
    const auto column = static_cast<ColumnIndex>(c);
    const double predicted_z =  // the depth axis is z (pinhole) or the range (spherical)
        g.point(g.azimuth_bin_of(column), g.elevation_bin_of(column), predicted.depth_m[column]).z();
    const double error = std::abs(predicted_z - z);
    abs_error += error;
    q.good += error <= 2 * 1.425e-3 * z * z ? 1 : 0;
  }
  q.within = returns ? static_cast<double>(q.good) / returns : 0;
  q.coverage = returns ? static_cast<double>(covered) / returns : 0;
  q.mean_abs_error_m = covered ? abs_error / covered : 0;
  return q;
}

/// A permutation of 0..n-1 from a seeded SplitMix64 stream (the same on every platform).
std::vector<ColumnIndex> permutation(std::size_t n, std::uint64_t seed) {
  std::vector<ColumnIndex> p(n);
  std::iota(p.begin(), p.end(), ColumnIndex{0});
  std::uint64_t state = seed * 0x9e3779b97f4a7c15ull + 1;
  for (std::size_t i = n - 1; i > 0; --i) {
    state += 0x9e3779b97f4a7c15ull;
    std::uint64_t z = state;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    std::swap(p[i], p[z % (i + 1)]);
  }
  return p;
}

/// One run: a strategy at one budget, shot after shot, with the metric at checkpoints.
class Run {
public:
  Run(const Scene& scene, Strategy strategy, int budget, const Options& options,
      DepthPredictionRule rule = DepthPredictionRule::nearest)
      : scene_(scene), strategy_(strategy), rule_(rule), budget_(budget), options_(options),
        mapper_(kinect_v1(scene.intrinsics)), sensor_(scene.depth_m, scene.intrinsics, sensor_params(options)),
        returns_(ReturnRecord::for_grid(mapper_.geometry().width(), mapper_.geometry().height())),
        map_(pixel_columns(mapper_.geometry(), scene.intrinsics)) {
    for (ColumnIndex c = 0; c < map_.observable.size(); ++c)
      if (map_.observable[c]) observable_columns_.push_back(c);
  }

  void run(std::ostream& csv) {
    const auto n = static_cast<double>(scene_.depth_m.size());
    // (a) is the reference: kReferenceFrames full frames, scored after each.
    const double limit = strategy_ == full ? 0 : options_.frames * n;
    const double checkpoint_every = strategy_ == full ? 0 : std::max<double>(budget_, n / 20);
    double next_checkpoint = checkpoint_every, expected_since = 0;
    std::size_t good_before = 0;
    while (strategy_ == full ? shots_ < kReferenceFrames : static_cast<double>(rays_asked_) < limit - 0.5) {
      throw_if_stop_requested();  // a run is thousands of shots; the library polls within each
      const Shot shot = next_shot();
      if (shot.stop && stop_rays_ == 0) stop_rays_ = rays_asked_;
      acquire(shot.columns);
      expected_since += shot.expected_gain;
      if (static_cast<double>(rays_asked_) + 0.5 < next_checkpoint && static_cast<double>(rays_asked_) < limit - 0.5) continue;
      next_checkpoint += checkpoint_every;
      const Quality q = map_quality(mapper_, scene_, map_, options_.radius, rule_);
      csv << scene_.name << ',' << run_name(strategy_, rule_) << ',' << budget_ << ',' << shots_ << ',' << rays_asked_ << ','
          << returned_ << ',' << q.within << ',' << q.coverage << ',' << q.mean_abs_error_m << ',' << expected_since << ','
          << static_cast<double>(q.good) - static_cast<double>(good_before) << ',' << (shot.stop ? 1 : 0) << '\n';
      curve_.push_back({static_cast<double>(rays_asked_), q.within});
      calibration_.push_back({expected_since, static_cast<double>(q.good) - static_cast<double>(good_before)});
      good_before = q.good;
      expected_since = 0;
    }
  }

  const std::vector<std::pair<double, double>>& curve() const { return curve_; }
  const std::vector<std::pair<double, double>>& calibration() const { return calibration_; }
  std::size_t stop_rays() const { return stop_rays_; }
  double seconds_per_shot() const { return shots_ ? seconds_ / static_cast<double>(shots_) : 0; }

private:
  static VirtualSensorParams sensor_params(const Options& options) {
    VirtualSensorParams p;
    p.seed = options.seed;
    return p;
  }

  Shot next_shot() {
    Shot shot;
    if (strategy_ == full) {
      shot.columns = observable_columns_;
    } else if (strategy_ == uniform) {
      for (int i = 0; i < budget_; ++i) {
        if (order_position_ == order_.size()) {  // every ray once before any twice
          order_ = permutation(observable_columns_.size(), options_.seed + passes_++);
          order_position_ = 0;
        }
        shot.columns.push_back(observable_columns_[order_[order_position_++]]);
      }
    } else if (strategy_ == decimation) {
      const GridGeometry& g = mapper_.geometry();
      const int step = decimation_step(g.width(), g.height(), budget_);
      const int offset = static_cast<int>(shots_ % static_cast<std::size_t>(step * step));  // row-major cycle
      for (ColumnIndex c : decimation_pattern(g.width(), g.height(), step, offset % step, offset / step))
        if (map_.observable[c]) shot.columns.push_back(c);
    } else {
      PlanRequest request;
      request.budget_rays = budget_;
      request.negative_share = strategy_ == guided_reacquire ? options_.share : 0.0;
      request.candidates = map_.observable;
      if (is_coarse_to_fine(strategy_)) {
        request.shape = ShotShape::coarse_to_fine;
        request.refine_by = strategy_ == coarse_both          ? RefineBy::both
                            : strategy_ == coarse_improvement ? RefineBy::improvement
                                                              : RefineBy::residual;
        // The residual of the predictor's own local model: nearest sample -> constant, linear -> plane.
        request.local_model = rule_ == DepthPredictionRule::linear ? LocalModel::plane : LocalModel::constant;
      }
      shot = plan_next_shot(mapper_, returns_, request);
    }
    return shot;
  }

  void acquire(const std::vector<ColumnIndex>& columns) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::uint32_t> pixels(columns.size());
    for (std::size_t i = 0; i < columns.size(); ++i) pixels[i] = static_cast<std::uint32_t>(map_.pixel_of_column[columns[i]]);
    const std::vector<float> depth = sensor_.shoot(pixels);
    const std::vector<Eigen::Vector3f> points = sensor_.points(pixels, depth);
    mapper_.insert(PointSpan::from(points));
    if (strategy_ == guided_returns || strategy_ == guided_reacquire || is_coarse_to_fine(strategy_)) {
      std::vector<std::uint8_t> got(depth.size());
      for (std::size_t i = 0; i < depth.size(); ++i) got[i] = depth[i] > 0;
      returns_.record_shot(columns, got);
    }
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rays_asked_ += columns.size();
    returned_ += points.size();
    ++shots_;
  }

  const Scene& scene_;
  Strategy strategy_;
  DepthPredictionRule rule_;
  int budget_;
  Options options_;
  Mapper mapper_;
  VirtualSensor sensor_;
  ReturnRecord returns_;
  PixelColumns map_;
  std::vector<ColumnIndex> observable_columns_;
  std::vector<ColumnIndex> order_;
  std::size_t order_position_ = 0, shots_ = 0, rays_asked_ = 0, returned_ = 0, stop_rays_ = 0;
  std::uint64_t passes_ = 0;
  double seconds_ = 0;
  std::vector<std::pair<double, double>> curve_, calibration_;
};

/// Points (rays asked) at which a curve first reaches `target`, -1 if never.
double points_to_reach(const std::vector<std::pair<double, double>>& curve, double target) {
  for (const auto& [points, quality] : curve)
    if (quality >= target) return points;
  return -1;
}

/// Where the quality stops rising: the first point within 99% of the run's best quality.
double knee(const std::vector<std::pair<double, double>>& curve) {
  double best = 0;
  for (const auto& point : curve) best = std::max(best, point.second);
  return points_to_reach(curve, 0.99 * best);
}

double pearson(const std::vector<std::pair<double, double>>& xy) {
  const double n = static_cast<double>(xy.size());
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  for (const auto& [x, y] : xy) sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y;
  const double vx = sxx - sx * sx / n, vy = syy - sy * sy / n;
  return vx > 0 && vy > 0 ? (sxy - sx * sy / n) / std::sqrt(vx * vy) : 0;
}

struct SummaryRow {
  std::string scene, strategy;
  double budget_share, final_quality, points_to_95, stop_points, knee_points, calibration_r, ms_per_shot;
};

std::vector<SummaryRow> evaluate_scene(const Scene& scene, const Options& options, OutputFolder& out) {
  const std::string path = out.file(scene.name + ".csv");
  std::ofstream csv(path);
  if (!csv) throw IoError("cannot write " + path);
  csv << "scene,strategy,budget_rays,shot,rays_asked,returns,quality,coverage,mean_abs_error_m,expected_gain,"
         "realised_good_rays,plan_stop\n";
  const auto n = static_cast<int>(scene.depth_m.size());
  Run reference(scene, full, n, options);
  reference.run(csv);
  const double five_frames = reference.curve().back().second;
  std::vector<SummaryRow> rows;
  const auto frames = [n](double points) { return points < 0 ? -1.0 : points / n; };
  const auto add = [&](const Run& run, const std::string& name, double share) {
    rows.push_back({scene.name, name, share, run.curve().back().second,
                    frames(points_to_reach(run.curve(), 0.95 * five_frames)),
                    run.stop_rays() ? frames(static_cast<double>(run.stop_rays())) : -1.0, frames(knee(run.curve())),
                    pearson(run.calibration()), 1e3 * run.seconds_per_shot()});
  };
  add(reference, kStrategyNames[full], 1.0);
  for (double share : options.budgets)
    for (DepthPredictionRule rule : options.predictors)
      for (Strategy s : options.strategies) {
        Run run(scene, s, std::max(1, static_cast<int>(std::lround(share * n))), options, rule);
        run.run(csv);
        add(run, run_name(s, rule), share);
        std::fprintf(stderr, "%s %s %.2f: quality %.4f, 95%% of 5 frames at %.3f frames\n", scene.name.c_str(),
                     run_name(s, rule).c_str(), share, rows.back().final_quality, rows.back().points_to_95);
      }
  return rows;
}

void write_summary(const std::vector<SummaryRow>& rows, const std::string& path) {
  std::ofstream csv(path);
  csv << "scene,strategy,budget_share,final_quality,frames_to_95pct_of_5_full,stop_frames,knee_frames,"
         "calibration_r,ms_per_shot\n";
  for (const auto& r : rows)
    csv << r.scene << ',' << r.strategy << ',' << r.budget_share << ',' << r.final_quality << ',' << r.points_to_95 << ','
        << r.stop_points << ',' << r.knee_points << ',' << r.calibration_r << ',' << r.ms_per_shot << '\n';
  if (!csv.flush()) throw IoError("cannot write '" + path + "'");
}

Options parse_options(const CommandLine& command_line) {
  Options o;
  o.budgets = parse_number_list("-budgets", *command_line.text("-budgets"));
  for (double b : o.budgets)
    if (!(b > 0 && b <= 1)) throw InvalidParameter("-budgets " + *command_line.text("-budgets") + " is invalid: every share must be in (0, 1]");
  o.frames = *command_line.number("-frames");
  o.share = *command_line.number("-negative_share");
  o.radius = *command_line.integer("-radius");
  o.seed = static_cast<std::uint64_t>(*command_line.integer("-seed"));
  const std::string names = *command_line.text("-strategies");
  for (Strategy s : kCompared)
    if (names == "all" || ("," + names + ",").find("," + std::string(kStrategyNames[s]) + ",") != std::string::npos)
      o.strategies.push_back(s);
  std::size_t listed = names == "all" ? o.strategies.size() : static_cast<std::size_t>(std::count(names.begin(), names.end(), ',') + 1);
  if (o.strategies.empty() || listed != o.strategies.size())
    throw InvalidParameter("-strategies " + names + " is invalid: 'all' or a comma-separated list of b_uniform, "
                           "c_decimation, d_guided, e_returns, f_reacquire, g_coarse_to_fine, g_improvement, g_residual");
  const std::string predictors = *command_line.text("-predictors");
  for (const std::string& name : {std::string("nearest"), std::string("linear")})
    if (("," + predictors + ",").find("," + name + ",") != std::string::npos)
      o.predictors.push_back(name == "linear" ? DepthPredictionRule::linear : DepthPredictionRule::nearest);
  if (o.predictors.empty() || static_cast<std::size_t>(std::count(predictors.begin(), predictors.end(), ',') + 1) != o.predictors.size())
    throw InvalidParameter("-predictors " + predictors + " is invalid: a comma-separated list of nearest, linear");
  return o;
}

int run(const CommandLine& command_line) {
  const Options o = parse_options(command_line);
  const ToolOptions frame_options = parse_tool_options(command_line);
  const std::vector<std::string>& scenes = command_line.positionals();
  if (scenes.empty()) throw InvalidParameter("no scene given (see -h)");
  OutputFolder out = open_output_folder(command_line);
  std::vector<SummaryRow> all;
  for (const std::string& input : scenes) {
    throw_if_stop_requested();
    const InputScope scope(input);
    const Scene scene = load_scene(input, frame_options);
    std::fprintf(stderr, "%s: %d x %d, fx %.1f\n", scene.name.c_str(), scene.intrinsics.width, scene.intrinsics.height,
                 scene.intrinsics.fx);
    const std::vector<SummaryRow> rows = evaluate_scene(scene, o, out);
    all.insert(all.end(), rows.begin(), rows.end());
  }
  write_summary(all, out.file("summary.csv"));
  out.commit();
  std::printf("wrote %s/summary.csv and one CSV per scene\n", out.path().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return run_tool(argc, argv, kFlags, run); }
