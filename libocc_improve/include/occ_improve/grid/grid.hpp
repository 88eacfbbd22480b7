#pragma once
// The sparse spherical store. It knows log-odds and clamping, nothing of sensors or OPDFs.
//
// Layout (inspired by OctoMap's pruned octree, but following the grid's rays):
//  - columns are grouped in tiles of kTileSize x kTileSize; a tile is allocated on first touch, so an
//    untouched tile costs one null pointer (an octree's missing child);
//  - each column holds a leading uniform run [0, uniform_end) as ONE value (in clamped mode: the free
//    space carved to the clamp, an octree's pruned node), then a dense window of the voxels whose
//    values differ, then an implicit tail of untouched voxels (log-odds 0, P = 0.5).
// Memory is therefore proportional to the voxels a truncated OPDF touched and left non-uniform.
#include "occ_improve/geometry/geometry.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace occ_improve {

enum class UpdateMode {
  clamped,  ///< L clamped to [L_min, L_max] after each update, as OctoMap does (default)
  exact,    ///< eq. 2 exactly: log-odds summed without bounds
};

/// The default memory cap: half of the machine's physical memory (sysconf on POSIX systems), or 8 GiB
/// where it cannot be read. Physical, not available, memory: the same machine refuses the same inputs.
std::size_t default_memory_cap_bytes();

struct GridOptions {
  UpdateMode mode = UpdateMode::clamped;
  double probability_min = 0.001;  ///< clamp (clamped mode); OctoMap's default is 0.1192
  double probability_max = 0.999;  ///< clamp (clamped mode); OctoMap's default is 0.971
  /// Refuse a geometry whose worst case (grid_worst_case_bytes) exceeds this.
  std::size_t memory_cap_bytes = default_memory_cap_bytes();

  void validate() const;
  /// OctoMap's clamping thresholds (0.1192 / 0.971).
  static GridOptions octomap_clamping();
};

/// Dense bytes per column besides its voxels: the column record, its change flag, the surface map
/// (depth, probability, bin, unknown), the improvement map, and the per-column outputs and analyses the
/// tools build (region and segment labels, rendered images, predicted depth, rankings).
constexpr double kWorstCaseBytesPerColumn = 32 + 1 + 13 + 4 + 64;
/// Insertion scratch rows per worker thread: one float per depth bin each (integrate.hpp).
constexpr double kInsertionScratchRowsPerThread = 64;

/// The most memory a run on a grid of geometry `g` may need, computed from the parameters before
/// anything is allocated: per column, every voxel stored as a float plus kWorstCaseBytesPerColumn (an
/// empty grid is legal, but the dense per-column maps are not free); per depth bin, the depth axis's
/// tables (two doubles) and the insertion's scratch rows of every hardware thread.
double grid_worst_case_bytes(const GeometryParams& g);

/// Throws ResourceLimit naming the bins, the worst case and the cap when grid_worst_case_bytes(g) >
/// memory_cap_bytes.
/// Called before a geometry is built, since building it allocates the depth axis.
void require_within_memory_cap(const GeometryParams& g, std::size_t memory_cap_bytes);

/// One ray's voxels: a uniform run, a dense window, an untouched tail.
struct ColumnData {
  std::int32_t uniform_end = 0;  ///< bins [0, uniform_end) hold uniform_value
  float uniform_value = 0.0f;
  std::vector<float> window;  ///< bins [uniform_end, uniform_end + window.size())

  std::int32_t window_end() const { return uniform_end + static_cast<std::int32_t>(window.size()); }
  float value(int bin) const {
    if (bin < uniform_end) return uniform_value;
    const int i = bin - uniform_end;
    return i < static_cast<int>(window.size()) ? window[static_cast<std::size_t>(i)] : 0.0f;
  }
  bool touched() const { return uniform_end > 0 || !window.empty(); }
};

class ColumnGrid {
public:
  static constexpr int kTileSize = 8;

  /// Throws InvalidParameter for bad options, ResourceLimit when the worst case exceeds the cap.
  ColumnGrid(const GridGeometry& geometry, const GridOptions& options = {});

  const GridGeometry& geometry() const { return geometry_; }
  const GridOptions& options() const { return options_; }
  bool clamped() const { return options_.mode == UpdateMode::clamped; }
  float log_odds_min() const { return log_odds_min_; }
  float log_odds_max() const { return log_odds_max_; }

  /// Column contents, or nullptr when the column was never touched.
  const ColumnData* find(ColumnIndex column) const;
  /// Column contents, allocating its tile when needed. Not thread-safe across tiles that share a
  /// tile row; the insertion splits work on tile-row boundaries for that reason.
  ColumnData& touch(ColumnIndex column);

  float log_odds(ColumnIndex column, int depth_bin) const;
  double probability(ColumnIndex column, int depth_bin) const;

  /// Columns touched since the last take_changed_columns() (ascending), and resets the record.
  std::vector<ColumnIndex> take_changed_columns();
  void mark_changed(ColumnIndex column) { changed_[column] = 1; }

  std::size_t touched_column_count() const;
  std::size_t stored_voxel_count() const;  ///< voxels held in windows (uniform runs count as one)
  std::size_t memory_bytes() const;        ///< heap bytes held by the store
  std::size_t allocated_tile_count() const;
  void clear();

  /// Merges leading window voxels equal to the uniform value into the uniform run.
  static void compact(ColumnData& column);

private:
  struct Tile {
    ColumnData columns[kTileSize * kTileSize];
  };
  std::size_t tile_of(ColumnIndex column, std::size_t& slot) const;

  GridGeometry geometry_;
  GridOptions options_;
  float log_odds_min_, log_odds_max_;
  int tiles_x_, tiles_y_;
  std::vector<std::unique_ptr<Tile>> tiles_;
  std::vector<std::uint8_t> changed_;
};

/// Cached read access for hot loops: remembers the last tile so neighbouring lookups skip the tile
/// table (the role of Bonxai's accessor and OpenVDB's ValueAccessor).
class GridAccessor {
public:
  explicit GridAccessor(const ColumnGrid& grid) : grid_(&grid) {}
  const ColumnData* find(ColumnIndex column) {
    if (column != last_column_) {
      last_column_ = column;
      last_ = grid_->find(column);
    }
    return last_;
  }
  float log_odds(ColumnIndex column, int bin) {
    const ColumnData* c = find(column);
    return c ? c->value(bin) : 0.0f;
  }

private:
  const ColumnGrid* grid_;
  ColumnIndex last_column_ = ~ColumnIndex{0};
  const ColumnData* last_ = nullptr;
};

/// Deprecated name (0.1) of ColumnGrid, kept for one release (CHANGELOG.md).
using SphericalGrid [[deprecated("renamed ColumnGrid in 0.2")]] = ColumnGrid;

}  // namespace occ_improve
