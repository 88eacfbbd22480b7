#pragma once
// A dense depth from sparse samples, by one of two rules (docs/SELECTIVE.md "Predicted depth").
//
// Samples: in a surface, a column is a sample when its surface is known with evidence of a return inside
// the column: not unknown, P >= kSampleProbabilityMin and inside the depth range. A column only carved
// free, or free to the grid's end, has P <= 0.5. A column that only the edges of its neighbours' OPDFs
// reached has P just above 0.5 (on the pixel-native grid a neighbour's return reaches it at angular term
// B >= 12: P_s < 0.5 + 1e-5 per return) and is not a sample: counting it made every column beside a
// measured one a sample at the neighbour's depth, so the linear rule copied depths there instead of
// interpolating (docs/SELECTIVE.md, "Samples"). In a sparse depth image, a pixel is a sample when its
// depth is > 0 (0 or NaN: none).
//
// Rule `nearest`:
//  - a sample keeps its own depth; any other column takes the depth of the nearest sample in chessboard
//    distance (8-connected steps), at most radius_columns away, else 0 (no prediction);
//  - of several samples at the same distance the first reached wins: a breadth-first search from all
//    samples at once, seeded in ascending column order, visiting neighbours in a fixed order.
// Rule `linear` (surface-aware; predicts exactly the columns `nearest` predicts, only the values differ):
//  - the samples are triangulated in the image plane (Delaunay, sample_triangulation.hpp);
//  - inside a continuous triangle, i.e. whose vertex depths differ by at most discontinuity_sigmas x sigma(z)
//    (the sensor model's sigma at the farthest vertex) or whose vertices each lie within
//    discontinuity_sigmas of the plane of their Delaunay neighbours (a slanted surface; a step puts the
//    vertices beside it far off that plane), and whose edges span at most 2 x radius_columns columns
//    (chessboard), the depth is interpolated linearly in INVERSE depth (barycentric in pixel
//    coordinates): a plane of the scene is affine in 1/z over a pinhole image, so a slanted plane is
//    reproduced exactly, where linear interpolation of z would bow;
//  - inside a triangle across a discontinuity (neither test holds) nothing is interpolated: a column
//    takes the depth of the triangle's nearest vertex (Euclidean, in pixels), and of equidistant vertices
//    the nearer surface (smaller depth) wins, since a foreground edge hides what lies behind it;
//  - elsewhere (outside the samples' convex hull, in triangles with a longer edge) the depth of a nearest
//    sample in chessboard distance (a two-pass distance transform: of equidistant samples it may pick
//    another than `nearest` does).
// Depths are in the surface's own convention (SurfaceMap::depth_m; z for a pinhole binning).
#include "occ_improve/planning/sample_triangulation.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "occ_improve/maps/surface.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace occ_improve {

enum class DepthPredictionRule { nearest, linear };

struct DepthPredictionParams {
  int radius_columns = 16;  ///< furthest sample used, in columns (chessboard distance); >= 0
  DepthPredictionRule rule = DepthPredictionRule::nearest;
  /// linear: a triangle whose vertex depths differ by more than this many sigma(z) is not interpolated
  /// (6: the independent prototype of issue 20; docs/SELECTIVE.md gives the measured choice); > 0
  double discontinuity_sigmas = 6.0;
  void validate() const;  ///< InvalidParameter naming the field (radius < 0, sigmas <= 0 or NaN, bad rule)
};

struct PredictedDepth {
  int width = 0, height = 0;
  std::vector<float> depth_m;          ///< per column; 0 where no sample lies within the radius
  /// chessboard distance to the nearest sample (the sample used by `nearest`; 0: a sample; -1: none)
  std::vector<std::int32_t> distance;
  ColumnShape shape() const { return ColumnShape::of_arrays(width, height, {depth_m.size(), distance.size()}); }
};

/// The least surface probability of a sample: eq. 1 on its ray (d_rho = 0) for one return at angular term
/// B = 3, 1/2 (1 + e^-7)^-1 + e^-3 / 3 = 0.51614, rounded down. On the pixel-native grid (angular sigma
/// 1/sqrt(12) px) B = 3 is a return on the middle of the column's edge, half a pixel from its centre; a
/// pixel's own return lies at the centre (B = 0, P = 0.82). On the paper's spherical grid every return
/// inside a column gives it B <= 1.6 (P >= 0.56). tests/test_depth_prediction.cpp ties it to eq. 1.
constexpr float kSampleProbabilityMin = 0.516f;

/// True when column c of `surface` is a sample (rule above).
inline bool is_depth_sample(const SurfaceMap& surface, std::size_t c) {
  return surface.unknown[c] == 0 && surface.probability[c] >= kSampleProbabilityMin && surface.depth_m[c] > 0.0f;
}

/// The surface's samples as a sparse depth image (its depth where is_depth_sample, else 0).
std::vector<float> sample_depth_image(const SurfaceMap& surface);

/// The nearest rule over the whole surface. Throws InvalidParameter for a bad radius or for the linear
/// rule (which needs a SensorModel: the overload below), InvalidInput when the surface's arrays do not
/// hold width x height values.
PredictedDepth predict_depth(const SurfaceMap& surface, const DepthPredictionParams& params = {});
/// Either rule over the whole surface; `model` gives sigma(z) for the linear rule's discontinuity test.
PredictedDepth predict_depth(const SurfaceMap& surface, const SensorModel& model, const DepthPredictionParams& params);

/// Either rule from a sparse depth image (width x height depths in metres, row-major; 0 or NaN: no
/// sample), usable without a map. Throws InvalidParameter for bad params or a size outside [1, 2^20],
/// InvalidInput when the image does not hold width x height values or holds a negative or infinite depth
/// (naming the pixel).
PredictedDepth predict_dense_depth(const std::vector<float>& sparse_depth_m, int width, int height,
                                   const SensorModel& model, const DepthPredictionParams& params = {});

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
