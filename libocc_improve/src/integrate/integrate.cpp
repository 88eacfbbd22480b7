// Insertion, step 2 (eq. 2): one measurement's truncated OPDF added to a column (the column kernel and
// its vector loops, with eq. 1's skip bounds), and a band of tile rows updated tile by tile. Step 1
// (points -> measurements, band scheduling): measurements.cpp; the public entry points: insert.cpp;
// depth images: depth_image.cpp.
#include "integrate/column_updates.hpp"

#include "support/fast_math.hpp"
#include "occ_improve/cancel.hpp"
#include "sensor/opdf_bounds.hpp"
#include "sensor/opdf_kernel.hpp"
#include "support/parallel.hpp"
#include "support/vector_clones.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <tuple>
#include <utility>

namespace occ_improve {

namespace {

using detail::fast_exp;
using detail::fast_log;
using detail::Measurement;
using detail::MeasurementChunks;

// The per-voxel loops below are compiled for x86-64-v3 (AVX2 + FMA: Haswell and later) beside baseline
// x86-64 (support/vector_clones.hpp).
#define OCC_IMPROVE_VECTOR_KERNEL OCC_IMPROVE_CLONES("arch=x86-64-v3")

// Beyond this depth offset (in sigmas, as a function of B) |logit P_s| < kSkipEpsilon / 2:
//   the step term deviates from 1/2 by < eps/8 once u > log(4/eps), the peak term is < eps/8 once
//   t^2 + B > log(8/(3 eps)), and |logit(1/2 + d)| < 4.001 |d|. (Half the allowed epsilon: the residues
//   summed over a column's measurements stay well inside the surface's 1e-5 tie tolerance.)
//   Where B >= log(8/(3 eps)) (14.8: a pixel-native return's diagonal neighbours, B = 24) the peak term is
//   below eps/8 at every depth, so the offset is the step term's alone, (log(4/eps) - 4 - B)/2 (-6.4
//   sigmas at B = 24): such a neighbour only carves free space, and its update stops 6.4 sigmas in front
//   of its return instead of at it.
const double kStepLimit = std::log(4.0 / kSkipEpsilon), kPeakLimit = std::log(8.0 / (3.0 * kSkipEpsilon));
double skip_offset_sigmas(double angular_term) {
  const double step_offset = (kStepLimit - 4.0 - angular_term) / 2.0;
  if (angular_term >= kPeakLimit) return step_offset;
  return std::max(step_offset, std::sqrt(kPeakLimit - angular_term));
}

// Bound b) of integrate.hpp: at t <= this offset (in sigmas) t <= -3 - B/2 (u <= -2, where logit P_s <=
// log(1/2) + u + 0.072) and log(1/2) + u <= L_min - kBoundMargin, so logit P_s <= L_min - 0.128 and one
// such measurement takes a voxel holding L <= 0 to L_min.
double to_lmin_offset_sigmas(double angular_term, float lmin) {
  const double t_bound = -3.0 - 0.5 * angular_term;
  const double t_fresh = 0.5 * (lmin - kBoundMargin - (std::log(0.5) + 4.0 + angular_term));
  return std::min(t_bound, t_fresh);
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

// The loops below over a scratch row or a measurement's terms run over whole aligned blocks of
// kLaneBlock bins: [first, end) widened to block bounds, the bins outside [first, end) written back
// unchanged. Scratch rows and terms are padded to whole blocks and aligned (aligned_floats), so every loop
// is the vector body alone: no scalar remainder, no peeling, which on the 8-14 bins a (measurement,
// column) pair updates cost more than the vector work itself.
constexpr int kLaneBlock = 8;
constexpr std::size_t kLaneBlockBytes = kLaneBlock * sizeof(float);
constexpr int block_floor(int i) { return i / kLaneBlock * kLaneBlock; }
constexpr int block_ceil(int i) { return (i + kLaneBlock - 1) / kLaneBlock * kLaneBlock; }

// The row, with the compiler told that it starts on a block boundary.
template <typename T>
T* block_aligned(T* row) {
#if defined(__GNUC__)
  return static_cast<T*>(__builtin_assume_aligned(row, kLaneBlockBytes));
#else
  return row;
#endif
}

// A buffer of `count` floats (a multiple of kLaneBlock) in `storage`, starting on a block boundary.
float* aligned_floats(std::vector<float>& storage, std::size_t count) {
  storage.resize(count + kLaneBlock);
  const auto misalignment = reinterpret_cast<std::uintptr_t>(storage.data()) % kLaneBlockBytes;
  return storage.data() + (misalignment ? (kLaneBlockBytes - misalignment) / sizeof(float) : 0);
}

// Clamped mode works on odds O = e^L during a call: O <- clamp(O * odds P_s, e^L_min, e^L_max) is eq. 2
// with clamping after each update, without a log per voxel and measurement (one exp and one log per voxel
// the call reaches, ColumnScratch).
OCC_IMPROVE_VECTOR_KERNEL
void multiply_odds_clamped(float* o, const float* e, const float* g, int first, int end, float a, float omin,
                           float omax) {
  const int from = block_floor(first), to = block_ceil(end);
  o = block_aligned(o);
  e = block_aligned(e);
  g = block_aligned(g);
  for (int i = from; i < to; ++i) {
    const detail::OpdfOdds odds = detail::opdf_odds(e[i] * a, g[i] * a);
    const float v = o[i] * (odds.n / odds.m);
    const float clamped = v < omin ? omin : (v > omax ? omax : v);
    o[i] = i >= first && i < end ? clamped : o[i];
  }
}

// The clamps map to each other exactly both ways (whatever rounding the vector clone does), so that
// uniform runs are recognised.
OCC_IMPROVE_VECTOR_KERNEL
void log_odds_to_odds(float* w, int first, int end, float omin, float omax, float lmin, float lmax) {
  const int from = block_floor(first), to = block_ceil(end);
  w = block_aligned(w);
  for (int i = from; i < to; ++i) {
    const float l = w[i], o = fast_exp(l);
    const float converted = l <= lmin ? omin : (l >= lmax ? omax : o);
    w[i] = i >= first && i < end ? converted : l;
  }
}

OCC_IMPROVE_VECTOR_KERNEL
void odds_to_log_odds(float* w, int first, int end, float omin, float omax, float lmin, float lmax) {
  const int from = block_floor(first), to = block_ceil(end);
  w = block_aligned(w);
  for (int i = from; i < to; ++i) {
    const float o = w[i], l = fast_log(o);
    const float converted = o <= omin ? lmin : (o >= omax ? lmax : l);
    w[i] = i >= first && i < end ? converted : o;
  }
}

OCC_IMPROVE_VECTOR_KERNEL
void add_logit(float* w, const float* e, const float* g, int n, float a) {
  for (int i = 0; i < n; ++i) w[i] += logit_from_terms(e[i], g[i], a);
}

// One measurement's bin terms, computed on demand over the bins its columns need, in whole blocks of
// kLaneBlock bins (the depth axis padded to whole blocks: the padding's terms are never read as bins).
class MeasurementTerms {
public:
  explicit MeasurementTerms(const DepthAxis& depth) : depth_(depth) {
    const auto n = static_cast<std::size_t>(block_ceil(depth.bins()));
    e_ = aligned_floats(e_storage_, n);
    g_ = aligned_floats(g_storage_, n);
    centres_.assign(depth.centres().begin(), depth.centres().end());
    centres_.resize(n, depth.centres().back());
  }

  void reset(double rho_bar, double sigma, double folded_angular_term = 0.0) {
    rho_bar_ = rho_bar;
    inv_sigma_ = 1.0 / sigma;
    folded_angular_term_ = static_cast<float>(folded_angular_term);
    run_keep_ = depth_.first_centre_above(rho_bar + sigma * kNonPositiveT);
    lo_ = hi_ = 0;
  }
  void ensure(int first, int last) {
    if (first >= last) return;
    first = block_floor(first);
    last = block_ceil(last);
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
  const float* e() const { return e_; }
  const float* g() const { return g_; }

private:
  void compute(int first, int last) {
    opdf_bin_terms(centres_.data() + first, last - first, rho_bar_, inv_sigma_, folded_angular_term_, e_ + first, g_ + first);
  }
  const DepthAxis& depth_;
  std::vector<float> e_storage_, g_storage_;
  float *e_ = nullptr, *g_ = nullptr;
  std::vector<double> centres_;  ///< the axis's, the padding repeating the last
  double rho_bar_ = 0, inv_sigma_ = 1;
  float folded_angular_term_ = 0;
  int run_keep_ = 0, lo_ = 0, hi_ = 0;
};

// One column's voxels while a call updates it: the whole depth axis in a scratch row. Only [run_end, tail)
// is materialised: bins below run_end hold the leading L_min run (clamped mode), bins from tail on are
// untouched (L = 0). Clamped mode holds [run_end, odds_end) in odds e^L (one exp and one log per voxel
// and call instead of a log per voxel and measurement): the bins the call's measurements have reached so
// far. The bins behind stay in log-odds and are stored back bit for bit: a conversion there and back
// would move them by up to 5e-7 + 2e-7 |L| per call, and a small shot's columns are mostly such bins. Exact mode
// holds log-odds throughout. A column is loaded once per call, receives all its measurements of the call
// in input order, and is stored back once, so its window is neither reallocated nor shifted per
// measurement.
struct ColumnScratch {
  float* v = nullptr;  ///< v[b] is bin b
  int run_end = 0, tail = 0;
  int odds_end = 0;  ///< clamped mode: run_end <= odds_end <= tail
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
    s.run_end = s.odds_end = own_run ? c.uniform_end : 0;
    s.tail = window_end;
    s.loaded = true;
  }

  /// Clamped mode, right after load (all in log-odds): bins below `cut` (FreeSpaceBound) that hold L <= 0
  /// end the call at L_min, so the leading run takes them before any measurement is applied; the run stops
  /// early at a bin with L > 0, which is evaluated as usual.
  void extend_run(ColumnScratch& s, int cut) const {
    if (cut > s.run_end) {
      const int materialised_end = std::min(cut, s.tail);
      int b = s.run_end;
      while (b < materialised_end && s.v[b] <= 0.0f) ++b;
      s.run_end = b < materialised_end ? b : cut;
      s.tail = std::max(s.tail, s.run_end);
    }
    s.odds_end = s.run_end;
  }

  /// The column's new contents, back in log-odds in its scratch row (valid until the row is loaded again).
  ColumnContents contents(ColumnScratch& s, ColumnIndex column) const {
    if (clamped_) odds_to_log_odds(s.v, s.run_end, s.odds_end, omin_, omax_, lmin_, lmax_);
    s.loaded = false;
    return {column, s.run_end, s.run_end > 0 ? lmin_ : 0.0f, s.v + s.run_end, static_cast<std::uint32_t>(s.tail - s.run_end)};
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
      const int fresh = std::min(depth_.first_centre_above(rho_bar + sigma * to_lmin_offset_sigmas(angular_term, lmin_)), end);
      if (fresh > first) first = s.run_end = s.tail = s.odds_end = fresh;
    }
    // 3. The remaining bins up to the support's end, in odds (materialised ones converted on first reach,
    //    new ones L = 0, odds 1), evaluated; leading voxels at the lower clamp join the run (in odds, then
    //    in log-odds behind).
    if (first >= end) return;
    if (end > s.odds_end) {
      const int materialised_end = std::min(end, s.tail);
      if (materialised_end > s.odds_end)
        log_odds_to_odds(o, s.odds_end, materialised_end, omin_, omax_, lmin_, lmax_);
      extend_tail(s, end, 1.0f);
      s.odds_end = end;
    }
    terms.ensure(first, end);
    multiply_odds_clamped(o, terms.e(), terms.g(), first, end, a, omin_, omax_);
    while (s.run_end < s.odds_end && o[s.run_end] <= omin_) ++s.run_end;
    if (s.run_end == s.odds_end) {
      while (s.run_end < s.tail && o[s.run_end] <= lmin_) ++s.run_end;
      s.odds_end = s.run_end;
    }
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

// The measurements of each tile of a band of tile rows, in input order (a counting sort over the band's
// rows of TileRows): tile t's are items[begin[t]] .. items[begin[t + 1] - 1], tiles numbered row by row
// within the band.
struct BandTiles {
  int first_tile_row, end_tile_row, tile_columns;
  std::vector<std::uint32_t> begin, items;

  BandTiles(const MeasurementChunks& measurements, const detail::TileRows& rows, int first_row, int end_row, int columns)
      : first_tile_row(first_row), end_tile_row(end_row), tile_columns(columns) {
    begin.assign(count() + 1, 0);
    for_each_tile(measurements, rows, [&](std::size_t t, std::uint32_t) { ++begin[t + 1]; });
    for (std::size_t t = 0; t < count(); ++t) begin[t + 1] += begin[t];
    std::vector<std::uint32_t> next(begin.begin(), begin.end() - 1);
    items.resize(begin.back());
    for_each_tile(measurements, rows, [&](std::size_t t, std::uint32_t mi) { items[next[t]++] = mi; });
  }
  std::size_t count() const {
    return static_cast<std::size_t>(end_tile_row - first_tile_row) * static_cast<std::size_t>(tile_columns);
  }

private:
  static constexpr int kTile = ColumnGrid::kTileSize;
  // visit(tile, measurement) for each tile of the band each measurement overlaps, row by row in input order.
  template <typename Visit>
  void for_each_tile(const MeasurementChunks& measurements, const detail::TileRows& rows, Visit&& visit) const {
    for (int r = first_tile_row; r < end_tile_row; ++r) {
      const std::size_t row_start = static_cast<std::size_t>(r - first_tile_row) * static_cast<std::size_t>(tile_columns);
      for (std::uint32_t k = rows.begin[static_cast<std::size_t>(r)]; k < rows.begin[static_cast<std::size_t>(r) + 1]; ++k) {
        poll_stop(k);  // a dense band holds millions of measurements
        const std::uint32_t mi = rows.items[k];
        const Measurement& m = measurements.slots[mi];
        for (int t = m.azimuth_first / kTile; t <= m.azimuth_last / kTile; ++t) visit(row_start + static_cast<std::size_t>(t), mi);
      }
    }
  }
};

// One tile's columns while its measurements are applied: a column is loaded on its first measurement and
// stored after the tile's last. Within the tile, a measurement's depth terms are computed once for all its
// columns, and B = B_azimuth + B_elevation, e^-B = e^-B_azimuth e^-B_elevation, once per row and column.
class TileUpdate {
public:
  TileUpdate(ColumnGrid& grid, const SensorModel& model, std::vector<float>& scratch_rows)
      : grid_(grid), g_(grid.geometry()), kernel_(grid), terms_(g_.depth()), column_terms_(g_.depth()),
        inv_sigma_azimuth_(1.0 / model.sigma_horizontal(g_.binning())),
        inv_sigma_elevation_(1.0 / model.sigma_vertical(g_.binning())), lmin_(grid.log_odds_min()) {
    // Rows of whole lane blocks, each starting on a block boundary: the kernel's loops run over whole blocks.
    const auto row_floats = static_cast<std::size_t>(block_ceil(g_.depth().bins()));
    float* rows = aligned_floats(scratch_rows, kTile * kTile * row_floats);
    for (int i = 0; i < kTile * kTile; ++i) scratch_[i].v = rows + static_cast<std::size_t>(i) * row_floats;
  }

  void start(int a_first, int e_first) {
    a_first_ = a_first;
    e_first_ = e_first;
    a_last_ = std::min(a_first + kTile, g_.width()) - 1;
    e_last_ = std::min(e_first + kTile, g_.height()) - 1;
    std::fill(std::begin(free_space_), std::end(free_space_), FreeSpaceBound{});
  }

  /// Clamped mode: folds one of the tile's measurements into the FreeSpaceBound of its columns. Called for
  /// every measurement of the tile before the first apply.
  /// front_m takes every measurement of the column; to_lmin_m only the one at the measurement's smallest B
  /// in the tile (its own column where the tile holds it): a bound from some of the measurements is still
  /// a bound, and that one reaches furthest.
  void bound(const Measurement& m) {
    const TileColumns r = columns_of(m);
    const double front_m = m.rho + m.sigma * kNonPositiveT;
    for (int e = r.e0; e <= r.e1; ++e)
      for (int a = r.a0; a <= r.a1; ++a) {
        double& f = free_space_[(e - e_first_) * kTile + (a - a_first_)].front_m;
        f = std::min(f, front_m);
      }
    int a_near = r.a0, e_near = r.e0;
    double azimuth_b = azimuth_term(a_near, m), elevation_b = elevation_term(e_near, m);
    for (int a = r.a0 + 1; a <= r.a1; ++a)
      if (const double b = azimuth_term(a, m); b < azimuth_b) std::tie(a_near, azimuth_b) = std::make_pair(a, b);
    for (int e = r.e0 + 1; e <= r.e1; ++e)
      if (const double b = elevation_term(e, m); b < elevation_b) std::tie(e_near, elevation_b) = std::make_pair(e, b);
    double& to_lmin_m = free_space_[(e_near - e_first_) * kTile + (a_near - a_first_)].to_lmin_m;
    to_lmin_m = std::max(to_lmin_m, m.rho + m.sigma * to_lmin_offset_sigmas(azimuth_b + elevation_b, lmin_));
  }

  void apply(const Measurement& m) {
    const TileColumns r = columns_of(m);
    const double sigma = m.sigma;
    terms_.reset(m.rho, sigma);
    for (int a = r.a0; a <= r.a1; ++a) {
      azimuth_b_[a - a_first_] = azimuth_term(a, m);
      azimuth_factor_[a - a_first_] = fast_exp(static_cast<float>(-azimuth_b_[a - a_first_]));
    }
    for (int e = r.e0; e <= r.e1; ++e) {
      const double elevation_b = elevation_term(e, m);
      const float elevation_factor = fast_exp(static_cast<float>(-elevation_b));
      for (int a = r.a0; a <= r.a1; ++a) {
        const int i = (e - e_first_) * kTile + (a - a_first_);
        ColumnScratch& s = scratch_[i];
        if (!s.loaded) load(g_.column(a, e), i);
        const double b = azimuth_b_[a - a_first_] + elevation_b;
        if (b <= kMaxFactoredB) {
          kernel_.apply(s, m.rho, b, sigma, terms_, azimuth_factor_[a - a_first_] * elevation_factor);
        } else {
          column_terms_.reset(m.rho, sigma, b);
          kernel_.apply(s, m.rho, b, sigma, column_terms_, 1.0f);
        }
        ++column_updates_;
      }
    }
  }

  /// Stores the tile's loaded columns (one write of the tile); with a surface, refreshes theirs and lists
  /// those that changed.
  void finish(SurfaceMap* surface, std::vector<ColumnIndex>& surface_changed) {
    std::size_t stored = 0;
    for (int e = e_first_; e <= e_last_; ++e)
      for (int a = a_first_; a <= a_last_; ++a) {
        ColumnScratch& s = scratch_[(e - e_first_) * kTile + (a - a_first_)];
        if (s.loaded) contents_[stored++] = kernel_.contents(s, g_.column(a, e));
      }
    grid_.store_windows(contents_, stored);
    for (std::size_t i = 0; i < stored; ++i) {
      const ColumnIndex c = contents_[i].column;
      grid_.mark_changed(c);
      if (surface && refresh_column_surface(grid_, c, grid_.find(c), *surface)) surface_changed.push_back(c);
    }
  }

  std::size_t column_updates() const { return column_updates_; }

private:
  static constexpr int kTile = ColumnGrid::kTileSize;

  // A measurement's columns within the tile.
  struct TileColumns {
    int a0, a1, e0, e1;
  };
  TileColumns columns_of(const Measurement& m) const {
    return {std::max(m.azimuth_first, a_first_), std::min(m.azimuth_last, a_last_), std::max(m.elevation_first, e_first_),
            std::min(m.elevation_last, e_last_)};
  }
  double azimuth_term(int a, const Measurement& m) const {
    const double d = (g_.azimuth().centre(a) - m.azimuth) * inv_sigma_azimuth_;
    return d * d;
  }
  double elevation_term(int e, const Measurement& m) const {
    const double d = (g_.elevation().centre(e) - m.elevation) * inv_sigma_elevation_;
    return d * d;
  }

  // Free space a whole call carves in one column, whatever the order of its measurements (clamped mode).
  // Below front_m every measurement of the call has t <= kNonPositiveT, so logit P_s <= 0 for all of them;
  // below to_lmin_m at least one of them alone takes a voxel holding L <= 0 below L_min (bound b: by 0.128
  // at least, far beyond float rounding in the odds). Under clamping after each update a voxel that only
  // receives non-positive terms ends at max(L_min, L + sum), so every voxel below both that holds L <= 0
  // ends the call at L_min: the column's leading run takes it at load (ColumnKernel::extend_run) and no
  // measurement evaluates it. A neighbour whose update lies wholly in front of the column's own return
  // then costs O(1), and its free-space carving never materialises bins the return would clamp anyway.
  struct FreeSpaceBound {
    double front_m = std::numeric_limits<double>::infinity();
    double to_lmin_m = -std::numeric_limits<double>::infinity();
  };

  void load(ColumnIndex c, int i) {
    ColumnScratch& s = scratch_[i];
    static const ColumnData kUntouched;
    const ColumnData* data = grid_.find(c);
    kernel_.load(data ? *data : kUntouched, s);
    if (grid_.clamped()) {
      const FreeSpaceBound& f = free_space_[i];
      kernel_.extend_run(s, g_.depth().first_centre_above(std::min(f.front_m, f.to_lmin_m)));
    }
  }

  ColumnGrid& grid_;
  const GridGeometry& g_;
  const ColumnKernel kernel_;
  MeasurementTerms terms_, column_terms_;
  const double inv_sigma_azimuth_, inv_sigma_elevation_;
  const float lmin_;
  ColumnScratch scratch_[kTile * kTile];
  ColumnContents contents_[kTile * kTile];  // the loaded columns' contents, stored together
  FreeSpaceBound free_space_[kTile * kTile];
  float azimuth_factor_[kTile];
  double azimuth_b_[kTile];
  int a_first_ = 0, e_first_ = 0, a_last_ = -1, e_last_ = -1;
  std::size_t column_updates_ = 0;
};

}  // namespace

std::size_t detail::update_band(ColumnGrid& grid, const SensorModel& model, const MeasurementChunks& measurements,
                                const TileRows& rows, int first_tile_row, int end_tile_row,
                                std::vector<float>& scratch_rows, SurfaceMap* surface,
                                std::vector<ColumnIndex>& surface_changed) {
  constexpr int kTile = ColumnGrid::kTileSize;
  const GridGeometry& g = grid.geometry();
  const detail::FlushDenormals flush_denormals;
  const int tile_columns = (g.width() + kTile - 1) / kTile;
  const BandTiles tiles(measurements, rows, first_tile_row, end_tile_row, tile_columns);
  TileUpdate update(grid, model, scratch_rows);
  const auto tile_origin = [&](std::size_t t) {
    return std::make_pair(static_cast<int>(t % static_cast<std::size_t>(tile_columns)) * kTile,
                          (first_tile_row + static_cast<int>(t / static_cast<std::size_t>(tile_columns))) * kTile);
  };
  const auto measurements_in = [&](std::size_t t) { return tiles.begin[t + 1] - tiles.begin[t]; };
  std::size_t next = 0;  // the next tile with measurements after t
  for (std::size_t t = 0; t < tiles.count(); ++t) {
    if (measurements_in(t) == 0) continue;
    throw_if_stop_requested();  // per tile: up to 64 columns' measurements
    // A tile with fewer measurements than columns (a small shot into a map) does too little work to hide
    // its loads from a store of tens of MB, which then wait on memory column by column: ask for the next
    // such tile while this one is updated (bench_select_round: insertion -16 to -24 %). A dense tile (a
    // whole frame) reads its columns in order, which the hardware prefetcher follows (asking for it
    // too measured 2 % slower on the 7-Scenes pipeline).
    for (next = std::max(next, t + 1); next < tiles.count() && measurements_in(next) == 0; ++next) {
    }
    if (next < tiles.count() && measurements_in(next) < ColumnGrid::kTileColumns) {
      const auto [a, e] = tile_origin(next);
      grid.prefetch_tile(g.column(a, e));
    }
    const auto [a, e] = tile_origin(t);
    update.start(a, e);
    if (grid.clamped())
      for (std::uint32_t k = tiles.begin[t]; k < tiles.begin[t + 1]; ++k) update.bound(measurements.slots[tiles.items[k]]);
    for (std::uint32_t k = tiles.begin[t]; k < tiles.begin[t + 1]; ++k) update.apply(measurements.slots[tiles.items[k]]);
    update.finish(surface, surface_changed);
  }
  return update.column_updates();
}


void logit_opdf_profile(const double* centres, std::size_t n, double rho_bar, double angular_term, double sigma_rho,
                        float* out) {
  std::vector<float> e(n), g(n);
  const bool factored = angular_term <= kMaxFactoredB;
  opdf_bin_terms(centres, static_cast<int>(n), rho_bar, 1.0 / sigma_rho, factored ? 0.0f : static_cast<float>(angular_term),
                 e.data(), g.data());
  logit_profile_from_terms(e.data(), g.data(), static_cast<int>(n),
                           factored ? fast_exp(static_cast<float>(-angular_term)) : 1.0f, out);
}

}  // namespace occ_improve
