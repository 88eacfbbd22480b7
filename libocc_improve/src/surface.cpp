#include "occ_improve/surface.hpp"

#include "occ_improve/sensor_model.hpp"

#include <algorithm>
#include <limits>

namespace occ_improve {

std::size_t SurfaceMap::known_count() const {
  return static_cast<std::size_t>(std::count(unknown.begin(), unknown.end(), std::uint8_t{0}));
}

SurfaceVoxel column_surface(const ColumnData* c, const SphericalGrid& grid) {
  SurfaceVoxel s;
  if (c == nullptr || !c->touched()) return s;
  const DepthAxis& depth = grid.geometry().depth();
  const int bins = depth.bins();
  const int uniform_end = std::min<int>(c->uniform_end, bins);
  const int window_end = std::min<int>(c->window_end(), bins);

  // Largest value over the uniform run, the window and the untouched tail (log-odds 0).
  float best = -std::numeric_limits<float>::infinity();
  if (uniform_end > 0) best = c->uniform_value;
  for (int b = uniform_end; b < window_end; ++b) best = std::max(best, c->window[static_cast<std::size_t>(b - c->uniform_end)]);
  if (window_end < bins) best = std::max(best, 0.0f);

  // The nearest run of bins within the tie tolerance of it, walked segment by segment so the uniform run
  // and the tail cost O(1).
  const float floor_value = best - kSurfaceTieTolerance;
  const auto window_at = [&](int b) { return c->window[static_cast<std::size_t>(b - c->uniform_end)]; };
  int first = window_end;  // the tail, unless the uniform run or a window bin comes first
  if (uniform_end > 0 && c->uniform_value >= floor_value) {
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
  if (grid.clamped() && best >= grid.log_odds_max()) {  // saturated peak: centre of the run
    s.bin = (first + last) / 2;
    s.depth_m = static_cast<float>(0.5 * (depth.centre(first) + depth.centre(last)));
  } else {
    s.bin = first;
    s.depth_m = static_cast<float>(depth.centre(first));
  }
  s.probability = static_cast<float>(probability_from_logit(c->value(s.bin)));
  return s;
}

namespace {
void store(SurfaceMap& m, std::size_t i, const SurfaceVoxel& v) {
  m.depth_m[i] = v.depth_m;
  m.probability[i] = v.probability;
  m.bin[i] = v.bin;
  m.unknown[i] = v.unknown ? 1 : 0;
}
SurfaceVoxel load(const SurfaceMap& m, std::size_t i) {
  return {m.depth_m[i], m.probability[i], m.bin[i], m.unknown[i] != 0};
}
}  // namespace

SurfaceMap compute_surface(const SphericalGrid& grid) {
  const SphericalGeometry& g = grid.geometry();
  SurfaceMap m;
  m.width = g.width();
  m.height = g.height();
  const std::size_t n = g.column_count();
  m.depth_m.assign(n, 0.0f);
  m.probability.assign(n, 0.5f);
  m.bin.assign(n, -1);
  m.unknown.assign(n, 1);
  GridAccessor access(grid);
  for (std::size_t i = 0; i < n; ++i) {
    const ColumnData* c = access.find(static_cast<ColumnIndex>(i));
    if (c && c->touched()) store(m, i, column_surface(c, grid));
  }
  return m;
}

std::vector<ColumnIndex> update_surface(const SphericalGrid& grid, const std::vector<ColumnIndex>& columns,
                                        SurfaceMap& surface) {
  std::vector<ColumnIndex> changed;
  for (ColumnIndex c : columns) {
    const SurfaceVoxel v = column_surface(grid.find(c), grid);
    if (!(v == load(surface, c))) {
      store(surface, c, v);
      changed.push_back(c);
    }
  }
  return changed;
}

}  // namespace occ_improve
