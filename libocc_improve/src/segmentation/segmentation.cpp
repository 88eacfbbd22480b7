#include "occ_improve/segmentation/segmentation.hpp"

#include "occ_improve/integrate/integrate.hpp"  // InsertionOptions::kMaxThreads: one bound for every thread count

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "support/parallel.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <numeric>

namespace occ_improve {

using detail::require_parameter;

void SegmentationParams::validate() const {
  require_parameter(std::isfinite(contour_improvement_below) && contour_improvement_below < 0,
                    "contour_improvement_below", contour_improvement_below, "finite and < 0");
  require_parameter(min_segment_columns >= 1, "min_segment_columns", static_cast<double>(min_segment_columns), ">= 1");
  require_parameter(std::isfinite(plane_distance_m) && plane_distance_m > 0, "plane_distance_m", plane_distance_m,
                    "finite and > 0");
  require_parameter(std::isfinite(plane_distance_per_m2) && plane_distance_per_m2 >= 0 && plane_distance_per_m2 <= 1,
                    "plane_distance_per_m2", plane_distance_per_m2, "in [0, 1]");
  require_parameter(plane_min_columns >= 3, "plane_min_columns", static_cast<double>(plane_min_columns), ">= 3");
  require_parameter(plane_ransac_iterations >= 1 && plane_ransac_iterations <= 100000, "plane_ransac_iterations",
                    plane_ransac_iterations, "in [1, 100000]");
  require_parameter(std::isfinite(crease_arm_m) && crease_arm_m > 0 && crease_arm_m <= 1, "crease_arm_m", crease_arm_m,
                    "in (0, 1]");
  require_parameter(std::isfinite(crease_arm_per_m2) && crease_arm_per_m2 >= 0 && crease_arm_per_m2 <= 1,
                    "crease_arm_per_m2", crease_arm_per_m2, "in [0, 1]");
  require_parameter(std::isfinite(crease_smoothing_share) && crease_smoothing_share >= 0 && crease_smoothing_share <= 1,
                    "crease_smoothing_share", crease_smoothing_share, "in [0, 1]");
  require_parameter(std::isfinite(crease_min_bend_deg) && crease_min_bend_deg > 0 && crease_min_bend_deg < 180,
                    "crease_min_bend_deg", crease_min_bend_deg, "in (0, 180)");
  require_parameter(std::isfinite(crease_min_view_angle_deg) && crease_min_view_angle_deg >= 0 &&
                        crease_min_view_angle_deg < 90,
                    "crease_min_view_angle_deg", crease_min_view_angle_deg, "in [0, 90)");
  require_parameter(std::isfinite(crease_view_angle_range_m) && crease_view_angle_range_m >= 0,
                    "crease_view_angle_range_m", crease_view_angle_range_m, "finite and >= 0");
  require_parameter(crease_max_arm_px >= 2 && crease_max_arm_px <= 256, "crease_max_arm_px", crease_max_arm_px,
                    "in [2, 256]");
  static const std::string thread_range = "in [0, " + std::to_string(InsertionOptions::kMaxThreads) + "] (0: all cores)";
  require_parameter(threads >= 0 && threads <= InsertionOptions::kMaxThreads, "threads", threads, thread_range.c_str());
}

// The crease arm of segmentation_defaults in sigmas of the range-dependent depth noise (only that term: a
// constant sigma such as the paper's 4.7 cm is the model's allowance, not the data's noise).
constexpr double kCreaseArmSigmas = 6.0;
// The plane's inlier band of segmentation_defaults, likewise: 2.5 sigma keeps 98.8 % of a Gaussian's points
// (beyond 1.3 m for kinect_v1, where it passes the 6 mm band; make segment-eval's tables are nearer).
constexpr double kPlaneBandSigmas = 2.5;
// Beyond this range the crease's minimum view angle shrinks as 1 / range (segmentation.hpp).
constexpr double kCreaseViewAngleRangeM = 1.5;

SegmentationParams segmentation_defaults(const SensorPreset& preset) {
  return segmentation_defaults(preset.geometry, preset.model);
}

SegmentationParams segmentation_defaults(const GeometryParams& geometry, const SensorModelParams& model) {
  SegmentationParams params;
  // With a constant sigma_rho (the paper's 4.7 cm) the band is shallow: a lower bar keeps the contours closed.
  if (model.sigma_depth_per_m2 == 0.0) params.contour_improvement_below = -0.01f;
  // Pixel-native surfaces lie along z with no range rings, within the Kinect's ~2-3 mm noise of a table at
  // 1-1.5 m: a 6 mm band keeps the objects' bottom rows out of the plane (mean F on mosd_learn 0.839 with
  // 6 mm against 0.818 with 10 mm; 0.83-0.84 anywhere in 4-7.5 mm: make segment-eval -plane_distance).
  if (geometry.angular_binning == AngularBinning::pinhole) params.plane_distance_m = 0.006;
  params.crease_arm_per_m2 = kCreaseArmSigmas * model.sigma_depth_per_m2;
  params.plane_distance_per_m2 = kPlaneBandSigmas * model.sigma_depth_per_m2;
  params.crease_view_angle_range_m = kCreaseViewAngleRangeM;
  return params;
}

namespace {

constexpr std::uint32_t kNone = 0;
constexpr std::uint32_t kUnassigned = std::numeric_limits<std::uint32_t>::max();
// Combines two per-ray masks: set where `ray` is and `excluded` is not (bitwise, so loops over it vectorise).
constexpr auto and_not = [](std::uint8_t ray, std::uint8_t excluded) -> std::uint8_t { return ray & !excluded; };

// Runs body(first_row, end_row) on `threads` threads (0: the hardware's), each on its own block of rows,
// the blocks holding about equal shares of the rows' weights (the work each row holds). Every caller's rows
// are independent and each block writes only its own, so the result is the same for any split.
template <typename Body>
void for_row_blocks(const std::vector<std::size_t>& weight_of_row, int threads, Body&& body) {
  const int rows = static_cast<int>(weight_of_row.size());
  const int parts = std::max(1, std::min(detail::resolve_thread_count(threads), rows));
  const std::vector<int> first_row = detail::weighted_blocks(weight_of_row, parts);
  detail::run_parts(parts, [&](int part, int) {
    body(first_row[static_cast<std::size_t>(part)], first_row[static_cast<std::size_t>(part) + 1]);
  });
}

// The valid rays: a known, occupied surface inside the depth range, on an observable column (a NaN
// improvement: outside the camera or a mask, which takes no part even where a neighbour's measurement gave
// it a surface). Occupied is P > 0.5, not the planner's depth-sample rule (P >= 0.516, is_depth_sample):
// the columns only neighbours' OPDF tails reach lie along depth edges and carry the contours; with the
// sample rule the mosd_learn boundary recall fell from 0.75 to 0.27 and the pooled F from 0.932 to 0.919.
std::vector<std::uint8_t> valid_rays(const GridGeometry& geometry, const SurfaceMap& surface,
                                     const ImprovementMap& improvement) {
  std::vector<std::uint8_t> valid(surface.size());
  const int bins = geometry.depth().bins();
  // Bitwise & rather than &&, and the arrays through plain pointers (a byte store through a vector's
  // operator[] may alias the other vectors' bookkeeping): the loop runs in vector instructions.
  const std::uint8_t* unknown = surface.unknown.data();
  const std::int32_t* bin = surface.bin.data();
  const float *depth = surface.depth_m.data(), *probability = surface.probability.data();
  const float* value = improvement.value.data();
  std::uint8_t* out = valid.data();
  for (std::size_t c = 0, n = valid.size(); c < n; ++c)
    out[c] = !unknown[c] & (bin[c] >= 0) & (bin[c] < bins) & (depth[c] > 0) & (probability[c] > 0.5f) &
             !std::isnan(value[c]);
  return valid;
}

// The valid rays' surface points (zero elsewhere). The binning's back-projection is most of the cost: rows
// run on `threads` threads.
std::vector<Eigen::Vector3f> surface_points(const GridGeometry& geometry, const SurfaceMap& surface,
                                            const std::vector<std::uint8_t>& valid, int threads) {
  std::vector<Eigen::Vector3f> points(surface.size(), Eigen::Vector3f::Zero());
  const std::vector<std::size_t> equal_rows(static_cast<std::size_t>(geometry.height()), 1);
  for_row_blocks(equal_rows, threads, [&](int first_row, int end_row) {
    const int width = geometry.width();
    for (int e = first_row; e < end_row; ++e)
      for (int a = 0; a < width; ++a) {
        const ColumnIndex c = geometry.column(a, e);
        if (valid[c]) points[c] = geometry.point(a, e, surface.depth_m[c]).cast<float>();
      }
  });
  return points;
}

// The plane's inlier band at a point: plane_distance_m, or wider where the depth noise is (plane_distance_per_m2).
struct PlaneBand {
  float floor_m, per_m2;
  explicit PlaneBand(const SegmentationParams& params)
      : floor_m(static_cast<float>(params.plane_distance_m)), per_m2(static_cast<float>(params.plane_distance_per_m2)) {}
  float at(const Eigen::Vector3f& p) const { return std::max(floor_m, per_m2 * p.squaredNorm()); }
  bool holds(const Eigen::Vector3f& normal, float offset, const Eigen::Vector3f& p) const {
    return std::abs(normal.dot(p) + offset) < at(p);
  }
};

// The RANSAC scoring subsample, one contiguous array per coordinate and its points' bands: it stays in
// cache over all iterations and a plane scores it in vector instructions.
struct ScoringSample {
  Eigen::ArrayXf x, y, z, band;
  ScoringSample(const std::vector<Eigen::Vector3f>& points, const std::vector<std::uint32_t>& candidates,
                std::size_t stride, const PlaneBand& plane_band) {
    const auto size = static_cast<Eigen::Index>((candidates.size() + stride - 1) / stride);
    x.resize(size), y.resize(size), z.resize(size), band.resize(size);
    for (Eigen::Index i = 0; i < size; ++i) {
      const Eigen::Vector3f& p = points[candidates[static_cast<std::size_t>(i) * stride]];
      x[i] = p.x(), y[i] = p.y(), z[i] = p.z(), band[i] = plane_band.at(p);
    }
  }
  /// Points within their band of the plane, or some count <= `to_beat` once the plane cannot have more than
  /// that (most hypotheses stop there: only a larger count changes the search). The distance is summed as
  /// Eigen's Vector3f::dot sums it, x + (y + z), so a point scores here exactly as normal.dot(p) + offset
  /// classifies it in the refinement.
  std::size_t inliers(const Eigen::Vector3f& normal, float offset, std::size_t to_beat) const {
    constexpr Eigen::Index kBlock = 256;  // points between two checks of the bound
    const float nx = normal.x(), ny = normal.y(), nz = normal.z();
    const Eigen::Index size = x.size();
    std::size_t count = 0;
    for (Eigen::Index begin = 0; begin < size; begin += kBlock) {
      const Eigen::Index end = std::min(size, begin + kBlock);
      int in_block = 0;  // a plain counted loop over plain arrays: vector instructions
      for (Eigen::Index i = begin; i < end; ++i) in_block += std::abs(nx * x[i] + (ny * y[i] + nz * z[i]) + offset) < band[i];
      count += static_cast<std::size_t>(in_block);
      if (count + static_cast<std::size_t>(size - end) <= to_beat) return count;
    }
    return count;
  }
};

// The least-squares plane through the points within their band of a plane: its normal is the inliers'
// covariance's smallest eigenvector. Returns the inlier count (the plane is left as it was without inliers).
std::size_t refine_plane(const std::vector<Eigen::Vector3f>& points, const std::vector<std::uint32_t>& candidates,
                         const PlaneBand& band, Eigen::Vector3f& normal, float& offset) {
  // The sums of the coordinates and of their 6 distinct products (the second moment is symmetric), each
  // summed in candidate order.
  double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
  std::size_t inliers = 0;
  for (std::uint32_t c : candidates)
    if (band.holds(normal, offset, points[c])) {
      const double x = points[c].x(), y = points[c].y(), z = points[c].z();
      sx += x, sy += y, sz += z;
      sxx += x * x, sxy += x * y, sxz += x * z, syy += y * y, syz += y * z, szz += z * z;
      ++inliers;
    }
  if (inliers == 0) return 0;
  const auto count = static_cast<double>(inliers);
  const Eigen::Vector3d mean = Eigen::Vector3d(sx, sy, sz) / count;
  Eigen::Matrix3d second;
  second << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
  const Eigen::Matrix3d covariance = second / count - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  normal = solver.eigenvectors().col(0).cast<float>();
  offset = -normal.dot(mean.cast<float>());
  return inliers;
}

// RANSAC for the plane with most inliers among the valid rays (scored on a subsample), refined by a
// least-squares fit to its inliers. Marks the inliers in `plane` and returns their count (0 when the best
// plane is smaller than params.plane_min_columns).
std::size_t find_dominant_plane(const std::vector<Eigen::Vector3f>& points, const std::vector<std::uint8_t>& valid,
                                std::size_t valid_columns, const SegmentationParams& params,
                                std::vector<std::uint8_t>& plane) {
  if (valid_columns < params.plane_min_columns) return 0;
  // The valid rays' indices, written branch-free: every ray is written, and the next overwrites it unless valid.
  std::vector<std::uint32_t> candidates(valid.size() + 1);
  std::size_t kept = 0;
  for (std::size_t c = 0; c < valid.size(); ++c) {
    candidates[kept] = static_cast<std::uint32_t>(c);
    kept += valid[c];
  }
  candidates.resize(kept);
  // A fixed stride keeps the scoring cost near 5,000 points whatever the image size.
  const PlaneBand band(params);
  const ScoringSample sample(points, candidates, std::max<std::size_t>(1, candidates.size() / 5000), band);
  std::uint64_t state = 0x9E3779B97F4A7C15ull ^ params.plane_seed;
  auto next_index = [&]() {  // splitmix64: deterministic and good enough for sampling
    state += 0x9E3779B97F4A7C15ull;
    std::uint64_t z = state;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return candidates[(z ^ (z >> 31)) % candidates.size()];
  };
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
    const std::size_t score = sample.inliers(normal, offset, best_score);
    if (score > best_score) best_score = score, best_normal = normal, best_offset = offset;
  }
  if (best_score == 0) return 0;
  if (refine_plane(points, candidates, band, best_normal, best_offset) < params.plane_min_columns) return 0;
  std::size_t count = 0;
  for (std::uint32_t c : candidates)
    if (band.holds(best_normal, best_offset, points[c])) plane[c] = 1, ++count;
  return count >= params.plane_min_columns ? count : 0;
}

// The bounding box of the member rays (width 0 when there are none).
struct RayBox {
  int a0 = 0, e0 = 0, width = 0, height = 0;
};
RayBox member_box(const std::vector<std::uint8_t>& member, int width, int height) {
  int a_min = width, a_max = -1, e_min = height, e_max = -1;
  for (int e = 0; e < height; ++e) {
    const auto row = member.begin() + static_cast<std::ptrdiff_t>(e) * width;
    const auto first = std::find(row, row + width, 1);
    if (first == row + width) continue;
    const auto last = std::find(std::make_reverse_iterator(row + width), std::make_reverse_iterator(first), 1);
    a_min = std::min(a_min, static_cast<int>(first - row));
    a_max = std::max(a_max, static_cast<int>(last.base() - row) - 1);
    e_min = std::min(e_min, e), e_max = e;
  }
  if (a_max < 0) return {};
  return {a_min, e_min, a_max - a_min + 1, e_max - e_min + 1};
}

// Summed-area tables of the surface points over the member rays, so a ray's neighbourhood mean costs four
// look-ups whatever its radius (which follows the ray's depth). Only member rays (valid, not contour, not plane) are
// summed, so a mean never mixes the two sides of a depth step. The table covers the member rays' bounding box
// but holds only a window of its rows, computed as a scan down the image advances: a ray's means read only
// rows within `reach` of its own, and the whole table (7 MB for a table-top frame) cost 1-4 ms of page
// faults and memory traffic per frame. Each row is summed exactly as in the whole table.
// Each mean is computed once and kept while its row is in the window: a ray's centre is an end of its
// neighbours' sections and its ends are the centres and ends of others (of the 9 means a ray reads, most
// were read before at the same radius).
class PointMeans {
public:
  PointMeans(const std::vector<Eigen::Vector3f>& points, const std::vector<std::uint8_t>& member, int width,
             const RayBox& box, int reach)
      : points_(points), member_(member), image_width_(width), box_(box), reach_(reach),
        window_(power_of_two_at_least(std::min(box.height + 1, 2 * reach))) {
    memo_.resize(static_cast<std::size_t>(reach) + 1);  // every radius up front: an AtRadius keeps a Memo&
    if (box_.width == 0) return;
    sum_.resize(static_cast<std::size_t>(window_) * (box_.width + 1));
    std::fill_n(&at(0, 0), box_.width + 1, Eigen::Vector4d::Zero());
  }
  /// Makes the rows the means around image row e read available (rows more than `reach` above it may go).
  void advance_to(int e) {
    for (const int last = std::min(box_.height, e - box_.e0 + reach_); summed_ < last; ++summed_) sum_next_row();
  }
  class AtRadius;
  /// The means at radius r: fetched once per ray, then read for the ray and its sections' ends.
  AtRadius at_radius(int r);

private:
  // The means computed at one radius, in a window of rows like the table's.
  struct Memo {
    std::vector<Eigen::Vector3f> value;
    std::vector<std::uint8_t> known;
    std::vector<int> row_held;  // per slot of the window: the box row its entries are of (-1: none yet)
  };
  Memo& memo_for(int r) {
    Memo& memo = memo_.at(static_cast<std::size_t>(r));  // a radius is within the reach
    if (memo.row_held.empty()) {
      memo.value.resize(static_cast<std::size_t>(window_) * box_.width);
      memo.known.resize(memo.value.size());
      memo.row_held.assign(static_cast<std::size_t>(window_), -1);
    }
    return memo;
  }
  Eigen::Vector3f box_mean(int a, int e, int r) const {
    const int a0 = std::clamp(a - r - box_.a0, 0, box_.width), a1 = std::clamp(a + r + 1 - box_.a0, 0, box_.width);
    const int e0 = std::clamp(e - r - box_.e0, 0, box_.height), e1 = std::clamp(e + r + 1 - box_.e0, 0, box_.height);
    const Eigen::Vector4d* top = &at(0, e0);
    const Eigen::Vector4d* bottom = &at(0, e1);
    const Eigen::Vector4d s = bottom[a1] - bottom[a0] - top[a1] + top[a0];
    return (s.head<3>() / std::max(s.w(), 1.0)).cast<float>();
  }
  static int power_of_two_at_least(int rows) {
    int out = 1;
    while (out < rows) out *= 2;
    return out;
  }
  // Table row summed_ + 1 (the sums over the box's first summed_ + 1 image rows) from row summed_.
  void sum_next_row() {
    const Eigen::Vector4d* above = &at(0, summed_);
    Eigen::Vector4d* below = &at(0, summed_ + 1);
    below[0] = Eigen::Vector4d::Zero();
    Eigen::Vector4d row = Eigen::Vector4d::Zero();
    const std::size_t first = static_cast<std::size_t>(box_.e0 + summed_) * image_width_ + box_.a0;
    for (int a = 0; a < box_.width; ++a) {
      const std::size_t c = first + a;
      if (member_[c]) row += Eigen::Vector4d(points_[c].x(), points_[c].y(), points_[c].z(), 1.0);
      below[a + 1] = above[a + 1] + row;
    }
  }
  // A power-of-two window: the row in it is a mask, not a division, on every look-up.
  Eigen::Vector4d& at(int a, int e) { return sum_[static_cast<std::size_t>(e & (window_ - 1)) * (box_.width + 1) + a]; }
  const Eigen::Vector4d& at(int a, int e) const {
    return sum_[static_cast<std::size_t>(e & (window_ - 1)) * (box_.width + 1) + a];
  }
  const std::vector<Eigen::Vector3f>& points_;
  const std::vector<std::uint8_t>& member_;
  int image_width_;
  RayBox box_;
  int reach_, window_;
  int summed_ = 0;  // table rows 0..summed_ are summed; the last window_ of them are kept
  std::vector<Eigen::Vector4d> sum_;
  std::vector<Memo> memo_;  // by radius
};

// Means at one radius. mean(a, e): of the member points in the square of radius r around the member ray
// (a, e) (zero when it holds none); r and the distance from the row last advanced to together within the
// reach. Inline: a ray reads 9 of them and most were computed before.
class PointMeans::AtRadius {
public:
  AtRadius(PointMeans& means, Memo& memo, int r) : means_(means), memo_(memo), r_(r) {}
  Eigen::Vector3f mean(int a, int e) {
    const RayBox& box = means_.box_;
    const int row = e - box.e0, slot = row & (means_.window_ - 1);
    const std::size_t first = static_cast<std::size_t>(slot) * box.width;
    if (memo_.row_held[static_cast<std::size_t>(slot)] != row) forget_row(first, slot, row);
    const std::size_t i = first + static_cast<std::size_t>(a - box.a0);
    if (!memo_.known[i]) memo_.value[i] = means_.box_mean(a, e, r_), memo_.known[i] = 1;
    return memo_.value[i];
  }

private:
  // The slot now holds another row: none of its means is known.
  void forget_row(std::size_t first, int slot, int row) {
    std::fill_n(memo_.known.begin() + static_cast<std::ptrdiff_t>(first), means_.box_.width, 0);
    memo_.row_held[static_cast<std::size_t>(slot)] = row;
  }
  PointMeans& means_;
  Memo& memo_;
  int r_;
};

PointMeans::AtRadius PointMeans::at_radius(int r) { return AtRadius(*this, memo_for(r), r); }

// The angle between the rays of two neighbouring columns at the image centre: converts the crease arm
// from metres on the surface to pixels.
double column_angle_rad(const GridGeometry& geometry) {
  const int a = std::max(0, geometry.width() / 2 - 1), e = geometry.height() / 2;
  if (geometry.width() < 2) return 1.0;
  const double cosine = geometry.direction(a, e).dot(geometry.direction(a + 1, e));
  return std::acos(std::clamp(cosine, -1.0, 1.0));
}

// A crease arm of a given length in pixels (step 3), the smoothing radius that goes with it and the steps of
// a diagonal section: each is sqrt(2) longer, so fewer of them for the same arm.
struct ArmPixels {
  int arm, radius, diagonal_steps;
};
// Per arm length, 0 to the longest: the roundings once per frame rather than per ray.
std::vector<ArmPixels> arm_table(const SegmentationParams& params) {
  std::vector<ArmPixels> arms(static_cast<std::size_t>(params.crease_max_arm_px) + 1);
  for (int arm = 0; arm <= params.crease_max_arm_px; ++arm)
    arms[static_cast<std::size_t>(arm)] = {arm, static_cast<int>(std::lround(params.crease_smoothing_share * arm)),
                                           std::max(1, static_cast<int>(std::lround(arm / std::sqrt(2.0))))};
  return arms;
}
// The crease arm's length in pixels at a ray of the given range.
int arm_length_px(double range_m, double pixel_rad, const SegmentationParams& params) {
  // Clamped, then rounded half up: std::lround of the unclamped value, since the bounds are whole and x + 0.5
  // is exact for x >= 2 (a libm call per ray was 2 % of the crease scan).
  const double arm_m = std::max(params.crease_arm_m, params.crease_arm_per_m2 * range_m * range_m);
  const double arm = std::clamp(arm_m / (range_m * pixel_rad), 2.0, static_cast<double>(params.crease_max_arm_px));
  return static_cast<int>(arm + 0.5);
}

// The cosine of the minimum view angle at a range: crease_min_view_angle_deg, shrinking as
// crease_view_angle_range_m / range beyond that range; from a table of 1 cm steps (a cosine per ray was a
// libm call on each of the ~250 000).
class ViewAngleCosines {
public:
  explicit ViewAngleCosines(const SegmentationParams& params)
      : angle_rad_(params.crease_min_view_angle_deg * M_PI / 180.0), from_m_(params.crease_view_angle_range_m) {
    cosine_.resize(kSteps);
    for (int i = 0; i < kSteps; ++i) cosine_[static_cast<std::size_t>(i)] = computed((i + 0.5) * kStepM);
  }
  float at(float range_m) const {
    const float step = range_m / static_cast<float>(kStepM);
    return step < kSteps ? cosine_[static_cast<std::size_t>(step)] : computed(range_m);  // beyond 20 m: a LiDAR's
  }

private:
  float computed(double range_m) const {
    return static_cast<float>(std::cos(from_m_ > 0 && range_m > from_m_ ? angle_rad_ * from_m_ / range_m : angle_rad_));
  }
  static constexpr double kStepM = 0.01;
  static constexpr int kSteps = 2000;  // 20 m
  double angle_rad_, from_m_;
  std::vector<float> cosine_;
};

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
                                          const std::vector<std::uint8_t>& member,
                                          const std::vector<std::uint8_t>& passable, const SegmentationParams& params) {
  const int width = geometry.width(), height = geometry.height();
  std::vector<std::uint8_t> crease(member.size(), 0);
  const RayBox box = member_box(member, width, height);
  const std::vector<ArmPixels> arms = arm_table(params);
  // The farthest row a ray's means read: the longest arm, its smoothing radius and the summed-area table's
  // row past the square.
  const int reach = arms.back().arm + arms.back().radius + 1;
  const double pixel_rad = column_angle_rad(geometry);
  const float max_cosine = static_cast<float>(std::cos(M_PI - params.crease_min_bend_deg * M_PI / 180.0));
  const ViewAngleCosines step_cosine(params);
  constexpr std::array<std::array<int, 2>, 4> kDirections{{{1, 0}, {0, 1}, {1, 1}, {-1, 1}}};
  auto ray = [&](int a, int e) { return static_cast<std::size_t>(e) * width + a; };
  // Every ray of the section passable: it crosses no hole and not the plane. Checked last, on folds only.
  auto passable_section = [&](int a0, int e0, int du, int dv, int steps) {
    for (int k = 0; k <= steps; ++k)
      if (!passable[ray(a0 + k * du, e0 + k * dv)]) return false;
    return true;
  };
  auto folds = [&](PointMeans& means, int a, int e) {
    const int length = arm_length_px(points[ray(a, e)].norm(), pixel_rad, params);
    const auto [arm, radius, diagonal_steps] = arms[static_cast<std::size_t>(length)];
    PointMeans::AtRadius at_radius = means.at_radius(radius);
    const Eigen::Vector3f centre = at_radius.mean(a, e);
    const float centre_range = centre.norm();
    for (const auto& [du, dv] : kDirections) {
      const int steps = du != 0 && dv != 0 ? diagonal_steps : arm;
      const int a0 = a - du * steps, e0 = e - dv * steps, a1 = a + du * steps, e1 = e + dv * steps;
      if (std::min(a0, a1) < 0 || std::max(a0, a1) >= width || e0 < 0 || e1 >= height) continue;
      if (!member[ray(a0, e0)] || !member[ray(a1, e1)]) continue;
      const Eigen::Vector3f before = at_radius.mean(a0, e0) - centre, after = at_radius.mean(a1, e1) - centre;
      const float before_norm = before.norm(), after_norm = after.norm();
      if (!(before_norm > 0 && after_norm > 0)) continue;
      // Flat: the arms point in opposite directions (cosine -1); the bend is 180 deg minus their angle.
      if (before.dot(after) <= max_cosine * before_norm * after_norm) continue;
      if ((before + after).dot(centre) >= 0) continue;  // convex: the chord's midpoint lies behind the point
      const float cosine = step_cosine.at(centre_range);
      if (std::abs(before.dot(centre)) > cosine * before_norm * centre_range ||
          std::abs(after.dot(centre)) > cosine * after_norm * centre_range)
        continue;  // an arm along the line of sight: a depth step
      if (passable_section(a0, e0, du, dv, 2 * steps)) return true;
    }
    return false;
  };
  // Every ray is tested: testing every second ray each way (2 x 2 blocks) was a third cheaper, but left
  // the band closing around a stack only at the defaults (a 0.5 cm change of the arm joined learn17's boxes).
  // The cost is per member ray, and the objects often fill one part of the image: the threads' blocks
  // hold about as many member rays each.
  std::vector<std::size_t> members_of_row(static_cast<std::size_t>(height));
  for (int e = 0; e < height; ++e) {
    const auto row = member.begin() + static_cast<std::ptrdiff_t>(ray(0, e));
    members_of_row[static_cast<std::size_t>(e)] = static_cast<std::size_t>(std::count(row, row + width, 1));
  }
  for_row_blocks(members_of_row, params.threads, [&](int first_row, int end_row) {
    PointMeans means(points, member, width, box, reach);
    for (int e = first_row; e < end_row; ++e) {
      throw_if_stop_requested();
      means.advance_to(e);
      for (int a = 0; a < width; ++a) crease[ray(a, e)] = member[ray(a, e)] && folds(means, a, e);
    }
  });
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

// Valid rays no segment reached through 4-neighbours (islands between holes), in islands of fewer than
// min_segment_columns rays, join the segment of the nearest labelled ray within kIslandReachColumns whose
// surface lies within the plane band of theirs: one surface seen through holes. A wall crossing the grid's
// far end, whose rays fall in and out of the depth range with the noise, broke into hundreds of segments of
// 1-25 rays (a held-out trial: 829 on a slanted wall from 4.6 to 8.6 m; 1-45 rays without quantisation).
// An island takes the label its rays find closest in depth; larger islands, and those with no such neighbour (a far wall seen through a
// gap in a near object), stay segments of their own.
constexpr int kIslandReachColumns = 4;
// `rays` (row by row) are the small islands' (`island` of each, `islands` of them), called once the larger
// islands are labelled. In rounds, so that a chain of islands (the far end's band of rays flickering in and
// out of range is tens of columns wide) joins from the segment inwards; each round attaches only islands
// next to a labelled ray, so the result does not depend on scan order. Returns the number of rays attached.
std::size_t attach_small_islands(const std::vector<Eigen::Vector3f>& points, const SurfaceMap& surface, int width,
                                 int height, const SegmentationParams& params, const std::vector<std::uint32_t>& rays,
                                 const std::vector<std::uint32_t>& island, std::size_t islands,
                                 std::vector<std::uint32_t>& label) {
  struct Nearest {
    float jump = std::numeric_limits<float>::infinity();
    std::uint32_t label = kUnassigned;
  };
  const PlaneBand band(params);
  std::size_t attached = 0;
  for (;;) {
    throw_if_stop_requested();
    std::vector<Nearest> nearest(islands + 1);
    for (const std::uint32_t c : rays) {
      if (label[c] != kUnassigned) continue;
      const int a = static_cast<int>(c % static_cast<std::uint32_t>(width)), e = static_cast<int>(c / static_cast<std::uint32_t>(width));
      Nearest& best = nearest[island[c]];
      const float tolerance = band.at(points[c]);
      for (int v = std::max(0, e - kIslandReachColumns); v <= std::min(height - 1, e + kIslandReachColumns); ++v)
        for (int u = std::max(0, a - kIslandReachColumns); u <= std::min(width - 1, a + kIslandReachColumns); ++u) {
          const std::size_t n = static_cast<std::size_t>(v) * width + u;
          if (label[n] == kNone || label[n] == kUnassigned) continue;
          const float jump = std::abs(surface.depth_m[n] - surface.depth_m[c]);
          if (jump < tolerance && jump < best.jump) best = {jump, label[n]};
        }
    }
    std::size_t now = 0;
    for (const std::uint32_t c : rays)
      if (label[c] == kUnassigned && nearest[island[c]].label != kUnassigned) label[c] = nearest[island[c]].label, ++now;
    if (now == 0) return attached;
    attached += now;
  }
}

// Valid regions no segment reached (islands between holes), found once: those of at least
// min_segment_columns rays become segments + 1, segments + 2, ... (in scan order), the small ones of a
// surface seen through holes join it (attach_small_islands: the larger islands, labelled first, may take
// them), and the small ones left become segments after those. Returns the number of new segments; adds the
// rays attached to `attached`.
std::uint32_t label_islands(const std::vector<Eigen::Vector3f>& points, const SurfaceMap& surface, int width, int height,
                            const SegmentationParams& params, std::uint32_t segments, std::vector<std::uint32_t>& label,
                            std::size_t& attached) {
  std::vector<std::uint8_t> unassigned(label.size());
  std::transform(label.begin(), label.end(), unassigned.begin(),
                 [](std::uint32_t l) -> std::uint8_t { return l == kUnassigned; });
  std::vector<std::uint32_t> island(label.size(), kUnassigned);
  const std::vector<std::size_t> sizes = connected_components(unassigned, width, height, island);
  std::vector<std::uint32_t> segment_of(sizes.size() + 1, kUnassigned);  // per island
  std::uint32_t labelled = 0;
  for (std::size_t k = 0; k < sizes.size(); ++k)
    if (sizes[k] >= params.min_segment_columns) segment_of[k + 1] = segments + ++labelled;
  std::vector<std::uint32_t> small_rays;  // row by row
  for (std::size_t c = 0; c < label.size(); ++c) {
    if (!unassigned[c]) continue;
    label[c] = segment_of[island[c]];
    if (label[c] == kUnassigned) small_rays.push_back(static_cast<std::uint32_t>(c));
  }
  attached += attach_small_islands(points, surface, width, height, params, small_rays, island, sizes.size(), label);
  // The small islands left, numbered in the order of their first ray, as scanning them afresh would.
  for (const std::uint32_t c : small_rays) {
    if (label[c] != kUnassigned) continue;
    if (segment_of[island[c]] == kUnassigned) segment_of[island[c]] = segments + ++labelled;
    label[c] = segment_of[island[c]];
  }
  return labelled;
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
  // The per-ray masks combine with bitwise operators in std::transform: branch-free loops over plain
  // pointers, which the compiler vectorises.
  const std::vector<std::uint8_t> valid = valid_rays(geometry, surface, improvement);
  out.contour.resize(n);
  std::transform(valid.begin(), valid.end(), improvement.value.begin(), out.contour.begin(),
                 [&](std::uint8_t v, float i) -> std::uint8_t { return v & (i < params.contour_improvement_below); });
  std::vector<std::uint8_t> interior(n);  // valid, not contour (crease and plane rays leave below): where segments grow
  std::transform(valid.begin(), valid.end(), out.contour.begin(), interior.begin(), and_not);
  out.valid_columns = static_cast<std::size_t>(std::count(valid.begin(), valid.end(), 1));
  out.contour_columns = static_cast<std::size_t>(std::count(out.contour.begin(), out.contour.end(), 1));

  const std::vector<Eigen::Vector3f> points = surface_points(geometry, surface, valid, params.threads);
  std::vector<std::uint8_t> plane(n, 0);
  if (params.remove_dominant_plane) out.plane_columns = find_dominant_plane(points, valid, out.valid_columns, params, plane);
  if (out.plane_columns == 0) std::fill(plane.begin(), plane.end(), 0);
  out.crease.assign(n, 0);
  if (params.split_concave_creases) {
    // The plane is a segment already: no crease in or across it.
    std::vector<std::uint8_t> member(n), passable(n);
    std::transform(interior.begin(), interior.end(), plane.begin(), member.begin(), and_not);
    std::transform(valid.begin(), valid.end(), plane.begin(), passable.begin(), and_not);
    out.crease = concave_creases(geometry, points, member, passable, params);
    out.crease_columns = static_cast<std::size_t>(std::count(out.crease.begin(), out.crease.end(), 1));
  }
  std::transform(interior.begin(), interior.end(), out.crease.begin(), interior.begin(), and_not);
  std::transform(interior.begin(), interior.end(), plane.begin(), interior.begin(), and_not);

  // Working labels: kNone where no surface, kUnassigned where valid but not yet in a segment.
  std::vector<std::uint32_t> label(n);
  std::transform(valid.begin(), valid.end(), label.begin(), [](std::uint8_t v) { return v ? kUnassigned : kNone; });
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
  // Valid regions no segment reached (islands between holes): the small ones of a surface seen through
  // holes join it, the others become segments of their own.
  if (std::find(label.begin(), label.end(), kUnassigned) != label.end())
    segments += label_islands(points, surface, width, height, params, segments, label, out.attached_columns);

  // Statistics, then labels renumbered by size (largest first) so label 1 is the largest segment.
  std::vector<Segment> stats(segments);
  std::vector<double> depth_sum(segments, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
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
