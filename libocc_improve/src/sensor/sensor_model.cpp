#include "occ_improve/sensor/sensor_model.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace occ_improve {

using detail::require_parameter;

void SensorModelParams::validate() const {
  require_parameter(std::isfinite(sigma_azimuth_rad) && sigma_azimuth_rad > 0, "sigma_azimuth_rad", sigma_azimuth_rad,
                    "finite and > 0");
  require_parameter(std::isfinite(sigma_elevation_rad) && sigma_elevation_rad > 0, "sigma_elevation_rad",
                    sigma_elevation_rad, "finite and > 0");
  require_parameter(std::isfinite(sigma_u_px) && sigma_u_px > 0, "sigma_u_px", sigma_u_px, "finite and > 0");
  require_parameter(std::isfinite(sigma_v_px) && sigma_v_px > 0, "sigma_v_px", sigma_v_px, "finite and > 0");
  require_parameter(std::isfinite(sigma_depth_m) && sigma_depth_m >= 0, "sigma_depth_m", sigma_depth_m,
                    "finite and >= 0");
  require_parameter(std::isfinite(sigma_depth_per_m2) && sigma_depth_per_m2 >= 0, "sigma_depth_per_m2",
                    sigma_depth_per_m2, "finite and >= 0");
  require_parameter(std::isfinite(sigma_depth_floor_m) && sigma_depth_floor_m > 0, "sigma_depth_floor_m",
                    sigma_depth_floor_m, "finite and > 0");
  require_parameter(sigma_depth_m > 0 || sigma_depth_per_m2 > 0, "sigma_depth_m", sigma_depth_m,
                    "> 0 (or sigma_depth_per_m2 > 0)");
  require_parameter(std::isfinite(support_k) && support_k > 0 && support_k <= 10, "support_k", support_k,
                    "in (0, 10]");
}

namespace {

// The narrowest bin of an axis, in the binning's unit: the window in bins is widest there.
double narrowest_bin(const BinAxis& axis) {
  if (axis.uniform()) return axis.width();
  double narrowest = axis.width(0);
  for (int i = 1; i < axis.bins(); ++i) narrowest = std::min(narrowest, axis.width(i));
  return narrowest;
}

void require_angular_bounds(const char* name, double sigma, double support_k, double width, const char* unit) {
  std::ostringstream bound;
  bound << "<= " << kMaxAngularSigmaBins << " bin widths = " << kMaxAngularSigmaBins * width << ' ' << unit
        << " for this grid (a wider spread means the grid is finer than the sensor resolves: use fewer bins)";
  require_parameter(sigma <= kMaxAngularSigmaBins * width, name, sigma, bound.str().c_str());
  std::ostringstream support;
  support << "<= " << kMaxSupportBins << " bin widths = " << kMaxSupportBins * width << ' ' << unit
          << " for this grid (the region of support support_k x " << name << "; lower support_k or the sigma)";
  const std::string what = std::string("support_k x ") + name;
  require_parameter(support_k * sigma <= kMaxSupportBins * width, what.c_str(), support_k * sigma,
                    support.str().c_str());
}

}  // namespace

void SensorModelParams::validate_for(const GeometryParams& g) const {
  validate();
  const auto binning = make_angular_binning(g);
  const bool pixels = binning->unit() == AngularUnit::pixels;
  const char* unit = pixels ? "px" : "rad";
  require_angular_bounds(pixels ? "sigma_u_px" : "sigma_azimuth_rad", pixels ? sigma_u_px : sigma_azimuth_rad,
                         support_k, narrowest_bin(binning->horizontal()), unit);
  require_angular_bounds(pixels ? "sigma_v_px" : "sigma_elevation_rad", pixels ? sigma_v_px : sigma_elevation_rad,
                         support_k, narrowest_bin(binning->vertical()), unit);
  const double far_sigma =
      std::max(sigma_depth_floor_m, sigma_depth_m + sigma_depth_per_m2 * g.depth_max_m * g.depth_max_m);
  const double range = g.depth_max_m - g.depth_min_m;
  std::ostringstream depth;
  depth << "<= the depth range " << range << " m (support_k x sigma_rho at depth_max = " << g.depth_max_m
        << " m, from sigma_depth_m, sigma_depth_per_m2 and sigma_depth_floor_m)";
  require_parameter(support_k * far_sigma <= range, "support_k x sigma_rho(depth_max)", support_k * far_sigma,
                    depth.str().c_str());
}

SensorModel::SensorModel(const SensorModelParams& params) : params_(params) { params.validate(); }

namespace {
// log(sigmoid(u)) without overflow for any finite u.
double log_sigmoid(double u) { return u >= 0 ? -std::log1p(std::exp(-u)) : u - std::log1p(std::exp(u)); }
}  // namespace

double logit_opdf(double d_rho, double angular_term, double sigma_rho) {
  const double t = d_rho / sigma_rho;
  const double u = 2.0 * (t + 2.0) + angular_term;
  const double log_step = std::log(0.5) + log_sigmoid(u);             // log of 1/2 sigmoid(u)
  const double log_peak = std::log(1.0 / 3.0) - (t * t + angular_term);  // log of 1/3 exp(-(t^2 + B))
  const double hi = std::max(log_step, log_peak), lo = std::min(log_step, log_peak);
  const double log_p = hi + std::log1p(std::exp(lo - hi));
  // P <= 1/2 + 1/3, so log(1 - P) is well conditioned.
  return log_p - std::log1p(-std::exp(log_p));
}

double opdf_peak(double d_rho, double angular_term, double sigma_rho) {
  const double t = d_rho / sigma_rho;
  return std::exp(-(t * t + angular_term)) / 3.0;
}

double opdf(double d_rho, double angular_term, double sigma_rho) {
  const double t = d_rho / sigma_rho;
  const double u = 2.0 * (t + 2.0) + angular_term;
  return 0.5 / (1.0 + std::exp(-u)) + opdf_peak(d_rho, angular_term, sigma_rho);
}

}  // namespace occ_improve
