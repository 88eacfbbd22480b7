#include "occ_improve/integrate.hpp"

#include "fast_math.hpp"
#include "occ_improve/errors.hpp"
#include "parallel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace occ_improve {

namespace {

using detail::fast_exp;
using detail::fast_log;

// Beyond this depth offset (in sigmas, as a function of B) |logit P_s| < kSkipEpsilon:
//   the step term deviates from 1/2 by < eps/4 once u > log(4/eps), the peak term is < eps/4 once
//   t^2 + B > log(8/(3 eps)).
double skip_offset_sigmas(double angular_term) {
  static const double step_limit = std::log(4.0 / kSkipEpsilon), peak_limit = std::log(8.0 / (3.0 * kSkipEpsilon));
  return std::max((step_limit - 4.0 - angular_term) / 2.0, std::sqrt(std::max(0.0, peak_limit - angular_term)));
}

// In exact mode, bins with u < kLinearU take logit P_s = log(1/2) + u: there log(1 + e^u) < 2.1e-9 and the
// peak term is below e^-120 of the step term (t <= -12).
constexpr double kLinearU = -20.0;

struct Measurement {
  double rho, azimuth, elevation;
  int azimuth_first, azimuth_last, elevation_first, elevation_last;
};

struct ThreadScratch {
  std::vector<float> profile;
  std::size_t column_updates = 0;
};

// Adds one measurement's truncated OPDF to one column.
class ColumnKernel {
public:
  ColumnKernel(const SphericalGrid& grid) : grid_(grid), depth_(grid.geometry().depth()) {
    clamped_ = grid.clamped();
    lmin_ = grid.log_odds_min();
    lmax_ = grid.log_odds_max();
    saturation_ = static_cast<double>(lmin_) - static_cast<double>(lmax_);
  }

  void apply(ColumnData& column, double rho_bar, double angular_term, double sigma, ThreadScratch& scratch) const {
    const int bins = depth_.bins();
    const int end = depth_.first_centre_above(rho_bar + sigma * skip_offset_sigmas(angular_term));
    if (clamped_) {
      // Voxels where logit P_s <= L_min - L_max end at L_min whatever they held: they are not evaluated.
      // The bound keeps a margin of 1.5 sigma: there the step term is < e^(L_min - L_max - 3) and the
      // peak term negligible, so logit P_s < L_min - L_max.
      const double t_saturate = (saturation_ - std::log(0.5) - 4.0 - angular_term) / 2.0 - 1.5;
      const int saturated = std::min(depth_.first_centre_above(rho_bar + sigma * t_saturate), bins);
      const int first = saturated, count = std::max(end - first, 0);
      scratch.profile.resize(static_cast<std::size_t>(count));
      logit_opdf_profile(depth_.centres().data() + first, static_cast<std::size_t>(count), rho_bar, angular_term,
                         sigma, scratch.profile.data());
      apply_clamped(column, saturated, first, end, scratch.profile.data());
    } else {
      const double t_linear = (kLinearU - 4.0 - angular_term) / 2.0;
      const int linear_end = std::min(depth_.first_centre_above(rho_bar + sigma * t_linear), end);
      const int count = std::max(end - linear_end, 0);
      scratch.profile.resize(static_cast<std::size_t>(count));
      logit_opdf_profile(depth_.centres().data() + linear_end, static_cast<std::size_t>(count), rho_bar,
                         angular_term, sigma, scratch.profile.data());
      apply_exact(column, linear_end, end, scratch.profile.data(), rho_bar, angular_term, sigma);
    }
    ++scratch.column_updates;
  }

private:
  void apply_clamped(ColumnData& c, int saturated, int first, int end, const float* profile) const {
    if (saturated > c.uniform_end) {
      const auto drop = std::min<std::size_t>(static_cast<std::size_t>(saturated - c.uniform_end), c.window.size());
      c.window.erase(c.window.begin(), c.window.begin() + static_cast<std::ptrdiff_t>(drop));
      c.uniform_end = saturated;
      c.uniform_value = lmin_;
    }
    // Inside the uniform run (all L_min) only voxels with logit P_s > 0 change; materialise from the first.
    const int run_overlap_end = std::min(c.uniform_end, end);
    for (int b = first; b < run_overlap_end; ++b) {
      if (profile[b - first] > 0.0f) {
        c.window.insert(c.window.begin(), static_cast<std::size_t>(c.uniform_end - b), lmin_);
        c.uniform_end = b;
        break;
      }
    }
    if (c.window_end() < end) c.window.resize(static_cast<std::size_t>(end - c.uniform_end), 0.0f);
    float* w = c.window.data() - c.uniform_end;  // w[b] is bin b
    for (int b = std::max(first, static_cast<int>(c.uniform_end)); b < end; ++b) {
      const float v = w[b] + profile[b - first];
      w[b] = v < lmin_ ? lmin_ : (v > lmax_ ? lmax_ : v);
    }
    SphericalGrid::compact(c);
  }

  void apply_exact(ColumnData& c, int linear_end, int end, const float* profile, double rho_bar, double angular_term,
                   double sigma) const {
    if (c.window_end() < end) c.window.resize(static_cast<std::size_t>(end), 0.0f);
    float* w = c.window.data();
    const double* centres = depth_.centres().data();
    const double offset = std::log(0.5) + 4.0 + angular_term, slope = 2.0 / sigma;
    for (int b = 0; b < linear_end; ++b) w[b] += static_cast<float>(offset + slope * (centres[b] - rho_bar));
    for (int b = linear_end; b < end; ++b) w[b] += profile[b - linear_end];
  }

  const SphericalGrid& grid_;
  const DepthAxis& depth_;
  bool clamped_;
  float lmin_, lmax_;
  double saturation_;
};

bool to_measurement(const float* p, const SphericalGeometry& g, const SensorModel& model, Measurement& m,
                    InsertionReport& report) {
  const double x = p[0], y = p[1], z = p[2];
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) || (x == 0 && y == 0 && z == 0)) {
    ++report.skipped_invalid;
    return false;
  }
  const SphericalPoint s = to_spherical(x, y, z);
  int a, e;
  if (!g.locate(s.azimuth, s.elevation, a, e)) {
    ++report.skipped_outside_fov;
    return false;
  }
  m.rho = s.rho;
  m.azimuth = s.azimuth;
  m.elevation = s.elevation;
  const double ka = model.support_azimuth_rad(), ke = model.support_elevation_rad();
  g.azimuth().overlapping(s.azimuth - ka, s.azimuth + ka, m.azimuth_first, m.azimuth_last);
  g.elevation().overlapping(s.elevation - ke, s.elevation + ke, m.elevation_first, m.elevation_last);
  if (s.rho >= g.depth().max()) ++report.beyond_depth_range;
  ++report.points_inserted;
  return true;
}

}  // namespace

void logit_opdf_profile(const double* centres, std::size_t n, double rho_bar, double angular_term, double sigma_rho,
                        float* out) {
  const double inv_sigma = 1.0 / sigma_rho;
  const float b = static_cast<float>(angular_term);
  for (std::size_t i = 0; i < n; ++i) {
    const float t = static_cast<float>((centres[i] - rho_bar) * inv_sigma);
    const float x = fast_exp(-(2.0f * t + 4.0f + b));       // e^-u
    const float g = fast_exp(-(t * t + b)) * (1.0f / 3.0f);  // peak term
    // P = 1/(2(1+x)) + g; odds P/(1-P) rearranged so that both sides stay accurate near P = 1/2.
    const float gx = g * (1.0f + x);
    out[i] = fast_log((0.5f + gx) / (0.5f + x - gx));
  }
}

PointSpan PointSpan::from(const std::vector<Eigen::Vector3f>& points) {
  return {points.empty() ? nullptr : points.front().data(), points.size(), 3};
}

PointSpan PointSpan::from(const Eigen::Matrix3Xf& points) {
  return {points.data(), static_cast<std::size_t>(points.cols()), 3};
}

InsertionReport& InsertionReport::operator+=(const InsertionReport& o) {
  points_received += o.points_received;
  points_inserted += o.points_inserted;
  skipped_invalid += o.skipped_invalid;
  skipped_outside_fov += o.skipped_outside_fov;
  beyond_depth_range += o.beyond_depth_range;
  column_updates += o.column_updates;
  seconds += o.seconds;
  return *this;
}

InsertionReport insert_points(SphericalGrid& grid, const SensorModel& model, PointSpan points,
                              const InsertionOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (points.count > 0 && points.xyz == nullptr) throw InvalidInput("insert_points: null point buffer with count > 0");
  if (points.stride_floats < 3) {
    std::ostringstream m;
    m << "insert_points: stride_floats = " << points.stride_floats << " is invalid: must be >= 3";
    throw InvalidInput(m.str());
  }
  const SphericalGeometry& g = grid.geometry();
  const int threads = detail::resolve_thread_count(options.threads);

  // 1. Points -> measurements, in input order (parallel over contiguous chunks).
  std::vector<std::vector<Measurement>> chunks(static_cast<std::size_t>(threads));
  std::vector<InsertionReport> chunk_reports(static_cast<std::size_t>(threads));
  detail::run_parts(threads, [&](int part, int parts) {
    const std::size_t begin = points.count * static_cast<std::size_t>(part) / static_cast<std::size_t>(parts);
    const std::size_t end = points.count * static_cast<std::size_t>(part + 1) / static_cast<std::size_t>(parts);
    auto& out = chunks[static_cast<std::size_t>(part)];
    out.reserve(end - begin);
    Measurement m;
    for (std::size_t i = begin; i < end; ++i)
      if (to_measurement(points.xyz + i * points.stride_floats, g, model, m,
                         chunk_reports[static_cast<std::size_t>(part)]))
        out.push_back(m);
  });
  InsertionReport report;
  report.points_received = points.count;
  std::vector<Measurement> measurements;
  for (std::size_t p = 0; p < chunks.size(); ++p) {
    report += chunk_reports[p];
    measurements.insert(measurements.end(), chunks[p].begin(), chunks[p].end());
  }

  // 2. Measurements -> columns. Each thread owns a band of tile rows, so no two threads share a tile or
  //    a column, and every column sees its measurements in input order: results do not depend on threads.
  const int tile_rows = (g.height() + SphericalGrid::kTileSize - 1) / SphericalGrid::kTileSize;
  const int parts = std::max(1, std::min(threads, tile_rows));
  const ColumnKernel kernel(grid);
  const UniformAxis &az = g.azimuth(), &el = g.elevation();
  std::vector<std::size_t> updates(static_cast<std::size_t>(parts), 0);
  detail::run_parts(parts, [&](int part, int n) {
    const int row_begin = tile_rows * part / n * SphericalGrid::kTileSize;
    const int row_end = std::min(tile_rows * (part + 1) / n * SphericalGrid::kTileSize, g.height());
    ThreadScratch scratch;
    for (const Measurement& m : measurements) {
      const int e0 = std::max(m.elevation_first, row_begin), e1 = std::min(m.elevation_last, row_end - 1);
      if (e0 > e1) continue;
      const double sigma = model.sigma_depth_at(m.rho);
      for (int e = e0; e <= e1; ++e)
        for (int a = m.azimuth_first; a <= m.azimuth_last; ++a) {
          const double b = model.angular_term(az.centre(a) - m.azimuth, el.centre(e) - m.elevation);
          const ColumnIndex c = g.column(a, e);
          kernel.apply(grid.touch(c), m.rho, b, sigma, scratch);
          grid.mark_changed(c);
        }
    }
    updates[static_cast<std::size_t>(part)] = scratch.column_updates;
  });
  for (std::size_t u : updates) report.column_updates += u;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

std::vector<Eigen::Vector3f> depth_image_to_points(const DepthImage& image) {
  const PinholeIntrinsics& k = image.intrinsics;
  try {
    k.validate();
  } catch (const InvalidParameter& e) {
    throw InvalidInput(std::string("depth image intrinsics: ") + e.what());
  }
  const std::size_t expected = static_cast<std::size_t>(k.width) * static_cast<std::size_t>(k.height);
  if (image.pixel_count != expected) {
    std::ostringstream m;
    m << "depth image has " << image.pixel_count << " pixels but the intrinsics say " << k.width << " x " << k.height
      << " = " << expected;
    throw InvalidInput(m.str());
  }
  if (image.depth_m == nullptr) throw InvalidInput("depth image buffer is null");
  std::vector<Eigen::Vector3f> points(expected);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(k.width) + static_cast<std::size_t>(u);
      const float z = image.depth_m[i];
      if (!(z > 0.0f) || !std::isfinite(z)) {
        points[i] = Eigen::Vector3f(nan, nan, nan);
        continue;
      }
      points[i] = Eigen::Vector3f(static_cast<float>((u - k.cx) * z / k.fx), static_cast<float>((v - k.cy) * z / k.fy), z);
    }
  return points;
}

InsertionReport insert_depth_image(SphericalGrid& grid, const SensorModel& model, const DepthImage& image,
                                   const InsertionOptions& options) {
  const auto points = depth_image_to_points(image);
  return insert_points(grid, model, PointSpan::from(points), options);
}

InsertionReport insert_frames(SphericalGrid& grid, const SensorModel& model, const std::vector<PointSpan>& frames,
                              const InsertionOptions& options) {
  InsertionReport total;
  for (const PointSpan& f : frames) total += insert_points(grid, model, f, options);
  return total;
}

}  // namespace occ_improve
