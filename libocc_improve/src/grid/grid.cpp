#include "occ_improve/grid/grid.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <sstream>
#include <thread>

#if __has_include(<unistd.h>)
#include <unistd.h>  // sysconf: the machine's physical memory, for the default cap
#endif

namespace occ_improve {

using detail::require_parameter;

void GridOptions::validate() const {
  require_parameter(probability_min > 0 && probability_min < 0.5, "probability_min", probability_min, "in (0, 0.5)");
  require_parameter(probability_max > 0.5 && probability_max < 1, "probability_max", probability_max, "in (0.5, 1)");
  require_parameter(memory_cap_bytes > 0, "memory_cap_bytes", static_cast<double>(memory_cap_bytes), "> 0");
  // An enum set from a number (Python's UpdateMode(7)) ran as exact and was saved as exact.
  require_parameter(mode == UpdateMode::clamped || mode == UpdateMode::exact, "mode", static_cast<double>(mode),
                    "clamped (0) or exact (1)");
}

GridOptions GridOptions::octomap_clamping() {
  GridOptions o;
  o.probability_min = 0.1192;
  o.probability_max = 0.971;
  return o;
}

std::size_t default_memory_cap_bytes() {
  constexpr std::size_t kFallback = std::size_t{8} << 30;
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGE_SIZE)
  const long pages = sysconf(_SC_PHYS_PAGES), page_bytes = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page_bytes > 0) return static_cast<std::size_t>(pages) / 2 * static_cast<std::size_t>(page_bytes);
#endif
  return kFallback;
}

double grid_worst_case_bytes(const GeometryParams& g) {
  const double columns = static_cast<double>(g.azimuth_bins) * g.elevation_bins;
  const double per_column = static_cast<double>(g.depth_bins) * sizeof(float) + kWorstCaseBytesPerColumn;
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  const double per_bin = 2.0 * sizeof(double) + kInsertionScratchRowsPerThread * sizeof(float) * threads;
  return columns * per_column + per_bin * (g.depth_bins + 1.0);
}

void require_within_memory_cap(const GeometryParams& g, std::size_t memory_cap_bytes) {
  const double worst_case = grid_worst_case_bytes(g);
  if (worst_case <= static_cast<double>(memory_cap_bytes)) return;
  std::ostringstream m;
  m << "grid of " << g.azimuth_bins << " x " << g.elevation_bins << " x " << g.depth_bins << " bins may need up to "
    << worst_case / (1 << 20) << " MiB (its voxels, " << kWorstCaseBytesPerColumn
    << " bytes of maps per column and the tables per depth bin), above memory_cap_bytes = "
    << static_cast<double>(memory_cap_bytes) / (1 << 20) << " MiB";
  throw ResourceLimit(m.str());
}

ColumnGrid::ColumnGrid(const GridGeometry& geometry, const GridOptions& options)
    : geometry_(geometry), options_(options) {
  options.validate();
  require_within_memory_cap(geometry.params(), options.memory_cap_bytes);
  log_odds_min_ = static_cast<float>(logit(options.probability_min));
  log_odds_max_ = static_cast<float>(logit(options.probability_max));
  tiles_x_ = (geometry.width() + kTileSize - 1) / kTileSize;
  tiles_y_ = (geometry.height() + kTileSize - 1) / kTileSize;
  tiles_.resize(static_cast<std::size_t>(tiles_x_) * tiles_y_);
  changed_.assign(geometry.column_count(), 0);
}

std::size_t ColumnGrid::tile_of(ColumnIndex column, std::size_t& slot) const {
  const int a = geometry_.azimuth_bin_of(column), e = geometry_.elevation_bin_of(column);
  slot = static_cast<std::size_t>((e % kTileSize) * kTileSize + (a % kTileSize));
  return static_cast<std::size_t>(e / kTileSize) * tiles_x_ + static_cast<std::size_t>(a / kTileSize);
}

const ColumnData* ColumnGrid::find(ColumnIndex column) const {
  std::size_t slot;
  const auto& tile = tiles_[tile_of(column, slot)];
  return tile ? &tile->columns[slot] : nullptr;
}

void ColumnGrid::prefetch_tile(ColumnIndex column) const {
  if (column >= changed_.size()) return;  // a hint: nothing to fetch outside the grid
  std::size_t slot;
  const Tile* tile = tiles_[tile_of(column, slot)].get();
  if (!tile) return;
  constexpr std::size_t kLine = 64;
  const char* records = reinterpret_cast<const char*>(tile->columns);
  for (std::size_t b = 0; b < sizeof tile->columns; b += kLine) __builtin_prefetch(records + b);
  const char* windows = reinterpret_cast<const char*>(tile->storage.data());
  for (std::size_t b = 0; b < tile->storage.size() * sizeof(float); b += kLine) __builtin_prefetch(windows + b);
}

ColumnGrid::Tile& ColumnGrid::allocated_tile(std::size_t tile_index) {
  auto& tile = tiles_[tile_index];
  if (!tile) tile = std::make_unique<Tile>();
  return *tile;
}

float ColumnGrid::log_odds(ColumnIndex column, int depth_bin) const {
  const ColumnData* c = find(column);
  return c ? c->value(depth_bin) : 0.0f;
}

double ColumnGrid::probability(ColumnIndex column, int depth_bin) const {
  return probability_from_logit(log_odds(column, depth_bin));
}

std::vector<ColumnIndex> ColumnGrid::take_changed_columns() {
  std::vector<ColumnIndex> out;
  const auto take = [&](std::size_t first, std::size_t end) {
    for (std::size_t i = first; i < end; ++i)
      if (changed_[i]) {
        out.push_back(static_cast<ColumnIndex>(i));
        changed_[i] = 0;
      }
  };
  // Eight flags at a time: a small shot changes a few percent of the columns, and a byte-by-byte scan of
  // all of them was ~2 % of a closed-loop round (bench_select_round).
  constexpr std::size_t kWord = sizeof(std::uint64_t);
  std::size_t i = 0;
  for (; i + kWord <= changed_.size(); i += kWord) {
    std::uint64_t flags;
    std::memcpy(&flags, changed_.data() + i, kWord);
    if (flags) take(i, i + kWord);
  }
  take(i, changed_.size());
  return out;
}

std::size_t ColumnGrid::touched_column_count() const {
  std::size_t n = 0;
  for (const auto& t : tiles_)
    if (t)
      for (const auto& c : t->columns) n += c.touched() ? 1 : 0;
  return n;
}

std::size_t ColumnGrid::stored_voxel_count() const {
  std::size_t n = 0;
  for (const auto& t : tiles_)
    if (t)
      for (const auto& c : t->columns) n += c.window.size() + (c.uniform_end > 0 ? 1 : 0);
  return n;
}

std::size_t ColumnGrid::memory_bytes() const {
  std::size_t n = tiles_.capacity() * sizeof(tiles_[0]) + changed_.capacity();
  for (const auto& t : tiles_)
    if (t) n += sizeof(Tile) + t->storage.capacity() * sizeof(float);
  return n;
}

std::size_t ColumnGrid::allocated_tile_count() const {
  std::size_t n = 0;
  for (const auto& t : tiles_) n += t ? 1 : 0;
  return n;
}

void ColumnGrid::clear() {
  for (auto& t : tiles_) t.reset();
  std::fill(changed_.begin(), changed_.end(), 0);
}

namespace {

// The contents with the leading values equal to the run's value joined to the run.
ColumnContents merge_leading_run(ColumnContents c) {
  if (c.uniform_end == 0) return c;
  std::uint32_t n = 0;
  while (n < c.count && c.values[n] == c.uniform_value) ++n;
  return {c.column, c.uniform_end + static_cast<std::int32_t>(n), c.uniform_value, c.values + n, c.count - n};
}

}  // namespace

void ColumnGrid::assign(const ColumnContents& contents) {
  std::size_t slot;
  const std::size_t tile_index = tile_of(contents.column, slot);
  write_tile(allocated_tile(tile_index), &contents, &slot, 1, Growth::column_by_column);
}

void ColumnGrid::store_windows(const ColumnContents* contents, std::size_t count) {
  if (count == 0) return;
  if (count > kTileColumns) throw InvalidInput("store_windows: " + std::to_string(count) + " columns for one tile");
  std::size_t slots[kTileColumns];
  const std::size_t tile_index = tile_of(contents[0].column, slots[0]);
  for (std::size_t i = 1; i < count; ++i)
    if (tile_of(contents[i].column, slots[i]) != tile_index)
      throw InvalidInput("store_windows: column " + std::to_string(contents[i].column) + " is not in the tile of column " +
                         std::to_string(contents[0].column));
  write_tile(allocated_tile(tile_index), contents, slots, count, Growth::insertion);
}

void ColumnGrid::store_windows(const ColumnContents* contents, const std::size_t* slots, std::size_t count) {
  if (count == 0) return;
  if (count > kTileColumns) throw InvalidInput("store_windows: " + std::to_string(count) + " columns for one tile");
  std::size_t first_slot;
  const std::size_t tile_index = tile_of(contents[0].column, first_slot);
  const auto width = static_cast<std::size_t>(geometry_.width());
  const auto at = [&](std::size_t slot) { return (slot / kTileSize) * width + slot % kTileSize; };
  // The tile's first column, which every column of it is a slot away from.
  const std::size_t origin = contents[0].column - at(first_slot);
  for (std::size_t i = 0; i < count; ++i)
    if (slots[i] >= kTileColumns || contents[i].column != origin + at(slots[i]))
      throw InvalidInput("store_windows: column " + std::to_string(contents[i].column) + " is not slot " +
                         std::to_string(slots[i]) + " of the tile of column " + std::to_string(contents[0].column));
  write_tile(allocated_tile(tile_index), contents, slots, count, Growth::insertion);
}

void ColumnGrid::write_tile(Tile& tile, const ColumnContents* contents, const std::size_t* slots, std::size_t count,
                            Growth growth) {
  ColumnContents merged[kTileColumns];
  std::size_t outgrowing = 0;  // room needed after the tile's windows: the windows that outgrow their place
  for (std::size_t i = 0; i < count; ++i) {
    merged[i] = merge_leading_run(contents[i]);
    if (merged[i].count > tile.columns[slots[i]].window.place_bins_) outgrowing += merged[i].count;
  }
  if (outgrowing > tile.storage.capacity() - tile.storage.size()) {
    // An eighth spare for a stored tile that outgrew its room, so that its next growth moves a window or
    // two rather than the whole tile (none on its first store); a quarter while building column by column.
    const std::size_t held = window_bins(tile);
    rebuild(tile, merged, slots, count, growth == Growth::insertion ? held / 8 : (held + outgrowing) / 4);
    return;
  }
  for (std::size_t i = 0; i < count; ++i) {
    const ColumnContents& c = merged[i];
    ColumnData& column = tile.columns[slots[i]];
    column.uniform_end = c.uniform_end;
    column.uniform_value = c.uniform_value;
    ColumnWindow& w = column.window;
    if (c.count > w.place_bins_) {  // after the windows, within the capacity: no window moves
      const std::size_t at = tile.storage.size();
      tile.storage.resize(at + c.count);
      w.data_ = tile.storage.data() + at;
      w.place_bins_ = c.count;
    }
    // memmove: assign's values may be a window of this tile (the written column's own included).
    if (c.count > 0) std::memmove(w.data_, c.values, c.count * sizeof(float));
    w.size_ = c.count;
  }
  // Windows that shrank keep their places: once over a quarter of the storage (and 16 bins) is spare, the
  // insertion trims it (a static view's windows narrow over its first frames).
  constexpr std::size_t kSpareBinsKept = 16;
  const std::size_t held = window_bins(tile);
  if (growth == Growth::insertion && tile.storage.capacity() > held + held / 4 + kSpareBinsKept)
    rebuild(tile, nullptr, nullptr, 0, 0);
}

std::size_t ColumnGrid::window_bins(const Tile& tile) {
  std::size_t bins = 0;
  for (const ColumnData& c : tile.columns) bins += c.window.size_;
  return bins;
}

// Every window of the tile back to back in new storage (the written ones from their merged contents), then
// `spare` bins of capacity, never beyond a full window per column: the worst case stays every voxel as a
// float (grid_worst_case_bytes).
void ColumnGrid::rebuild(Tile& tile, const ColumnContents* contents, const std::size_t* slots, std::size_t count,
                         std::size_t spare) const {
  ColumnContents next[kTileColumns];
  for (std::size_t s = 0; s < kTileColumns; ++s) {
    const ColumnData& c = tile.columns[s];
    next[s] = c.contents();
  }
  for (std::size_t i = 0; i < count; ++i) next[slots[i]] = contents[i];
  std::size_t live = 0;
  for (const ColumnContents& c : next) live += c.count;
  const std::size_t most = kTileColumns * static_cast<std::size_t>(geometry_.depth().bins());
  std::vector<float> storage;
  storage.reserve(std::max(live, std::min(live + spare, most)));
  for (std::size_t s = 0; s < kTileColumns; ++s) {
    ColumnData& column = tile.columns[s];
    column.uniform_end = next[s].uniform_end;
    column.uniform_value = next[s].uniform_value;
    column.window.data_ = storage.data() + storage.size();
    column.window.size_ = column.window.place_bins_ = next[s].count;
    storage.insert(storage.end(), next[s].values, next[s].values + next[s].count);
  }
  tile.storage.swap(storage);
}

void ColumnGrid::shrink_to_fit() {
  for (auto& t : tiles_)
    if (t && t->storage.capacity() > window_bins(*t)) rebuild(*t, nullptr, nullptr, 0, 0);
}

}  // namespace occ_improve
