#pragma once
// The next shot of a selective sensor: which rays to acquire, what they are expected to bring, and
// whether acquiring more is still worth it (docs/SELECTIVE.md).
//
// A ray's score is its improvement (eqs. 3-4, the ImprovementMap) times its return probability
// (return_model.hpp; an empty record gives 1: no discount). Columns the sensor cannot observe hold NaN
// improvement (improvement.hpp): a rays shot never takes them, and they add nothing to a window's or a
// pattern's sum. A shot's expected gain is the sum of the
// scores of the rays it takes by rank. That sum assumes the rays' gains add up; rays closer than the
// improvement window (3 x 3 columns) share surface voxels, so it overstates a dense shot's gain a little.
//
// Shapes:
//  - rays: any budget_rays rays, highest score first (a mask over the columns restricts the choice);
//  - window: the window_width x window_height rectangle of largest summed score (ROI readout);
//  - decimation: the regular pattern of every step-th column and row, step the smallest one whose
//    pattern fits the budget, at the offset of largest summed score.
// Ties: rays are ordered by rank_key (ranking.hpp), the one order top_rays uses too: equal scores (at
// the start every ray is unknown and equal) go to the ray of lower spread rank, a fixed hash of the
// column index, so that a tie is broken evenly over the view instead of row by row; equal windows and
// offsets go to the lowest (row, column). No spacing is imposed between chosen rays: with one column per
// pixel each ray is a distinct measurement, and rays whose neighbours have just been measured score
// lower at the next plan anyway.
// Re-acquisition (the paper: "regions of negative improvement can be re-acquired"): negative_share of a
// rays shot goes to the rays of most negative score (depth transitions); they do not count in the gain.
// Stop: the plan says stop when the expected gain is below stop_gain_per_ray_below x the rays taken by
// rank, i.e. when the best rays left are worth less than a ray seen once.
#include "occ_improve/improvement.hpp"
#include "occ_improve/return_model.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

enum class ShotShape { rays, window, decimation };

struct PlanRequest {
  int budget_rays = 4096;  ///< rays per shot, in [1, columns]
  ShotShape shape = ShotShape::rays;
  int window_width_columns = 64, window_height_columns = 64;  ///< window shape; its area <= budget_rays
  double negative_share = 0.0;  ///< rays shape: share of the budget for negative rays, in [0, 1)
  /// Default 0.1: below the level of a ray seen once with the pixel-native kinect_v1 (0.138; no data:
  /// 0.324), so the plan stops once every ray that returns has been measured at least twice (or is silent
  /// and discounted by the return model). Why twice: a second measurement is what settles a ray's depth
  /// between two disparity levels (docs/SELECTIVE.md). Must be finite and >= 0.
  double stop_gain_per_ray_below = 0.1;
  /// rays shape: optional mask over the columns (row-major, 1 = the sensor may take the ray), e.g. the
  /// observable columns. Empty: every column.
  std::vector<std::uint8_t> candidates;
  ReturnModelParams return_model;
  /// InvalidParameter naming the value (budget <= 0 or above the grid, bad share, window larger than
  /// the grid or the budget), InvalidInput for a mask of the wrong size.
  void validate(int grid_width, int grid_height) const;
};

struct Shot {
  std::vector<ColumnIndex> columns;  ///< rays shape: by rank, then the negative ones; else ascending
  double expected_gain = 0;          ///< sum of the scores of the rays taken by rank
  std::size_t ranked_rays = 0;       ///< rays taken by rank (the rest are re-acquisitions)
  bool stop = false;                 ///< expected_gain < stop_gain_per_ray_below * ranked_rays
  std::string reason;
};

/// The next shot. `returns` must match the map's size (ReturnRecord::for_grid for none yet).
/// Throws as PlanRequest::validate, InvalidInput when `returns` does not match the map.
Shot plan_next_shot(const ImprovementMap& improvement, const ReturnRecord& returns, const PlanRequest& request);

/// score = improvement x return probability (the ranking plan_next_shot uses).
std::vector<float> shot_scores(const ImprovementMap& improvement, const ReturnRecord& returns,
                               const ReturnModelParams& params = {});

/// The smallest step whose pattern (every step-th column and row) has at most budget_rays rays.
int decimation_step(int width, int height, int budget_rays);
/// Columns (ascending) of the pattern of `step` at offset (offset_x, offset_y), each in [0, step).
std::vector<ColumnIndex> decimation_pattern(int width, int height, int step, int offset_x, int offset_y);

}  // namespace occ_improve
