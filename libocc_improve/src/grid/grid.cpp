#include "occ_improve/grid/grid.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <algorithm>
#include <cmath>
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

ColumnData& ColumnGrid::touch(ColumnIndex column) {
  std::size_t slot;
  auto& tile = tiles_[tile_of(column, slot)];
  if (!tile) tile = std::make_unique<Tile>();
  return tile->columns[slot];
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
  for (std::size_t i = 0; i < changed_.size(); ++i)
    if (changed_[i]) {
      out.push_back(static_cast<ColumnIndex>(i));
      changed_[i] = 0;
    }
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
    if (t) {
      n += sizeof(Tile);
      for (const auto& c : t->columns) n += c.window.capacity() * sizeof(float);
    }
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

void ColumnGrid::compact(ColumnData& column) {
  if (column.uniform_end == 0) return;
  std::size_t n = 0;
  while (n < column.window.size() && column.window[n] == column.uniform_value) ++n;
  if (n == 0) return;
  column.window.erase(column.window.begin(), column.window.begin() + static_cast<std::ptrdiff_t>(n));
  column.uniform_end += static_cast<std::int32_t>(n);
}

}  // namespace occ_improve
