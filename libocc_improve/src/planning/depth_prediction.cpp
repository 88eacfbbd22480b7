#include "occ_improve/planning/depth_prediction.hpp"
#include "planning/checked_triangulation.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <type_traits>

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

constexpr std::int32_t kFar = std::numeric_limits<std::int32_t>::max() / 2;  // no sample yet; + 1 never overflows

/// a where `take`, else b, by masks: the compiler makes a conditional a branch where it may (the row's
/// chain: unpredictable; the row's fold: not vectorized).
std::int32_t select_bits(bool take, std::int32_t a, std::int32_t b) {
  const std::int32_t mask = -static_cast<std::int32_t>(take);
  return (a & mask) | (b & ~mask);
}

/// One row of a distance-transform pass (`forward`: left to right under the row above; else right to left
/// over the row below) over distances d and depths z (a float's bits: integer selects). `next` holds the
/// row passed last, padded with a far pixel at each end (index x + 1 is pixel x). The sequential pass
/// relaxed each pixel from its current value, then the pixel just passed in the row, then the passed row's
/// pixels behind, beside and ahead of it, keeping the first strict minimum. The passed row is known before
/// the row starts, so it is folded first over the whole row into `keep` and `chain_below` (no dependency:
/// vectorized; __restrict, as the alias checks of seven arrays exceed the compiler's limit); only the chain
/// along the row stays sequential, one compare per pixel.
template <bool forward>
void relax_row(std::int32_t* d, std::int32_t* z, const std::int32_t* next_d, const std::int32_t* next_z, std::size_t W,
               std::int32_t* __restrict keep_d, std::int32_t* __restrict keep_z, std::int32_t* __restrict chain_below) {
  for (std::size_t x = 0; x < W; ++x) {
    const std::size_t behind = forward ? x : x + 2, ahead = forward ? x + 2 : x;
    const std::int32_t behind_d = next_d[behind], beside_d = next_d[x + 1], ahead_d = next_d[ahead];
    const std::int32_t behind_z = next_z[behind], beside_z = next_z[x + 1], ahead_z = next_z[ahead];
    const std::int32_t own_d = d[x], own_z = z[x];  // every load unconditional: selects, not branches
    const bool beside_first = beside_d < behind_d;
    const std::int32_t first_d = beside_first ? beside_d : behind_d, first_z = select_bits(beside_first, beside_z, behind_z);
    const bool ahead_first = ahead_d < first_d;
    const std::int32_t via_d = (ahead_first ? ahead_d : first_d) + 1, via_z = select_bits(ahead_first, ahead_z, first_z);
    // The pixel keeps the better of its own value and the passed row's (its own on a tie); the pixel just
    // passed wins when its distance + 1 beats its own value and does not lose to the passed row's.
    keep_z[x] = select_bits(via_d < own_d, via_z, own_z);
    keep_d[x] = std::min(via_d, own_d);
    chain_below[x] = std::min(own_d - 1, via_d);
  }
  std::int32_t last_d = kFar, last_z = 0;  // the pixel just passed (none at the row's start: never below the bound)
  for (std::size_t k = 0; k < W; ++k) {
    const std::size_t x = forward ? k : W - 1 - k;
    last_z = select_bits(last_d < chain_below[x], last_z, keep_z[x]);
    last_d = std::min(last_d + 1, keep_d[x]);  // the same as by the select, with a shorter chain
    d[x] = last_d;
    z[x] = last_z;
  }
}

std::int32_t float_bits(float f) {
  std::int32_t b;
  std::memcpy(&b, &f, sizeof b);
  return b;
}

float bits_float(std::int32_t b) {
  float f;
  std::memcpy(&f, &b, sizeof f);
  return f;
}

/// Chessboard distance to the nearest sample and that sample's depth, for every column, by the two-pass
/// distance transform (exact for the chessboard metric, a fraction of the breadth-first search's time); of
/// equidistant samples the first found by the passes wins. Beyond `radius`: distance -1, depth 0.
PredictedDepth distance_transform(const std::vector<float>& sparse, int w, int h, int radius) {
  const std::size_t n = sparse.size();
  PredictedDepth out{w, h, std::vector<float>(n), std::vector<std::int32_t>(n)};
  std::vector<std::int32_t> depth_bits(n);  // the nearest sample's depth, as a float's bits
  for (std::size_t c = 0; c < n; ++c) {
    const bool sample = sparse[c] > 0.0f;
    out.distance[c] = sample ? 0 : kFar;
    depth_bits[c] = sample ? float_bits(sparse[c]) : 0;
  }
  // Forward pass: left, up-left, up, up-right; backward pass: the mirror.
  const auto W = static_cast<std::size_t>(w);
  std::vector<std::int32_t> next_d(W + 2), next_z(W + 2), keep_d(W), keep_z(W), chain_below(W);
  const auto pass = [&](auto forward) {
    std::fill(next_d.begin(), next_d.end(), kFar);  // no row passed yet
    std::fill(next_z.begin(), next_z.end(), 0);
    for (int k = 0; k < h; ++k) {
      throw_if_stop_requested();
      const std::size_t row = static_cast<std::size_t>(forward ? k : h - 1 - k) * W;
      std::int32_t* d = out.distance.data() + row;
      relax_row<decltype(forward)::value>(d, depth_bits.data() + row, next_d.data(), next_z.data(), W, keep_d.data(),
                                           keep_z.data(), chain_below.data());
      std::copy(d, d + W, next_d.begin() + 1);
      std::copy(depth_bits.begin() + static_cast<std::ptrdiff_t>(row), depth_bits.begin() + static_cast<std::ptrdiff_t>(row + W),
                next_z.begin() + 1);
    }
  };
  pass(std::true_type{});
  pass(std::false_type{});
  std::int32_t* d = out.distance.data();
  float* depth = out.depth_m.data();
  for (std::size_t c = 0; c < n; ++c) {
    const bool near = d[c] <= radius;
    d[c] = select_bits(near, d[c], -1);
    depth[c] = bits_float(select_bits(near, depth_bits[c], 0));
  }
  return out;
}

/// Calls f(column, x, y, e0, e1, e2) for every pixel (x, y) inside triangle t or on its edges, e_i >= 0 being
/// twice the area of the sub-triangle opposite vertex i (barycentric weights x twice the area). The edge
/// functions step by one addition per pixel.
template <class F>
void for_each_pixel(const SampleTriangulation& s, std::size_t t, F&& f) {
  const auto& v = s.triangles[t];
  const int x0 = s.x(v[0]), y0 = s.y(v[0]), x1 = s.x(v[1]), y1 = s.y(v[1]), x2 = s.x(v[2]), y2 = s.y(v[2]);
  const int xmin = std::min({x0, x1, x2}), xmax = std::max({x0, x1, x2});
  const int ymin = std::min({y0, y1, y2}), ymax = std::max({y0, y1, y2});
  // e(a, b, p) = (bx - ax)(py - ay) - (by - ay)(px - ax): + (bx - ax) per row, - (by - ay) per column.
  const auto at = [](int ax, int ay, int bx, int by, int px, int py) {
    return static_cast<std::int64_t>(bx - ax) * (py - ay) - static_cast<std::int64_t>(by - ay) * (px - ax);
  };
  std::int64_t r0 = at(x1, y1, x2, y2, xmin, ymin), r1 = at(x2, y2, x0, y0, xmin, ymin), r2 = at(x0, y0, x1, y1, xmin, ymin);
  const std::int64_t sx0 = -(y2 - y1), sx1 = -(y0 - y2), sx2 = -(y1 - y0);
  const std::int64_t sy0 = x2 - x1, sy1 = x0 - x2, sy2 = x1 - x0;
  for (int y = ymin; y <= ymax; ++y, r0 += sy0, r1 += sy1, r2 += sy2) {
    std::int64_t e0 = r0, e1 = r1, e2 = r2;
    const std::size_t row = static_cast<std::size_t>(y) * static_cast<std::size_t>(s.width);
    bool entered = false;
    for (int x = xmin; x <= xmax; ++x, e0 += sx0, e1 += sx1, e2 += sx2) {
      if ((e0 | e1 | e2) >= 0) {  // all three non-negative
        f(row + static_cast<std::size_t>(x), x, y, e0, e1, e2);
        entered = true;
      } else if (entered) {
        break;  // a triangle's row is one run of pixels
      }
    }
  }
}

/// Interpolable triangles: barycentric in inverse depth. `open`: columns still to be written.
void interpolate(const SampleTriangulation& s, std::size_t t, PredictedDepth& out, std::vector<std::uint8_t>& open) {
  const auto& v = s.triangles[t];
  // Barycentric weights e_i / (2 area): pre-scale the vertices' inverse depths once per triangle.
  const double twice_area = 2.0 * s.area_px2(t);
  float w[3];
  for (int i = 0; i < 3; ++i)
    w[i] = static_cast<float>(1.0 / (twice_area * s.vertex_depth_m[static_cast<std::size_t>(v[static_cast<std::size_t>(i)])]));
  for_each_pixel(s, t, [&](std::size_t c, int, int, std::int64_t e0, std::int64_t e1, std::int64_t e2) {
    if (!open[c]) return;
    out.depth_m[c] = 1.0f / (static_cast<float>(e0) * w[0] + static_cast<float>(e1) * w[1] + static_cast<float>(e2) * w[2]);
    open[c] = 0;
  });
}

/// Triangles across a discontinuity: the nearest vertex, the nearer surface on a tie.
void nearest_vertex(const SampleTriangulation& s, std::size_t t, PredictedDepth& out, std::vector<std::uint8_t>& open) {
  const auto& v = s.triangles[t];
  for_each_pixel(s, t, [&](std::size_t c, int x, int y, std::int64_t, std::int64_t, std::int64_t) {
    if (!open[c]) return;
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
    open[c] = 0;
  });
}

/// The linear rule (header) on top of the distance transform's nearest samples, over a checked image.
void linear_fill(const std::vector<float>& sparse, const SensorModel& model, const DepthPredictionParams& params,
                 PredictedDepth& out) {
  TriangulationParams tp;
  tp.discontinuity_sigmas = params.discontinuity_sigmas;
  tp.max_edge_columns = std::max(1, 2 * params.radius_columns);
  const SampleTriangulation s = detail::triangulate_checked_samples(sparse, out.width, out.height, model, tp);
  std::vector<std::uint8_t> open(sparse.size());
  for (std::size_t c = 0; c < open.size(); ++c) open[c] = out.distance[c] > 0;  // predicted, not a sample
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    poll_stop(t, 1024);
    if (s.interpolable[t]) interpolate(s, t, out, open);
  }
  // Shared edges: an interpolable neighbour wrote them first, with the values of the two continuous ends.
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    poll_stop(t, 1024);
    if (!s.interpolable[t] && s.longest_edge_columns(t) <= tp.max_edge_columns) nearest_vertex(s, t, out, open);
  }
}

void check_surface(const SurfaceMap& surface) { require_shape("predict_depth: surface map", surface.shape()); }

}  // namespace

std::vector<float> sample_depth_image(const SurfaceMap& surface) {
  check_surface(surface);
  std::vector<float> image(surface.depth_m.size(), 0.0f);
  for (std::size_t c = 0; c < image.size(); ++c)
    if (is_depth_sample(surface, c)) image[c] = surface.depth_m[c];
  return image;
}

namespace {

// A sample deeper than the sensor model's own sigma there is no depth this sensor measured in metres:
// millimetres taken as metres (2000 m, sigma 5.7 km for a Kinect) made every triangle continuous and
// spread the values over the image. NaN and 0 are no samples (checked before).
void require_depths_in_metres(const std::vector<float>& depth, int width, const SensorModel& model) {
  std::size_t c = 0;
  for (std::size_t i = 1; i < depth.size(); ++i)
    if (depth[i] > depth[c] || !(depth[c] == depth[c])) c = i;  // NaN (no sample) never stays the deepest
  const float z = depth.empty() ? 0.0f : depth[c];
  if (!(z > 0.0f) || model.sigma_depth_at(z) < z) return;
  std::ostringstream m;
  m << "sparse depth image: pixel (" << c % static_cast<std::size_t>(width) << ", " << c / static_cast<std::size_t>(width)
    << ") holds depth " << z << " m, where the sensor's sigma is " << model.sigma_depth_at(z)
    << " m: not a depth in metres (millimetres?)";
  throw InvalidInput(m.str());
}

}  // namespace

PredictedDepth predict_dense_depth(const std::vector<float>& sparse_depth_m, int width, int height,
                                   const SensorModel& model, const DepthPredictionParams& params) {
  params.validate();
  check_sparse_depth_image(sparse_depth_m, width, height);
  require_depths_in_metres(sparse_depth_m, width, model);
  if (params.rule == DepthPredictionRule::nearest) return nearest_fill(sparse_depth_m, width, height, params.radius_columns);
  PredictedDepth out = distance_transform(sparse_depth_m, width, height, params.radius_columns);
  linear_fill(sparse_depth_m, model, params, out);
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
  require_shape("depth_agreement: prediction", predicted.shape(), "the reference surface map", reference.shape());
  DepthAgreement a;
  for (std::size_t c = 0; c < predicted.depth_m.size(); ++c) {
    if (!is_depth_sample(reference, c)) continue;
    ++a.reference_samples;
    const double z = reference.depth_m[c];
    if (predicted.distance[c] >= 0 && std::abs(predicted.depth_m[c] - z) <= sigmas * model.sigma_depth_at(z)) ++a.within;
  }
  return a;
}

}  // namespace occ_improve
