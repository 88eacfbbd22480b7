#pragma once
// An image-plane Delaunay triangulation of sparse depth samples, with a per-sample non-planarity: what the
// linear depth prediction interpolates over, and what a planner reads to put rays where the surface is not
// yet explained by its samples (issue 20).
//
// Choice (docs/SELECTIVE.md "Predicted depth"): the core takes no geometry library (Eigen and std only), so
// the triangulation is written here: Bowyer-Watson insertion of the sample pixels in Hilbert-curve order
// (each insertion starts its walk next to the previous one), inside a super triangle whose corners lie
// 2^22 px away. Sample pixels have integer coordinates, so the orientation and in-circle tests are exact
// integer arithmetic (64-bit, 128-bit where a super corner takes part): no tolerance, no failure on
// collinear or co-circular pixels (a grid is full of both). Four co-circular pixels are decided by a
// symbolic perturbation of the points' lifts (simulation of simplicity, ordered by (y, x)), so the
// triangulation of a set of samples does not depend on their insertion order: SampleTriangulator, which
// inserts a planner's samples shot by shot, builds the same triangles. Triangles with a super corner are
// dropped at the end; because the corners are finite, a few hull triangles may differ from the exact Delaunay
// triangulation of the samples alone (near-collinear hull chains), which interpolation does not notice.
// 640 x 480 at 5 % samples (12 524 of capture0001): 5.6 ms CPU on one thread of the build machine, median of
// 5 runs interleaved with the previous version's 6.1 ms at load ~2 (bench_depth_prediction
// --benchmark_filter=TriangulateSamples/real:1 --benchmark_min_time=2), about the breadth-first nearest
// fill's time (tests/bench/bench_depth_prediction.cpp, docs/SELECTIVE.md).
//
// Non-planarity of a sample: leave-one-out, the plane through its Delaunay neighbours (least squares in
// inverse depth, in which a plane of the scene is affine in pixel coordinates for a pinhole binning) is
// evaluated at the sample's pixel, giving depth z_fit = 1/w_fit; the residual is |z - z_fit| / sigma(z_fit),
// the sample's distance from its neighbours' plane in units of the sensor's noise there. Where the fitted
// plane passes behind the camera (w_fit <= 0) it is |1/z - w_fit| / (sigma(z) / z^2), the same to first
// order and finite. A sample with fewer than 3 neighbours or collinear ones has 0 (nothing to measure).
// The plane's sums are exact (1/z in fixed point, 2^-30 per metre), so a residual depends on the
// triangulation alone, not on the order its triangles are listed in.
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace occ_improve {

struct TriangulationParams {
  /// A triangle is continuous (no depth discontinuity inside) when the spread of its vertex depths
  /// (max - min) is at most this many sigma(z) at its farthest vertex's depth (the larger noise of the two
  /// ends), or when each of its vertices lies within this many sigmas of its neighbours' plane
  /// (residual_sigmas: a slanted plane, whose depths spread by many sigma over a triangle); > 0.
  double discontinuity_sigmas = 6.0;
  /// A triangle is interpolable when it is continuous ...
  /// ... and when each of its edges spans at most this many columns in chessboard distance; >= 1.
  int max_edge_columns = 32;
  void validate() const;  ///< InvalidParameter naming the field
};

struct SampleTriangulation {
  int width = 0, height = 0;
  /// The sample's column (y x width + x): ascending from triangulate_samples; from SampleTriangulator,
  /// each update's new samples in ascending order after the earlier ones (removed ones left out).
  std::vector<ColumnIndex> vertex_column;
  std::vector<std::int32_t> vertex_x, vertex_y;  ///< its pixel (column % width, column / width)
  std::vector<float> vertex_depth_m;             ///< its depth
  std::vector<float> residual_sigmas;      ///< leave-one-out non-planarity (header comment), >= 0
  /// Vertex indices, counter-clockwise in (x, y) with y down the image as the second coordinate (i.e. a
  /// positive cross product (b - a) x (c - a)).
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<std::uint8_t> interpolable;  ///< per triangle: depth spread and edge lengths within the params

  std::size_t vertex_count() const { return vertex_column.size(); }
  int x(std::int32_t v) const { return vertex_x[static_cast<std::size_t>(v)]; }
  int y(std::int32_t v) const { return vertex_y[static_cast<std::size_t>(v)]; }
  /// Area of triangle t in pixels^2.
  double area_px2(std::size_t t) const;
  /// Longest edge of t in columns (chessboard distance).
  int longest_edge_columns(std::size_t t) const;
  /// Largest residual_sigmas of t's vertices.
  double non_planarity_sigmas(std::size_t t) const;
  /// area_px2 x non_planarity_sigmas: the planner's refinement score.
  double score(std::size_t t) const { return area_px2(t) * non_planarity_sigmas(t); }
  /// The column holding t's centroid (rounded to the nearest pixel; always inside the image).
  ColumnIndex centroid_column(std::size_t t) const;
};

/// Throws InvalidParameter for a width or height outside [1, 2^20], InvalidInput when `sparse_depth_m`
/// does not hold width x height values or holds a negative or infinite depth (naming the pixel).
void check_sparse_depth_image(const std::vector<float>& sparse_depth_m, int width, int height);

/// Triangulates the samples of a sparse depth image (width x height depths in metres, row-major; 0 or NaN:
/// no sample). Throws InvalidParameter for bad params or a non-positive size, InvalidInput when the image
/// does not hold width x height values or a depth is negative or infinite (naming the pixel). Fewer than 3
/// samples (or all collinear) give no triangle. Polls cancel.hpp.
SampleTriangulation triangulate_samples(const std::vector<float>& sparse_depth_m, int width, int height,
                                        const SensorModel& model, const TriangulationParams& params = {});

/// The triangulation of samples that accumulate from call to call (a planner's measured rays, shot after
/// shot). Bowyer-Watson is incremental: update() inserts only the samples that are new since the previous
/// call into the triangulation it keeps, instead of triangulating every sample again (docs/SELECTIVE.md,
/// "Speed"), refreshes the depths (a sample's depth changes as measurements fuse), recomputes the
/// residuals of the vertices whose neighbours or depths changed (all of them when the model's depth noise
/// changed) and the flags of all triangles. A vertex whose pixel holds no sample any more (its surface
/// fell below the sample rule) is removed: its star gives way to the Delaunay triangulation of its link.
/// It starts over from scratch on the first call, when the image's size changes, and after an update that
/// threw (a cancel, too many samples).
/// Every update gives triangulate_samples' triangles for the same samples, with the same residuals and
/// flags (co-circular samples are decided by a fixed rule, not by the order they came or went: header
/// comment); only the vertices' numbering differs: they keep their order from update to update (a
/// removal renumbers the later ones), and each update's new samples come after the earlier ones.
class SampleTriangulator {
public:
  SampleTriangulator();
  ~SampleTriangulator();
  SampleTriangulator(SampleTriangulator&&) noexcept;
  SampleTriangulator& operator=(SampleTriangulator&&) noexcept;

  /// Throws as triangulate_samples. The reference is valid until the next update, a move or the
  /// destruction. Not thread-safe: one triangulator per acquisition, updated by one thread at a time.
  const SampleTriangulation& update(const std::vector<float>& sparse_depth_m, int width, int height,
                                    const SensorModel& model, const TriangulationParams& params = {});
  /// The last update's result (empty before the first, and after an update that threw).
  const SampleTriangulation& triangulation() const;
  /// Samples the last update inserted and removed, and whether it started over.
  std::size_t inserted_last() const;
  std::size_t removed_last() const;
  bool started_over_last() const;
  /// Updates that completed since construction, and how many of them started over.
  std::size_t updates() const { return updates_; }
  std::size_t start_overs() const { return start_overs_; }

  struct State;  ///< opaque

private:
  std::unique_ptr<State> state_;
  std::size_t updates_ = 0, start_overs_ = 0;
};

/// Indices of the `count` triangles of highest score(), highest first (ties: lower index first); fewer
/// when there are fewer triangles with a positive score.
std::vector<std::size_t> top_scored_triangles(const SampleTriangulation& triangulation, std::size_t count);

}  // namespace occ_improve
