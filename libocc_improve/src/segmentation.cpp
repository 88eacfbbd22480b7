#include "occ_improve/segmentation.hpp"

#include "occ_improve/errors.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

namespace occ_improve {

using detail::require_parameter;

void SegmentationParams::validate() const {
  require_parameter(std::isfinite(contour_improvement_below) && contour_improvement_below < 0,
                    "contour_improvement_below", contour_improvement_below, "finite and < 0");
  require_parameter(min_segment_columns >= 1, "min_segment_columns", static_cast<double>(min_segment_columns), ">= 1");
  require_parameter(std::isfinite(plane_distance_m) && plane_distance_m > 0, "plane_distance_m", plane_distance_m,
                    "finite and > 0");
  require_parameter(plane_min_columns >= 3, "plane_min_columns", static_cast<double>(plane_min_columns), ">= 3");
  require_parameter(plane_ransac_iterations >= 1 && plane_ransac_iterations <= 100000, "plane_ransac_iterations",
                    plane_ransac_iterations, "in [1, 100000]");
}

SegmentationParams segmentation_defaults(const SensorPreset& preset) {
  SegmentationParams params;
  // With the paper's constant sigma_rho the band is shallow: a lower bar keeps the contours closed.
  if (preset.name == "kinect_v1_paper") params.contour_improvement_below = -0.01f;
  // Pixel-native surfaces lie along z with no range rings, within the Kinect's ~2-3 mm noise of a table at
  // 1-1.5 m: a 6 mm band keeps the objects' bottom rows out of the plane (mean F on mosd_learn 0.839 with
  // 6 mm against 0.818 with 10 mm; 0.83-0.84 anywhere in 4-7.5 mm: make segment-eval -plane_distance).
  if (preset.geometry.angular_binning == AngularBinning::pinhole) params.plane_distance_m = 0.006;
  return params;
}

namespace {

constexpr std::uint32_t kNone = 0;
constexpr std::uint32_t kUnassigned = std::numeric_limits<std::uint32_t>::max();

// The valid rays: a known, occupied surface inside the depth range.
std::vector<std::uint8_t> valid_rays(const SphericalGeometry& geometry, const SurfaceMap& surface) {
  std::vector<std::uint8_t> valid(surface.size(), 0);
  const int bins = geometry.depth().bins();
  for (std::size_t c = 0; c < surface.size(); ++c)
    valid[c] = !surface.unknown[c] && surface.bin[c] >= 0 && surface.bin[c] < bins && surface.depth_m[c] > 0 &&
               surface.probability[c] > 0.5f;
  return valid;
}

std::vector<Eigen::Vector3f> surface_points(const SphericalGeometry& geometry, const SurfaceMap& surface,
                                            const std::vector<std::uint8_t>& valid) {
  std::vector<Eigen::Vector3f> points(surface.size(), Eigen::Vector3f::Zero());
  for (int e = 0; e < geometry.height(); ++e)
    for (int a = 0; a < geometry.width(); ++a) {
      const ColumnIndex c = geometry.column(a, e);
      if (valid[c]) points[c] = geometry.point(a, e, surface.depth_m[c]).cast<float>();
    }
  return points;
}

// RANSAC for the plane with most inliers among the valid rays (scored on a subsample), refined by a
// least-squares fit to its inliers. Marks the inliers in `plane` and returns their count (0 when the best
// plane is smaller than params.plane_min_columns).
std::size_t find_dominant_plane(const std::vector<Eigen::Vector3f>& points, const std::vector<std::uint8_t>& valid,
                                const SegmentationParams& params, std::vector<std::uint8_t>& plane) {
  std::vector<std::uint32_t> candidates;
  for (std::size_t c = 0; c < valid.size(); ++c)
    if (valid[c]) candidates.push_back(static_cast<std::uint32_t>(c));
  if (candidates.size() < params.plane_min_columns) return 0;
  // A fixed stride keeps the scoring cost near 5,000 points whatever the image size.
  const std::size_t stride = std::max<std::size_t>(1, candidates.size() / 5000);
  std::uint64_t state = 0x9E3779B97F4A7C15ull ^ params.plane_seed;
  auto next_index = [&]() {  // splitmix64: deterministic and good enough for sampling
    state += 0x9E3779B97F4A7C15ull;
    std::uint64_t z = state;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return candidates[(z ^ (z >> 31)) % candidates.size()];
  };
  const float band = static_cast<float>(params.plane_distance_m);
  Eigen::Vector3f best_normal = Eigen::Vector3f::UnitZ();
  float best_offset = 0;
  std::size_t best_score = 0;
  for (int iteration = 0; iteration < params.plane_ransac_iterations; ++iteration) {
    const Eigen::Vector3f& p0 = points[next_index()];
    const Eigen::Vector3f& p1 = points[next_index()];
    const Eigen::Vector3f& p2 = points[next_index()];
    Eigen::Vector3f normal = (p1 - p0).cross(p2 - p0);
    const float norm = normal.norm();
    if (!(norm > 1e-9f)) continue;
    normal /= norm;
    const float offset = -normal.dot(p0);
    std::size_t score = 0;
    for (std::size_t i = 0; i < candidates.size(); i += stride)
      score += std::abs(normal.dot(points[candidates[i]]) + offset) < band;
    if (score > best_score) best_score = score, best_normal = normal, best_offset = offset;
  }
  if (best_score == 0) return 0;
  // Least-squares refinement on the inliers: the normal is the covariance's smallest eigenvector.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  std::size_t inliers = 0;
  for (std::uint32_t c : candidates)
    if (std::abs(best_normal.dot(points[c]) + best_offset) < band) {
      const Eigen::Vector3d p = points[c].cast<double>();
      mean += p;
      second += p * p.transpose();
      ++inliers;
    }
  if (inliers < params.plane_min_columns) return 0;
  mean /= static_cast<double>(inliers);
  const Eigen::Matrix3d covariance = second / static_cast<double>(inliers) - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3f normal = solver.eigenvectors().col(0).cast<float>();
  const float offset = -normal.dot(mean.cast<float>());
  std::size_t count = 0;
  for (std::uint32_t c : candidates)
    if (std::abs(normal.dot(points[c]) + offset) < band) plane[c] = 1, ++count;
  return count >= params.plane_min_columns ? count : 0;
}

// Labels 4-connected components of rays where `member` is set; returns each component's size
// (component k has label k + 1 in `label`).
std::vector<std::size_t> connected_components(const std::vector<std::uint8_t>& member, int width, int height,
                                              std::vector<std::uint32_t>& label) {
  std::vector<std::size_t> sizes;
  std::vector<std::uint32_t> stack;
  for (std::size_t seed = 0; seed < member.size(); ++seed) {
    if (!member[seed] || label[seed] != kUnassigned) continue;
    const auto id = static_cast<std::uint32_t>(sizes.size() + 1);
    std::size_t size = 0;
    stack.push_back(static_cast<std::uint32_t>(seed));
    label[seed] = id;
    while (!stack.empty()) {
      const std::uint32_t c = stack.back();
      stack.pop_back();
      ++size;
      const int a = static_cast<int>(c % static_cast<std::uint32_t>(width)), e = static_cast<int>(c / static_cast<std::uint32_t>(width));
      const std::array<std::pair<bool, std::uint32_t>, 4> neighbours{{{a > 0, c - 1},
                                                                      {a + 1 < width, c + 1},
                                                                      {e > 0, c - static_cast<std::uint32_t>(width)},
                                                                      {e + 1 < height, c + static_cast<std::uint32_t>(width)}}};
      for (const auto& [inside, n] : neighbours)
        if (inside && member[n] && label[n] == kUnassigned) label[n] = id, stack.push_back(n);
    }
    sizes.push_back(size);
  }
  return sizes;
}

// Grows the labelled rays into the valid unlabelled ones, one 4-neighbour ring per wave; each ray takes
// the label of its labelled neighbour closest in depth. Decisions of a wave only see the previous waves,
// so the result does not depend on scan order. Returns the number of rays attached.
std::size_t attach_to_closest_in_depth(const std::vector<std::uint8_t>& valid, const SurfaceMap& surface, int width,
                                       int height, std::vector<std::uint32_t>& label) {
  auto for_neighbours = [&](std::uint32_t c, auto&& visit) {
    const int a = static_cast<int>(c % static_cast<std::uint32_t>(width)), e = static_cast<int>(c / static_cast<std::uint32_t>(width));
    if (a > 0) visit(c - 1);
    if (a + 1 < width) visit(c + 1);
    if (e > 0) visit(c - static_cast<std::uint32_t>(width));
    if (e + 1 < height) visit(c + static_cast<std::uint32_t>(width));
  };
  std::vector<std::uint8_t> queued(label.size(), 0);
  std::vector<std::uint32_t> frontier;
  for (std::size_t c = 0; c < label.size(); ++c)
    if (valid[c] && label[c] == kUnassigned) {
      bool touches = false;
      for_neighbours(static_cast<std::uint32_t>(c), [&](std::uint32_t n) { touches |= label[n] != kUnassigned && label[n] != kNone; });
      if (touches) frontier.push_back(static_cast<std::uint32_t>(c)), queued[c] = 1;
    }
  std::size_t attached = 0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> decisions;
  while (!frontier.empty()) {
    decisions.clear();
    for (std::uint32_t c : frontier) {
      float best = std::numeric_limits<float>::infinity();
      std::uint32_t chosen = kUnassigned;
      for_neighbours(c, [&](std::uint32_t n) {
        if (label[n] == kUnassigned || label[n] == kNone) return;
        const float jump = std::abs(surface.depth_m[n] - surface.depth_m[c]);
        if (jump < best) best = jump, chosen = label[n];
      });
      decisions.emplace_back(c, chosen);
    }
    frontier.clear();
    for (const auto& [c, chosen] : decisions) label[c] = chosen;
    attached += decisions.size();
    for (const auto& [c, chosen] : decisions)
      for_neighbours(c, [&](std::uint32_t n) {
        if (valid[n] && label[n] == kUnassigned && !queued[n]) queued[n] = 1, frontier.push_back(n);
      });
  }
  return attached;
}

}  // namespace

Segmentation segment_improvement(const SphericalGeometry& geometry, const SurfaceMap& surface,
                                 const ImprovementMap& improvement, const SegmentationParams& params) {
  params.validate();
  const int width = geometry.width(), height = geometry.height();
  const std::size_t n = geometry.column_count();
  if (surface.width != width || surface.height != height || surface.size() != n || surface.unknown.size() != n ||
      surface.bin.size() != n || surface.probability.size() != n)
    throw InvalidInput("segment_improvement: the surface map does not match the grid geometry");
  if (improvement.width != width || improvement.height != height || improvement.value.size() != n)
    throw InvalidInput("segment_improvement: the improvement map does not match the grid geometry");

  Segmentation out;
  out.width = width;
  out.height = height;
  out.contour.assign(n, 0);
  std::vector<std::uint8_t> valid = valid_rays(geometry, surface);
  // Columns that are not observable (NaN: outside the camera or a mask) take no part, even where a
  // neighbour's measurement gave them a surface.
  for (std::size_t c = 0; c < n; ++c)
    if (std::isnan(improvement.value[c])) valid[c] = 0;
  std::vector<std::uint8_t> interior(n, 0);  // valid, not contour, not plane: where segments grow
  for (std::size_t c = 0; c < n; ++c) {
    if (!valid[c]) continue;
    ++out.valid_columns;
    out.contour[c] = improvement.value[c] < params.contour_improvement_below;
    out.contour_columns += out.contour[c];
    interior[c] = !out.contour[c];
  }

  const std::vector<Eigen::Vector3f> points = surface_points(geometry, surface, valid);
  std::vector<std::uint8_t> plane(n, 0);
  if (params.remove_dominant_plane) out.plane_columns = find_dominant_plane(points, valid, params, plane);
  if (out.plane_columns == 0) std::fill(plane.begin(), plane.end(), 0);

  // Working labels: kNone where no surface, kUnassigned where valid but not yet in a segment.
  std::vector<std::uint32_t> label(n, kUnassigned);
  for (std::size_t c = 0; c < n; ++c) {
    if (!valid[c]) label[c] = kNone;
    if (plane[c]) interior[c] = 0;
  }
  std::vector<std::size_t> sizes = connected_components(interior, width, height, label);
  // Regions too small to stand alone go back to the pool that is attached by depth.
  std::vector<std::uint32_t> kept(sizes.size() + 1, kUnassigned);
  std::uint32_t segments = 0;
  for (std::size_t k = 0; k < sizes.size(); ++k)
    if (sizes[k] >= params.min_segment_columns) kept[k + 1] = ++segments;
  const std::uint32_t plane_label = out.plane_columns > 0 ? ++segments : kUnassigned;
  for (std::size_t c = 0; c < n; ++c) {
    if (plane[c]) label[c] = plane_label;
    else if (label[c] != kNone && label[c] != kUnassigned) label[c] = kept[label[c]];
  }
  out.attached_columns = attach_to_closest_in_depth(valid, surface, width, height, label);
  // Valid regions no segment reached (islands between holes) become segments of their own.
  std::vector<std::uint8_t> islands(n, 0);
  for (std::size_t c = 0; c < n; ++c) islands[c] = label[c] == kUnassigned;
  std::vector<std::uint32_t> island_label(n, kUnassigned);
  const std::vector<std::size_t> island_sizes = connected_components(islands, width, height, island_label);
  for (std::size_t c = 0; c < n; ++c)
    if (islands[c]) label[c] = segments + island_label[c];
  segments += static_cast<std::uint32_t>(island_sizes.size());

  // Statistics, then labels renumbered by size (largest first) so label 1 is the largest segment.
  std::vector<Segment> stats(segments);
  std::vector<double> depth_sum(segments, 0.0);
  for (int e = 0; e < height; ++e)
    for (int a = 0; a < width; ++a) {
      const ColumnIndex c = geometry.column(a, e);
      if (label[c] == kNone) continue;
      Segment& s = stats[label[c] - 1];
      ++s.columns;
      s.centroid_m += points[c].cast<double>();
      depth_sum[label[c] - 1] += surface.depth_m[c];
    }
  std::vector<std::uint32_t> order(segments);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) { return stats[x].columns > stats[y].columns; });
  std::vector<std::uint32_t> renumber(segments + 1, kNone);
  for (std::uint32_t rank = 0; rank < segments; ++rank) {
    const std::uint32_t old = order[rank];
    if (stats[old].columns == 0) continue;  // a kept label can lose nothing, but stay safe
    Segment s = stats[old];
    s.label = static_cast<std::uint32_t>(out.segments.size() + 1);
    s.centroid_m /= static_cast<double>(s.columns);
    s.mean_depth_m = depth_sum[old] / static_cast<double>(s.columns);
    s.plane = old + 1 == plane_label;
    renumber[old + 1] = s.label;
    out.segments.push_back(s);
  }
  out.label.resize(n);
  for (std::size_t c = 0; c < n; ++c) out.label[c] = label[c] == kNone ? kNone : renumber[label[c]];
  return out;
}

std::array<std::uint8_t, 3> segment_colour(std::uint32_t label) {
  if (label == 0) return {0, 0, 0};
  // A multiplicative hash spreads consecutive labels over distinct, never-black colours.
  const std::uint32_t h = label * 2654435761u;
  return {static_cast<std::uint8_t>(64 + (h >> 24) % 192), static_cast<std::uint8_t>(64 + (h >> 16) % 192),
          static_cast<std::uint8_t>(64 + (h >> 8) % 192)};
}

Image render_segmentation(const Segmentation& segmentation) {
  Image image;
  image.width = segmentation.width;
  image.height = segmentation.height;
  image.channels = 3;
  image.pixels.assign(segmentation.label.size() * 3, 0);
  for (std::size_t c = 0; c < segmentation.label.size(); ++c) {
    const auto rgb = segment_colour(segmentation.label[c]);
    std::copy(rgb.begin(), rgb.end(), image.pixels.begin() + static_cast<std::ptrdiff_t>(3 * c));
  }
  return image;
}

Image render_contours(const Segmentation& segmentation) {
  Image image;
  image.width = segmentation.width;
  image.height = segmentation.height;
  image.channels = 1;
  image.pixels.assign(segmentation.label.size(), 0);
  for (std::size_t c = 0; c < segmentation.label.size(); ++c)
    image.pixels[c] = segmentation.contour[c] ? 255 : (segmentation.label[c] != 0 ? 96 : 0);
  return image;
}

}  // namespace occ_improve
