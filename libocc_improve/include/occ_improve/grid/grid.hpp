#pragma once
// The sparse spherical store. It knows log-odds and clamping, nothing of sensors or OPDFs.
//
// Layout (inspired by OctoMap's pruned octree, but following the grid's rays):
//  - columns are grouped in tiles of kTileSize x kTileSize; a tile is allocated on first touch, so an
//    untouched tile costs one null pointer (an octree's missing child);
//  - each column holds a leading uniform run [0, uniform_end) as ONE value (in clamped mode: the free
//    space carved to the clamp, an octree's pruned node), then a dense window of the voxels whose
//    values differ, then an implicit tail of untouched voxels (log-odds 0, P = 0.5);
//  - a tile's windows lie back to back in one array of the tile (one allocation per tile, none per
//    column on the insertion's path): a window that shrinks keeps its place, one that outgrows it moves
//    to the tile's spare room, or the tile's array is rebuilt.
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

/// A column's dense window: a read-only view of its bins in its tile's storage (ColumnGrid::assign and
/// ColumnGrid::store_windows write it), valid until the next write to a column of the same tile. Not
/// copyable: a copy would silently follow, or outlive, the tile's later writes.
class ColumnWindow {
public:
  ColumnWindow() = default;
  ColumnWindow(const ColumnWindow&) = delete;
  ColumnWindow& operator=(const ColumnWindow&) = delete;
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const float* data() const { return data_; }
  const float* begin() const { return data_; }
  const float* end() const { return data_ + size_; }
  float operator[](std::size_t i) const { return data_[i]; }

private:
  friend class ColumnGrid;
  float* data_ = nullptr;
  std::uint32_t size_ = 0;
  std::uint32_t place_bins_ = 0;  // bins its place in the tile's storage holds (>= size_)
};

/// A column's contents: bins [0, uniform_end) hold uniform_value, then `count` values from `values`, then
/// untouched bins (log-odds 0). Written to a grid, leading values equal to uniform_value (when
/// uniform_end > 0) join the run.
struct ColumnContents {
  ColumnIndex column = 0;
  std::int32_t uniform_end = 0;
  float uniform_value = 0.0f;
  const float* values = nullptr;
  std::uint32_t count = 0;

  std::int32_t window_end() const { return uniform_end + static_cast<std::int32_t>(count); }
  float value(int bin) const {
    if (bin < uniform_end) return uniform_value;
    const auto i = static_cast<std::uint32_t>(bin - uniform_end);
    return i < count ? values[i] : 0.0f;
  }
  bool touched() const { return uniform_end > 0 || count > 0; }
};

/// One ray's voxels: a uniform run, a dense window, an untouched tail.
struct ColumnData {
  std::int32_t uniform_end = 0;  ///< bins [0, uniform_end) hold uniform_value
  float uniform_value = 0.0f;
  ColumnWindow window;  ///< bins [uniform_end, uniform_end + window.size())

  /// The column's voxels as contents (a view of its window: valid as long as the window).
  ColumnContents contents(ColumnIndex column = 0) const {
    return {column, uniform_end, uniform_value, window.data(), static_cast<std::uint32_t>(window.size())};
  }
  std::int32_t window_end() const { return contents().window_end(); }
  float value(int bin) const { return contents().value(bin); }
  bool touched() const { return contents().touched(); }
};

class ColumnGrid {
public:
  static constexpr int kTileSize = 8;
  static constexpr std::size_t kTileColumns = kTileSize * kTileSize;

  /// Throws InvalidParameter for bad options, ResourceLimit when the worst case exceeds the cap.
  ColumnGrid(const GridGeometry& geometry, const GridOptions& options = {});
  /// Moved, never copied (a grid is tens of MB; to keep or duplicate one, save_map and load_map): declared
  /// so that a copy fails at the caller's line, not inside the standard library's vector of tiles.
  ColumnGrid(const ColumnGrid&) = delete;
  ColumnGrid& operator=(const ColumnGrid&) = delete;
  ColumnGrid(ColumnGrid&&) noexcept = default;
  ColumnGrid& operator=(ColumnGrid&&) noexcept = default;

  const GridGeometry& geometry() const { return geometry_; }
  const GridOptions& options() const { return options_; }
  bool clamped() const { return options_.mode == UpdateMode::clamped; }
  float log_odds_min() const { return log_odds_min_; }
  float log_odds_max() const { return log_odds_max_; }

  /// Column contents, or nullptr when the column was never touched.
  const ColumnData* find(ColumnIndex column) const;
  /// Writes one column (allocating its tile when needed), e.g. while a grid is built column by column: the tile's storage
  /// grows by a quarter at a time (shrink_to_fit trims it). The values may be any column's window.
  void assign(const ColumnContents& contents);
  /// Writes several columns of ONE tile (the insertion's store, once per tile and call): a window that
  /// fits its place is written there, the others after the tile's windows; when the storage lacks room it
  /// is rebuilt once, every window back to back (no spare room on a tile's first store, an eighth after
  /// that; one allocation per tile, none per column), and once more than a quarter of it is spare it is
  /// trimmed. The values must not lie in the tile's storage. Throws InvalidInput when the columns are not
  /// all of one tile.
  void store_windows(const ColumnContents* contents, std::size_t count);
  /// The same, with slots[i] the index of contents[i].column in its tile (row by row), which a caller
  /// walking the tile knows: the columns are checked against them by a multiplication each, where finding
  /// each one's tile takes a division (InvalidInput when a slot or a column does not agree).
  void store_windows(const ColumnContents* contents, const std::size_t* slots, std::size_t count);
  /// Rebuilds every tile's storage with its windows back to back and no spare room.
  void shrink_to_fit();

  /// Asks the memory system for the tile of `column`: its column records and its windows' storage. A hint:
  /// it changes nothing, and does nothing for a tile never written or a column outside the grid. The
  /// insertion calls it for the next tile it will update when that tile has few measurements (a small
  /// shot): loading its windows from a store of tens of MB otherwise waits on memory column by column.
  void prefetch_tile(ColumnIndex column) const;

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

private:
  // A tile's columns and the storage of their windows: one allocation per tile rather than per column.
  struct Tile {
    ColumnData columns[kTileColumns];
    std::vector<float> storage;  // the windows; spare capacity after them takes windows that outgrow their place
  };
  // Spare room a rebuilt tile keeps: the insertion's (none on a first store, an eighth after, and trimmed
  // once a quarter is spare) or a column-by-column build's (a quarter).
  enum class Growth { insertion, column_by_column };
  std::size_t tile_of(ColumnIndex column, std::size_t& slot) const;
  Tile& allocated_tile(std::size_t tile_index);  // the tile, allocated when needed
  void write_tile(Tile& tile, const ColumnContents* contents, const std::size_t* slots, std::size_t count,
                  Growth growth);
  static std::size_t window_bins(const Tile& tile);  // bins its windows hold
  void rebuild(Tile& tile, const ColumnContents* contents, const std::size_t* slots, std::size_t count,
               std::size_t spare) const;

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
