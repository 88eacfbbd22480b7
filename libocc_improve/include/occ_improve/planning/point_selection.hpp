#pragma once
// Which points of a frame to keep, by the map: selective sensing for a stream (ImprovementFilter's top
// modes, Python's Mapper.keep_points). Chosen against the map before the frame is inserted, then only the
// kept points inserted, it builds a map closer to the map of all points than pcl::RandomSample or
// pcl::VoxelGrid keeping as many (docs/SELECTIVE.md, "A cell's sample first").
//
// The order (every constant below is the rule's, none is tuned):
//  - cells: the grid's columns are cut into cells of s x s, s = floor(sqrt(rays / keep)) with `rays` the
//    distinct rays the points fall in (SamplingCells), so a cell holds about one kept point and the kept
//    points cover the view evenly instead of clumping as a random sample does;
//  - rounds: round r takes the r-th point of every cell; inside a cell, distinct rays before a second
//    point of one ray, then the better point; in the last, partial round the cells whose point is better
//    go first;
//  - better: first a ray that holds a depth sample (is_depth_sample, depth_prediction.hpp) over one that
//    does not. At the sampling scale a ray without a sample in a cell that has one is predicted from it
//    (predict_depth), so one more measurement of the cell's sample, which averages the sensor's noise,
//    is worth more than a first sample beside it; a cell without samples takes its unmeasured rays, so
//    newly seen parts of the view are covered first. Then the ray's improvement (the least settled
//    sample first), the mean improvement of its block of 4 x 4 columns (the multi-scale improvement,
//    multiscale.hpp: of two unseen rays, the one in the less known block first), then the ray's spread
//    rank (rank_key: a tie is spread over the view, never broken by the points' order, which on an
//    organized frame would keep the top rows).
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/maps/multiscale.hpp"
#include "occ_improve/maps/surface.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace occ_improve {

/// A point that has a ray: the caller's id for it (its index in the cloud) and the column it falls in.
/// Each entry is one point; ids need not be distinct (the choice returns each kept entry's id).
struct PointOnRay {
  std::uint64_t point = 0;
  ColumnIndex column = 0;
};

/// The points of `points` that have a ray in `geometry` (valid, in the field of view), their id = their
/// index in the span. Polls Ctrl-C.
std::vector<PointOnRay> points_on_rays(PointSpan points, const GridGeometry& geometry);

/// The maps the choice reads (a Mapper's: geometry(), surface(), improvement(), pyramid()).
struct MapView {
  const GridGeometry& geometry;
  const SurfaceMap& surface;
  const ImprovementMap& improvement;
  const ImprovementPyramid& pyramid;
};

/// How many to keep: `count` points, or `fraction` (in [0, 1]) of the points on an observable ray,
/// rounded to the nearest whole point (the base the PCL filter's setTopFraction counts).
struct KeepAmount {
  static KeepAmount count(std::size_t points) { return {false, points, 0.0}; }
  static KeepAmount fraction(double share) { return {true, 0, share}; }
  bool is_fraction = false;
  std::size_t points = 0;
  double share = 0.0;
};

/// The ids of the points to keep (order above), ascending: `amount` of them, at most the points on an
/// observable ray. Points on a ray that is not observable (NaN improvement: masked, or no pixel sees it;
/// improvement.hpp) are never kept. InvalidParameter for a fraction outside [0, 1]; InvalidInput naming
/// the first point whose column lies outside the grid, a map whose size is not the grid's, or more than
/// 2^32 - 1 points at once.
/// Deterministic: the same points and map give the same ids. Polls Ctrl-C (Cancelled).
std::vector<std::uint64_t> keep_points_by_map(const std::vector<PointOnRay>& points, KeepAmount amount,
                                              const MapView& map);

}  // namespace occ_improve
