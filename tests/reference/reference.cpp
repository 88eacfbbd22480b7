#include "reference/reference.hpp"

#include "occ_improve/maps/improvement.hpp"

#include "occ_improve/maps/surface.hpp"

#include <algorithm>
#include <cmath>

namespace occ_improve::reference {

long double logit_opdf(long double d, long double b, long double s) {
  const long double t = d / s;
  const long double u = 2.0L * (d + 2.0L * s) / s + b;
  // log P = log(1/2 sigmoid(u) + 1/3 exp(-(t^2 + b)))
  const long double log_step = std::log(0.5L) - std::log1p(std::exp(-u));
  const long double log_peak = std::log(1.0L / 3.0L) - (t * t + b);
  const long double m = std::max(log_step, log_peak);
  const long double log_p = m + std::log(std::exp(log_step - m) + std::exp(log_peak - m));
  return log_p - std::log1p(-std::exp(log_p));
}

namespace {

// A point's angular position and depth coordinate, from CONVENTIONS 1 (spherical, and lidar_rings whose rows are
// elevations too) and CONVENTIONS 2c (pinhole) as written, without the library's projection.
struct Position {
  double h = 0, v = 0, depth = 0;
};

bool reference_position(const GridGeometry& g, const Eigen::Vector3f& q, Position& out) {
  const double x = q.x(), y = q.y(), z = q.z();
  if (g.binning() == AngularBinning::pinhole) {
    if (!(z > 0)) return false;
    const PinholeIntrinsics& k = *g.params().camera;
    out = {k.fx * x / z + k.cx, k.fy * y / z + k.cy, z};
  } else {
    out = {std::atan2(x, z), std::atan2(y, std::hypot(x, z)), std::sqrt(x * x + y * y + z * z)};
  }
  const auto inside = [](const UniformAxis& axis, double value) { return value >= axis.min() && value < axis.max(); };
  return inside(g.azimuth(), out.h) && inside(g.elevation(), out.v);
}

// Upper edge of bin i: the bins' extents as the axis defines them (non-uniform rows: lidar_rings).
double upper(const BinAxis& axis, int i) { return axis.uniform() ? axis.lower(i) + axis.width() : axis.lower(i + 1); }

double sigma_h(const GridGeometry& g, const SensorModelParams& p) {
  return g.binning() == AngularBinning::pinhole ? p.sigma_u_px : p.sigma_azimuth_rad;
}
double sigma_v(const GridGeometry& g, const SensorModelParams& p) {
  return g.binning() == AngularBinning::pinhole ? p.sigma_v_px : p.sigma_elevation_rad;
}

}  // namespace

DenseGrid::DenseGrid(const GridGeometry& geometry, const SensorModel& model, const GridOptions& options)
    : geometry_(geometry), model_(model), options_(options), bins_(static_cast<std::size_t>(geometry.depth().bins())) {
  lmin_ = std::log(options.probability_min / (1 - options.probability_min));
  lmax_ = std::log(options.probability_max / (1 - options.probability_max));
  values_.assign(geometry.column_count() * bins_, 0.0);
  touched_.assign(geometry.column_count(), 0);
}

void DenseGrid::insert(const std::vector<Eigen::Vector3f>& points) {
  const auto& g = geometry_;
  const auto& p = model_.params();
  for (const auto& q : points) {
    if (!q.allFinite() || q.isZero()) continue;
    Position s;
    if (!reference_position(g, q, s)) continue;
    const double sh = sigma_h(g, p), sv = sigma_v(g, p);
    const double ka = p.support_k * sh, ke = p.support_k * sv;
    const double sigma = model_.sigma_depth_at(s.depth);
    for (int e = 0; e < g.height(); ++e) {
      // Column extent [lower, lower + width) overlaps [centre - k s, centre + k s].
      const double elo = g.elevation().lower(e), ehi = upper(g.elevation(), e);
      if (ehi <= s.v - ke || elo > s.v + ke) continue;
      for (int a = 0; a < g.width(); ++a) {
        const double alo = g.azimuth().lower(a), ahi = upper(g.azimuth(), a);
        if (ahi <= s.h - ka || alo > s.h + ka) continue;
        const double da = (g.azimuth().centre(a) - s.h) / sh;
        const double de = (g.elevation().centre(e) - s.v) / sv;
        const long double b = da * da + de * de;
        const std::size_t column = g.column(a, e);
        touched_[column] = 1;
        for (std::size_t k = 0; k < bins_; ++k) {
          double& v = values_[column * bins_ + k];
          v += static_cast<double>(logit_opdf(g.depth().centre(static_cast<int>(k)) - s.depth, b, sigma));
          if (options_.mode == UpdateMode::clamped) v = std::min(std::max(v, lmin_), lmax_);
        }
      }
    }
  }
}

DenseGrid::Surface DenseGrid::surface(std::size_t column) const {
  Surface s;
  if (!touched_[column]) return s;
  const double* v = &values_[column * bins_];
  double best = v[0];
  for (std::size_t k = 1; k < bins_; ++k) best = std::max(best, v[k]);
  const double floor_value = best - kSurfaceTieTolerance;  // CONVENTIONS 6 ties, as surface.hpp defines them
  std::size_t first = 0;
  while (v[first] < floor_value) ++first;
  std::size_t last = first;
  while (last + 1 < bins_ && v[last + 1] >= floor_value) ++last;
  s.unknown = false;
  const auto& depth = geometry_.depth();
  if (first == 0 && last == bins_ - 1) {
    s.bin = static_cast<int>(bins_);
    s.depth_m = depth.max();
    s.probability = 1.0 / (1.0 + std::exp(-best));
    return s;
  }
  if (last == bins_ - 1 && best < -kSurfaceTieTolerance) {  // surface.hpp: a peak beyond the grid
    s.bin = static_cast<int>(bins_);
    s.depth_m = depth.max();
    s.probability = 1.0 / (1.0 + std::exp(-v[0]));
    return s;
  }
  if (options_.mode == UpdateMode::clamped && best >= lmax_) {
    s.bin = static_cast<int>((first + last) / 2);
    s.depth_m = 0.5 * (depth.centre(static_cast<int>(first)) + depth.centre(static_cast<int>(last)));
  } else {
    s.bin = static_cast<int>(first);
    s.depth_m = depth.centre(static_cast<int>(first));
  }
  s.probability = 1.0 / (1.0 + std::exp(-v[s.bin]));
  return s;
}

std::vector<double> improvement_map(const GridGeometry& g, const SensorModel& model,
                                    const std::vector<DenseGrid::Surface>& surfaces) {
  const auto& p = model.params();
  const double sh = sigma_h(g, p), sv = sigma_v(g, p);
  const double ka = p.support_k * sh, ke = p.support_k * sv;
  std::vector<double> result(g.column_count(), 0.0);
  for (int ej = 0; ej < g.height(); ++ej)
    for (int aj = 0; aj < g.width(); ++aj) {
      const std::size_t j = g.column(aj, ej);
      const double rho_j = surfaces[j].unknown ? 0.0 : surfaces[j].depth_m;
      const double theta = g.azimuth().centre(aj), phi = g.elevation().centre(ej);
      const double sigma = model.sigma_depth_at(rho_j);
      double sum = 0;
      for (int e = 0; e < g.height(); ++e) {
        const double elo = g.elevation().lower(e), ehi = upper(g.elevation(), e);
        if (ehi <= phi - ke || elo > phi + ke) continue;
        for (int a = 0; a < g.width(); ++a) {
          const double alo = g.azimuth().lower(a), ahi = upper(g.azimuth(), a);
          if (ahi <= theta - ka || alo > theta + ka) continue;
          const DenseGrid::Surface& v = surfaces[g.column(a, e)];
          const double rho_i = v.unknown ? 0.0 : v.depth_m, p_i = v.unknown ? 0.5 : v.probability;
          const double da = (g.azimuth().centre(a) - theta) / sh;
          const double de = (g.elevation().centre(e) - phi) / sv;
          const long double logit_s = logit_opdf(rho_i - rho_j, da * da + de * de, sigma);
          const double p_s = static_cast<double>(1.0L / (1.0L + std::exp(-logit_s)));
          const double den = p_i * p_s + (1 - p_i) * (1 - p_s);
          sum += (den > 0 ? p_i * p_s / den : p_i) - p_i;  // a certain prior stays unchanged
        }
      }
      result[j] = sum;
    }
  return result;
}

std::vector<double> improvement_map(const DenseGrid& grid) {
  std::vector<DenseGrid::Surface> surfaces(grid.geometry().column_count());
  for (std::size_t c = 0; c < surfaces.size(); ++c) surfaces[c] = grid.surface(c);
  return improvement_map(grid.geometry(), grid.model(), surfaces);
}

GridGeometry crop(const GridGeometry& full, int azimuth_first, int elevation_first, int width, int height) {
  GeometryParams p = full.params();
  if (p.angular_binning == AngularBinning::pinhole) {
    // The same pixels of a smaller image: the principal point moves with the crop's origin.
    p.camera->cx -= azimuth_first;
    p.camera->cy -= elevation_first;
    p.camera->width = width;
    p.camera->height = height;
  } else {
    p.azimuth_min_rad = full.azimuth().lower(azimuth_first);
    p.azimuth_max_rad = full.azimuth().lower(azimuth_first) + width * full.azimuth().width();
    p.elevation_min_rad = full.elevation().lower(elevation_first);
    p.elevation_max_rad = full.elevation().lower(elevation_first) + height * full.elevation().width();
  }
  p.azimuth_bins = width;
  p.elevation_bins = height;
  return GridGeometry(p);
}

std::vector<DenseGrid::Surface> surfaces_of(const SurfaceMap& surface) {
  std::vector<DenseGrid::Surface> surfaces(surface.size());
  for (std::size_t c = 0; c < surfaces.size(); ++c)
    surfaces[c] = {surface.depth_m[c], surface.probability[c], surface.bin[c], surface.unknown[c] != 0};
  return surfaces;
}

ImprovementAgreement compare_improvement(const GridGeometry& geometry, const SensorModel& model,
                                         const SurfaceMap& surface) {
  const std::vector<double> expected = improvement_map(geometry, model, surfaces_of(surface));
  const ImprovementMap fast = compute_improvement(geometry, model, surface);
  ImprovementAgreement a;
  for (std::size_t c = 0; c < expected.size(); ++c) {
    a.max_difference = std::max(a.max_difference, std::abs(expected[c] - fast.value[c]));
    a.max_abs_reference = std::max(a.max_abs_reference, std::abs(expected[c]));
  }
  return a;
}

SurfaceAgreement compare_surfaces(const ColumnGrid& fast, const DenseGrid& ref) {
  SurfaceAgreement a;
  const SurfaceMap s = compute_surface(fast);
  for (std::size_t c = 0; c < s.size(); ++c) {
    const DenseGrid::Surface r = ref.surface(c);
    ++a.columns;
    a.touched += r.unknown ? 0 : 1;
    if (r.bin == s.bin[c] && (r.unknown == (s.unknown[c] != 0))) ++a.same_bin;
    a.max_dp = std::max(a.max_dp, std::abs(r.probability - s.probability[c]));
  }
  return a;
}

double max_log_odds_difference(const ColumnGrid& fast, const DenseGrid& ref) {
  const GridGeometry& g = fast.geometry();
  double max_dl = 0;
  for (std::size_t c = 0; c < g.column_count(); ++c)
    for (int b = 0; b < g.depth().bins(); ++b)
      max_dl = std::max(max_dl, std::abs(ref.log_odds(c, b) - fast.log_odds(static_cast<ColumnIndex>(c), b)));
  return max_dl;
}

}  // namespace occ_improve::reference
