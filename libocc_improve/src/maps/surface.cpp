#include "occ_improve/maps/surface.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "support/parallel.hpp"

#include <algorithm>
#include <limits>

namespace occ_improve {

std::size_t SurfaceMap::known_count() const {
  return static_cast<std::size_t>(std::count(unknown.begin(), unknown.end(), std::uint8_t{0}));
}

namespace {
// Maximum of n floats with eight independent accumulators: a single running max is a serial dependency
// chain (one maxss per value); eight lanes let the compiler use packed max instructions.
float window_max(const float* v, std::size_t n) {
  constexpr std::size_t kLanes = 8;
  float lane[kLanes];
  for (float& l : lane) l = -std::numeric_limits<float>::infinity();
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes)
    for (std::size_t k = 0; k < kLanes; ++k) lane[k] = v[i + k] > lane[k] ? v[i + k] : lane[k];
  for (; i < n; ++i) lane[0] = v[i] > lane[0] ? v[i] : lane[0];
  float best = lane[0];
  for (std::size_t k = 1; k < kLanes; ++k) best = std::max(best, lane[k]);
  return best;
}

bool set_if_changed(SurfaceMap& surface, ColumnIndex column, const SurfaceVoxel& v) {
  if (v == surface.at(column)) return false;
  surface.set(column, v);
  return true;
}

}  // namespace

SurfaceVoxel column_surface(const ColumnContents& c, const ColumnGrid& grid) {
  SurfaceVoxel s;
  if (!c.touched()) return s;
  const DepthAxis& depth = grid.geometry().depth();
  const int bins = depth.bins();
  const int uniform_end = std::min<int>(c.uniform_end, bins);
  const int window_end = std::min<int>(c.window_end(), bins);

  // Largest value over the uniform run, the window and the untouched tail (log-odds 0).
  float best = window_max(c.values, static_cast<std::size_t>(window_end - uniform_end));
  if (uniform_end > 0) best = std::max(best, c.uniform_value);
  if (window_end < bins) best = std::max(best, 0.0f);

  // The nearest run of bins within the tie tolerance of it, walked segment by segment so the uniform run
  // and the tail cost O(1).
  const float floor_value = best - kSurfaceTieTolerance;
  const auto window_at = [&](int b) { return c.values[b - c.uniform_end]; };
  int first = window_end;  // the tail, unless the uniform run or a window bin comes first
  if (uniform_end > 0 && c.uniform_value >= floor_value) {
    first = 0;
  } else {
    for (int b = uniform_end; b < window_end; ++b)
      if (window_at(b) >= floor_value) {
        first = b;
        break;
      }
  }
  int last = std::max(first, uniform_end - 1);  // a run starting in the uniform run spans all of it
  while (last + 1 < window_end && window_at(last + 1) >= floor_value) ++last;
  if (last + 1 >= window_end && window_end < bins && 0.0f >= floor_value) last = bins - 1;

  s.unknown = false;
  if (first == 0 && last == bins - 1) {  // every bin holds the same value
    s.bin = bins;
    s.depth_m = static_cast<float>(depth.max());
    s.probability = static_cast<float>(probability_from_logit(best));
    return s;
  }
  if (last == bins - 1 && best < -kSurfaceTieTolerance) {  // rising to a peak beyond the grid
    s.bin = bins;
    s.depth_m = static_cast<float>(depth.max());
    s.probability = static_cast<float>(probability_from_logit(c.value(0)));
    return s;
  }
  if (grid.clamped() && best >= grid.log_odds_max()) {  // saturated peak: centre of the run
    s.bin = (first + last) / 2;
    s.depth_m = static_cast<float>(0.5 * (depth.centre(first) + depth.centre(last)));
  } else {
    s.bin = first;
    s.depth_m = static_cast<float>(depth.centre(first));
  }
  s.probability = static_cast<float>(probability_from_logit(c.value(s.bin)));
  return s;
}

SurfaceVoxel column_surface(const ColumnData* c, const ColumnGrid& grid) {
  return c == nullptr ? SurfaceVoxel{} : column_surface(c->contents(), grid);
}

bool refresh_column_surface(const ColumnGrid& grid, ColumnIndex column, const ColumnData* data, SurfaceMap& surface) {
  return set_if_changed(surface, column, column_surface(data, grid));
}

bool detail::refresh_written_column_surface(const ColumnGrid& grid, const ColumnContents& written, SurfaceMap& surface) {
  return set_if_changed(surface, written.column, column_surface(written, grid));
}

SurfaceMap compute_surface(const ColumnGrid& grid, int threads) {
  const GridGeometry& g = grid.geometry();
  SurfaceMap m;
  m.width = g.width();
  m.height = g.height();
  const std::size_t n = g.column_count();
  m.depth_m.assign(n, 0.0f);
  m.probability.assign(n, 0.5f);
  m.bin.assign(n, -1);
  m.unknown.assign(n, 1);
  if (grid.allocated_tile_count() == 0) return m;  // a fresh grid: every column unknown, nothing to look up
  detail::run_parts(detail::resolve_thread_count(threads), [&](int part, int parts) {
    GridAccessor access(grid);
    const std::size_t begin = n * static_cast<std::size_t>(part) / static_cast<std::size_t>(parts);
    const std::size_t end = n * static_cast<std::size_t>(part + 1) / static_cast<std::size_t>(parts);
    for (std::size_t i = begin; i < end; ++i) {
      poll_stop(i);
      const ColumnData* c = access.find(static_cast<ColumnIndex>(i));
      if (c && c->touched()) m.set(i, column_surface(c, grid));
    }
  });
  return m;
}

std::vector<ColumnIndex> update_surface(const ColumnGrid& grid, const std::vector<ColumnIndex>& columns,
                                        SurfaceMap& surface, int threads) {
  const int parts = std::max(1, std::min(detail::resolve_thread_count(threads),
                                         static_cast<int>(columns.size() / 4096) + 1));
  std::vector<std::vector<ColumnIndex>> changed(static_cast<std::size_t>(parts));
  detail::run_parts(parts, [&](int part, int n) {
    const std::size_t begin = columns.size() * static_cast<std::size_t>(part) / static_cast<std::size_t>(n);
    const std::size_t end = columns.size() * static_cast<std::size_t>(part + 1) / static_cast<std::size_t>(n);
    for (std::size_t i = begin; i < end; ++i) {
      poll_stop(i);
      const ColumnIndex c = columns[i];
      // Distinct columns: no two parts write the same entry.
      if (refresh_column_surface(grid, c, grid.find(c), surface)) changed[static_cast<std::size_t>(part)].push_back(c);
    }
  });
  std::vector<ColumnIndex> out = std::move(changed[0]);
  for (std::size_t p = 1; p < changed.size(); ++p) out.insert(out.end(), changed[p].begin(), changed[p].end());
  return out;
}

}  // namespace occ_improve
