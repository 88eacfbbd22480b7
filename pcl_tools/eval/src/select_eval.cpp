#include "occ_improve/eval/select_eval.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sim/virtual_sensor.hpp"
#include "occ_improve/timing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <numeric>
#include <optional>
#include <utility>

namespace occ_improve {

namespace {

constexpr std::size_t kReferenceFrames = 5;  ///< the target's "quality of 5 full frames"

const char* const kStrategyNames[] = {"a_full",      "b_uniform",       "c_decimation",
                                      "d_guided",    "e_returns",       "f_reacquire",
                                      "g_coarse_to_fine", "g_improvement", "g_residual", "g_triangles",
                                      "o_oracle"};

/// The refinement of a strategy that plans coarse-to-fine shots ((g), and the oracle, which starts from
/// (g) triangles'); none for the others.
std::optional<RefineBy> coarse_refinement(SelectStrategy s) {
  switch (s) {
    case SelectStrategy::coarse_both: return RefineBy::both;
    case SelectStrategy::coarse_improvement: return RefineBy::improvement;
    case SelectStrategy::coarse_residual: return RefineBy::residual;
    case SelectStrategy::coarse_triangles:
    case SelectStrategy::oracle: return RefineBy::triangles;
    default: return std::nullopt;
  }
}

/// The items of `known` a comma-separated `list` names, in `known`'s order; none when a name is unknown or
/// repeated (the list then names more items than it found).
template <class T, class NameOf>
std::vector<T> named_in_list(const std::string& list, const std::vector<T>& known, NameOf name_of) {
  std::vector<T> out;
  for (const T& item : known)
    if (("," + list + ",").find("," + std::string(name_of(item)) + ",") != std::string::npos) out.push_back(item);
  const auto listed = static_cast<std::size_t>(std::count(list.begin(), list.end(), ',') + 1);
  if (listed != out.size()) out.clear();
  return out;
}

}  // namespace

const char* select_strategy_name(SelectStrategy strategy) { return kStrategyNames[static_cast<int>(strategy)]; }

const std::vector<SelectStrategy>& compared_select_strategies() {
  using S = SelectStrategy;
  static const std::vector<SelectStrategy> compared{S::uniform,         S::decimation,  S::guided,
                                                    S::guided_returns,  S::guided_reacquire, S::coarse_both,
                                                    S::coarse_improvement, S::coarse_residual, S::coarse_triangles};
  return compared;
}

std::vector<SelectStrategy> select_strategies_by_names(const std::string& names) {
  if (names == "all") return compared_select_strategies();
  std::vector<SelectStrategy> known = compared_select_strategies();
  known.push_back(SelectStrategy::oracle);  // run when named
  const std::vector<SelectStrategy> out = named_in_list(names, known, select_strategy_name);
  if (out.empty()) {
    std::string listing;
    for (SelectStrategy s : known) listing += (listing.empty() ? "" : ", ") + std::string(select_strategy_name(s));
    throw InvalidParameter("-strategies " + names + " is invalid: 'all' or a comma-separated list of " + listing);
  }
  return out;
}

std::vector<DepthPredictionRule> select_predictors_by_names(const std::string& names) {
  const auto name_of = [](DepthPredictionRule r) { return r == DepthPredictionRule::linear ? "linear" : "nearest"; };
  const std::vector<DepthPredictionRule> out =
      named_in_list(names, std::vector<DepthPredictionRule>{DepthPredictionRule::nearest, DepthPredictionRule::linear}, name_of);
  if (out.empty()) throw InvalidParameter("-predictors " + names + " is invalid: a comma-separated list of nearest, linear");
  return out;
}

namespace {

/// A run's name: the strategy's, with "_linear" for the linear predictor (the prefix b_, c_, ... stays).
std::string run_name(SelectStrategy s, DepthPredictionRule rule) {
  return std::string(select_strategy_name(s)) + (rule == DepthPredictionRule::linear ? "_linear" : "");
}

struct Quality {
  double within = 0, coverage = 0, mean_abs_error_m = 0;
  std::size_t good = 0;
  /// Scene-return rays never asked whose prediction is off (or missing), and those of them off by at most
  /// 3 sigma(z): how much of what is left wrong is of the sensor noise's size, and how much larger.
  std::size_t wrong_unasked = 0, wrong_unasked_within_3sigma = 0;
};
constexpr double kThreeSigmaInTolerances = 1.5;  ///< the tolerance is 2 sigma(z)

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

PredictedDepth predicted_depth(const Mapper& mapper, int radius, DepthPredictionRule rule) {
  DepthPredictionParams params;
  params.radius_columns = radius;
  params.rule = rule;
  return predict_depth(mapper.surface(), mapper.model(), params);
}

/// The metric's tolerance at the scene's z: 2 sigma(z) = 2 x 1.425e-3 z^2.
double tolerance_m(double z) { return 2 * 1.425e-3 * z * z; }

/// The predicted z of a column (the depth axis is z for pinhole binnings, the range for spherical ones).
double predicted_z(const GridGeometry& g, ColumnIndex column, const PredictedDepth& predicted) {
  return g.point(g.azimuth_bin_of(column), g.elevation_bin_of(column), predicted.depth_m[column]).z();
}

/// Whether the scene has a return at depth z (0 or NaN: none).
bool has_return(double z) { return z > 0; }

/// |the predicted z - the scene's z| at a column, +inf where nothing is predicted.
double prediction_error_m(const GridGeometry& g, ColumnIndex column, const PredictedDepth& predicted, double z) {
  if (predicted.distance[column] < 0) return std::numeric_limits<double>::infinity();
  return std::abs(predicted_z(g, column, predicted) - z);
}

/// The same in tolerances: above 1, the ray's prediction is wrong (the metric and the oracle's rule).
double error_in_tolerances(const GridGeometry& g, ColumnIndex column, const PredictedDepth& predicted, double z) {
  return prediction_error_m(g, column, predicted, z) / tolerance_m(z);
}

/// The metric: for every scene pixel with a return, the map's z there (`predicted`: the surface sample of
/// the pixel's column, else predict_depth) within tolerance_m of the scene's z.
Quality map_quality(const GridGeometry& g, const PredictedDepth& predicted, const SelectScene& scene,
                    const PixelColumns& map, const std::vector<std::uint8_t>& asked) {
  Quality q;
  std::size_t returns = 0, covered = 0;
  double abs_error = 0;
  for (std::size_t p = 0; p < scene.depth_m.size(); ++p) {
    const double z = scene.depth_m[p];
    if (!has_return(z)) continue;
    ++returns;
    const std::int64_t c = map.column_of_pixel[p];
    if (c < 0) continue;
    const auto column = static_cast<ColumnIndex>(c);
    const double error = prediction_error_m(g, column, predicted, z), tolerances = error_in_tolerances(g, column, predicted, z);
    if (tolerances > 1 && !asked[column]) {
      ++q.wrong_unasked;
      q.wrong_unasked_within_3sigma += tolerances <= kThreeSigmaInTolerances ? 1 : 0;
    }
    if (std::isinf(error)) continue;  // nothing predicted
    ++covered;
    abs_error += error;
    q.good += tolerances <= 1 ? 1 : 0;
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
  Run(const SelectScene& scene, SelectStrategy strategy, int budget, const SelectEvalOptions& options,
      DepthPredictionRule rule = DepthPredictionRule::nearest)
      : scene_(scene), strategy_(strategy), rule_(rule), budget_(budget), options_(options),
        mapper_(kinect_v1(scene.intrinsics)), sensor_(scene.depth_m, scene.intrinsics, sensor_params(options)),
        returns_(ReturnRecord::for_grid(mapper_.geometry().width(), mapper_.geometry().height())),
        map_(pixel_columns(mapper_.geometry(), scene.intrinsics)), asked_(map_.observable.size(), 0) {
    for (ColumnIndex c = 0; c < map_.observable.size(); ++c)
      if (map_.observable[c]) observable_columns_.push_back(c);
  }

  void run(std::ostream& csv) {
    const auto n = static_cast<double>(scene_.depth_m.size());
    // (a) is the reference: kReferenceFrames full frames, scored after each.
    const double limit = strategy_ == SelectStrategy::full ? 0 : options_.frames * n;
    const double checkpoint_every = strategy_ == SelectStrategy::full ? 0 : std::max<double>(budget_, n / 20);
    double next_checkpoint = checkpoint_every;
    Shot last;
    while (strategy_ == SelectStrategy::full ? shots_ < kReferenceFrames : static_cast<double>(rays_asked_) < limit - 0.5) {
      throw_if_stop_requested();  // a run is thousands of shots; the library polls within each
      Shot shot = next_shot();
      if (shot.columns.empty()) break;  // the plan has nothing left to take: the curve ends here
      if (shot.stop && stop_rays_ == 0) stop_rays_ = rays_asked_;
      acquire(shot.columns);
      expected_since_ += shot.expected_gain;
      last = std::move(shot);
      if (static_cast<double>(rays_asked_) + 0.5 < next_checkpoint && static_cast<double>(rays_asked_) < limit - 0.5) continue;
      next_checkpoint += checkpoint_every;
      checkpoint(csv, last);
    }
    // A plan that ran out before a checkpoint (a frame of few valid rays: the coverage pass took them all)
    // ends its curve where it stopped; a run without any checkpoint crashed the summary.
    if (curve_.empty() || curve_.back().first != static_cast<double>(rays_asked_)) checkpoint(csv, last);
  }

  /// Scores the map now: one CSV row, a point of the curve and of the calibration (`shot`: the last one).
  void checkpoint(std::ostream& csv, const Shot& shot) {
    const Quality q = map_quality(mapper_.geometry(), prediction(), scene_, map_, asked_);
    csv << scene_.name << ',' << run_name(strategy_, rule_) << ',' << budget_ << ',' << shots_ << ',' << rays_asked_ << ','
        << returned_ << ',' << q.within << ',' << q.coverage << ',' << q.mean_abs_error_m << ',' << expected_since_ << ','
        << static_cast<double>(q.good) - static_cast<double>(good_before_) << ',' << (shot.stop ? 1 : 0) << ','
        << shot.stop_gain_per_ray << ',' << q.wrong_unasked << ',' << q.wrong_unasked_within_3sigma << '\n';
    curve_.push_back({static_cast<double>(rays_asked_), q.within});
    calibration_.push_back({expected_since_, static_cast<double>(q.good) - static_cast<double>(good_before_)});
    good_before_ = q.good;
    expected_since_ = 0;
  }

  const std::vector<std::pair<double, double>>& curve() const { return curve_; }
  const std::vector<std::pair<double, double>>& calibration() const { return calibration_; }
  std::size_t stop_rays() const { return stop_rays_; }
  double seconds_per_shot() const { return shots_ ? seconds_ / static_cast<double>(shots_) : 0; }

private:
  static VirtualSensorParams sensor_params(const SelectEvalOptions& options) {
    VirtualSensorParams p;
    p.seed = options.seed;
    return p;
  }

  Shot next_shot() {
    Shot shot;
    if (strategy_ == SelectStrategy::full) {
      shot.columns = observable_columns_;
    } else if (strategy_ == SelectStrategy::uniform) {
      for (int i = 0; i < budget_; ++i) {
        if (order_position_ == order_.size()) {  // every ray once before any twice
          order_ = permutation(observable_columns_.size(), options_.seed + passes_++);
          order_position_ = 0;
        }
        shot.columns.push_back(observable_columns_[order_[order_position_++]]);
      }
    } else if (strategy_ == SelectStrategy::decimation) {
      const GridGeometry& g = mapper_.geometry();
      const int step = decimation_step(g.width(), g.height(), budget_);
      const int offset = static_cast<int>(shots_ % static_cast<std::size_t>(step * step));  // row-major cycle
      for (ColumnIndex c : decimation_pattern(g.width(), g.height(), step, offset % step, offset / step))
        if (map_.observable[c]) shot.columns.push_back(c);
    } else {
      PlanRequest request;
      request.budget_rays = budget_;
      request.negative_share = strategy_ == SelectStrategy::guided_reacquire ? options_.share : 0.0;
      request.candidates = map_.observable;
      if (const std::optional<RefineBy> refine_by = coarse_refinement(strategy_)) {
        request.shape = ShotShape::coarse_to_fine;
        request.refine_by = *refine_by;
        // The residual of the predictor's own local model: nearest sample -> constant, linear -> plane.
        request.local_model = rule_ == DepthPredictionRule::linear ? LocalModel::plane : LocalModel::constant;
      }
      shot = plan_next_shot(mapper_, returns_, request, plan_memory_);
      if (strategy_ == SelectStrategy::oracle && shots_ > 0) shot = oracle_shot(shot);
    }
    return shot;
  }

  /// The run's predicted depth of the map as it is, computed once per map: a checkpoint and the oracle's
  /// next shot (at 5 %, every shot is a checkpoint) read the same one.
  const PredictedDepth& prediction() {
    if (!prediction_) prediction_ = predicted_depth(mapper_, options_.radius, rule_);
    return *prediction_;
  }

  /// (o): the unasked rays whose predicted depth is more than the tolerance off the scene's (no prediction
  /// counts as off), worst first, then `planned`'s rays; the expected gain is the count of the former.
  Shot oracle_shot(const Shot& planned) {
    const PredictedDepth& predicted = prediction();
    const GridGeometry& g = mapper_.geometry();
    std::vector<std::pair<double, ColumnIndex>> wrong;  // (error in tolerances, column)
    for (ColumnIndex c : observable_columns_) {
      const double z = scene_.depth_m[static_cast<std::size_t>(map_.pixel_of_column[c])];
      if (!has_return(z) || asked_[c]) continue;
      const double error = error_in_tolerances(g, c, predicted, z);
      if (error > 1) wrong.push_back({error, c});
    }
    const std::size_t taken = std::min(wrong.size(), static_cast<std::size_t>(budget_));
    std::partial_sort(wrong.begin(), wrong.begin() + static_cast<std::ptrdiff_t>(taken), wrong.end(),
                      [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
    Shot shot = planned;
    shot.columns.clear();
    std::vector<std::uint8_t> in_shot(map_.observable.size(), 0);
    for (std::size_t i = 0; i < taken; ++i) shot.columns.push_back(wrong[i].second), in_shot[wrong[i].second] = 1;
    for (ColumnIndex c : planned.columns)
      if (shot.columns.size() < static_cast<std::size_t>(budget_) && !in_shot[c]) shot.columns.push_back(c), in_shot[c] = 1;
    shot.expected_gain = static_cast<double>(taken);
    return shot;
  }

  void acquire(const std::vector<ColumnIndex>& columns) {
    const auto start = SteadyClock::now();
    std::vector<std::uint32_t> pixels(columns.size());
    for (std::size_t i = 0; i < columns.size(); ++i) pixels[i] = static_cast<std::uint32_t>(map_.pixel_of_column[columns[i]]);
    const std::vector<float> depth = sensor_.shoot(pixels);
    const std::vector<Eigen::Vector3f> points = sensor_.points(pixels, depth);
    mapper_.insert(PointSpan::from(points));
    if (strategy_ == SelectStrategy::guided_returns || strategy_ == SelectStrategy::guided_reacquire ||
        coarse_refinement(strategy_)) {
      returns_.record_shot(columns, VirtualSensor::returned(depth));
    }
    seconds_ += seconds_since(start);
    prediction_.reset();  // the map changed
    for (ColumnIndex c : columns) asked_[c] = 1;
    rays_asked_ += columns.size();
    returned_ += points.size();
    ++shots_;
  }

  const SelectScene& scene_;
  SelectStrategy strategy_;
  DepthPredictionRule rule_;
  int budget_;
  SelectEvalOptions options_;
  Mapper mapper_;
  VirtualSensor sensor_;
  ReturnRecord returns_;
  PlanMemory plan_memory_;
  PixelColumns map_;
  std::vector<std::uint8_t> asked_;  ///< per column: asked at least once
  std::optional<PredictedDepth> prediction_;  ///< of the map as it is (prediction()); reset by a shot
  std::vector<ColumnIndex> observable_columns_;
  std::vector<ColumnIndex> order_;
  std::size_t order_position_ = 0, shots_ = 0, rays_asked_ = 0, returned_ = 0, stop_rays_ = 0;
  std::uint64_t passes_ = 0;
  double seconds_ = 0;
  std::vector<std::pair<double, double>> curve_, calibration_;
  double expected_since_ = 0;    ///< the shots' expected gain since the last checkpoint
  std::size_t good_before_ = 0;  ///< good rays at the last checkpoint
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

}  // namespace

std::vector<SelectSummaryRow> evaluate_select_scene(const SelectScene& scene, const SelectEvalOptions& options,
                                                    std::ostream& csv) {
  csv << "scene,strategy,budget_rays,shot,rays_asked,returns,quality,coverage,mean_abs_error_m,expected_gain,"
         "realised_good_rays,plan_stop,stop_gain_per_ray,wrong_unasked,wrong_unasked_within_3sigma\n";
  const auto n = static_cast<int>(scene.depth_m.size());
  Run reference(scene, SelectStrategy::full, n, options);
  reference.run(csv);
  const double five_frames = reference.curve().back().second;
  std::vector<SelectSummaryRow> rows;
  const auto frames = [n](double points) { return points < 0 ? -1.0 : points / n; };
  const auto add = [&](const Run& run, const std::string& name, double share) {
    rows.push_back({scene.name, name, share, run.curve().back().second,
                    frames(points_to_reach(run.curve(), 0.95 * five_frames)),
                    run.stop_rays() ? frames(static_cast<double>(run.stop_rays())) : -1.0, frames(knee(run.curve())),
                    pearson(run.calibration()), 1e3 * run.seconds_per_shot()});
  };
  add(reference, select_strategy_name(SelectStrategy::full), 1.0);
  for (double share : options.budgets)
    for (DepthPredictionRule rule : options.predictors)
      for (SelectStrategy s : options.strategies) {
        Run run(scene, s, std::max(1, static_cast<int>(std::lround(share * n))), options, rule);
        run.run(csv);
        add(run, run_name(s, rule), share);
        std::fprintf(stderr, "%s %s %.2f: quality %.4f, 95%% of 5 frames at %.3f frames\n", scene.name.c_str(),
                     run_name(s, rule).c_str(), share, rows.back().final_quality, rows.back().points_to_95);
      }
  return rows;
}

void write_select_summary(const std::vector<SelectSummaryRow>& rows, const std::string& path) {
  std::ofstream csv(path);
  csv << "scene,strategy,budget_share,final_quality,frames_to_95pct_of_5_full,stop_frames,knee_frames,"
         "calibration_r,ms_per_shot\n";
  for (const auto& r : rows)
    csv << r.scene << ',' << r.strategy << ',' << r.budget_share << ',' << r.final_quality << ',' << r.points_to_95 << ','
        << r.stop_points << ',' << r.knee_points << ',' << r.calibration_r << ',' << r.ms_per_shot << '\n';
  if (!csv.flush()) throw IoError("cannot write '" + path + "'");
}

}  // namespace occ_improve
