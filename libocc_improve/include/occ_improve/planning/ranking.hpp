#pragma once
// Where to look next: the best rays, connected regions of high improvement, and when to stop (CONVENTIONS 9).
//
// Conventions (docs/METHOD.md, "Ranking"):
//  - one order of rays everywhere (rank_key): larger value first; equal values go to the lower spread
//    rank, a fixed hash of the column index, so a tie (at the start every ray is unknown and equal) is
//    spread over the view instead of taken row by row. top_rays, a region's peak and centre, and the
//    planner (planner.hpp) all rank with it;
//  - regions are 8-connected (diagonal neighbours join), so a thin diagonal no-data band or depth edge
//    stays one region;
//  - a region's centre is its medoid: the column of the region with the least summed distance (in
//    columns and rows, L1) to the region's other columns. Not the mean position: a region wrapped around
//    an object (its shadow, its border) has its mean on the object, outside the region, and a sensor
//    aimed there looks at what it has already seen;
//  - positions are grid coordinates u (column = azimuth bin, grows to the right, +x) and v (row =
//    elevation bin, grows downwards, +y): with the pixel-native presets, the image pixel (u, v);
//  - columns that are not observable (NaN improvement, improvement.hpp) are never ranked, never in a
//    region and never counted by the stop signal.
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/maps/surface.hpp"

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

/// The rank of a ray: larger key = ranked first. The value's order, then the complement of the column's
/// spread rank (MurmurHash3's 32-bit finaliser of the column index: a bijection, so no two columns tie).
std::uint64_t rank_key(float value, ColumnIndex column);

/// The k columns of largest rank_key among the eligible ones (nullptr: all), best first; NaN values (not
/// observable) are never taken. Returns min(k, eligible non-NaN columns) columns.
std::vector<ColumnIndex> best_columns(const std::vector<float>& value, const std::uint8_t* eligible, std::size_t k);
/// Mean of the largest ceil(share x n) of the n eligible (nullptr: all), non-NaN values; 0 when n = 0.
/// share in (0, 1] (the caller validates it). Exact: the same histogram bound as best_columns, then the
/// bound's bucket sorted.
double mean_of_best_share(const std::vector<float>& value, const std::uint8_t* eligible, double share);

/// The cells of a jittered grid at the scale of a sampling of k among `candidates` columns of a grid
/// `width` columns wide: s x s columns with s = floor(sqrt(candidates / k)) (at least 1), so that the k
/// samples put about one in each cell. Shared by spread_best_columns and keep_points_by_map (point_selection.hpp).
struct SamplingCells {
  SamplingCells(std::size_t candidates, std::size_t k, int width);
  int side = 1;    ///< columns a side
  int across = 1;  ///< cells per row of cells
  std::size_t count(int height) const { return static_cast<std::size_t>(across) * static_cast<std::size_t>((height + side - 1) / side); }
  std::size_t cell_of(int column_u, int row_v) const {
    return static_cast<std::size_t>(row_v / side) * static_cast<std::size_t>(across) + static_cast<std::size_t>(column_u / side);
  }
};

/// The k best eligible columns of a grid `width` columns wide, spread as a jittered grid at the scale of k:
/// cells of s x s columns, s = floor(sqrt(eligible non-NaN columns / k)), one column per cell per round
/// (the cell's largest rank_key), each round's cells by that key; so a tie (a view nothing has reached)
/// is covered evenly rather than as a random sample clumps it. Returns min(k, eligible non-NaN) columns.
/// Throws InvalidInput when width > 0 and `value` does not hold whole rows of it (and there is a column
/// to take).
std::vector<ColumnIndex> spread_best_columns(const std::vector<float>& value, const std::uint8_t* eligible, int width,
                                             std::size_t k);

struct RankedRay {
  ColumnIndex column;
  int azimuth_bin, elevation_bin;  ///< u (column) and v (row); the image pixel with the pixel-native presets
  float improvement;
  float depth_m;  ///< surface depth (0 where unknown)
};

/// The k rays of highest improvement, best first, ties by rank_key (best_columns).
/// k <= 0 -> InvalidParameter; maps of different sizes -> InvalidInput. Returns min(k, rays) rays.
std::vector<RankedRay> top_rays(const ImprovementMap& map, const SurfaceMap& surface, int k);

struct RegionOptions {
  /// A column belongs to a region when its improvement >= this. 0.2 lies between the level of a ray
  /// observed once (~0.14 pixel-native, ~0.13 paper preset) and the no-data level (0.324), so regions are
  /// the areas without data (holes, shadows, beyond range) and their borders, not the observed surface.
  float min_improvement = 0.2f;
  std::size_t min_area_columns = 4;   ///< smaller regions are dropped (isolated noisy rays)
  void validate() const;              ///< NaN / infinite threshold -> InvalidParameter
};

/// A region's columns are named by grid coordinates (u, v): column and row, pixels with the pixel-native
/// presets (v grows downwards).
struct Region {
  double summed_improvement = 0;
  std::size_t area_columns = 0;
  float peak_improvement = 0;
  int peak_u = 0, peak_v = 0;      ///< the column of peak_improvement (ties by rank_key)
  int centre_u = 0, centre_v = 0;  ///< the medoid: always a column of the region (ties by rank_key)
  int min_u = 0, min_v = 0, max_u = 0, max_v = 0;  ///< bounding box, inclusive
  Eigen::Vector3d centre_direction = Eigen::Vector3d::UnitZ();  ///< unit ray through the centre column, sensor frame
  double centre_azimuth_rad = 0, centre_elevation_rad = 0;      ///< CONVENTIONS 1 angles of centre_direction
  double mean_depth_m = 0;                                      ///< over known columns, 0 if none
};

/// 8-connected regions of improvement >= min_improvement with at least min_area_columns columns,
/// sorted by summed_improvement (descending). Throws InvalidInput for maps of mismatched sizes.
std::vector<Region> find_regions(const GridGeometry& geometry, const ImprovementMap& map,
                                 const SurfaceMap& surface, const RegionOptions& options = {});

/// The columns of `regions` (find_regions' result on this map with these options, or its first K):
/// label i + 1 for the columns of regions[i], 0 elsewhere. Each region is grown again from its peak by
/// find_regions' rule. Throws InvalidInput for a region that is not one of this map's (its peak below the
/// threshold, or another area), and as find_regions.
std::vector<std::uint32_t> region_labels(const GridGeometry& geometry, const ImprovementMap& map,
                                         const std::vector<Region>& regions, const RegionOptions& options = {});

/// When to stop acquiring. Defaults are scaled for a 640 x 480 map with the paper's model, where one
/// unknown ray is worth ~0.32 and a ray observed once ~0.13 (docs/METHOD.md):
///  - total: 10 = about 30 unknown rays or 75 once-seen rays left in the whole view;
///  - best region: 1 = the best region is worth less than ~8 once-seen rays (a 3 x 3 patch).
/// Only rays >= ray_floor count towards the total: the small residuals of well-observed rays add up to
/// hundreds over a 640 x 480 view and would keep the signal from ever firing.
struct StopCriteria {
  double total_improvement_below = 10.0;
  double best_region_below = 1.0;
  double ray_floor = 0.01;
  void validate() const;  ///< NaN / negative -> InvalidParameter
};

struct StopSignal {
  bool stop;
  double total_improvement;        ///< sum of ray improvements >= ray_floor
  double best_region_improvement;  ///< largest summed improvement of the regions, 0 without any
  std::string reason;              ///< why (or why not) stop, for logs
};

/// stop = total < total_improvement_below OR best region < best_region_below.
StopSignal stop_signal(const ImprovementMap& map, const std::vector<Region>& regions,
                       const StopCriteria& criteria = {});

/// Progress over a sequence of frames: acquisition has stopped paying when the total expected improvement
/// fell by less than min_relative_gain (of the previous total) for `patience` frames in a row. Needed
/// because rays that never return data (black or specular surfaces, projector shadows) keep their
/// no-data improvement forever, so the absolute thresholds above may never fire on a real scene.
/// Default 3%: on the built-in sample (static view, paper preset) each frame lowers the total by 8% at
/// frame 3, 4.5% at frame 9, 3% around frame 16 and 2% around frame 29 (diminishing returns), so the
/// monitor stops after ~19 frames.
struct ProgressCriteria {
  double min_relative_gain = 0.03;
  int patience = 3;
  void validate() const;  ///< gain NaN / outside [0, 1), patience < 1 -> InvalidParameter
};

/// Evaluates the stop signal frame after frame: stop_signal(), or progress stalled.
class StopMonitor {
public:
  explicit StopMonitor(const StopCriteria& criteria = {}, const ProgressCriteria& progress = {});
  /// Call once per acquired frame, with the maps after that frame.
  StopSignal update(const ImprovementMap& map, const std::vector<Region>& regions);
  int stalled_frames() const { return stalled_frames_; }

private:
  StopCriteria criteria_;
  ProgressCriteria progress_;
  double previous_total_ = -1.0;  ///< < 0 before the first frame
  int stalled_frames_ = 0;
};

}  // namespace occ_improve
