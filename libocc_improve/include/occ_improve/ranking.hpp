#pragma once
// Where to look next: the best rays, connected regions of high improvement, and when to stop (SPEC 9).
//
// Conventions (docs/METHOD.md, "Ranking"):
//  - regions are 8-connected (diagonal neighbours join), so a thin diagonal no-data band or depth edge
//    stays one region;
//  - a region's centroid is the mean of its columns' centre positions in the binning's unit (angles, or
//    pixels), so each column counts once and the centroid is the middle of the area to re-acquire, not
//    pulled towards its peak;
//  - columns that are not observable (NaN improvement, improvement.hpp) are never ranked, never in a
//    region and never counted by the stop signal.
#include "occ_improve/geometry.hpp"
#include "occ_improve/improvement.hpp"
#include "occ_improve/surface.hpp"

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

namespace occ_improve {

struct RankedRay {
  ColumnIndex column;
  int azimuth_bin, elevation_bin;
  float improvement;
  float depth_m;  ///< surface depth (0 where unknown)
};

/// The k rays of highest improvement, best first (ties: lower column index first).
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

struct Region {
  double summed_improvement;
  std::size_t area_columns;
  float peak_improvement;
  double centroid_horizontal, centroid_vertical;        ///< mean column centre, binning's unit (rad or px)
  double centroid_azimuth_rad, centroid_elevation_rad;  ///< angles of centroid_direction (SPEC 1)
  Eigen::Vector3d centroid_direction;                   ///< unit vector in the sensor frame
  double mean_depth_m;                                  ///< over known columns, 0 if none
};

/// 8-connected regions of improvement >= min_improvement with at least min_area_columns columns,
/// sorted by summed_improvement (descending). Throws InvalidInput for maps of mismatched sizes.
std::vector<Region> find_regions(const SphericalGeometry& geometry, const ImprovementMap& map,
                                 const SurfaceMap& surface, const RegionOptions& options = {});

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
