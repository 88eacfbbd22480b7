#include "occ_improve/depth_prediction.hpp"

#include "occ_improve/errors.hpp"

#include <string>

namespace occ_improve {

void DepthPredictionParams::validate() const {
  detail::require_parameter(radius_columns >= 0, "radius_columns", radius_columns, ">= 0");
}

PredictedDepth predict_depth(const SurfaceMap& surface, const DepthPredictionParams& params) {
  params.validate();
  const std::size_t n = static_cast<std::size_t>(surface.width) * static_cast<std::size_t>(surface.height);
  if (surface.depth_m.size() != n || surface.probability.size() != n || surface.unknown.size() != n)
    throw InvalidInput("predict_depth: surface arrays do not hold " + std::to_string(surface.width) + " x " +
                       std::to_string(surface.height) + " values");
  PredictedDepth out{surface.width, surface.height, std::vector<float>(n, 0.0f), std::vector<std::int32_t>(n, -1)};
  std::vector<ColumnIndex> queue;  // breadth-first: the front is every column at the current distance
  queue.reserve(n);
  for (std::size_t c = 0; c < n; ++c)
    if (is_depth_sample(surface, c)) {
      out.depth_m[c] = surface.depth_m[c];
      out.distance[c] = 0;
      queue.push_back(static_cast<ColumnIndex>(c));
    }
  const int w = surface.width, h = surface.height;
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const ColumnIndex c = queue[head];
    const std::int32_t next = out.distance[c] + 1;
    if (next > params.radius_columns) break;  // the queue is in distance order: nothing nearer is left
    const int x = static_cast<int>(c % static_cast<ColumnIndex>(w)), y = static_cast<int>(c / static_cast<ColumnIndex>(w));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int xx = x + dx, yy = y + dy;
        if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
        const std::size_t o = static_cast<std::size_t>(yy) * static_cast<std::size_t>(w) + static_cast<std::size_t>(xx);
        if (out.distance[o] >= 0) continue;
        out.distance[o] = next;
        out.depth_m[o] = out.depth_m[c];
        queue.push_back(static_cast<ColumnIndex>(o));
      }
  }
  return out;
}

}  // namespace occ_improve
