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

// The per-voxel loops below are compiled twice, for x86-64-v3 (AVX2 + FMA: Haswell and later) and for
// baseline x86-64, and the loader picks the clone the CPU supports: vector code without -march=native.
// They vectorise only with -fno-trapping-math (set on this file in CMake); check with -fopt-info-vec.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define OCC_IMPROVE_VECTOR_KERNEL __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define OCC_IMPROVE_VECTOR_KERNEL
#endif

// Beyond this depth offset (in sigmas, as a function of B) |logit P_s| < kSkipEpsilon / 2:
//   the step term deviates from 1/2 by < eps/8 once u > log(4/eps), the peak term is < eps/8 once
//   t^2 + B > log(8/(3 eps)), and |logit(1/2 + d)| < 4.001 |d|. (Half the allowed epsilon: the residues
//   summed over a column's measurements stay well inside the surface's 1e-5 tie tolerance.)
double skip_offset_sigmas(double angular_term) {
  static const double step_limit = std::log(4.0 / kSkipEpsilon), peak_limit = std::log(8.0 / (3.0 * kSkipEpsilon));
  return std::max((step_limit - 4.0 - angular_term) / 2.0, std::sqrt(std::max(0.0, peak_limit - angular_term)));
}

// In exact mode, bins with u < kLinearU take logit P_s = log(1/2) + u: there log(1 + e^u) < 2.1e-9 and the
// peak term is below e^-120 of the step term (t <= -12).
constexpr double kLinearU = -20.0;

// Clamped-mode shortcuts (exact under clamping; see integrate.hpp):
//  - logit P_s <= 0 wherever t <= kNonPositiveT, for every B >= 0: P_s <= 1/2 there because
//    (2/3)(e^-B + e^(2t+4)) <= (2/3)(1 + e^1) = 2.48 < e^(t^2) = 9.49 at t = -1.5 and the gap widens below.
//    Bins of the leading L_min run stay at L_min.
//  - for t <= -3 - B/2 (u <= -2): P_s <= 1/2 e^u (1 + 6.1e-4) (the peak term is (2/3) e^-((t+1)^2 + 3 + 2B)
//    <= 6.1e-4 of the step term) and -log(1 - P_s) <= 0.071, so logit P_s <= log(1/2) + u + 0.072. An
//    untouched bin (L = 0) with log(1/2) + u <= L_min - kBoundMargin therefore ends at L_min: not evaluated.
constexpr double kNonPositiveT = -1.5;
constexpr double kBoundMargin = 0.2;

// e_b = e^-(2 t_b + 4) and g_b = e^-(t_b^2) / 3 for bins [0, n): the B-free factors of e^-u and of the peak
// term, shared by every column of one measurement (a column multiplies both by e^-B).
// With angular_term = B0 != 0 the factor e^-B0 is folded in (for columns with B > kMaxFactoredB).
OCC_IMPROVE_VECTOR_KERNEL
void opdf_bin_terms(const double* centres, int n, double rho_bar, double inv_sigma, float angular_term, float* e,
                    float* g) {
  for (int i = 0; i < n; ++i) {
    const float t = static_cast<float>((centres[i] - rho_bar) * inv_sigma);
    e[i] = fast_exp(-(2.0f * t + 4.0f + angular_term));
    g[i] = fast_exp(-(t * t + angular_term)) * (1.0f / 3.0f);
  }
}

// Columns with B above this take terms of their own: e^-B (fast_exp saturates at e^-87) times e_b would
// lose e^-u where e_b is large.
constexpr double kMaxFactoredB = 60.0;

// logit P_s from the bin terms, with a = e^-B: x = e^-u, P = 1/(2(1+x)) + g and the odds P/(1-P)
// rearranged so that numerator and denominator both stay accurate near P = 1/2.
inline float logit_from_terms(float e, float g, float a) {
  const float x = e * a, gx = g * a * (1.0f + x);
  return fast_log((0.5f + gx) / (0.5f + x - gx));
}

OCC_IMPROVE_VECTOR_KERNEL
void logit_profile_from_terms(const float* e, const float* g, int n, float a, float* out) {
  for (int i = 0; i < n; ++i) out[i] = logit_from_terms(e[i], g[i], a);
}

// Clamped mode works on odds O = e^L during a frame: O <- clamp(O * odds P_s, e^L_min, e^L_max) is eq. 2
// with clamping after each update, without a log per voxel and measurement (one per voxel and frame).
OCC_IMPROVE_VECTOR_KERNEL
void multiply_odds_clamped(float* o, const float* e, const float* g, int n, float a, float omin, float omax) {
  for (int i = 0; i < n; ++i) {
    const float x = e[i] * a, gx = g[i] * a * (1.0f + x);
    const float v = o[i] * ((0.5f + gx) / (0.5f + x - gx));
    o[i] = v < omin ? omin : (v > omax ? omax : v);
  }
}

// The clamps map to each other exactly both ways (whatever rounding the vector clone does), so that
// uniform runs are recognised.
OCC_IMPROVE_VECTOR_KERNEL
void log_odds_to_odds(float* w, int n, float omin, float omax, float lmin, float lmax) {
  for (int i = 0; i < n; ++i) {
    const float l = w[i], o = fast_exp(l);
    w[i] = l <= lmin ? omin : (l >= lmax ? omax : o);
  }
}

OCC_IMPROVE_VECTOR_KERNEL
void odds_to_log_odds(float* w, int n, float omin, float omax, float lmin, float lmax) {
  for (int i = 0; i < n; ++i) {
    const float o = w[i], l = fast_log(o);
    w[i] = o <= omin ? lmin : (o >= omax ? lmax : l);
  }
}

OCC_IMPROVE_VECTOR_KERNEL
void add_logit(float* w, const float* e, const float* g, int n, float a) {
  for (int i = 0; i < n; ++i) w[i] += logit_from_terms(e[i], g[i], a);
}

// DepthAxis::first_centre_above without the call, the division and the libm floor on the hot path: uniform
// bins guess the index in closed form, then the same fix-up against the stored centres makes the result
// identical (the first bin whose centre is > rho). Inverse-depth bins use the generic lookup.
class CentreLocator {
public:
  explicit CentreLocator(const DepthAxis& depth)
      : depth_(depth),
        centres_(depth.centres().data()),
        bins_(depth.bins()),
        uniform_(depth.binning() == DepthBinning::uniform),
        min_(depth.min()),
        bins_per_metre_(depth.bins() / (depth.max() - depth.min())) {}

  int first_centre_above(double rho) const {
    if (!uniform_) return depth_.first_centre_above(rho);
    const double ci = (rho - min_) * bins_per_metre_;  // centre(b) > rho  <=>  b + 0.5 > ci
    int b = !(ci >= -0.5) ? 0 : (ci >= bins_ ? bins_ : static_cast<int>(ci + 0.5));  // floor: ci + 0.5 >= 0
    while (b > 0 && centres_[b - 1] > rho) --b;
    while (b < bins_ && centres_[b] <= rho) ++b;
    return b;
  }

private:
  const DepthAxis& depth_;
  const double* centres_;
  int bins_;
  bool uniform_;
  double min_, bins_per_metre_;
};

struct Measurement {
  double rho, azimuth, elevation;
  int azimuth_first, azimuth_last, elevation_first, elevation_last;
};

// One measurement's bin terms, computed on demand over the bins its columns need ([lo, hi), by bin).
class MeasurementTerms {
public:
  explicit MeasurementTerms(const DepthAxis& depth)
      : locator_(depth),
        centres_(depth.centres().data()),
        bins_(depth.bins()),
        e_(static_cast<std::size_t>(depth.bins())),
        g_(static_cast<std::size_t>(depth.bins())) {}

  void reset(double rho_bar, double sigma, double folded_angular_term = 0.0) {
    rho_bar_ = rho_bar;
    inv_sigma_ = 1.0 / sigma;
    folded_angular_term_ = static_cast<float>(folded_angular_term);
    run_keep_ = locator_.first_centre_above(rho_bar + sigma * kNonPositiveT);
    lo_ = hi_ = 0;
  }
  void ensure(int first, int last) {
    if (first >= last) return;
    if (lo_ == hi_) {
      compute(first, last);
      lo_ = first;
      hi_ = last;
      return;
    }
    // Neighbouring columns ask for a bin or two more: extend by a few at once (short vector loops are
    // mostly scalar prologue and epilogue).
    if (first < lo_) {
      const int from = std::max(first - kTermsMargin, 0);
      compute(from, lo_);
      lo_ = from;
    }
    if (last > hi_) {
      const int to = std::min(last + kTermsMargin, bins_);
      compute(hi_, to);
      hi_ = to;
    }
  }
  /// Bins below it have t <= kNonPositiveT (where logit P_s <= 0 for every B).
  int run_keep() const { return run_keep_; }
  const float* e() const { return e_.data(); }
  const float* g() const { return g_.data(); }

private:
  void compute(int first, int last) {
    opdf_bin_terms(centres_ + first, last - first, rho_bar_, inv_sigma_, folded_angular_term_, e_.data() + first,
                   g_.data() + first);
  }
  static constexpr int kTermsMargin = 4;
  CentreLocator locator_;
  const double* centres_;
  int bins_;
  std::vector<float> e_, g_;
  double rho_bar_ = 0, inv_sigma_ = 1;
  float folded_angular_term_ = 0;
  int run_keep_ = 0, lo_ = 0, hi_ = 0;
};

// Clamped mode: a column's window returns from odds to log-odds this many measurements after its first
// update of the call (3 image rows of an organized 640-wide frame).
constexpr std::size_t kOddsLag = 2048;

// Window bins reserved beyond the current need when a window grows: later measurements of the same
// column usually reach a bin or two further, and each growth would otherwise reallocate.
constexpr std::size_t kWindowSlack = 2;

// Adds one measurement's truncated OPDF to one column. In clamped mode a column's window holds odds from
// its first update in an insertion call (begin_odds) until finish_odds (kOddsLag measurements later, or at
// the end of the call); its uniform run keeps L_min throughout.
class ColumnKernel {
public:
  explicit ColumnKernel(const SphericalGrid& grid) : depth_(grid.geometry().depth()), locator_(depth_) {
    clamped_ = grid.clamped();
    lmin_ = grid.log_odds_min();
    lmax_ = grid.log_odds_max();
    omin_ = fast_exp(lmin_);
    omax_ = fast_exp(lmax_);
  }

  bool clamped() const { return clamped_; }

  /// `terms` are the measurement's, with a = e^-B the column's factor (or B folded in and a = 1).
  void apply(ColumnData& column, double rho_bar, double angular_term, double sigma, MeasurementTerms& terms,
             float a) const {
    const int end = locator_.first_centre_above(rho_bar + sigma * skip_offset_sigmas(angular_term));
    if (clamped_)
      apply_clamped(column, end, rho_bar, angular_term, sigma, a, terms);
    else
      apply_exact(column, end, rho_bar, angular_term, sigma, a, terms);
  }

  void begin_odds(ColumnData& c) const {
    if (c.uniform_end > 0 && c.uniform_value != lmin_) {  // not a run this kernel made (e.g. a loaded map)
      c.window.insert(c.window.begin(), static_cast<std::size_t>(c.uniform_end), c.uniform_value);
      c.uniform_end = 0;
    }
    log_odds_to_odds(c.window.data(), static_cast<int>(c.window.size()), omin_, omax_, lmin_, lmax_);
  }

  void finish_odds(ColumnData& c) const {
    odds_to_log_odds(c.window.data(), static_cast<int>(c.window.size()), omin_, omax_, lmin_, lmax_);
    SphericalGrid::compact(c);
  }

  // A window first grows over the whole support of one measurement, then its front collapses into the
  // run as more measurements agree: without this, a third of the store would be spare capacity. Once
  // per column and call (a column finished early may be converted again and regrow within the call).
  static void release_spare(ColumnData& c) {
    if (c.window.capacity() > c.window.size() + 2 * kWindowSlack) c.window.shrink_to_fit();
  }

private:
  // Capacity for `size` window bins. Clamped mode releases spare capacity at the end of the call
  // (release_spare), so within a call it grows geometrically: a window grows at both ends over many
  // measurements, and an exact fit would reallocate (and copy) at most of them.
  void reserve_window(ColumnData& c, std::size_t size) const {
    if (c.window.capacity() >= size) return;
    c.window.reserve(size + (clamped_ ? size / 2 : 0) + kWindowSlack);
  }

  void grow_window(ColumnData& c, int end, float fill) const {
    const auto needed = static_cast<std::size_t>(end - c.uniform_end);
    if (needed <= c.window.size()) return;
    reserve_window(c, needed);
    c.window.resize(needed, fill);
  }

  // Leading window voxels at the lower clamp join the uniform run.
  void merge_leading_min(ColumnData& c) const {
    std::size_t n = 0;
    while (n < c.window.size() && c.window[n] <= omin_) ++n;
    if (n == 0) return;
    c.window.erase(c.window.begin(), c.window.begin() + static_cast<std::ptrdiff_t>(n));
    c.uniform_end += static_cast<std::int32_t>(n);
    c.uniform_value = lmin_;
  }

  void apply_clamped(ColumnData& c, int end, double rho_bar, double angular_term, double sigma, float a,
                     MeasurementTerms& terms) const {
    // 1. The leading L_min run only changes where t > kNonPositiveT: materialise it from there.
    const int run_keep = terms.run_keep();
    if (c.uniform_end > run_keep && run_keep < end) {
      reserve_window(c, static_cast<std::size_t>(std::max(c.window_end(), end) - run_keep));
      c.window.insert(c.window.begin(), static_cast<std::size_t>(c.uniform_end - run_keep), omin_);
      c.uniform_end = run_keep;
    }
    // 2. An empty window means untouched voxels (L = 0) from the run's end: there the bound on logit P_s
    //    for t <= -3 - B/2 is a depth threshold below which they end at L_min without evaluation. (Window
    //    voxels are simply evaluated: a vector update is cheaper than testing them one by one.)
    int first = c.uniform_end;
    if (c.window.empty()) {
      const double t_bound = -3.0 - 0.5 * angular_term;
      const double t_fresh = 0.5 * (lmin_ - kBoundMargin - (std::log(0.5) + 4.0 + angular_term));
      const int fresh = std::min(locator_.first_centre_above(rho_bar + sigma * std::min(t_bound, t_fresh)), end);
      if (fresh > first) {
        first = fresh;
        c.uniform_end = fresh;
        c.uniform_value = lmin_;
      }
    }
    // 3. The remaining bins up to the support's end, evaluated.
    if (first >= end) return;
    grow_window(c, end, 1.0f);
    terms.ensure(first, end);
    float* o = c.window.data() - c.uniform_end;  // o[b] is bin b
    multiply_odds_clamped(o + first, terms.e() + first, terms.g() + first, end - first, a, omin_, omax_);
    merge_leading_min(c);
  }

  void apply_exact(ColumnData& c, int end, double rho_bar, double angular_term, double sigma, float a,
                   MeasurementTerms& terms) const {
    const double t_linear = (kLinearU - 4.0 - angular_term) / 2.0;
    const int linear_end = std::min(locator_.first_centre_above(rho_bar + sigma * t_linear), end);
    if (c.uniform_end > 0) {  // exact mode keeps every bin in the window
      c.window.insert(c.window.begin(), static_cast<std::size_t>(c.uniform_end), c.uniform_value);
      c.uniform_end = 0;
    }
    grow_window(c, end, 0.0f);
    float* w = c.window.data();
    const double* centres = depth_.centres().data();
    const double offset = std::log(0.5) + 4.0 + angular_term, slope = 2.0 / sigma;
    for (int b = 0; b < linear_end; ++b) w[b] += static_cast<float>(offset + slope * (centres[b] - rho_bar));
    terms.ensure(linear_end, end);
    add_logit(w + linear_end, terms.e() + linear_end, terms.g() + linear_end, end - linear_end, a);
  }

  const DepthAxis& depth_;
  CentreLocator locator_;
  bool clamped_;
  float lmin_, lmax_, omin_, omax_;
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

// Splits the tile rows into `parts` bands of about equal work (column updates), so that neither thread
// waits for the other where the scene is uneven (floor below, far wall or no returns above). Returns
// parts + 1 tile-row boundaries. Any split gives the same result: each column has one owner.
std::vector<int> balanced_bands(const std::vector<Measurement>& measurements, int tile_rows, int parts) {
  std::vector<double> work(static_cast<std::size_t>(tile_rows), 0.0);
  for (const Measurement& m : measurements) {
    const double columns = m.azimuth_last - m.azimuth_first + 1;
    for (int e = m.elevation_first; e <= m.elevation_last; ++e)
      work[static_cast<std::size_t>(e / SphericalGrid::kTileSize)] += columns;
  }
  double total = 0;
  for (double w : work) total += w;
  std::vector<int> begin(static_cast<std::size_t>(parts) + 1, tile_rows);
  begin[0] = 0;
  double sum = 0;
  int part = 1;
  for (int r = 0; r < tile_rows && part < parts; ++r) {
    sum += work[static_cast<std::size_t>(r)];
    if (sum >= total * part / parts) begin[static_cast<std::size_t>(part++)] = r + 1;
  }
  return begin;
}

}  // namespace

void logit_opdf_profile(const double* centres, std::size_t n, double rho_bar, double angular_term, double sigma_rho,
                        float* out) {
  std::vector<float> e(n), g(n);
  const bool factored = angular_term <= kMaxFactoredB;
  opdf_bin_terms(centres, static_cast<int>(n), rho_bar, 1.0 / sigma_rho, factored ? 0.0f : static_cast<float>(angular_term),
                 e.data(), g.data());
  logit_profile_from_terms(e.data(), g.data(), static_cast<int>(n),
                           factored ? fast_exp(static_cast<float>(-angular_term)) : 1.0f, out);
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
  const std::vector<int> band_begin = balanced_bands(measurements, tile_rows, parts);
  const ColumnKernel kernel(grid);
  // One state per column (threads write disjoint columns): untouched this call, window in odds, or
  // converted back to log-odds (spare capacity released at the end of the call).
  enum : std::uint8_t { kUntouched = 0, kInOdds = 1, kFinished = 2 };
  std::vector<std::uint8_t> odds_state(kernel.clamped() ? g.column_count() : 0, 0);
  const UniformAxis &az = g.azimuth(), &el = g.elevation();
  const double inv_sigma_azimuth = 1.0 / model.params().sigma_azimuth_rad;
  const double inv_sigma_elevation = 1.0 / model.params().sigma_elevation_rad;
  std::vector<std::size_t> updates(static_cast<std::size_t>(parts), 0);
  detail::run_parts(parts, [&](int part, int) {
    const int row_begin = band_begin[static_cast<std::size_t>(part)] * SphericalGrid::kTileSize;
    const int row_end = std::min(band_begin[static_cast<std::size_t>(part) + 1] * SphericalGrid::kTileSize, g.height());
    const detail::FlushDenormals flush_denormals;
    MeasurementTerms terms(g.depth()), column_terms(g.depth());
    std::vector<double> azimuth_b(static_cast<std::size_t>(g.width()));
    std::vector<float> azimuth_f(static_cast<std::size_t>(g.width()));
    // Clamped mode: columns whose window holds odds, by the measurement that converted them. A column is
    // converted back once kOddsLag measurements have passed since (organized input has finished with it
    // by then), while its window is still in cache; a later touch converts it again.
    struct OddsColumn {
      ColumnIndex index;
      std::size_t since;
    };
    std::vector<OddsColumn> odds_columns;
    std::size_t odds_head = 0;
    std::vector<ColumnIndex> converted_columns;  // each once
    auto finish_until = [&](std::size_t since_limit) {
      while (odds_head < odds_columns.size() && odds_columns[odds_head].since < since_limit) {
        const ColumnIndex c = odds_columns[odds_head++].index;
        kernel.finish_odds(grid.touch(c));
        odds_state[c] = kFinished;
      }
      if (odds_head > 4096 && odds_head * 2 > odds_columns.size()) {
        odds_columns.erase(odds_columns.begin(), odds_columns.begin() + static_cast<std::ptrdiff_t>(odds_head));
        odds_head = 0;
      }
    };
    std::size_t column_updates = 0;
    for (std::size_t mi = 0; mi < measurements.size(); ++mi) {
      if (mi > kOddsLag) finish_until(mi - kOddsLag);  // the same schedule for any thread count
      const Measurement& m = measurements[mi];
      const int e0 = std::max(m.elevation_first, row_begin), e1 = std::min(m.elevation_last, row_end - 1);
      if (e0 > e1) continue;
      const double sigma = model.sigma_depth_at(m.rho);
      terms.reset(m.rho, sigma);
      // B = B_azimuth + B_elevation and e^-B = e^-B_azimuth e^-B_elevation, per row and per column once.
      for (int a = m.azimuth_first; a <= m.azimuth_last; ++a) {
        const double d = (az.centre(a) - m.azimuth) * inv_sigma_azimuth;
        azimuth_b[static_cast<std::size_t>(a - m.azimuth_first)] = d * d;
        azimuth_f[static_cast<std::size_t>(a - m.azimuth_first)] = fast_exp(static_cast<float>(-d * d));
      }
      for (int e = e0; e <= e1; ++e) {
        const double d = (el.centre(e) - m.elevation) * inv_sigma_elevation;
        const double elevation_b = d * d;
        const float elevation_f = fast_exp(static_cast<float>(-elevation_b));
        for (int a = m.azimuth_first; a <= m.azimuth_last; ++a) {
          const double b = azimuth_b[static_cast<std::size_t>(a - m.azimuth_first)] + elevation_b;
          const float factor = azimuth_f[static_cast<std::size_t>(a - m.azimuth_first)] * elevation_f;
          const ColumnIndex c = g.column(a, e);
          ColumnData& column = grid.touch(c);
          if (kernel.clamped() && odds_state[c] != kInOdds) {
            if (odds_state[c] == kUntouched) converted_columns.push_back(c);
            odds_state[c] = kInOdds;
            kernel.begin_odds(column);
            odds_columns.push_back({c, mi});
          }
          if (b <= kMaxFactoredB) {
            kernel.apply(column, m.rho, b, sigma, terms, factor);
          } else {
            column_terms.reset(m.rho, sigma, b);
            kernel.apply(column, m.rho, b, sigma, column_terms, 1.0f);
          }
          grid.mark_changed(c);
          ++column_updates;
        }
      }
    }
    finish_until(measurements.size());
    for (const ColumnIndex c : converted_columns) ColumnKernel::release_spare(grid.touch(c));
    updates[static_cast<std::size_t>(part)] = column_updates;
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
