#pragma once
// The improvement at the scale of the sampling (issue 20 part 2, docs/SELECTIVE.md "Multi-scale
// improvement"). The paper's improvement is defined for any binning; this keeps it on coarser
// pixel-native binnings of the same camera - blocks of 2, 4, 8 and 16 columns a side, i.e. the pinhole
// binnings fx/s, fy/s, cx/s, cy/s - fed by the same measurements, so that a ray that has not been measured
// inherits what its block knows:
//  - a block's improvement is the mean of its rays' improvement (eqs. 3-4, the fine ImprovementMap;
//    unobservable rays left out): settled flat blocks are low (~0.1 after two measurements), blocks with
//    depth transitions negative (the rays behind an edge would carve the near surface's voxels free,
//    imp_i ~ -P), blocks without data high (0.324, the no-data level);
//  - beside it, the moments of the block's depth samples (depth_prediction.hpp's is_depth_sample: column
//    u, row v, surface depth z) so that the deviation of the samples from the predictor's local model
//    (a constant for the nearest-sample predictor, a plane for a linear one) can be read in sigmas: the
//    geometric residual the planner compares with the paper's measure (planner.hpp, coarse_to_fine).
// Design: a pyramid, every level summarising the 2 x 2 blocks of the level below (OctoMap's inner nodes
// summarising their children, here over the image plane: the depth axis is already summarised by the
// surface). Chosen over keeping each level from the fine grid directly (one pass over s x s columns per
// changed block: 256 reads per 16-block against 4) and over incremental sums (+= new - old, which drift in
// float and make "incremental = recomputed" approximate): a block is always recomputed from its children
// in a fixed order, so an update is bit-identical to a rebuild and costs 4 reads per changed block per
// level. Memory: the levels hold 1/4 + 1/16 + 1/64 + 1/256 = 0.33 blocks per column, 89 bytes each
// (~30 bytes per column: a quarter of the per-column maps the grid already keeps, kWorstCaseBytesPerColumn).
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "occ_improve/maps/surface.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace occ_improve {

/// A block's summary. Moments are sums over its depth samples, u and v in grid columns / rows (the
/// column's centre), z in the surface's convention (SurfaceMap::depth_m); doubles so that the plane fit's
/// cancellation (Szz against its fitted part) stays below 1e-9 relative over a 640 x 480 grid.
struct BlockSummary {
  float improvement_sum = 0;          ///< sum of the observable rays' improvement
  std::uint32_t observable_rays = 0;  ///< rays with a (non-NaN) improvement
  std::uint32_t samples = 0;          ///< depth samples (is_depth_sample)
  double su = 0, sv = 0, sz = 0, suu = 0, suv = 0, svv = 0, suz = 0, svz = 0, szz = 0;
  void add(const BlockSummary& o);
  /// Mean improvement; NaN when no ray of the block is observable.
  float mean_improvement() const;
};

/// Local model of the predictor whose error the residual estimates.
enum class LocalModel {
  constant,  ///< nearest-sample prediction: a column takes a neighbour's depth
  plane,     ///< linear prediction: a column takes the plane of its neighbours
};

class ImprovementPyramid {
public:
  static constexpr int kLevels = 4;  ///< blocks of 2, 4, 8, 16 columns a side
  static int block_size(int level) { return 2 << level; }
  /// The level of blocks of `columns` a side; InvalidParameter unless columns is 2, 4, 8 or 16.
  static int level_of_block_size(int columns);

  ImprovementPyramid() = default;
  /// Every level from the fine maps. InvalidInput when the maps' sizes differ (both named).
  ImprovementPyramid(const ImprovementMap& improvement, const SurfaceMap& surface);

  /// Recomputes the blocks holding one of `changed` (the rays whose improvement was recomputed and the
  /// columns whose surface changed; duplicates allowed) bottom-up; the result equals a rebuild exactly.
  /// Everything is checked before anything changes: InvalidInput for maps of another size or a column
  /// outside the grid.
  void update(const ImprovementMap& improvement, const SurfaceMap& surface, const std::vector<ColumnIndex>& changed);

  int width() const { return width_; }    ///< fine columns
  int height() const { return height_; }  ///< fine rows
  ColumnShape shape() const { return ColumnShape::of_grid(width_, height_); }
  int blocks_x(int level) const;
  int blocks_y(int level) const;
  std::size_t block_count(int level) const;
  /// Block (bx, by) of `level` (InvalidParameter naming the value when out of range).
  const BlockSummary& block(int level, int bx, int by) const;
  /// The block of `level` holding fine column c.
  std::size_t block_of_column(int level, ColumnIndex c) const;
  /// Block number `index` of `level` (row-major, as block_of_column numbers them; InvalidParameter naming
  /// the value when out of range).
  const BlockSummary& block_at(int level, std::size_t index) const;

  /// RMS deviation, in sigma_depth_at(mean depth) of `model`, of the depth samples of block (bx, by) and its
  /// 8 neighbours from their best constant or plane (least squares). NaN when they hold fewer samples
  /// than the model needs to leave a residual (constant: 2, plane: 4) or, for the plane, when the samples
  /// are collinear (then the constant's residual is returned).
  double residual_sigmas(int level, int bx, int by, const SensorModel& model, LocalModel local) const;

  std::size_t memory_bytes() const;

private:
  void check_maps(const ImprovementMap& improvement, const SurfaceMap& surface) const;
  void recompute(int level, std::size_t block, const ImprovementMap& improvement, const SurfaceMap& surface);
  int width_ = 0, height_ = 0;
  std::vector<BlockSummary> levels_[kLevels];
  std::vector<std::uint8_t> marks_[kLevels];  ///< update's scratch: all 0 between calls
};

}  // namespace occ_improve
