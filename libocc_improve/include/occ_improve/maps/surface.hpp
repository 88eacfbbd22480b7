#pragma once
// The surface of highest occupancy probability (CONVENTIONS 6): per column, the depth bin of largest
// log-odds, with the tie rules:
//  - never updated: depth 0, P = 0.5, unknown;
//  - all bins hold the same value: depth rho_max, that P;
//  - no bin more likely occupied than free (largest L < 0) and the largest at the far end: the return lies
//    just beyond the grid and only the rising edge of its OPDF is inside. Like a column free to the end:
//    depth rho_max, bin = depth_bins, P of its free space (bin 0). Without this rule such rays (P ~ 0.3
//    at the last bin) score up to 0.37 improvement, above the no-data level, though the grid can never
//    hold their surface (CONVENTIONS 7 wants rays beyond the depth range at ~0);
//  - otherwise the nearest run of maximal bins: its centre if the maximum is the clamp L_max,
//    else its first bin.
// "Maximal" means within kSurfaceTieTolerance of the maximum (in log-odds): CONVENTIONS 4 lets updates below
// 1e-6 be skipped and values are held in float, so bins closer than that to the maximum are ties, not
// a better surface (typical case: the unknown tail behind carved free space, L = 0 +- 1e-7).
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/maps/column_map.hpp"

#include <cstdint>
#include <vector>

namespace occ_improve {

constexpr float kSurfaceTieTolerance = 1e-5f;  ///< log-odds; Delta P < 2.5e-6

struct SurfaceVoxel {
  float depth_m = 0.0f;
  float probability = 0.5f;
  std::int32_t bin = -1;
  bool unknown = true;
  bool operator==(const SurfaceVoxel& o) const {
    return depth_m == o.depth_m && probability == o.probability && bin == o.bin && unknown == o.unknown;
  }
};

struct SurfaceMap {
  int width = 0, height = 0;
  std::vector<float> depth_m;         ///< surface depth per column (0 where unknown)
  std::vector<float> probability;     ///< P of the surface voxel
  std::vector<std::int32_t> bin;      ///< surface depth bin (-1 where unknown, depth_bins when all equal)
  std::vector<std::uint8_t> unknown;  ///< 1 where the column was never updated

  std::size_t size() const { return depth_m.size(); }
  std::size_t known_count() const;
  ColumnShape shape() const {
    return ColumnShape::of_arrays(width, height, {depth_m.size(), probability.size(), bin.size(), unknown.size()});
  }
  SurfaceVoxel at(std::size_t column) const;
  void set(std::size_t column, const SurfaceVoxel& voxel);
};

/// The surface voxel of one column (nullptr column = never touched).
SurfaceVoxel column_surface(const ColumnData* column, const ColumnGrid& grid);
/// The same from a column's contents (uniform run, then `count` values; both empty = never touched): the
/// surface of the column those contents are written to, whether or not the store has joined leading
/// values equal to the run's value to the run.
SurfaceVoxel column_surface(const ColumnContents& column, const ColumnGrid& grid);

inline SurfaceVoxel SurfaceMap::at(std::size_t c) const { return {depth_m[c], probability[c], bin[c], unknown[c] != 0}; }
inline void SurfaceMap::set(std::size_t c, const SurfaceVoxel& v) {
  depth_m[c] = v.depth_m;
  probability[c] = v.probability;
  bin[c] = v.bin;
  unknown[c] = v.unknown ? 1 : 0;
}

/// Recomputes the surface of `column` (whose data is `data`, nullptr if never touched) into `surface`;
/// true when it changed (depth, P, bin or flag). The one step of update_surface and of the insertion
/// that keeps a surface current.
bool refresh_column_surface(const ColumnGrid& grid, ColumnIndex column, const ColumnData* data, SurfaceMap& surface);
namespace detail {
/// refresh_column_surface for contents the caller has just written to the grid (ColumnGrid::store_windows),
/// without looking the column up again: the insertion's step, with the values still in its cache. The
/// contents must be what the grid now holds for written.column, or the surface falls out of step.
bool refresh_written_column_surface(const ColumnGrid& grid, const ColumnContents& written, SurfaceMap& surface);
}  // namespace detail

/// Full computation over the grid (threads: 0 = hardware concurrency).
SurfaceMap compute_surface(const ColumnGrid& grid, int threads = 0);

/// Recomputes the given columns; returns those whose surface (depth, P, bin or flag) changed, in the
/// order given. Columns are split in contiguous chunks over `threads` (0 = hardware concurrency).
std::vector<ColumnIndex> update_surface(const ColumnGrid& grid, const std::vector<ColumnIndex>& columns,
                                        SurfaceMap& surface, int threads = 0);

}  // namespace occ_improve
