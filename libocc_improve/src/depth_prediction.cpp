#include "occ_improve/depth_prediction.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"

#include <cmath>
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
    poll_stop(head);
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

DepthAgreement depth_agreement(const SurfaceMap& reference, const PredictedDepth& predicted, const SensorModel& model,
                               double sigmas) {
  detail::require_parameter(sigmas > 0, "sigmas", sigmas, "> 0");
  const std::size_t n = static_cast<std::size_t>(reference.width) * static_cast<std::size_t>(reference.height);
  if (predicted.width != reference.width || predicted.height != reference.height || predicted.depth_m.size() != n ||
      predicted.distance.size() != n || reference.depth_m.size() != n)
    throw InvalidInput("depth_agreement: prediction of " + std::to_string(predicted.width) + " x " +
                       std::to_string(predicted.height) + " columns against a reference of " +
                       std::to_string(reference.width) + " x " + std::to_string(reference.height));
  DepthAgreement a;
  for (std::size_t c = 0; c < n; ++c) {
    if (!is_depth_sample(reference, c)) continue;
    ++a.reference_samples;
    const double z = reference.depth_m[c];
    if (predicted.distance[c] >= 0 && std::abs(predicted.depth_m[c] - z) <= sigmas * model.sigma_depth_at(z)) ++a.within;
  }
  return a;
}

}  // namespace occ_improve
