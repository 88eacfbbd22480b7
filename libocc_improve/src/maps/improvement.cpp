#include "occ_improve/maps/improvement.hpp"

#include "support/fast_math.hpp"
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "sensor/opdf_bounds.hpp"
#include "sensor/opdf_kernel.hpp"
#include "support/parallel.hpp"
#include "support/vector_clones.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

namespace occ_improve {
namespace {

void require_matching_surface(const GridGeometry& g, const SurfaceMap& s) {
  require_shape("surface map", s.shape(), "the grid", ColumnShape::of_grid(g.width(), g.height()));
}

// imp_i of eq. 3 for one surface voxel (probability p) at d_rho from the simulated measurement, whose
// angular offset has the angular term b_angular = B, with eq. 1 from opdf_kernel.hpp: P_s = n / (n + m),
// so the posterior p P_s / (p P_s + (1 - p)(1 - P_s)) = p n / (p n + (1 - p) m) needs one division.
// Far in front x <= 2e38 and P_s stays ~1e-38. A certain prior (p = 0 or 1, den = 0) is left unchanged by
// Bayes: imp_i = 0. Branch-free so the row loop vectorises.
// kWithPeak = false drops g, for window offsets with B >= kPeakNegligibleB (opdf_bounds.hpp).
template <bool kWithPeak>
inline float surface_term(float p, float d_rho, float inv_sigma, float b_angular) {
  const float t = d_rho * inv_sigma;
  const detail::OpdfOdds odds =
      detail::opdf_odds(detail::opdf_x(t, b_angular), kWithPeak ? detail::opdf_g(t, b_angular) : 0.0f);
  const float num = p * odds.n;
  const float den = num + (1.0f - p) * odds.m;
  const float imp = num / (den > 0.0f ? den : 1.0f) - p;  // selects, not branches: the loop vectorises
  return den > 0.0f ? imp : 0.0f;
}

// The window rule and the per-offset angular factors, built once per geometry and model.
// B = B_h + B_v (eq. 1). The horizontal axis is uniform (AngularBinning's contract), so B_h depends on the
// column offset da only and is constant along a row; B_v depends on the row's own centre offsets, which
// differ from row to row on a non-uniform vertical axis (lidar_rings): B is tabulated per row and offset.
struct WindowKernel {
  std::vector<int> az_lo, az_hi, el_lo, el_hi;  // window offsets of each azimuth bin / elevation row
  int da_min = 0, da_max = 0, de_min = 0, de_max = 0;
  std::vector<float> angular_term;  // B per row and offset, at row_offsets(e) + offset_index(da, de)
  std::vector<std::uint8_t> needs_peak;  // B < kPeakNegligibleB, likewise
  // Per azimuth offset da: the azimuth bins whose window holds da, as [run_first, run_end) when they are
  // contiguous (always, for the uniform axes and clipping of today; the masked loop covers the rest).
  std::vector<int> run_first, run_end;
  std::vector<std::uint8_t> run_contiguous;

  WindowKernel(const GridGeometry& g, const SensorModel& model) {
    const AngularBinning& binning = g.binning();
    axis_offsets(g.azimuth(), model.support_horizontal(binning), az_lo, az_hi, da_min, da_max);
    axis_offsets(g.elevation(), model.support_vertical(binning), el_lo, el_hi, de_min, de_max);
    const std::size_t offsets = static_cast<std::size_t>(offsets_across()) * static_cast<std::size_t>(de_max - de_min + 1);
    angular_term.assign(offsets * static_cast<std::size_t>(g.height()), 0.0f);
    for (int e = 0; e < g.height(); ++e) {
      const auto ue = static_cast<std::size_t>(e);
      for (int de = el_lo[ue]; de <= el_hi[ue]; ++de) {
        const double b_vertical = model.vertical_term(binning, g.elevation().centre_offset(e, de));
        for (int da = da_min; da <= da_max; ++da)
          angular_term[row_offsets(e) + offset_index(da, de)] = static_cast<float>(
              model.horizontal_term(binning, g.azimuth().centre_offset(0, da)) + b_vertical);
      }
    }
    needs_peak.resize(angular_term.size());
    for (std::size_t o = 0; o < angular_term.size(); ++o) needs_peak[o] = angular_term[o] < kPeakNegligibleB;
    for (int da = da_min; da <= da_max; ++da) {
      int first = 0, last = -1, count = 0;
      for (int x = 0; x < g.width(); ++x)
        if (az_lo[static_cast<std::size_t>(x)] <= da && da <= az_hi[static_cast<std::size_t>(x)]) {
          if (count++ == 0) first = x;
          last = x;
        }
      run_first.push_back(first);
      run_end.push_back(last + 1);
      run_contiguous.push_back(count == last + 1 - first);
    }
  }
  /// Angular terms per row: every (da, de) offset of the widest window.
  std::size_t terms_per_row() const {
    return static_cast<std::size_t>(offsets_across()) * static_cast<std::size_t>(de_max - de_min + 1);
  }
  std::size_t row_offsets(int e) const { return static_cast<std::size_t>(e) * terms_per_row(); }
  int offsets_across() const { return da_max - da_min + 1; }
  std::size_t offset_index(int da, int de) const {
    return static_cast<std::size_t>((de - de_min) * offsets_across() + (da - da_min));
  }

  // Columns of this axis overlapping centre +- support, by the insertion's rule, as offsets.
  static void axis_offsets(const BinAxis& axis, double support, std::vector<int>& lo, std::vector<int>& hi,
                           int& lo_min, int& hi_max) {
    lo.resize(static_cast<std::size_t>(axis.bins()));
    hi.resize(lo.size());
    lo_min = 0;
    hi_max = 0;
    for (int i = 0; i < axis.bins(); ++i) {
      int first, last;
      axis.overlapping(axis.centre(i) - support, axis.centre(i) + support, first, last);
      lo[static_cast<std::size_t>(i)] = first - i;
      hi[static_cast<std::size_t>(i)] = last - i;
      lo_min = std::min(lo_min, first - i);
      hi_max = std::max(hi_max, last - i);
    }
  }

  // Eqs. 3-4 for one ray; the offsets are visited in the same order as in the row loop below, so both
  // give bit-identical sums.
  float ray(const GridGeometry& g, const SensorModel& model, const SurfaceMap& s, int a, int e) const {
    const ColumnIndex j = g.column(a, e);
    const float rho_j = s.depth_m[j];
    const float inv_sigma = static_cast<float>(1.0 / model.sigma_depth_at(rho_j));
    float sum = 0.0f;
    const auto ua = static_cast<std::size_t>(a), ue = static_cast<std::size_t>(e);
    for (int de = el_lo[ue]; de <= el_hi[ue]; ++de)
      for (int da = az_lo[ua]; da <= az_hi[ua]; ++da) {
        const ColumnIndex i = g.column(a + da, e + de);
        const std::size_t o = row_offsets(e) + offset_index(da, de);
        const float p_i = s.probability[i], d_rho = s.depth_m[i] - rho_j;
        sum += needs_peak[o] ? surface_term<true>(p_i, d_rho, inv_sigma, angular_term[o])
                             : surface_term<false>(p_i, d_rho, inv_sigma, angular_term[o]);
      }
    return sum;
  }

  // The rays [x_first, x_end) of row e at once (out[x] for those x): offset by offset, j along the row
  // (contiguous, vectorisable). On x86-64 GCC also builds an AVX2 clone picked at load time (no FMA:
  // results stay bit-identical to ray()).
  OCC_IMPROVE_CLONES("avx2") void row(const GridGeometry& g, const SensorModel& model, const SurfaceMap& s, int e,
                                  int x_first, int x_end, float* out, std::vector<float>& inv_sigma) const {
    const int w = g.width();
    const std::size_t row_start = static_cast<std::size_t>(e) * static_cast<std::size_t>(w);
    const float* rho_j = s.depth_m.data() + row_start;
    for (int x = x_first; x < x_end; ++x) {
      inv_sigma[static_cast<std::size_t>(x)] = static_cast<float>(1.0 / model.sigma_depth_at(rho_j[x]));
      out[x] = 0.0f;
    }
    const int* lo = az_lo.data();
    const int* hi = az_hi.data();
    const float* inv = inv_sigma.data();
    const auto ue = static_cast<std::size_t>(e);
    for (int de = el_lo[ue]; de <= el_hi[ue]; ++de) {
      const std::size_t other_start = static_cast<std::size_t>(e + de) * static_cast<std::size_t>(w);
      for (int da = da_min; da <= da_max; ++da) {
        const float* p_i = s.probability.data() + other_start;  // p_i[x + da]: column x + da of row e + de
        const float* rho_i = s.depth_m.data() + other_start;
        const float b_angular = angular_term[row_offsets(e) + offset_index(da, de)];
        // Same additions in the same order either way: the masked loop adds 0 outside the window.
        const auto accumulate = [&](auto with_peak, auto masked, int x_begin, int x_end) {
          for (int x = x_begin; x < x_end; ++x) {
            const float term =
                surface_term<decltype(with_peak)::value>(p_i[x + da], rho_i[x + da] - rho_j[x], inv[x], b_angular);
            if constexpr (decltype(masked)::value) {
              const bool in_window = (lo[x] <= da) & (da <= hi[x]);  // '&': no short-circuit branch
              out[x] += in_window ? term : 0.0f;
            } else {
              out[x] += term;
            }
          }
        };
        const bool peak = needs_peak[row_offsets(e) + offset_index(da, de)];
        const auto r = static_cast<std::size_t>(da - da_min);
        if (run_contiguous[r]) {
          const int from = std::max(run_first[r], x_first), to = std::min(run_end[r], x_end);
          if (peak)
            accumulate(std::true_type{}, std::false_type{}, from, to);
          else
            accumulate(std::false_type{}, std::false_type{}, from, to);
        } else {
          const int from = std::max({0, -da, x_first}), to = std::min({w, w - da, x_end});
          if (peak)
            accumulate(std::true_type{}, std::true_type{}, from, to);
          else
            accumulate(std::false_type{}, std::true_type{}, from, to);
        }
      }
    }
  }
};

// Whether row e's rays have bitwise the inputs of row `other`'s, so that the row loop would give the same
// values: the same window rows and angular terms, and the same surface depths and probabilities in every
// row of the window. An empty map's interior rows do (a fresh 640 x 480 map has a handful of distinct
// rows, ~0.3 ms instead of ~5 ms); a measured map's rows differ at the first compare of depths.
bool same_row_inputs(const WindowKernel& kernel, const SurfaceMap& s, int width, int e, int other) {
  const auto ue = static_cast<std::size_t>(e), uo = static_cast<std::size_t>(other);
  if (kernel.el_lo[ue] != kernel.el_lo[uo] || kernel.el_hi[ue] != kernel.el_hi[uo]) return false;
  if (std::memcmp(kernel.angular_term.data() + kernel.row_offsets(e), kernel.angular_term.data() + kernel.row_offsets(other),
                  kernel.terms_per_row() * sizeof(float)) != 0)
    return false;
  const auto w = static_cast<std::size_t>(width);
  for (int de = kernel.el_lo[ue]; de <= kernel.el_hi[ue]; ++de) {
    const std::size_t row = static_cast<std::size_t>(e + de) * w, other_row = static_cast<std::size_t>(other + de) * w;
    if (std::memcmp(s.depth_m.data() + row, s.depth_m.data() + other_row, w * sizeof(float)) != 0 ||
        std::memcmp(s.probability.data() + row, s.probability.data() + other_row, w * sizeof(float)) != 0)
      return false;
  }
  return true;
}

// Rays whose window holds a changed column: j with lo[j] <= c - j <= hi[j] on both axes. A few changed
// columns are scattered to the rays around them (cost proportional to the change); a whole frame's are
// gathered row by row over a mask, one byte OR per window offset and ray, in the row loop's offset order
// (vectorised; the scatter costs ~9 branchy updates per column, twice the whole improvement map).
std::vector<std::uint8_t> affected_rays(const GridGeometry& g, const WindowKernel& kernel,
                                        const std::vector<ColumnIndex>& changed) {
  const std::size_t columns = g.column_count();
  std::vector<std::uint8_t> affected(columns, 0);
  for (const ColumnIndex c : changed)
    if (c >= columns)
      throw InvalidInput("changed column " + std::to_string(c) + " is outside the grid (" + std::to_string(columns) +
                         " columns)");
  if (changed.size() < columns / 16) {
    for (const ColumnIndex c : changed) {
      const int ca = g.azimuth_bin_of(c), ce = g.elevation_bin_of(c);
      for (int e = std::max(0, ce - kernel.de_max); e <= std::min(g.height() - 1, ce - kernel.de_min); ++e) {
        const auto ue = static_cast<std::size_t>(e);
        if (ce - e < kernel.el_lo[ue] || ce - e > kernel.el_hi[ue]) continue;
        for (int a = std::max(0, ca - kernel.da_max); a <= std::min(g.width() - 1, ca - kernel.da_min); ++a) {
          const auto ua = static_cast<std::size_t>(a);
          if (ca - a >= kernel.az_lo[ua] && ca - a <= kernel.az_hi[ua]) affected[g.column(a, e)] = 1;
        }
      }
    }
    return affected;
  }
  std::vector<std::uint8_t> mask(columns, 0);
  for (const ColumnIndex c : changed) mask[c] = 1;
  const int w = g.width();
  for (int e = 0; e < g.height(); ++e) {
    std::uint8_t* row = affected.data() + static_cast<std::size_t>(e) * static_cast<std::size_t>(w);
    const auto ue = static_cast<std::size_t>(e);
    for (int de = kernel.el_lo[ue]; de <= kernel.el_hi[ue]; ++de) {
      const std::uint8_t* other = mask.data() + static_cast<std::size_t>(e + de) * static_cast<std::size_t>(w);
      for (int da = kernel.da_min; da <= kernel.da_max; ++da) {
        const auto r = static_cast<std::size_t>(da - kernel.da_min);
        if (kernel.run_contiguous[r]) {
          for (int x = kernel.run_first[r]; x < kernel.run_end[r]; ++x) row[x] |= other[x + da];
        } else {
          for (int x = std::max(0, -da); x < std::min(w, w - da); ++x)
            if (kernel.az_lo[static_cast<std::size_t>(x)] <= da && da <= kernel.az_hi[static_cast<std::size_t>(x)])
              row[x] |= other[x + da];
        }
      }
    }
  }
  return affected;
}

// Columns the sensor cannot observe hold NaN: "no value", never ranked (ranking.hpp).
void mask_unobservable(const GridGeometry& g, int e, float* row) {
  if (g.all_observable()) return;
  const std::size_t row_start = static_cast<std::size_t>(e) * static_cast<std::size_t>(g.width());
  for (int a = 0; a < g.width(); ++a)
    if (!g.observable(static_cast<ColumnIndex>(row_start + static_cast<std::size_t>(a))))
      row[a] = std::numeric_limits<float>::quiet_NaN();
}

void require_bins(const GridGeometry& g, int a, int e) {
  if (a < 0 || a >= g.width())
    throw InvalidParameter("azimuth_bin = " + std::to_string(a) + " is outside [0, " + std::to_string(g.width()) + ")");
  if (e < 0 || e >= g.height())
    throw InvalidParameter("elevation_bin = " + std::to_string(e) + " is outside [0, " +
                           std::to_string(g.height()) + ")");
}

}  // namespace

double ray_improvement(const GridGeometry& geometry, const SensorModel& model, const SurfaceMap& surface,
                       int azimuth_bin, int elevation_bin) {
  require_bins(geometry, azimuth_bin, elevation_bin);
  require_matching_surface(geometry, surface);
  return WindowKernel(geometry, model).ray(geometry, model, surface, azimuth_bin, elevation_bin);
}

ImprovementMap compute_improvement(const GridGeometry& geometry, const SensorModel& model,
                                   const SurfaceMap& surface, int threads) {
  detail::require_parameter(threads >= 0, "threads", threads, ">= 0");
  require_matching_surface(geometry, surface);
  const WindowKernel kernel(geometry, model);
  ImprovementMap map;
  map.width = geometry.width();
  map.height = geometry.height();
  map.value.resize(geometry.column_count());
  const int h = geometry.height();
  const int parts = std::min(detail::resolve_thread_count(threads), h);
  const int w = geometry.width();
  detail::run_parts(parts, [&](int part, int count) {
    std::vector<float> inv_sigma(static_cast<std::size_t>(w)), computed(static_cast<std::size_t>(w));
    int computed_row = -1;  // the last row the loop evaluated; `computed` holds its values before masking
    for (int e = h * part / count; e < h * (part + 1) / count; ++e) {
      throw_if_stop_requested();
      float* row = map.value.data() + static_cast<std::size_t>(e) * static_cast<std::size_t>(w);
      if (computed_row < 0 || !same_row_inputs(kernel, surface, w, e, computed_row)) {
        kernel.row(geometry, model, surface, e, 0, w, computed.data(), inv_sigma);
        computed_row = e;
      }
      std::copy(computed.begin(), computed.end(), row);
      mask_unobservable(geometry, e, row);
    }
  });
  return map;
}

std::vector<ColumnIndex> update_improvement(const GridGeometry& geometry, const SensorModel& model,
                                            const SurfaceMap& surface,
                                            const std::vector<ColumnIndex>& changed_surface_columns,
                                            ImprovementMap& map, int threads) {
  detail::require_parameter(threads >= 0, "threads", threads, ">= 0");
  require_matching_surface(geometry, surface);
  const std::size_t columns = geometry.column_count();
  if (map.width == 0 && map.height == 0 && map.value.empty()) {
    map = compute_improvement(geometry, model, surface, threads);
    std::vector<ColumnIndex> all(columns);
    for (std::size_t c = 0; c < columns; ++c) all[c] = static_cast<ColumnIndex>(c);
    return all;
  }
  require_shape("improvement map", map.shape(), "the grid", ColumnShape::of_grid(geometry.width(), geometry.height()));
  const WindowKernel kernel(geometry, model);

  const std::vector<std::uint8_t> affected = affected_rays(geometry, kernel, changed_surface_columns);
  std::vector<ColumnIndex> rays;
  for (std::size_t c = 0; c < columns; ++c)
    if (affected[c]) rays.push_back(static_cast<ColumnIndex>(c));

  // Rows with many affected rays go through the vectorised row loop over their spans of affected rays
  // (gaps shorter than kSpanGap bridged, their values computed and not copied), the others ray by ray;
  // both give bit-identical values. Rows are independent.
  constexpr int kSpanGap = 16;
  const int w = geometry.width(), h = geometry.height();
  const int parts = rays.size() < 20000 ? 1 : std::min(detail::resolve_thread_count(threads), h);
  detail::run_parts(parts, [&](int part, int count) {
    std::vector<float> scratch(static_cast<std::size_t>(w)), inv_sigma(static_cast<std::size_t>(w));
    for (int e = h * part / count; e < h * (part + 1) / count; ++e) {
      throw_if_stop_requested();
      const std::size_t row_start = static_cast<std::size_t>(e) * static_cast<std::size_t>(w);
      const auto row_affected = static_cast<int>(
          std::count(affected.begin() + static_cast<std::ptrdiff_t>(row_start),
                     affected.begin() + static_cast<std::ptrdiff_t>(row_start + static_cast<std::size_t>(w)), 1));
      if (row_affected == 0) continue;
      if (row_affected * 8 >= w) {
        const std::uint8_t* in_row = affected.data() + row_start;
        for (int a = 0; a < w;) {
          if (!in_row[a]) {
            ++a;
            continue;
          }
          int span_end = a + 1, last = a;
          for (; span_end < w && span_end - last <= kSpanGap; ++span_end)
            if (in_row[span_end]) last = span_end;
          kernel.row(geometry, model, surface, e, a, last + 1, scratch.data(), inv_sigma);
          a = last + 1;
        }
      }
      for (int a = 0; a < w; ++a) {
        const std::size_t j = row_start + static_cast<std::size_t>(a);
        if (!affected[j]) continue;
        map.value[j] = !geometry.observable(static_cast<ColumnIndex>(j)) ? std::numeric_limits<float>::quiet_NaN()
                       : row_affected * 8 >= w                             ? scratch[static_cast<std::size_t>(a)]
                                                                           : kernel.ray(geometry, model, surface, a, e);
      }
    }
  });
  return rays;
}

}  // namespace occ_improve
