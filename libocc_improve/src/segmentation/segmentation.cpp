#include "occ_improve/segmentation/segmentation.hpp"

#include "occ_improve/cancel.hpp"
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
  require_parameter(std::isfinite(crease_arm_m) && crease_arm_m > 0 && crease_arm_m <= 1, "crease_arm_m", crease_arm_m,
                    "in (0, 1]");
  require_parameter(std::isfinite(crease_smoothing_share) && crease_smoothing_share >= 0 && crease_smoothing_share <= 1,
                    "crease_smoothing_share", crease_smoothing_share, "in [0, 1]");
  require_parameter(std::isfinite(crease_min_bend_deg) && crease_min_bend_deg > 0 && crease_min_bend_deg < 180,
                    "crease_min_bend_deg", crease_min_bend_deg, "in (0, 180)");
  require_parameter(std::isfinite(crease_min_view_angle_deg) && crease_min_view_angle_deg >= 0 &&
                        crease_min_view_angle_deg < 90,
                    "crease_min_view_angle_deg", crease_min_view_angle_deg, "in [0, 90)");
  require_parameter(crease_max_arm_px >= 2 && crease_max_arm_px <= 256, "crease_max_arm_px", crease_max_arm_px,
                    "in [2, 256]");
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
std::vector<std::uint8_t> valid_rays(const GridGeometry& geometry, const SurfaceMap& surface) {
  std::vector<std::uint8_t> valid(surface.size(), 0);
  const int bins = geometry.depth().bins();
  for (std::size_t c = 0; c < surface.size(); ++c)
    valid[c] = !surface.unknown[c] && surface.bin[c] >= 0 && surface.bin[c] < bins && surface.depth_m[c] > 0 &&
               surface.probability[c] > 0.5f;
  return valid;
}

std::vector<Eigen::Vector3f> surface_points(const GridGeometry& geometry, const SurfaceMap& surface,
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
  // The scoring subsample copied into one contiguous block: it stays in cache over all iterations.
  std::vector<Eigen::Vector3f> sample;
  sample.reserve(candidates.size() / stride + 1);
  for (std::size_t i = 0; i < candidates.size(); i += stride) sample.push_back(points[candidates[i]]);
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
    for (const Eigen::Vector3f& p : sample) score += std::abs(normal.dot(p) + offset) < band;
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

// Summed-area tables of the surface points over the member rays, so a ray's neighbourhood mean costs four
// look-ups whatever its radius (which follows the ray's depth). Only member rays (valid, not contour, not plane) are
// summed, so a mean never mixes the two sides of a depth step.
class PointMeans {
public:
  PointMeans(const std::vector<Eigen::Vector3f>& points, const std::vector<std::uint8_t>& member, int width, int height) {
    // The tables cover only the box around the member rays (the objects, a fraction of a table-top frame).
    int a_min = width, a_max = -1, e_min = height, e_max = -1;
    for (int e = 0; e < height; ++e)
      for (int a = 0; a < width; ++a)
        if (member[static_cast<std::size_t>(e) * width + a])
          a_min = std::min(a_min, a), a_max = std::max(a_max, a), e_min = std::min(e_min, e), e_max = std::max(e_max, e);
    if (a_max < 0) return;
    a0_ = a_min, e0_ = e_min, width_ = a_max - a_min + 1, height_ = e_max - e_min + 1;
    sum_.assign(static_cast<std::size_t>(width_ + 1) * (height_ + 1), Eigen::Vector4d::Zero());
    for (int e = 0; e < height_; ++e) {
      Eigen::Vector4d row = Eigen::Vector4d::Zero();
      for (int a = 0; a < width_; ++a) {
        const std::size_t c = static_cast<std::size_t>(e + e0_) * width + a + a0_;
        if (member[c]) row += Eigen::Vector4d(points[c].x(), points[c].y(), points[c].z(), 1.0);
        at(a + 1, e + 1) = at(a + 1, e) + row;
      }
    }
  }
  /// Mean of the member points in the square of radius r around (a, e) (zero when it holds none).
  Eigen::Vector3f mean(int a, int e, int r) const {
    if (sum_.empty()) return Eigen::Vector3f::Zero();
    const int a0 = std::clamp(a - r - a0_, 0, width_), a1 = std::clamp(a + r + 1 - a0_, 0, width_);
    const int e0 = std::clamp(e - r - e0_, 0, height_), e1 = std::clamp(e + r + 1 - e0_, 0, height_);
    const Eigen::Vector4d s = at(a1, e1) - at(a0, e1) - at(a1, e0) + at(a0, e0);
    return (s.head<3>() / std::max(s.w(), 1.0)).cast<float>();
  }

private:
  Eigen::Vector4d& at(int a, int e) { return sum_[static_cast<std::size_t>(e) * (width_ + 1) + a]; }
  const Eigen::Vector4d& at(int a, int e) const { return sum_[static_cast<std::size_t>(e) * (width_ + 1) + a]; }
  int a0_ = 0, e0_ = 0, width_ = 0, height_ = 0;  // the member rays' bounding box
  std::vector<Eigen::Vector4d> sum_;
};

// The angle between the rays of two neighbouring columns at the image centre: converts the crease arm
// from metres on the surface to pixels.
double column_angle_rad(const GridGeometry& geometry) {
  const int a = std::max(0, geometry.width() / 2 - 1), e = geometry.height() / 2;
  if (geometry.width() < 2) return 1.0;
  const double cosine = geometry.direction(a, e).dot(geometry.direction(a + 1, e));
  return std::acos(std::clamp(cosine, -1.0, 1.0));
}

// The crease arm in pixels at a ray of the given range (step 3), and the smoothing radius that goes with it.
struct ArmPixels {
  int arm = 2, radius = 1;
};
ArmPixels arm_pixels(double range_m, double pixel_rad, const SegmentationParams& params) {
  ArmPixels out;
  out.arm = std::clamp(static_cast<int>(std::lround(params.crease_arm_m / (range_m * pixel_rad))), 2,
                       params.crease_max_arm_px);
  out.radius = static_cast<int>(std::lround(params.crease_smoothing_share * out.arm));
  return out;
}

// A section bends wherever one arm reaches across the crease, so crease rays form a band up to an arm wide
// on either side of it: wide enough to close around a box where a thin ridge breaks up in the noise (a
// ridge-only crease, tried, leaves gaps through which the boxes join again). The attachment by depth then
// splits the band along its middle.
//
// Concave creases (step 3 of the header): at each member ray (valid, not contour, not plane), the
// smoothed surface points an arm to either side in 4 image directions; the ray is a crease ray when, in
// any direction, the section bends by at least the minimum angle and its chord passes between the ray's
// point and the sensor (concave; a convex edge's chord passes behind the point). A section is skipped
// where it crosses a hole or the removed plane (the table's edge is the plane's business) or where an arm
// runs nearly along the line of sight: that is a depth step, not a crease between two faces both seen.
// Contour rays may lie on the section: the improvement's band often lines a crease too. The tests run
// cheapest and most selective first: most rays lie on flat faces and fail the bend at once.
std::vector<std::uint8_t> concave_creases(const GridGeometry& geometry, const std::vector<Eigen::Vector3f>& points,
                                          const PointMeans& means, const std::vector<std::uint8_t>& member,
                                          const std::vector<std::uint8_t>& passable, const SegmentationParams& params) {
  const int width = geometry.width(), height = geometry.height();
  std::vector<std::uint8_t> crease(member.size(), 0);
  const double pixel_rad = column_angle_rad(geometry);
  const float max_cosine = static_cast<float>(std::cos(M_PI - params.crease_min_bend_deg * M_PI / 180.0));
  const float step_cosine = static_cast<float>(std::cos(params.crease_min_view_angle_deg * M_PI / 180.0));
  constexpr std::array<std::array<int, 2>, 4> kDirections{{{1, 0}, {0, 1}, {1, 1}, {-1, 1}}};
  auto ray = [&](int a, int e) { return static_cast<std::size_t>(e) * width + a; };
  // Every ray of the section passable: it crosses no hole and not the plane. Checked last, on folds only.
  auto passable_section = [&](int a0, int e0, int du, int dv, int steps) {
    for (int k = 0; k <= steps; ++k)
      if (!passable[ray(a0 + k * du, e0 + k * dv)]) return false;
    return true;
  };
  auto folds = [&](int a, int e) {
    const auto [arm, radius] = arm_pixels(points[ray(a, e)].norm(), pixel_rad, params);
    const Eigen::Vector3f centre = means.mean(a, e, radius);
    const float centre_range = centre.norm();
    for (const auto& [du, dv] : kDirections) {
      // Diagonal steps are sqrt(2) longer: fewer of them for the same arm.
      const int steps = du != 0 && dv != 0 ? std::max(1, static_cast<int>(std::lround(arm / std::sqrt(2.0)))) : arm;
      const int a0 = a - du * steps, e0 = e - dv * steps, a1 = a + du * steps, e1 = e + dv * steps;
      if (std::min(a0, a1) < 0 || std::max(a0, a1) >= width || e0 < 0 || e1 >= height) continue;
      if (!member[ray(a0, e0)] || !member[ray(a1, e1)]) continue;
      const Eigen::Vector3f before = means.mean(a0, e0, radius) - centre, after = means.mean(a1, e1, radius) - centre;
      const float before_norm = before.norm(), after_norm = after.norm();
      if (!(before_norm > 0 && after_norm > 0)) continue;
      // Flat: the arms point in opposite directions (cosine -1); the bend is 180 deg minus their angle.
      if (before.dot(after) <= max_cosine * before_norm * after_norm) continue;
      if ((before + after).dot(centre) >= 0) continue;  // convex: the chord's midpoint lies behind the point
      if (std::abs(before.dot(centre)) > step_cosine * before_norm * centre_range ||
          std::abs(after.dot(centre)) > step_cosine * after_norm * centre_range)
        continue;  // an arm along the line of sight: a depth step
      if (passable_section(a0, e0, du, dv, 2 * steps)) return true;
    }
    return false;
  };
  // Every ray is tested: testing every second ray each way (2 x 2 blocks) was a third cheaper, but left
  // the band closing around a stack only at the defaults (a 0.5 cm change of the arm joined learn17's boxes).
  for (int e = 0; e < height; ++e) {
    throw_if_stop_requested();
    for (int a = 0; a < width; ++a) crease[ray(a, e)] = member[ray(a, e)] && folds(a, e);
  }
  return crease;
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

Segmentation segment_improvement(const GridGeometry& geometry, const SurfaceMap& surface,
                                 const ImprovementMap& improvement, const SegmentationParams& params) {
  params.validate();
  const int width = geometry.width(), height = geometry.height();
  const std::size_t n = geometry.column_count();
  const ColumnShape grid = ColumnShape::of_grid(width, height);
  require_shape("segment_improvement: surface map", surface.shape(), "the grid", grid);
  require_shape("segment_improvement: improvement map", improvement.shape(), "the grid", grid);

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
  out.crease.assign(n, 0);
  if (params.split_concave_creases) {
    // The plane is a segment already: no crease in or across it.
    std::vector<std::uint8_t> member(n, 0), passable(n, 0);
    for (std::size_t c = 0; c < n; ++c) {
      member[c] = interior[c] && !plane[c];
      passable[c] = valid[c] && !plane[c];
    }
    out.crease = concave_creases(geometry, points, PointMeans(points, member, width, height), member, passable, params);
    for (std::size_t c = 0; c < n; ++c) {
      out.crease_columns += out.crease[c];
      if (out.crease[c]) interior[c] = 0;
    }
  }

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
