#pragma once
// Selective acquisition against a virtual sensor (docs/SELECTIVE.md, "Evaluation"): does following the
// improvement map build a better map per point acquired than sampling uniformly? Strategies (a)-(g) acquire
// from a virtual Kinect v1 (virtual_sensor.hpp) over a scene's depth image; the map's predicted depth is
// scored against the scene's (quality: the share of scene-return rays whose predicted depth lies within
// 2 sigma(z) = 2 x 1.425e-3 z^2 of the scene's).
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/planning/depth_prediction.hpp"

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace occ_improve {

/// One scene: a depth image and its camera.
struct SelectScene {
  std::string name;
  std::vector<float> depth_m;  ///< z per pixel, 0 = no return
  PinholeIntrinsics intrinsics;
};

/// (a) full frames, (b) uniform random without replacement, (c) regular decimation, (d) improvement-guided,
/// (e) (d) + return model, (f) (e) + re-acquisition of negative rays, (g) coarse-to-fine by the multi-scale
/// improvement x the predictor's residual (coarse_both), by one of them, or by the samples' triangles
/// (coarse_triangles: area x non-planarity). (o) oracle is not a strategy but a reference that reads the
/// scene: after (g) triangles' first shot it asks the unasked rays whose predicted depth is wrong (more
/// than 2 sigma(z) off the scene's), worst first, then fills the shot with (g) triangles' rays: a greedy
/// planner that knows where the prediction fails (not an upper bound: (g) is ahead of it after some shots;
/// docs/SELECTIVE.md, "An oracle reference for (g)").
enum class SelectStrategy {
  full, uniform, decimation, guided, guided_returns, guided_reacquire, coarse_both, coarse_improvement, coarse_residual,
  coarse_triangles, oracle
};
/// "a_full", "b_uniform", ..., "g_coarse_to_fine", "g_improvement", "g_residual", "g_triangles", "o_oracle"
/// (the CSVs' names).
const char* select_strategy_name(SelectStrategy strategy);
/// Every strategy but (a), which is always run (the reference), and (o), which is run when named, in the
/// CSVs' order.
const std::vector<SelectStrategy>& compared_select_strategies();
/// The strategies a comma-separated list of names asks for (compared_select_strategies' order, then (o)),
/// or "all": compared_select_strategies(). Throws InvalidParameter for an unknown or repeated name,
/// listing the names.
std::vector<SelectStrategy> select_strategies_by_names(const std::string& names);
/// The predictors a comma-separated list of "nearest" and "linear" names, in that order. Throws
/// InvalidParameter for an unknown or repeated name.
std::vector<DepthPredictionRule> select_predictors_by_names(const std::string& names);

struct SelectEvalOptions {
  std::vector<double> budgets;  ///< rays per shot as shares of the image, in (0, 1]
  double frames = 5;            ///< points acquired per run, in full frames
  double share = 0.1;           ///< the negative rays' share of a shot in (f)
  int radius = 16;              ///< predict_depth radius [columns]
  std::uint64_t seed = 1;
  std::vector<SelectStrategy> strategies;  ///< besides (a), which is always run (the reference)
  std::vector<DepthPredictionRule> predictors;
};

/// One run's summary: a strategy at one budget share, scored with one predictor.
struct SelectSummaryRow {
  std::string scene, strategy;
  double budget_share, final_quality, points_to_95, stop_points, knee_points, calibration_r, ms_per_shot;
};

/// Runs (a), then every strategy at every budget with every predictor on `scene`, writing one CSV row per
/// checkpoint (header included) to `csv` and one progress line per run to stderr; returns the summaries.
std::vector<SelectSummaryRow> evaluate_select_scene(const SelectScene& scene, const SelectEvalOptions& options,
                                                    std::ostream& csv);

/// The summaries as summary.csv at `path` (IoError when it cannot be written).
void write_select_summary(const std::vector<SelectSummaryRow>& rows, const std::string& path);

}  // namespace occ_improve
