#include "occ_improve/integrate/integrate.hpp"

#include "support/fast_math.hpp"
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/timing.hpp"
#include "sensor/opdf_bounds.hpp"
#include "sensor/opdf_kernel.hpp"
#include "support/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <sstream>
#include <string>

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
//   Where B >= log(8/(3 eps)) (14.8: a pixel-native return's diagonal neighbours, B = 24) the peak term is
//   below eps/8 at every depth, so the offset is the step term's alone, (log(4/eps) - 4 - B)/2 (-6.4
//   sigmas at B = 24): such a neighbour only carves free space, and its update stops 6.4 sigmas in front
//   of its return instead of at it.
double skip_offset_sigmas(double angular_term) {
  static const double step_limit = std::log(4.0 / kSkipEpsilon), peak_limit = std::log(8.0 / (3.0 * kSkipEpsilon));
  const double step_offset = (step_limit - 4.0 - angular_term) / 2.0;
  if (angular_term >= peak_limit) return step_offset;
  return std::max(step_offset, std::sqrt(peak_limit - angular_term));
}

// e_b = x and g_b = g of eq. 1 (opdf_kernel.hpp) at B = 0 for bins [0, n): the B-free factors, shared by
// every column of one measurement (a column multiplies both by e^-B).
// With angular_term = B0 != 0 the factor e^-B0 is folded in (for columns with B > kMaxFactoredB).
OCC_IMPROVE_VECTOR_KERNEL
void opdf_bin_terms(const double* centres, int n, double rho_bar, double inv_sigma, float angular_term, float* e,
                    float* g) {
  for (int i = 0; i < n; ++i) {
    const float t = static_cast<float>((centres[i] - rho_bar) * inv_sigma);
    e[i] = detail::opdf_x(t, angular_term);
    g[i] = detail::opdf_g(t, angular_term);
  }
}

// logit P_s from the bin terms, with a = e^-B the column's factor.
inline float logit_from_terms(float e, float g, float a) {
  const detail::OpdfOdds odds = detail::opdf_odds(e * a, g * a);
  return fast_log(odds.n / odds.m);
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
    const detail::OpdfOdds odds = detail::opdf_odds(e[i] * a, g[i] * a);
    const float v = o[i] * (odds.n / odds.m);
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

struct Measurement {
  double rho, azimuth, elevation;  ///< depth coordinate [m] and position in the binning's unit
  double sigma;  ///< depth sigma at rho: computed once, used in every tile the support spans
  int azimuth_first, azimuth_last, elevation_first, elevation_last;
};

// The measurements of one call in input order: each input chunk's valid points at the chunk's start, so
// the threads that convert the chunks write in place and nothing is merged.
struct MeasurementChunks {
  std::vector<Measurement> slots;
  std::vector<std::pair<std::size_t, std::size_t>> ranges;  ///< [begin, end) of each chunk's measurements

  template <typename Visit>
  void for_each(Visit&& visit) const {
    for (const auto& [begin, end] : ranges)
      for (std::size_t i = begin; i < end; ++i) visit(i, slots[i]);
  }
};

// Buffers kept by the calling thread from one call to the next: a frame's measurements alone are
// megabytes, and fresh pages for them every frame cost more than the conversion itself.
struct InsertionWorkspace {
  MeasurementChunks measurements;
  std::vector<std::vector<float>> scratch_rows;  ///< per worker, one depth row per column of a tile
};

// One measurement's bin terms, computed on demand over the bins its columns need. They are computed in
// whole blocks of kTermsBlock bins (the vector width), so the vector loop ends in a scalar remainder only
// at the far end of the depth axis.
class MeasurementTerms {
public:
  explicit MeasurementTerms(const DepthAxis& depth)
      : depth_(depth), e_(static_cast<std::size_t>(depth.bins())), g_(static_cast<std::size_t>(depth.bins())) {}

  void reset(double rho_bar, double sigma, double folded_angular_term = 0.0) {
    rho_bar_ = rho_bar;
    inv_sigma_ = 1.0 / sigma;
    folded_angular_term_ = static_cast<float>(folded_angular_term);
    run_keep_ = depth_.first_centre_above(rho_bar + sigma * kNonPositiveT);
    lo_ = hi_ = 0;
  }
  void ensure(int first, int last) {
    if (first >= last) return;
    first = first / kTermsBlock * kTermsBlock;
    last = std::min((last + kTermsBlock - 1) / kTermsBlock * kTermsBlock, depth_.bins());
    if (lo_ == hi_) {
      compute(first, last);
      lo_ = first;
      hi_ = last;
      return;
    }
    if (first < lo_) {
      compute(first, lo_);
      lo_ = first;
    }
    if (last > hi_) {
      compute(hi_, last);
      hi_ = last;
    }
  }
  /// Bins below it have t <= kNonPositiveT (where logit P_s <= 0 for every B).
  int run_keep() const { return run_keep_; }
  const float* e() const { return e_.data(); }
  const float* g() const { return g_.data(); }

private:
  static constexpr int kTermsBlock = 8;
  void compute(int first, int last) {
    opdf_bin_terms(depth_.centres().data() + first, last - first, rho_bar_, inv_sigma_, folded_angular_term_, e_.data() + first,
                   g_.data() + first);
  }
  const DepthAxis& depth_;
  std::vector<float> e_, g_;
  double rho_bar_ = 0, inv_sigma_ = 1;
  float folded_angular_term_ = 0;
  int run_keep_ = 0, lo_ = 0, hi_ = 0;
};

// One column's voxels while a call updates it: the whole depth axis in a scratch row, in odds e^L in
// clamped mode (one exp and one log per voxel and call instead of a log per voxel and measurement), in
// log-odds in exact mode. Only [run_end, tail) is materialised: bins below run_end hold the leading L_min
// run (clamped mode), bins from tail on are untouched (L = 0). A column is loaded once per call, receives
// all its measurements of the call in input order, and is stored back once, so its window is neither
// reallocated nor shifted per measurement.
struct ColumnScratch {
  float* v = nullptr;  ///< v[b] is bin b
  int run_end = 0, tail = 0;
  bool loaded = false;
};

// Adds one measurement's truncated OPDF to one column.
class ColumnKernel {
public:
  explicit ColumnKernel(const ColumnGrid& grid) : depth_(grid.geometry().depth()) {
    clamped_ = grid.clamped();
    lmin_ = grid.log_odds_min();
    lmax_ = grid.log_odds_max();
    omin_ = fast_exp(lmin_);
    omax_ = fast_exp(lmax_);
  }

  void load(const ColumnData& c, ColumnScratch& s) const {
    const int window_end = c.window_end();
    // A leading run this kernel did not make (exact mode, or a map loaded from elsewhere) is evaluated
    // voxel by voxel like the window.
    const bool own_run = clamped_ && c.uniform_value == lmin_;
    std::fill(s.v, s.v + (own_run ? 0 : c.uniform_end), c.uniform_value);
    std::copy(c.window.begin(), c.window.end(), s.v + c.uniform_end);
    s.run_end = own_run ? c.uniform_end : 0;
    s.tail = window_end;
    if (clamped_) log_odds_to_odds(s.v + s.run_end, s.tail - s.run_end, omin_, omax_, lmin_, lmax_);
    s.loaded = true;
  }

  void store(ColumnScratch& s, ColumnData& c) const {
    if (clamped_) odds_to_log_odds(s.v + s.run_end, s.tail - s.run_end, omin_, omax_, lmin_, lmax_);
    c.uniform_end = s.run_end;
    c.uniform_value = s.run_end > 0 ? lmin_ : 0.0f;
    // Exact capacity unless the old one is close: after the first call a window keeps about its size.
    const auto size = static_cast<std::size_t>(s.tail - s.run_end);
    if (c.window.capacity() < size || c.window.capacity() > size + kWindowSlack)
      std::vector<float>(s.v + s.run_end, s.v + s.tail).swap(c.window);
    else
      c.window.assign(s.v + s.run_end, s.v + s.tail);
    ColumnGrid::compact(c);
    s.loaded = false;
  }

  /// `terms` are the measurement's, with a = e^-B the column's factor (or B folded in and a = 1).
  void apply(ColumnScratch& s, double rho_bar, double angular_term, double sigma, MeasurementTerms& terms,
             float a) const {
    const int end = depth_.first_centre_above(rho_bar + sigma * skip_offset_sigmas(angular_term));
    if (clamped_)
      apply_clamped(s, end, rho_bar, angular_term, sigma, a, terms);
    else
      apply_exact(s, end, rho_bar, angular_term, sigma, a, terms);
  }

private:
  // A window may keep this many spare bins of capacity from an earlier call before it is reallocated.
  static constexpr std::size_t kWindowSlack = 4;

  static void extend_tail(ColumnScratch& s, int end, float fill) {
    if (end <= s.tail) return;
    std::fill(s.v + s.tail, s.v + end, fill);
    s.tail = end;
  }

  void apply_clamped(ColumnScratch& s, int end, double rho_bar, double angular_term, double sigma, float a,
                     MeasurementTerms& terms) const {
    float* o = s.v;
    // 1. The leading L_min run only changes where t > kNonPositiveT: materialise it from there.
    const int run_keep = terms.run_keep();
    if (angular_term >= kNegligibleB && s.run_end >= run_keep) return;
    if (s.run_end > run_keep && run_keep < end) {
      std::fill(o + run_keep, o + s.run_end, omin_);
      s.run_end = run_keep;
    }
    // 2. Nothing materialised means untouched voxels (L = 0) from the run's end: there the bound on
    //    logit P_s for t <= -3 - B/2 is a depth threshold below which they end at L_min without
    //    evaluation. (Materialised voxels are simply evaluated: a vector update is cheaper than testing
    //    them one by one.)
    int first = s.run_end;
    if (s.run_end == s.tail) {
      const double t_bound = -3.0 - 0.5 * angular_term;
      const double t_fresh = 0.5 * (lmin_ - kBoundMargin - (std::log(0.5) + 4.0 + angular_term));
      const int fresh = std::min(depth_.first_centre_above(rho_bar + sigma * std::min(t_bound, t_fresh)), end);
      if (fresh > first) first = s.run_end = s.tail = fresh;
    }
    // 3. The remaining bins up to the support's end, evaluated; leading voxels at the lower clamp join
    //    the run.
    if (first >= end) return;
    extend_tail(s, end, 1.0f);
    terms.ensure(first, end);
    multiply_odds_clamped(o + first, terms.e() + first, terms.g() + first, end - first, a, omin_, omax_);
    while (s.run_end < s.tail && o[s.run_end] <= omin_) ++s.run_end;
  }

  void apply_exact(ColumnScratch& s, int end, double rho_bar, double angular_term, double sigma, float a,
                   MeasurementTerms& terms) const {
    const double t_linear = (kLinearU - 4.0 - angular_term) / 2.0;
    const int linear_end = std::min(depth_.first_centre_above(rho_bar + sigma * t_linear), end);
    extend_tail(s, end, 0.0f);
    float* w = s.v;
    const double* centres = depth_.centres().data();
    const double offset = std::log(0.5) + 4.0 + angular_term, slope = 2.0 / sigma;
    for (int b = 0; b < linear_end; ++b) w[b] += static_cast<float>(offset + slope * (centres[b] - rho_bar));
    terms.ensure(linear_end, end);
    add_logit(w + linear_end, terms.e() + linear_end, terms.g() + linear_end, end - linear_end, a);
  }

  const DepthAxis& depth_;
  bool clamped_;
  float lmin_, lmax_, omin_, omax_;
};

bool to_measurement(const float* p, const GridGeometry& g, const SensorModel& model, Measurement& m,
                    InsertionReport& report) {
  const double x = p[0], y = p[1], z = p[2];
  if (!is_valid_point(x, y, z)) {
    ++report.skipped_invalid;
    return false;
  }
  RayPosition r;
  if (!g.project(x, y, z, r)) {
    ++report.skipped_outside_fov;
    return false;
  }
  m.rho = r.depth;
  m.sigma = model.sigma_depth_at(r.depth);
  m.azimuth = r.horizontal;
  m.elevation = r.vertical;
  const double ka = model.support_horizontal(g.binning()), ke = model.support_vertical(g.binning());
  g.azimuth().overlapping(r.horizontal - ka, r.horizontal + ka, m.azimuth_first, m.azimuth_last);
  g.elevation().overlapping(r.vertical - ke, r.vertical + ke, m.elevation_first, m.elevation_last);
  if (r.depth >= g.depth().max()) ++report.beyond_depth_range;
  ++report.points_inserted;
  return true;
}

// Splits the tile rows into `parts` bands of about equal work (column updates), so that neither thread
// waits for the other where the scene is uneven (floor below, far wall or no returns above). Returns
// parts + 1 tile-row boundaries. Any split gives the same result: each column has one owner.
std::vector<int> balanced_bands(const MeasurementChunks& measurements, int tile_rows, int parts) {
  std::vector<double> work(static_cast<std::size_t>(tile_rows), 0.0);
  measurements.for_each([&](std::size_t, const Measurement& m) {
    const double columns = m.azimuth_last - m.azimuth_first + 1;
    for (int e = m.elevation_first; e <= m.elevation_last; ++e)
      work[static_cast<std::size_t>(e / ColumnGrid::kTileSize)] += columns;
  });
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

namespace {

// Both public insert_points: `surface` null, or the surface to keep current and where to list its changes.
InsertionReport insert(ColumnGrid& grid, const SensorModel& model, PointSpan points, const InsertionOptions& options,
                       SurfaceMap* surface, std::vector<ColumnIndex>* surface_changed) {
  const auto start = SteadyClock::now();
  options.validate();
  if (points.count > 0 && points.xyz == nullptr) throw InvalidInput("insert_points: null point buffer with count > 0");
  if (points.stride_floats < 3) {
    std::ostringstream m;
    m << "insert_points: stride_floats = " << points.stride_floats << " is invalid: must be >= 3";
    throw InvalidInput(m.str());
  }
  if (points.count > std::numeric_limits<std::uint32_t>::max())  // tiles index measurements with 32 bits
    throw InvalidInput("insert_points: more than 2^32 - 1 points in one call; insert them in parts");
  const GridGeometry& g = grid.geometry();
  const int threads = detail::resolve_thread_count(options.threads);

  // 1. Points -> measurements, in input order (parallel over contiguous chunks).
  thread_local InsertionWorkspace workspace;
  MeasurementChunks& measurements = workspace.measurements;
  if (measurements.slots.size() < points.count) measurements.slots.resize(points.count);
  measurements.ranges.assign(static_cast<std::size_t>(threads), {0, 0});
  std::vector<InsertionReport> chunk_reports(static_cast<std::size_t>(threads));
  detail::run_parts(threads, [&](int part, int parts) {
    const std::size_t begin = points.count * static_cast<std::size_t>(part) / static_cast<std::size_t>(parts);
    const std::size_t end = points.count * static_cast<std::size_t>(part + 1) / static_cast<std::size_t>(parts);
    std::size_t kept = begin;
    for (std::size_t i = begin; i < end; ++i)
      if (poll_stop(i), to_measurement(points.xyz + i * points.stride_floats, g, model, measurements.slots[kept],
                         chunk_reports[static_cast<std::size_t>(part)]))
        ++kept;
    measurements.ranges[static_cast<std::size_t>(part)] = {begin, kept};
  });
  InsertionReport report;
  report.points_received = points.count;
  for (const InsertionReport& r : chunk_reports) report += r;

  // 2. Measurements -> columns, tile by tile. Each thread owns a band of tile rows, so no two threads
  //    share a tile or a column, and every column sees its measurements in input order: results do not
  //    depend on threads. Within a tile, a measurement's depth terms are computed once for all its
  //    columns there, and the tile's columns stay in cache while its measurements are applied.
  constexpr int kTile = ColumnGrid::kTileSize;
  const int tile_rows = (g.height() + kTile - 1) / kTile, tile_columns = (g.width() + kTile - 1) / kTile;
  const int parts = std::max(1, std::min(threads, tile_rows));
  const std::vector<int> band_begin = balanced_bands(measurements, tile_rows, parts);
  const ColumnKernel kernel(grid);
  const UniformAxis &az = g.azimuth(), &el = g.elevation();
  const double inv_sigma_azimuth = 1.0 / model.sigma_horizontal(g.binning());
  const double inv_sigma_elevation = 1.0 / model.sigma_vertical(g.binning());
  const auto depth_bins = static_cast<std::size_t>(g.depth().bins());
  std::vector<std::size_t> updates(static_cast<std::size_t>(parts), 0);
  std::vector<std::vector<ColumnIndex>> changed(surface ? static_cast<std::size_t>(parts) : 0);
  auto& workspace_rows = workspace.scratch_rows;
  if (workspace_rows.size() < static_cast<std::size_t>(parts)) workspace_rows.resize(static_cast<std::size_t>(parts));
  detail::run_parts(parts, [&](int part, int) {
    const int first_tile_row = band_begin[static_cast<std::size_t>(part)];
    const int end_tile_row = band_begin[static_cast<std::size_t>(part) + 1];
    const detail::FlushDenormals flush_denormals;
    // 2a. The measurements of each tile of the band, in input order (a counting sort).
    const auto band_tiles = static_cast<std::size_t>(end_tile_row - first_tile_row) * static_cast<std::size_t>(tile_columns);
    auto for_each_tile = [&](const Measurement& m, auto&& visit) {
      const int row_first = std::max(m.elevation_first / kTile, first_tile_row);
      const int row_last = std::min(m.elevation_last / kTile, end_tile_row - 1);
      for (int r = row_first; r <= row_last; ++r)
        for (int t = m.azimuth_first / kTile; t <= m.azimuth_last / kTile; ++t)
          visit(static_cast<std::size_t>(r - first_tile_row) * static_cast<std::size_t>(tile_columns) + static_cast<std::size_t>(t));
    };
    std::vector<std::uint32_t> tile_begin(band_tiles + 1, 0);
    measurements.for_each([&](std::size_t, const Measurement& m) { for_each_tile(m, [&](std::size_t t) { ++tile_begin[t + 1]; }); });
    for (std::size_t t = 0; t < band_tiles; ++t) tile_begin[t + 1] += tile_begin[t];
    std::vector<std::uint32_t> tile_items(tile_begin.back()), next(tile_begin.begin(), tile_begin.end() - 1);
    measurements.for_each([&](std::size_t mi, const Measurement& m) {
      for_each_tile(m, [&](std::size_t t) { tile_items[next[t]++] = static_cast<std::uint32_t>(mi); });
    });

    // 2b. Tile by tile: load a column on its first measurement, store it after the tile's last.
    std::vector<float>& scratch_rows = workspace_rows[static_cast<std::size_t>(part)];
    scratch_rows.resize(kTile * kTile * depth_bins);
    ColumnScratch scratch[kTile * kTile];
    for (int i = 0; i < kTile * kTile; ++i) scratch[i].v = scratch_rows.data() + static_cast<std::size_t>(i) * depth_bins;
    MeasurementTerms terms(g.depth()), column_terms(g.depth());
    float azimuth_factor[kTile];
    double azimuth_b[kTile];
    std::size_t column_updates = 0;
    for (std::size_t t = 0; t < band_tiles; ++t) {
      if (tile_begin[t] == tile_begin[t + 1]) continue;
      throw_if_stop_requested();  // per tile: up to 64 columns' measurements
      const int a_first = static_cast<int>(t % static_cast<std::size_t>(tile_columns)) * kTile;
      const int e_first = (first_tile_row + static_cast<int>(t / static_cast<std::size_t>(tile_columns))) * kTile;
      const int a_last = std::min(a_first + kTile, g.width()) - 1, e_last = std::min(e_first + kTile, g.height()) - 1;
      for (std::uint32_t k = tile_begin[t]; k < tile_begin[t + 1]; ++k) {
        const Measurement& m = measurements.slots[tile_items[k]];
        const int a0 = std::max(m.azimuth_first, a_first), a1 = std::min(m.azimuth_last, a_last);
        const int e0 = std::max(m.elevation_first, e_first), e1 = std::min(m.elevation_last, e_last);
        const double sigma = m.sigma;
        terms.reset(m.rho, sigma);
        // B = B_azimuth + B_elevation and e^-B = e^-B_azimuth e^-B_elevation, per row and per column once.
        for (int a = a0; a <= a1; ++a) {
          const double d = (az.centre(a) - m.azimuth) * inv_sigma_azimuth;
          azimuth_b[a - a_first] = d * d;
          azimuth_factor[a - a_first] = fast_exp(static_cast<float>(-d * d));
        }
        for (int e = e0; e <= e1; ++e) {
          const double d = (el.centre(e) - m.elevation) * inv_sigma_elevation;
          const double elevation_b = d * d;
          const float elevation_factor = fast_exp(static_cast<float>(-elevation_b));
          for (int a = a0; a <= a1; ++a) {
            ColumnScratch& s = scratch[(e - e_first) * kTile + (a - a_first)];
            if (!s.loaded) kernel.load(grid.touch(g.column(a, e)), s);
            const double b = azimuth_b[a - a_first] + elevation_b;
            if (b <= kMaxFactoredB) {
              kernel.apply(s, m.rho, b, sigma, terms, azimuth_factor[a - a_first] * elevation_factor);
            } else {
              column_terms.reset(m.rho, sigma, b);
              kernel.apply(s, m.rho, b, sigma, column_terms, 1.0f);
            }
            ++column_updates;
          }
        }
      }
      for (int e = e_first; e <= e_last; ++e)
        for (int a = a_first; a <= a_last; ++a) {
          ColumnScratch& s = scratch[(e - e_first) * kTile + (a - a_first)];
          if (!s.loaded) continue;
          const ColumnIndex c = g.column(a, e);
          ColumnData& column = grid.touch(c);
          kernel.store(s, column);
          grid.mark_changed(c);
          // Columns of this thread's band only.
          if (surface && refresh_column_surface(grid, c, &column, *surface))
            changed[static_cast<std::size_t>(part)].push_back(c);
        }
    }
    updates[static_cast<std::size_t>(part)] = column_updates;
  });
  for (std::size_t u : updates) report.column_updates += u;
  if (surface_changed) {
    surface_changed->clear();
    for (const auto& part : changed) surface_changed->insert(surface_changed->end(), part.begin(), part.end());
  }
  report.seconds = seconds_since(start);
  return report;
}

}  // namespace

InsertionReport insert_points(ColumnGrid& grid, const SensorModel& model, PointSpan points,
                              const InsertionOptions& options) {
  return insert(grid, model, points, options, nullptr, nullptr);
}

InsertionReport insert_points(ColumnGrid& grid, const SensorModel& model, PointSpan points, SurfaceMap& surface,
                              std::vector<ColumnIndex>& surface_changed, const InsertionOptions& options) {
  const GridGeometry& g = grid.geometry();
  require_shape("surface map", surface.shape(), "the grid", ColumnShape::of_grid(g.width(), g.height()));
  return insert(grid, model, points, options, &surface, &surface_changed);
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

void InsertionOptions::validate() const {
  const std::string range = "in [0, " + std::to_string(kMaxThreads) + "] (0: all cores)";
  detail::require_parameter(threads >= 0 && threads <= kMaxThreads, "threads", threads, range.c_str());
}

void require_grid_camera(const GridGeometry& geometry, const PinholeIntrinsics& intrinsics) {
  const std::optional<PinholeIntrinsics>& camera = geometry.params().camera;
  if (!camera || same_camera(*camera, intrinsics)) return;
  throw InvalidParameter("intrinsics (" + camera_text(intrinsics) + ") are not the camera the grid was built for (" +
                         camera_text(*camera) + "): its pixels would fall in other columns or outside the field " +
                         "of view; build the preset from these intrinsics");
}

InsertionReport insert_depth_image(ColumnGrid& grid, const SensorModel& model, const DepthImage& image,
                                   const InsertionOptions& options) {
  require_grid_camera(grid.geometry(), image.intrinsics);
  const auto points = depth_image_to_points(image);
  return insert_points(grid, model, PointSpan::from(points), options);
}

InsertionReport insert_frames(ColumnGrid& grid, const SensorModel& model, const std::vector<PointSpan>& frames,
                              const InsertionOptions& options) {
  InsertionReport total;
  for (const PointSpan& f : frames) total += insert_points(grid, model, f, options);
  return total;
}

}  // namespace occ_improve
