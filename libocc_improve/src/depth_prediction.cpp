#include "occ_improve/depth_prediction.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace occ_improve {

void DepthPredictionParams::validate() const {
  detail::require_parameter(radius_columns >= 0, "radius_columns", radius_columns, ">= 0");
  detail::require_parameter(rule == DepthPredictionRule::nearest || rule == DepthPredictionRule::linear, "rule",
                            static_cast<double>(rule), "nearest (0) or linear (1)");
  detail::require_parameter(discontinuity_sigmas > 0, "discontinuity_sigmas", discontinuity_sigmas, "> 0");
}

namespace {

/// The nearest rule (header) over a checked sparse image.
PredictedDepth nearest_fill(const std::vector<float>& sparse, int w, int h, int radius) {
  const std::size_t n = sparse.size();
  PredictedDepth out{w, h, std::vector<float>(n, 0.0f), std::vector<std::int32_t>(n, -1)};
  std::vector<ColumnIndex> queue;  // breadth-first: the front is every column at the current distance
  queue.reserve(n);
  for (std::size_t c = 0; c < n; ++c)
    if (sparse[c] > 0.0f) {
      out.depth_m[c] = sparse[c];
      out.distance[c] = 0;
      queue.push_back(static_cast<ColumnIndex>(c));
    }
  for (std::size_t head = 0; head < queue.size(); ++head) {
    poll_stop(head);
    const ColumnIndex c = queue[head];
    const std::int32_t next = out.distance[c] + 1;
    if (next > radius) break;  // the queue is in distance order: nothing nearer is left
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

/// Calls f(column, e0, e1, e2) for every pixel inside triangle t or on its edges, e_i >= 0 being twice the
/// area of the sub-triangle opposite vertex i (barycentric weights x twice the area).
template <class F>
void for_each_pixel(const SampleTriangulation& s, std::size_t t, F&& f) {
  const auto& v = s.triangles[t];
  const int x0 = s.x(v[0]), y0 = s.y(v[0]), x1 = s.x(v[1]), y1 = s.y(v[1]), x2 = s.x(v[2]), y2 = s.y(v[2]);
  const auto edge = [](int ax, int ay, int bx, int by, int px, int py) {
    return static_cast<std::int64_t>(bx - ax) * (py - ay) - static_cast<std::int64_t>(by - ay) * (px - ax);
  };
  for (int y = std::min({y0, y1, y2}); y <= std::max({y0, y1, y2}); ++y)
    for (int x = std::min({x0, x1, x2}); x <= std::max({x0, x1, x2}); ++x) {
      const std::int64_t e0 = edge(x1, y1, x2, y2, x, y), e1 = edge(x2, y2, x0, y0, x, y), e2 = edge(x0, y0, x1, y1, x, y);
      if (e0 >= 0 && e1 >= 0 && e2 >= 0)
        f(static_cast<std::size_t>(y) * static_cast<std::size_t>(s.width) + static_cast<std::size_t>(x), e0, e1, e2);
    }
}

/// Whether column c may take a value from a triangle: predicted by the nearest rule, not a sample, not
/// yet written by another triangle.
bool open_column(const PredictedDepth& out, const std::vector<std::uint8_t>& written, std::size_t c) {
  return out.distance[c] > 0 && !written[c];
}

/// Interpolable triangles: barycentric in inverse depth.
void interpolate(const SampleTriangulation& s, std::size_t t, PredictedDepth& out, std::vector<std::uint8_t>& written) {
  const auto& v = s.triangles[t];
  double w[3];
  for (int i = 0; i < 3; ++i) w[i] = 1.0 / s.vertex_depth_m[static_cast<std::size_t>(v[static_cast<std::size_t>(i)])];
  for_each_pixel(s, t, [&](std::size_t c, std::int64_t e0, std::int64_t e1, std::int64_t e2) {
    if (!open_column(out, written, c)) return;
    const double sum = static_cast<double>(e0 + e1 + e2);  // twice the area
    out.depth_m[c] = static_cast<float>(sum / (static_cast<double>(e0) * w[0] + static_cast<double>(e1) * w[1] +
                                               static_cast<double>(e2) * w[2]));
    written[c] = 1;
  });
}

/// Triangles across a discontinuity: the nearest vertex, the nearer surface on a tie.
void nearest_vertex(const SampleTriangulation& s, std::size_t t, PredictedDepth& out, std::vector<std::uint8_t>& written) {
  const auto& v = s.triangles[t];
  for_each_pixel(s, t, [&](std::size_t c, std::int64_t, std::int64_t, std::int64_t) {
    if (!open_column(out, written, c)) return;
    const int x = static_cast<int>(c % static_cast<std::size_t>(s.width)), y = static_cast<int>(c / static_cast<std::size_t>(s.width));
    long best_d2 = -1;
    float best_z = 0.0f;
    for (const std::int32_t i : v) {
      const long dx = s.x(i) - x, dy = s.y(i) - y, d2 = dx * dx + dy * dy;
      const float z = s.vertex_depth_m[static_cast<std::size_t>(i)];
      if (best_d2 < 0 || d2 < best_d2 || (d2 == best_d2 && z < best_z)) {
        best_d2 = d2;
        best_z = z;
      }
    }
    out.depth_m[c] = best_z;
    written[c] = 1;
  });
}

/// The linear rule (header) on top of the nearest rule's result.
void linear_fill(const std::vector<float>& sparse, const SensorModel& model, const DepthPredictionParams& params,
                 PredictedDepth& out) {
  TriangulationParams tp;
  tp.discontinuity_sigmas = params.discontinuity_sigmas;
  tp.max_edge_columns = std::max(1, 2 * params.radius_columns);
  const SampleTriangulation s = triangulate_samples(sparse, out.width, out.height, model, tp);
  std::vector<std::uint8_t> written(sparse.size(), 0);
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    poll_stop(t, 1024);
    if (s.interpolable[t]) interpolate(s, t, out, written);
  }
  // Shared edges: an interpolable neighbour wrote them first, with the values of the two continuous ends.
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    poll_stop(t, 1024);
    if (!s.interpolable[t] && s.longest_edge_columns(t) <= tp.max_edge_columns) nearest_vertex(s, t, out, written);
  }
}

void check_surface(const SurfaceMap& surface) {
  const std::size_t n = static_cast<std::size_t>(surface.width) * static_cast<std::size_t>(surface.height);
  if (surface.depth_m.size() != n || surface.probability.size() != n || surface.unknown.size() != n)
    throw InvalidInput("predict_depth: surface arrays do not hold " + std::to_string(surface.width) + " x " +
                       std::to_string(surface.height) + " values");
}

}  // namespace

std::vector<float> sample_depth_image(const SurfaceMap& surface) {
  check_surface(surface);
  std::vector<float> image(surface.depth_m.size(), 0.0f);
  for (std::size_t c = 0; c < image.size(); ++c)
    if (is_depth_sample(surface, c)) image[c] = surface.depth_m[c];
  return image;
}

PredictedDepth predict_dense_depth(const std::vector<float>& sparse_depth_m, int width, int height,
                                   const SensorModel& model, const DepthPredictionParams& params) {
  params.validate();
  check_sparse_depth_image(sparse_depth_m, width, height);
  PredictedDepth out = nearest_fill(sparse_depth_m, width, height, params.radius_columns);
  if (params.rule == DepthPredictionRule::linear) linear_fill(sparse_depth_m, model, params, out);
  return out;
}

PredictedDepth predict_depth(const SurfaceMap& surface, const SensorModel& model, const DepthPredictionParams& params) {
  params.validate();
  return predict_dense_depth(sample_depth_image(surface), surface.width, surface.height, model, params);
}

PredictedDepth predict_depth(const SurfaceMap& surface, const DepthPredictionParams& params) {
  params.validate();
  if (params.rule != DepthPredictionRule::nearest)
    throw InvalidParameter("predict_depth: rule = linear needs the sensor model (call the overload with a SensorModel)");
  check_surface(surface);
  if (surface.width <= 0 || surface.height <= 0)  // an empty surface predicts nothing
    return PredictedDepth{surface.width, surface.height, {}, {}};
  const std::vector<float> image = sample_depth_image(surface);
  return nearest_fill(image, surface.width, surface.height, params.radius_columns);
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
