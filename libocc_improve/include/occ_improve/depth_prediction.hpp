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
#include "occ_improve/surface.hpp"

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

}  // namespace occ_improve
