#pragma once
// The next shot of a selective sensor: which rays to acquire, what they are expected to bring, and
// whether acquiring more is still worth it (docs/SELECTIVE.md).
//
// A ray's score is its improvement (eqs. 3-4, the ImprovementMap) times its return probability
// (return_model.hpp; an empty record gives 1: no discount), times s / (s + R) for a ray whose R >= 2
// returns left its improvement >= 0.2 (near the no-data level 0.324: a depth edge's foreground ray, whose peak its
// neighbours' free space carves away, or a return beyond the grid; docs/SELECTIVE.md "Return model"). Columns the sensor cannot observe hold NaN
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
// coarse_to_fine (strategy (g), docs/SELECTIVE.md "Coarse-to-fine"): never the plain top-k.
//  1. coverage: every block of coverage_block_columns a side (the predictor's radius, so that once each
//     holds a sample every column has one within the radius) that holds no depth sample yet gets one ray,
//     its best-scoring one (ties by rank_key: a hashed, i.e. jittered, position in the block), while p
//     (below) is >= kCoverageMinReturn (0.5: one unanswered ask in a block halves its return rate);
//  2. refinement with the rays left, R: at the coarsest level of the pyramid (multiscale.hpp) with at
//     least kBlocksPerRay (4) x R blocks (else blocks of 2), so that a shot takes at most a quarter of the
//     blocks and their priority, not the tiling, decides which (with a candidate mask: blocks holding a
//     candidate, R at most the candidates left); one ray per block (its best-scoring ray,
//     blocks with a coverage ray of this shot left out), blocks by priority:
//       improvement: |the block's mean improvement| x p (no data 0.324 high, settled low, a depth transition
//                    negative, hence re-acquired: the paper's "regions of negative improvement")
//       residual:    min(r, residual_cap_sigmas) / residual_cap_sigmas x p x the share of the block's rays
//                    without a return of their own in the record (no record: without a depth sample), r = ImprovementPyramid::residual_sigmas under the
//                    predictor's local model; a block with too few samples inherits its parent's r, and
//                    with none up to 16 columns r = 0 (unseen: the coverage pass's; or silent)
//       both:        the residual's priority x |mean improvement|
//     or, with triangles, not by blocks: the rays that returned (no record: the surface's depth samples)
//     are triangulated in the image plane (sample_triangulation.hpp) and one ray goes to the centroid of
//     each of the R triangles of largest area x non-planarity (its vertices' largest leave-one-out plane
//     residual, in sigmas) x the centroid ray's return probability: large triangles are where the
//     samples are sparse, non-planar ones where a linear prediction is wrong (the independent prototype
//     of issue 20). Needs the surface: the Mapper overload of plan_next_shot. Its expected gain is in
//     rays made good (good_rays.hpp: rays whose depth comes within 2 sigma): the paper's improvement of
//     a centroid is low by construction (its neighbours' OPDFs reach it), while what it adds is to the
//     linear prediction. Its stop reads the mean score of the view's best stop_view_share of rays,
//     whatever the shot's size;
//     (default residual: in the ablation the paper's measure made (g) slower on every scene)
//     with p = the return probability of the block's best ray x the block's return rate (R + 1) / (A + 1)
//     over the record's asks of its columns (the per-ray prior only reaches 8 neighbours; measured without
//     it, (g) spent 40-45 % of its rays on silent ones on capture0001 and office1). Blocks whose best
//     score is <= 0 have nothing to take. The expected gain is the sum of the taken rays' scores, the stop rule the one above.
// Re-acquisition (the paper: "regions of negative improvement can be re-acquired"): negative_share of a
// rays shot goes to the rays of most negative score (depth transitions); they do not count in the gain.
// Stop: the plan says stop when the expected gain is below stop_gain_per_ray_below x the rays taken by
// rank, i.e. when the best rays left are worth less than a ray seen once (refined by triangles: when the
// view's best stop_view_share of rays score below stop_gain_per_ray_below on average).
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/maps/multiscale.hpp"
#include "occ_improve/planning/return_model.hpp"
#include "occ_improve/planning/sample_triangulation.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

enum class ShotShape { rays, window, decimation, coarse_to_fine };

/// What ranks coarse_to_fine's refinement (the ablation of docs/SELECTIVE.md): blocks (improvement,
/// residual, both) or the measured samples' triangles (triangles).
enum class RefineBy { improvement, residual, both, triangles };

class Mapper;

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
  /// coarse_to_fine refined by triangles: the stop reads the mean score of this share of the view's
  /// observable (candidate) rays, the best ones, not of the shot's: a map's state, not a shot's size,
  /// decides when to stop (measured: over the best `budget` rays left, 1 % shots stopped 13-20 % after
  /// the knee and 20 % shots within 8 %; over the best fifth, every budget within 10 % on the real scenes,
  /// docs/SELECTIVE.md). In (0, 1].
  double stop_view_share = 0.2;
  /// Optional mask over the columns (row-major, 1 = the sensor may take the ray), e.g. the observable
  /// columns; empty: every column. Every shape keeps to it: the rays shapes rank candidates only, a window
  /// or decimation pattern is chosen by its candidates' scores and leaves the others out of the shot.
  std::vector<std::uint8_t> candidates;
  ReturnModelParams return_model;
  /// coarse_to_fine: side of the coverage pass's blocks, 2, 4, 8 or 16 columns. 16 = the evaluation's
  /// predictor radius (DepthPredictionParams::radius_columns).
  int coverage_block_columns = 16;
  /// Default residual, which both overloads of plan_next_shot can compute. The tools (occ_plan,
  /// occ_improve_live -simulate) default to triangles, the best with the linear predictor
  /// (docs/SELECTIVE.md, "Samples"), which needs the Mapper overload.
  RefineBy refine_by = RefineBy::residual;
  /// coarse_to_fine: the predictor's local model (nearest sample: constant; linear: plane).
  LocalModel local_model = LocalModel::constant;
  /// coarse_to_fine: residuals are capped here. 8 sigma: four times the metric's 2-sigma tolerance; a
  /// larger deviation is a depth edge whatever its size, and one edge should not outrank every other block.
  double residual_cap_sigmas = 8.0;
  /// InvalidParameter naming the value (budget <= 0 or above the grid, bad share, window larger than
  /// the grid or the budget), InvalidInput for a mask of the wrong size.
  void validate(int grid_width, int grid_height) const;
};

struct Shot {
  std::vector<ColumnIndex> columns;  ///< rays shape: by rank, then the negative ones; else ascending
  /// Sum of the scores of the rays taken by rank; refined by triangles, the rays they are expected to
  /// make good (good_rays.hpp; negative when they are expected to lower the quality).
  double expected_gain = 0;
  /// What the stop compares with stop_gain_per_ray_below: expected_gain / ranked_rays; refined by
  /// triangles, the mean score of the view's best stop_view_share of rays.
  double stop_gain_per_ray = 0;
  std::size_t ranked_rays = 0;  ///< rays taken by rank (the rest are re-acquisitions)
  bool stop = false;            ///< ranked_rays == 0 or stop_gain_per_ray < stop_gain_per_ray_below
  std::string reason;
};

/// The next shot. `returns` must match the map's size (ReturnRecord::for_grid for none yet).
/// Throws as PlanRequest::validate, InvalidInput when `returns` does not match the map; coarse_to_fine
/// needs the pyramid (the overloads below): InvalidParameter naming the shape here.
Shot plan_next_shot(const ImprovementMap& improvement, const ReturnRecord& returns, const PlanRequest& request);
/// Any shape; coarse_to_fine reads the pyramid and the model's sigma(z). InvalidInput when the pyramid
/// is not of the map's size.
Shot plan_next_shot(const ImprovementMap& improvement, const ImprovementPyramid& pyramid, const SensorModel& model,
                    const ReturnRecord& returns, const PlanRequest& request);
/// The same with the mapper's improvement, pyramid and model.
Shot plan_next_shot(const Mapper& mapper, const ReturnRecord& returns, const PlanRequest& request);

/// What one plan passes to the next within one acquisition (one mapper, one record): the triangulation of
/// the measured samples, which refine_by triangles then extends with each shot's new samples instead of
/// triangulating all of them again (SampleTriangulator; bench_select_round's plan 48-53 -> 22-29 ms a round,
/// docs/SELECTIVE.md "Speed"). Other shapes and refinements leave it as it is.
struct PlanMemory {
  SampleTriangulator triangulation;
};
/// The same as the mapper overload, keeping `memory` from call to call: the same shots (the
/// triangulation does not depend on the order its samples came in), sooner.
Shot plan_next_shot(const Mapper& mapper, const ReturnRecord& returns, const PlanRequest& request, PlanMemory& memory);

/// score = improvement x return probability, discounted for rays whose returns did not settle them (the
/// ranking plan_next_shot uses; the header's first paragraph).
std::vector<float> shot_scores(const ImprovementMap& improvement, const ReturnRecord& returns,
                               const ReturnModelParams& params = {});

/// The smallest step whose pattern (every step-th column and row) has at most budget_rays rays.
int decimation_step(int width, int height, int budget_rays);
/// Columns (ascending) of the pattern of `step` at offset (offset_x, offset_y), each in [0, step).
std::vector<ColumnIndex> decimation_pattern(int width, int height, int step, int offset_x, int offset_y);

}  // namespace occ_improve
