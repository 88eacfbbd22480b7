#pragma once
// The improvement map (eqs. 3 and 4, CONVENTIONS 7-8): per ray j, the expected change of occupancy probability
// that one more measurement a_j along j would bring to the surface voxels it touches.
//
// Conventions (docs/METHOD.md, "Improvement"):
//  - a_j is simulated on the ray through j's bin centre at j's surface depth rho_j (0 for an unknown ray);
//  - its window is every column whose angular extent overlaps the +-k sigma box around j's centre
//    (BinAxis::overlapping, the rule the insertion uses), clipped to the grid (3 x 3 with the paper
//    preset);
//  - for each column i of the window, v_i is i's surface voxel (rho_i, P_i; unknown: rho_i = 0, P_i = 1/2):
//      Ps    = P_s(rho_i - rho_j, B(centre_i - centre_j), sigma_rho(rho_j))   (eq. 1)
//      imp_i = P_i Ps / (P_i Ps + (1 - P_i)(1 - Ps)) - P_i                     (eq. 3)
//    and imp(a_j) = sum of imp_i (eq. 4), negative values kept. Where P_i is exactly 0 or 1 (possible in
//    exact mode) the Bayesian update leaves it unchanged and imp_i = 0.
//  - Float approximation: the map is evaluated in float with the project's polynomial exp (relative error
//    < 2e-7), with B taken per window offset from a table (exact for uniform angular axes), with one
//    division per term, and without eq. 1's peak term for window offsets with B >= 16 (it changes P_s and
//    1 - P_s by a relative < 8e-8 there, so imp_i by < 4e-8; the paper preset's diagonal neighbours). Against the same formula in double on the same surface
//    the per-ray error is < 1e-5 (asserted; measured 3e-7 on the sample scene, clamped mode). P_i is the
//    SurfaceMap's float: in exact mode, where P can come within 1e-7 of 0 or 1, 1 - P_i loses precision.
//  - The full map runs a vectorised loop per elevation row (an AVX2 clone on x86-64 GCC, no FMA); the
//    one-ray path performs the same float operations in the same order, so both are bit-identical and
//    the incremental update equals the full recomputation exactly.
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/maps/column_map.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "occ_improve/maps/surface.hpp"

#include <vector>

namespace occ_improve {

/// Improvement per column, same indexing as SurfaceMap / ColumnIndex (row = elevation bin).
/// Columns the sensor cannot observe (GridGeometry::observable) hold NaN in the maps computed by
/// compute_improvement / update_improvement: they have no value to act on (use nan-aware reductions).
struct ImprovementMap {
  int width = 0, height = 0;
  std::vector<float> value;
  ColumnShape shape() const { return ColumnShape::of_arrays(width, height, {value.size()}); }
};

/// Eqs. 3-4 for the ray through column (azimuth_bin, elevation_bin): the one definition every path uses.
/// Builds the window tables on each call (~10 us on the paper preset): use the map functions for many rays.
/// Throws InvalidParameter for a bin outside the grid, InvalidInput when the surface does not match it.
double ray_improvement(const GridGeometry& geometry, const SensorModel& model, const SurfaceMap& surface,
                       int azimuth_bin, int elevation_bin);

/// The whole map. threads = 0: hardware concurrency. Throws InvalidInput when the surface does not
/// match the geometry, InvalidParameter for threads < 0.
ImprovementMap compute_improvement(const GridGeometry& geometry, const SensorModel& model,
                                   const SurfaceMap& surface, int threads = 0);

/// Incremental update (CONVENTIONS 8): recomputes exactly the rays whose window contains one of
/// `changed_surface_columns` (as returned by update_surface) and returns them (ascending). The result
/// equals compute_improvement on the new surface. An empty `map` is computed in full (every ray returned).
/// threads as compute_improvement's (an update of fewer than 20000 rays runs on the calling thread).
/// Throws InvalidInput for a map or surface of another size, or a column outside the grid, InvalidParameter
/// for threads < 0.
std::vector<ColumnIndex> update_improvement(const GridGeometry& geometry, const SensorModel& model,
                                            const SurfaceMap& surface,
                                            const std::vector<ColumnIndex>& changed_surface_columns,
                                            ImprovementMap& map, int threads = 0);

}  // namespace occ_improve
