// Insertion, step 2 (eq. 2): measurements' truncated OPDFs added to a column (the column kernel and its
// vector loops, with eq. 1's skip bounds), and a band of tile rows updated tile by tile. Step 1
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
static_assert((kLaneBlock & (kLaneBlock - 1)) == 0, "block bounds by masks");
constexpr int block_floor(int bin) { return bin & ~(kLaneBlock - 1); }  // bins are >= 0
constexpr int block_ceil(int bin) { return block_floor(bin + kLaneBlock - 1); }

// The row, with the compiler told that it starts on a block boundary.
template <typename T>
T* block_aligned(T* row) {
#if defined(__GNUC__)
  return static_cast<T*>(__builtin_assume_aligned(row, kLaneBlockBytes));
#else
  return row;
#endif
}

// A buffer of `count` floats (a multiple of kLaneBlock) in `storage`, starting on a block boundary. The
// storage only grows: a tile's term pool is sized per tile, and resizing it down and up again would zero
// the difference every time.
float* aligned_floats(std::vector<float>& storage, std::size_t count) {
  if (storage.size() < count + kLaneBlock) storage.resize(count + kLaneBlock);
  const auto misalignment = reinterpret_cast<std::uintptr_t>(storage.data()) % kLaneBlockBytes;
  return storage.data() + (misalignment ? (kLaneBlockBytes - misalignment) / sizeof(float) : 0);
}

// A measurement of a tile (clamped mode) and the bins [lo, hi) its factored pairs evaluate (lo widened to
// a block boundary once planned).
struct TileMeasurement {
  const Measurement* m;
  int run_keep;  ///< the first bin with t > kNonPositiveT
  int lo, hi;
};

// A measurement's angular terms within a tile: B of its columns there (lanes [0, kTile), from its first
// column in the tile) and of its rows (lanes [kTile, 2 kTile)); their factors e^-B lie in the part's
// factor list from `factors`, the columns' then the rows'.
struct TileAngles {
  double b[2 * ColumnGrid::kTileSize];
  std::size_t factors;
};

// e^x of `count` floats in place, in one vector pass over a part's measurements: the exps of one
// measurement are few and each a chain of a dozen dependent operations, which a pass over ~100
// measurements overlaps. Compiled for AVX2 without FMA beside baseline x86-64, so every lane rounds as
// the scalar fast_exp does (FMA would contract its polynomial and change the factors' last bits).
OCC_IMPROVE_CLONES("avx2")
void exponentiate(float* x, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) x[i] = fast_exp(x[i]);
}

// Where one (measurement, column) pair of a call updates the column, decided before any pair of the column
// is applied (clamped mode): bins [first, end) are evaluated, none when first >= end. Listed with end the
// support's end and first = end; the plan sets first for a pair that evaluates.
struct PairPlan {
  /// The pair's measurement in the tile's list; once the terms are placed, its entry of the terms' origins
  /// (a pair with B > kMaxFactoredB: an entry of its own, for its own terms).
  std::uint32_t measurement;
  float a;                    ///< e^-B, or 1 where B > kMaxFactoredB is folded into the pair's own terms
  double angular_term;        ///< B
  int first, end;
};

// Clamped mode works on odds O = e^L during a call: O <- clamp(O * odds P_s, e^L_min, e^L_max) is eq. 2
// with clamping after each update, without a log per voxel and measurement (one exp and one log per voxel
// the call reaches, ColumnScratch). One call applies a column's pairs in input order (one call per column:
// the per-pair work is the vector loop alone).
OCC_IMPROVE_VECTOR_KERNEL
void multiply_odds_clamped(float* o, const PairPlan* pairs, std::size_t count, const float* e_pool, const float* g_pool,
                           const std::ptrdiff_t* origins, float omin, float omax) {
  for (std::size_t k = 0; k < count; ++k) {
    const PairPlan& p = pairs[k];
    if (p.first >= p.end) continue;
    const int from = block_floor(p.first), first = p.first - from, end = p.end - from, to = block_ceil(p.end) - from;
    float* row = block_aligned(o + from);
    const std::ptrdiff_t terms = origins[p.measurement] + from;
    const float* e = block_aligned(e_pool + terms);
    const float* g = block_aligned(g_pool + terms);
    const float a = p.a;
    for (int i = 0; i < to; ++i) {
      const detail::OpdfOdds odds = detail::opdf_odds(e[i] * a, g[i] * a);
      const float v = row[i] * (odds.n / odds.m);
      const float clamped = v < omin ? omin : (v > omax ? omax : v);
      row[i] = i >= first && i < end ? clamped : row[i];
    }
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

// The depth axis's bin centres, padded to whole blocks by repeating the last (the padding's terms are
// computed but never read as bins).
std::vector<double> padded_centres(const DepthAxis& depth) {
  std::vector<double> centres(depth.centres().begin(), depth.centres().end());
  centres.resize(static_cast<std::size_t>(block_ceil(depth.bins())), depth.centres().back());
  return centres;
}

// Exact mode: one measurement's bin terms, computed on demand over the bins its columns need, in whole
// blocks of kLaneBlock bins (the depth axis padded to whole blocks: the padding's terms are never read as bins).
class MeasurementTerms {
public:
  /// `centres`: padded_centres of the axis, kept by the caller.
  MeasurementTerms(const DepthAxis& depth, const std::vector<double>& centres) : centres_(centres) {
    const auto n = static_cast<std::size_t>(block_ceil(depth.bins()));
    e_ = aligned_floats(e_storage_, n);
    g_ = aligned_floats(g_storage_, n);
  }

  void reset(double rho_bar, double sigma, double folded_angular_term = 0.0) {
    rho_bar_ = rho_bar;
    inv_sigma_ = 1.0 / sigma;
    folded_angular_term_ = static_cast<float>(folded_angular_term);
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
  const float* e() const { return e_; }
  const float* g() const { return g_; }

private:
  void compute(int first, int last) {
    opdf_bin_terms(centres_.data() + first, last - first, rho_bar_, inv_sigma_, folded_angular_term_, e_ + first, g_ + first);
  }
  std::vector<float> e_storage_, g_storage_;
  float *e_ = nullptr, *g_ = nullptr;
  const std::vector<double>& centres_;
  double rho_bar_ = 0, inv_sigma_ = 1;
  float folded_angular_term_ = 0;
  int lo_ = 0, hi_ = 0;
};

// The bin terms of a tile's measurements (clamped mode), each over the whole blocks of bins its pairs
// evaluate, in one pool: requested while the tile's columns are planned, then computed together.
class TileTerms {
public:
  /// `centres`: padded_centres of the depth axis, kept by the caller.
  explicit TileTerms(const std::vector<double>& centres) : centres_(centres) {}

  void clear() {
    requests_.clear();
    size_ = 0;
  }
  /// Asks for bins [first, end) (first on a block boundary; end widened to one) of the terms at rho_bar,
  /// sigma (with B folded in where folded_angular_term != 0); returns their origin in the pool: the terms of
  /// bin b at origin + b (where bin 0's would be).
  std::ptrdiff_t reserve(int first, int end, double rho_bar, double sigma, double folded_angular_term) {
    const std::size_t offset = size_;
    const int count = block_ceil(end) - first;
    requests_.push_back({offset, first, count, rho_bar, sigma, static_cast<float>(folded_angular_term)});
    size_ += static_cast<std::size_t>(count);
    return static_cast<std::ptrdiff_t>(offset) - first;
  }
  void compute() {
    e_ = aligned_floats(e_storage_, size_);
    g_ = aligned_floats(g_storage_, size_);
    for (const Request& r : requests_)
      opdf_bin_terms(centres_.data() + r.first, r.count, r.rho_bar, 1.0 / r.sigma, r.folded_angular_term, e_ + r.offset,
                     g_ + r.offset);
  }
  /// The pool: bin b of a request's terms at the origin reserve returned + b (its first bin block-aligned).
  const float* e() const { return e_; }
  const float* g() const { return g_; }

private:
  struct Request {
    std::size_t offset;
    int first, count;
    double rho_bar, sigma;
    float folded_angular_term;
  };
  const std::vector<double>& centres_;
  std::vector<Request> requests_;
  std::size_t size_ = 0;
  std::vector<float> e_storage_, g_storage_;
  float *e_ = nullptr, *g_ = nullptr;
};

// One column's voxels while a call updates it: the whole depth axis in a scratch row. Only [run_end, tail)
// is materialised: bins below run_end hold the leading L_min run (clamped mode), bins from tail on are
// untouched (L = 0). Clamped mode holds [run_end, odds_end) in odds e^L (one exp and one log per voxel
// and call instead of a log per voxel and measurement): the bins the call's measurements have reached so
// far (clamped mode plans the call's pairs first and converts those bins once, ColumnKernel::to_odds). The
// bins behind stay in log-odds and are stored back bit for bit: a conversion there and back
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

// A column's plan for a call (clamped mode): what its scratch row holds before the pairs are applied.
struct ColumnPlan {
  int lo, hi;              ///< the bins some pair evaluates: [lo, hi), none when lo >= hi
  int run_fill_end;        ///< the run's end before the first evaluation: [lo, run_fill_end) hold L_min
  int odds_from;           ///< [run_fill_end, odds_from): odds already (a part before in the call)
  int materialised_end;    ///< [odds_from, materialised_end) hold stored log-odds, bins from it L = 0
  int run_end, tail, odds_end;  ///< the column's state when no pair evaluates
  bool folded;             ///< a pair with B > kMaxFactoredB evaluates
};

// Adds measurements' truncated OPDFs to one column.
class ColumnKernel {
public:
  explicit ColumnKernel(const ColumnGrid& grid) : depth_(grid.geometry().depth()), bins_(depth_.bins()) {
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

  /// The first bin beyond the support for angular term B (eq. 1's skip): the first whose centre lies past
  /// the support's last depth.
  int support_end(double rho_bar, double angular_term, double sigma) const {
    return depth_.first_centre_above(rho_bar + sigma * skip_offset_sigmas(angular_term));
  }

  /// Exact mode: adds one measurement to the column. `terms` are the measurement's, with a = e^-B the
  /// column's factor (or B folded in and a = 1).
  void apply_exact(ColumnScratch& s, double rho_bar, double angular_term, double sigma, MeasurementTerms& terms,
                   float a) const {
    const int end = support_end(rho_bar, angular_term, sigma);
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

  /// Clamped mode, after load and extend_run: which bins each of the column's pairs (in input order)
  /// evaluates. Applying every pair to every bin in front of its support's end would give the same
  /// column; a pair skips exactly the bins where its update cannot change the clamped result:
  ///  a) bins of the leading L_min run where its t <= kNonPositiveT (logit P_s <= 0 there);
  ///  b) bins below bound b) of a column with nothing materialised (they end at L_min: they join the run);
  ///  b') all of a pair with B >= kNegligibleB whose support lies in the run (its end is in front of
  ///     t = kNonPositiveT, so a) covers it), or ends at or in front of the run's end (nothing to do).
  /// The run is followed as the pairs materialise it (a pair that reaches into it with t > kNonPositiveT
  /// takes it back from there), not as updates clamp voxels into it: a pair may then evaluate voxels the
  /// pair-by-pair kernel skipped by a), b) or b') after its per-pair run scans, which leaves them where
  /// they are (at L_min) for the same reasons. (A clamped grid holding values below L_min, which this
  /// kernel never writes, may keep some of them where that kernel stored L_min.) Each evaluating factored
  /// pair widens its measurement's [lo, hi) (the bins whose terms the tile computes).
  ColumnPlan plan(const ColumnScratch& s, PairPlan* pairs, std::size_t count, TileMeasurement* measurements) const {
    ColumnPlan c{std::numeric_limits<int>::max(), std::numeric_limits<int>::min(), 0, 0, 0, 0, 0, 0, false};
    int run_end = s.run_end, tail = s.tail, odds_end = s.odds_end;
    for (std::size_t i = 0; i < count; ++i) {
      PairPlan& p = pairs[i];
      TileMeasurement& tm = measurements[p.measurement];
      // Listed with first = end (the support's end): skipped, unless evaluated below.
      const int keep = tm.run_keep;
      const bool negligible = p.angular_term >= kNegligibleB;
      if (negligible && run_end >= keep) continue;  // b')
      // Past b') such a pair has run_end < keep, so a) cannot take the run back, and b) cannot extend it
      // past the support's end: it does nothing when that end is at or in front of the run's.
      if (negligible && p.end <= run_end) continue;
      const Measurement& m = *tm.m;
      int run_before = run_end;
      if (run_end > keep && keep < p.end) {  // a): the run taken back from keep
        run_end = keep;
      } else if (run_end == tail) {  // b) (nothing materialised)
        // It moves the run only when the centre at the run's end lies at or below the bound (the first
        // centre above the bound is then beyond the run's end): that comparison first, the lookup only then.
        const double to_lmin_last = m.rho + m.sigma * to_lmin_offset_sigmas(p.angular_term, lmin_);
        if (run_end < bins_ && depth_.centre(run_end) <= to_lmin_last) {
          const int fresh = std::min(depth_.first_centre_above(to_lmin_last), p.end);
          if (fresh > run_end) run_before = run_end = tail = odds_end = fresh;
        }
      }
      if (run_end >= p.end) continue;
      p.first = run_end;
      if (p.angular_term <= kMaxFactoredB) {
        tm.lo = std::min(tm.lo, p.first);
        tm.hi = std::max(tm.hi, p.end);
      } else {
        c.folded = true;
      }
      if (c.lo > c.hi) {
        c.run_fill_end = run_before;
        c.odds_from = odds_end;
        c.materialised_end = tail;
      }
      c.lo = std::min(c.lo, run_end);
      c.hi = std::max(c.hi, p.end);
      tail = std::max(tail, p.end);  // reached: materialised, in odds
      odds_end = std::max(odds_end, p.end);
    }
    c.run_end = run_end;
    c.tail = tail;
    c.odds_end = odds_end;
    return c;
  }

  /// Clamped mode: the scratch row as the plan's first evaluation finds it, in odds: the run taken back
  /// ([lo, run_fill_end), L_min), the odds a part before left, the stored log-odds converted up to hi, and
  /// untouched bins (L = 0) beyond them.
  void to_odds(ColumnScratch& s, const ColumnPlan& c) const {
    float* o = s.v;
    if (c.lo < c.run_fill_end) std::fill(o + c.lo, o + c.run_fill_end, omin_);
    const int converted_end = std::min(c.hi, c.materialised_end);
    if (c.odds_from < converted_end) log_odds_to_odds(o, c.odds_from, converted_end, omin_, omax_, lmin_, lmax_);
    if (c.materialised_end < c.hi) std::fill(o + c.materialised_end, o + c.hi, 1.0f);
  }

  /// Clamped mode: the column's pairs (their terms resolved), in input order.
  void multiply(ColumnScratch& s, const PairPlan* pairs, std::size_t count, const float* e_pool, const float* g_pool,
                const std::ptrdiff_t* origins) const {
    multiply_odds_clamped(s.v, pairs, count, e_pool, g_pool, origins, omin_, omax_);
  }

  /// Clamped mode, after the plan's pairs: the leading voxels at the lower clamp join the run (in odds,
  /// then in log-odds behind), and the row's state is ready for contents().
  void close(ColumnScratch& s, const ColumnPlan& c) const {
    if (c.lo >= c.hi) {
      s.run_end = c.run_end;
      s.odds_end = c.odds_end;
      s.tail = c.tail;
      return;
    }
    const float* o = s.v;
    // The row holds odds up to the last bin evaluated or the run's end at the first evaluation (a pair
    // that took the run back and ended in front of it leaves the rest of that stretch at L_min, in odds).
    const int odds_end = std::max(c.hi, c.odds_from);
    int run_end = c.lo;
    while (run_end < odds_end && o[run_end] <= omin_) ++run_end;
    s.tail = std::max(c.materialised_end, c.hi);
    s.odds_end = odds_end;
    if (run_end == odds_end) {
      while (run_end < s.tail && o[run_end] <= lmin_) ++run_end;
      s.odds_end = run_end;
    }
    s.run_end = run_end;
  }

private:
  static void extend_tail(ColumnScratch& s, int end, float fill) {
    if (end <= s.tail) return;
    std::fill(s.v + s.tail, s.v + end, fill);
    s.tail = end;
  }

  const DepthAxis& depth_;
  const int bins_;
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

// One tile's columns while its measurements are applied: each column is loaded once, receives its
// measurements in input order and is stored after the tile's last. Within the tile, a measurement's depth
// terms are computed once for all its columns, and B = B_azimuth + B_elevation, e^-B = e^-B_azimuth
// e^-B_elevation, once per row and column. Clamped mode (the default) goes a column at a time
// (apply_clamped), exact mode a measurement at a time (apply_exact).
class TileUpdate {
public:
  TileUpdate(const TileUpdate&) = delete;  // its term buffers refer to its centres_
  TileUpdate& operator=(const TileUpdate&) = delete;
  TileUpdate(ColumnGrid& grid, const SensorModel& model, std::vector<float>& scratch_rows)
      : grid_(grid), g_(grid.geometry()), kernel_(grid), centres_(padded_centres(g_.depth())),
        terms_(g_.depth(), centres_), column_terms_(g_.depth(), centres_), tile_terms_(centres_),
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
    reset_bounds();
  }

  /// Clamped mode: forgets the FreeSpaceBounds before a part of the tile's measurements is bounded.
  void reset_bounds() { std::fill(std::begin(free_space_), std::end(free_space_), FreeSpaceBound{}); }

  /// Exact mode: adds one of the tile's measurements to its columns (loading each on its first).
  void apply_exact(const Measurement& m) {
    terms_.reset(m.rho, m.sigma);
    TileAngles angles;
    factors_.resize(2 * kTile);
    const std::size_t factor_count = angles_of(m, angles, 0);
    exponentiate(factors_.data(), factor_count);
    for_each_column_of(m, angles, [&](int a, int e, double b, float factor) {
      const int i = slot(a, e);
      ColumnScratch& s = scratch_[i];
      if (!s.loaded) load(g_.column(a, e), i);
      if (b <= kMaxFactoredB) {
        kernel_.apply_exact(s, m.rho, b, m.sigma, terms_, factor);
      } else {
        column_terms_.reset(m.rho, m.sigma, b);
        kernel_.apply_exact(s, m.rho, b, m.sigma, column_terms_, 1.0f);
      }
      ++column_updates_;
    });
  }

  /// Clamped mode: a part of the tile's measurements (slots[items[k]], k < count, in input order), a column at
  /// a time. The pairs are listed per column, every loaded column plans its pairs (ColumnKernel::plan),
  /// each measurement's depth terms are computed once over the bins its pairs evaluate, and then each
  /// column's row receives its pairs in input order, converted to odds once and scanned for its run once:
  /// the bookkeeping is per column, not per pair.
  void apply_clamped(const std::uint32_t* items, std::size_t count, const Measurement* slots) {
    list_pairs(items, count, slots);
    plan_columns();
    compute_terms();
    for (const int i : listed_) {
      ColumnScratch& s = scratch_[i];
      kernel_.to_odds(s, plans_[i]);
      kernel_.multiply(s, pairs_[i].data(), pairs_[i].size(), tile_terms_.e(), tile_terms_.g(), terms_origins_.data());
      kernel_.close(s, plans_[i]);
    }
  }

  /// Stores the tile's loaded columns (one write of the tile); with a surface, refreshes theirs and lists
  /// those that changed.
  void finish(SurfaceMap* surface, std::vector<ColumnIndex>& surface_changed) {
    std::size_t stored = 0;
    for (int e = e_first_; e <= e_last_; ++e)
      for (int a = a_first_; a <= a_last_; ++a) {
        const int i = slot(a, e);
        if (!scratch_[i].loaded) continue;
        slots_[stored] = static_cast<std::size_t>(i);
        contents_[stored++] = kernel_.contents(scratch_[i], g_.column(a, e));
      }
    grid_.store_windows(contents_, slots_, stored);
    for (std::size_t i = 0; i < stored; ++i) {
      const ColumnIndex c = contents_[i].column;
      grid_.mark_changed(c);
      if (surface && detail::refresh_written_column_surface(grid_, contents_[i], *surface)) surface_changed.push_back(c);
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
  int slot(int a, int e) const { return (e - e_first_) * kTile + (a - a_first_); }

  // m's angular terms in the tile, their -B in factors_ from `at` (exponentiate makes them e^-B); returns
  // where the next measurement's start.
  std::size_t angles_of(const Measurement& m, TileAngles& t, std::size_t at) {
    const TileColumns r = columns_of(m);
    t.factors = at;
    for (int a = r.a0; a <= r.a1; ++a) {
      t.b[a - r.a0] = azimuth_term(a, m);
      factors_[at++] = static_cast<float>(-t.b[a - r.a0]);
    }
    for (int e = r.e0; e <= r.e1; ++e) {
      t.b[kTile + e - r.e0] = elevation_term(e, m);
      factors_[at++] = static_cast<float>(-t.b[kTile + e - r.e0]);
    }
    return at;
  }

  // visit(a, e, B, e^-B) for each of m's columns in the tile, row by row: B = B_azimuth + B_elevation and
  // e^-B = e^-B_azimuth e^-B_elevation, each factor computed once per column and once per row (`t`).
  template <typename Visit>
  void for_each_column_of(const Measurement& m, const TileAngles& t, Visit&& visit) const {
    const TileColumns r = columns_of(m);
    const float* column_factor = factors_.data() + t.factors;
    const float* row_factor = column_factor + (r.a1 - r.a0 + 1);
    for (int e = r.e0; e <= r.e1; ++e) {
      const double elevation_b = t.b[kTile + e - r.e0];
      const float elevation_factor = row_factor[e - r.e0];
      for (int a = r.a0; a <= r.a1; ++a) visit(a, e, t.b[a - r.a0] + elevation_b, column_factor[a - r.a0] * elevation_factor);
    }
  }

  // Clamped mode: folds measurement m into the to_lmin_m of one column's FreeSpaceBound, from its angular
  // terms `t` (every measurement of a part, before the part's columns are loaded: a column loaded in that
  // part takes them; list_pairs gathers front_m, which takes every measurement of a column). Only the
  // column at the measurement's smallest B in the tile (its own column where the tile holds it): a bound
  // from some of the measurements is still a bound, and that one reaches furthest.
  void bound_to_lmin(const Measurement& m, const TileAngles& t) {
    const TileColumns r = columns_of(m);
    // The first column and row of smallest term, from the first lane of each.
    const auto nearest = [](const double* terms, int count) {
      return static_cast<int>(std::min_element(terms, terms + count) - terms);
    };
    const int a_near = nearest(t.b, r.a1 - r.a0 + 1), e_near = nearest(t.b + kTile, r.e1 - r.e0 + 1);
    double& to_lmin_m = free_space_[slot(r.a0 + a_near, r.e0 + e_near)].to_lmin_m;
    to_lmin_m = std::max(to_lmin_m, m.rho + m.sigma * to_lmin_offset_sigmas(t.b[a_near] + t.b[kTile + e_near], lmin_));
  }

  // Each column's pairs, in input order, and the columns' FreeSpaceBounds; listed_ names the columns that
  // have some (a small shot's tile has a few of its 64).
  void list_pairs(const std::uint32_t* items, std::size_t count, const Measurement* slots) {
    for (const int i : listed_) pairs_[i].clear();
    listed_.clear();
    measurements_.resize(count);
    angles_.resize(count);
    factors_.resize(count * 2 * kTile);
    std::size_t factor_count = 0;
    for (std::size_t k = 0; k < count; ++k) factor_count = angles_of(slots[items[k]], angles_[k], factor_count);
    exponentiate(factors_.data(), factor_count);
    for (std::size_t k = 0; k < count; ++k) {
      const Measurement& m = slots[items[k]];
      const double front_m = m.rho + m.sigma * kNonPositiveT;  // where t = kNonPositiveT
      measurements_[k] = {&m, g_.depth().first_centre_above(front_m), std::numeric_limits<int>::max(),
                          std::numeric_limits<int>::min()};
      for_each_column_of(m, angles_[k], [&](int a, int e, double b, float factor) {
        const float a_factor = b <= kMaxFactoredB ? factor : 1.0f;
        const int i = slot(a, e);
        std::vector<PairPlan>& pairs = pairs_[i];
        if (pairs.empty()) listed_.push_back(i);
        // The support's end, looked up here where no pair waits on it (the plan's decisions for a column
        // follow one another; these lookups do not depend on them).
        const int end = kernel_.support_end(m.rho, b, m.sigma);
        pairs.push_back({static_cast<std::uint32_t>(k), a_factor, b, end, end});
        double& f = free_space_[i].front_m;
        f = std::min(f, front_m);
        ++column_updates_;
      });
      bound_to_lmin(m, angles_[k]);
    }
  }

  // Loads every column with pairs and plans them; each measurement learns the bins its pairs evaluate.
  void plan_columns() {
    folded_.clear();
    for (const int i : listed_) {
      std::vector<PairPlan>& pairs = pairs_[i];
      if (!scratch_[i].loaded) load(g_.column(a_first_ + i % kTile, e_first_ + i / kTile), i);
      plans_[i] = kernel_.plan(scratch_[i], pairs.data(), pairs.size(), measurements_.data());
      if (plans_[i].folded)
        for (PairPlan& p : pairs)
          if (p.first < p.end && p.angular_term > kMaxFactoredB) folded_.push_back(&p);
    }
  }

  // The depth terms every planned pair reads: a measurement's over its pairs' bins, and those of a pair
  // with B > kMaxFactoredB (B folded in) over its own; terms_origins_ gives where bin 0's would be in the
  // pool (the terms of bin b at origin + b), per measurement, then per folded pair (which now points there).
  void compute_terms() {
    tile_terms_.clear();
    terms_origins_.assign(measurements_.size(), 0);
    for (std::size_t k = 0; k < measurements_.size(); ++k) {
      TileMeasurement& tm = measurements_[k];
      if (tm.lo >= tm.hi) continue;
      tm.lo = block_floor(tm.lo);
      terms_origins_[k] = tile_terms_.reserve(tm.lo, tm.hi, tm.m->rho, tm.m->sigma, 0.0);
    }
    for (PairPlan* p : folded_) {
      const Measurement& m = *measurements_[p->measurement].m;
      const int from = block_floor(p->first);
      p->measurement = static_cast<std::uint32_t>(terms_origins_.size());
      terms_origins_.push_back(tile_terms_.reserve(from, p->end, m.rho, m.sigma, p->angular_term));
    }
    tile_terms_.compute();
  }

  // Free space a part of a call carves in one column, whatever the order of its measurements (clamped
  // mode; the part is the whole call unless the tile receives more than kMeasurementsPerPart, and a column
  // takes the bound of the part it is loaded in, the first with pairs for it; the parts after continue
  // from what that one left). Below front_m every measurement of the part has t <= kNonPositiveT, so
  // logit P_s <= 0 for all of them;
  // below to_lmin_m at least one of them alone takes a voxel holding L <= 0 below L_min (bound b: by 0.128
  // at least, far beyond float rounding in the odds). Under clamping after each update a voxel that only
  // receives non-positive terms ends at max(L_min, L + sum), so every voxel below both that holds L <= 0
  // ends the part at L_min: the column's leading run takes it at load (ColumnKernel::extend_run) and no
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
  const std::vector<double> centres_;      // padded_centres of the depth axis, for the terms
  MeasurementTerms terms_, column_terms_;  // exact mode
  TileTerms tile_terms_;                    // clamped mode
  std::vector<TileMeasurement> measurements_;
  std::vector<TileAngles> angles_;  // the part's measurements' (clamped mode)
  std::vector<float> factors_;      // their e^-B (TileAngles::factors)
  std::vector<std::ptrdiff_t> terms_origins_;
  std::vector<PairPlan> pairs_[kTile * kTile];
  std::vector<int> listed_;  // the columns with pairs in the part being applied
  std::vector<PairPlan*> folded_;  // the planned pairs with B > kMaxFactoredB that evaluate
  ColumnPlan plans_[kTile * kTile];
  const double inv_sigma_azimuth_, inv_sigma_elevation_;
  const float lmin_;
  ColumnScratch scratch_[kTile * kTile];
  ColumnContents contents_[kTile * kTile];  // the loaded columns' contents, stored together
  std::size_t slots_[kTile * kTile];         // and their slots in the tile
  FreeSpaceBound free_space_[kTile * kTile];
  int a_first_ = 0, e_first_ = 0, a_last_ = -1, e_last_ = -1;
  std::size_t column_updates_ = 0;
};

// Clamped mode: a tile's measurements are listed and planned in parts of at most this many.
constexpr std::size_t kMeasurementsPerPart = 1024;

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
    if (grid.clamped()) {
      // In parts of at most kMeasurementsPerPart (a frame's tile holds ~100): the pairs and terms a part
      // lists stay bounded however dense the input, and a part's columns stay loaded for the next, so
      // the result is the one of a single part.
      for (std::size_t k = tiles.begin[t]; k < tiles.begin[t + 1]; k += kMeasurementsPerPart) {
        if (k > tiles.begin[t]) {  // start() reset the bounds for the first part
          throw_if_stop_requested();
          update.reset_bounds();
        }
        const std::size_t end = std::min<std::size_t>(k + kMeasurementsPerPart, tiles.begin[t + 1]);
        update.apply_clamped(tiles.items.data() + k, end - k, measurements.slots.data());
      }
    } else {
      for (std::uint32_t k = tiles.begin[t]; k < tiles.begin[t + 1]; ++k) update.apply_exact(measurements.slots[tiles.items[k]]);
    }
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
