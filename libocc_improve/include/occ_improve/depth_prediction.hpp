#pragma once
// A dense depth from sparse samples: every column gets the surface depth of its nearest measured column.
//
// Rule (docs/SELECTIVE.md "Predicted depth"):
//  - a column is a sample when its surface is known with evidence of occupancy: not unknown, P > 0.5 and
//    inside the depth range (a column only carved free, or free to the grid's end, has P <= 0.5; a column
//    that only a neighbour's OPDF edge reached has P = 0.5 at the end of its carved free space);
//  - a sample keeps its own surface depth; any other column takes the depth of the nearest sample in
//    chessboard distance (8-connected steps), at most radius_columns away, else 0 (no prediction);
//  - of several samples at the same distance the first reached wins: a breadth-first search from all
//    samples at once, seeded in ascending column order, visiting neighbours in a fixed order.
// Depths are in the surface's own convention (SurfaceMap::depth_m).
#include "occ_improve/sensor_model.hpp"
#include "occ_improve/surface.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace occ_improve {

struct DepthPredictionParams {
  int radius_columns = 16;  ///< furthest sample used, in columns (chessboard distance); >= 0
  void validate() const;    ///< radius < 0 -> InvalidParameter
};

struct PredictedDepth {
  int width = 0, height = 0;
  std::vector<float> depth_m;          ///< per column; 0 where no sample lies within the radius
  std::vector<std::int32_t> distance;  ///< chessboard distance to the sample used (0: a sample; -1: none)
};

/// True when column c of `surface` is a sample (rule above).
inline bool is_depth_sample(const SurfaceMap& surface, std::size_t c) {
  return surface.unknown[c] == 0 && surface.probability[c] > 0.5f && surface.depth_m[c] > 0.0f;
}

/// The rule above over the whole surface. Throws InvalidParameter for a bad radius, InvalidInput when the
/// surface's arrays do not hold width x height values.
PredictedDepth predict_depth(const SurfaceMap& surface, const DepthPredictionParams& params = {});

/// How far a map's predicted depth agrees with a reference map (e.g. the map from all points): counted over
/// the reference's samples (is_depth_sample), a column agrees when its predicted depth lies within
/// `sigmas` x model.sigma_depth_at(reference depth) of the reference's surface depth; a column without a
/// prediction disagrees.
struct DepthAgreement {
  std::size_t reference_samples = 0, within = 0;
  /// within / reference_samples (0 when the reference has no sample).
  double share() const { return reference_samples ? static_cast<double>(within) / static_cast<double>(reference_samples) : 0.0; }
};

/// Throws InvalidParameter for sigmas <= 0 (or NaN), InvalidInput when the prediction's size is not the
/// reference surface's (both named).
DepthAgreement depth_agreement(const SurfaceMap& reference, const PredictedDepth& predicted, const SensorModel& model,
                               double sigmas = 2.0);

}  // namespace occ_improve
