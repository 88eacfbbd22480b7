#pragma once
// The sensor occupancy PDF of eq. 1 (CONVENTIONS 3) and its noise model (CONVENTIONS 2b).
//   P_s = 1/2 (1 + exp(-u))^-1 + 1/3 exp(-(d^2/s^2 + B)),
//   d = rho - rho_bar, B = d_theta^2/s_theta^2 + d_phi^2/s_phi^2, u = 2 (d + 2 s)/s + B.
// The angular offsets and sigmas are in the grid binning's unit (AngularBinning::unit()): radians
// (spherical, lidar_rings) or pixels (pinhole); rho is the binning's depth coordinate (range, or z).
#include "occ_improve/geometry/geometry.hpp"

#include <cmath>

namespace occ_improve {

struct SensorModelParams {
  double sigma_azimuth_rad = 4.33589667773576e-4;    ///< sqrt(1.88e-7 rad^2), the paper
  double sigma_elevation_rad = 4.33589667773576e-4;
  /// Angular sigmas of the pixel-native binning: the quantisation of one pixel, 1/sqrt(12) px.
  double sigma_u_px = 0.288675134594813;
  double sigma_v_px = 0.288675134594813;
  /// Depth noise: sigma_rho(rho) = max(sigma_depth_floor_m, sigma_depth_m + sigma_depth_per_m2 * rho^2).
  double sigma_depth_m = 0.0472228758124704;  ///< sqrt(2.23e3 mm^2), the paper's constant
  double sigma_depth_per_m2 = 0.0;            ///< quadratic term [1/m]; Kinect: 1.425e-3 (Khoshelham 2012)
  double sigma_depth_floor_m = 1e-3;          ///< keeps sigma > 0 for a simulated acquisition at depth 0
  double support_k = 2.0;                     ///< region of support, in standard deviations

  /// Throws InvalidParameter naming the first bad field.
  void validate() const;

  /// validate(), then the bounds that tie the sigmas to a grid's binning (docs/METHOD.md, "Sigma bounds"),
  /// each in the binning's own unit: the angular sigma of each axis at most kMaxAngularSigmaBins bin
  /// widths, the region of support k sigma at most kMaxSupportBins bin widths, and the depth support
  /// k sigma_rho(depth_max) at most the depth range. Beyond them the model says nothing the binning can
  /// show (a spread over many columns means the grid is finer than the sensor resolves), while insertion
  /// and improvement cost grow with the square of the window (an angle of 3.2 rad ran for hours).
  /// Throws InvalidParameter naming the field, its value and the bound.
  void validate_for(const GeometryParams& geometry) const;
};

/// Angular sigma bound of SensorModelParams::validate_for, in bin widths of its axis.
constexpr double kMaxAngularSigmaBins = 4.0;
/// Region-of-support bound (support_k x angular sigma) of validate_for, in bin widths: a window of at
/// most 17 x 17 columns per measurement and per ray.
constexpr double kMaxSupportBins = 8.0;

class SensorModel {
public:
  explicit SensorModel(const SensorModelParams& params);
  const SensorModelParams& params() const { return params_; }
  double sigma_depth_at(double rho_m) const {
    double s = params_.sigma_depth_m + params_.sigma_depth_per_m2 * rho_m * rho_m;
    return s > params_.sigma_depth_floor_m ? s : params_.sigma_depth_floor_m;
  }
  /// Angular sigmas in the binning's unit: (azimuth, elevation) [rad] or (u, v) [px].
  double sigma_horizontal(const AngularBinning& b) const {
    return b.unit() == AngularUnit::pixels ? params_.sigma_u_px : params_.sigma_azimuth_rad;
  }
  double sigma_vertical(const AngularBinning& b) const {
    return b.unit() == AngularUnit::pixels ? params_.sigma_v_px : params_.sigma_elevation_rad;
  }
  /// Half-widths of the region of support, k sigma, in the binning's unit.
  double support_horizontal(const AngularBinning& b) const { return params_.support_k * sigma_horizontal(b); }
  double support_vertical(const AngularBinning& b) const { return params_.support_k * sigma_vertical(b); }
  /// The two parts of B of eq. 1, B = B_h + B_v, for an angular offset in the binning's unit.
  double horizontal_term(const AngularBinning& b, double d_horizontal) const {
    const double h = d_horizontal / sigma_horizontal(b);
    return h * h;
  }
  double vertical_term(const AngularBinning& b, double d_vertical) const {
    const double v = d_vertical / sigma_vertical(b);
    return v * v;
  }
  /// B of eq. 1 for angular offsets in the binning's unit.
  double angular_term(const AngularBinning& b, double d_horizontal, double d_vertical) const {
    return horizontal_term(b, d_horizontal) + vertical_term(b, d_vertical);
  }

private:
  SensorModelParams params_;
};

/// logit(P_s) of eq. 1, evaluated stably in log space in double precision: finite for any finite
/// input, about log(1/2) + u far in front of the measurement, -> 0 behind it.
double logit_opdf(double d_rho, double angular_term, double sigma_rho);

/// P_s of eq. 1 itself.
double opdf(double d_rho, double angular_term, double sigma_rho);

/// The peak term of eq. 1, 1/3 exp(-(d^2/s^2 + B)): P_s minus it is the step term (opdf_bounds.hpp's bounds
/// name the two apart).
double opdf_peak(double d_rho, double angular_term, double sigma_rho);

inline double logit(double p) { return std::log(p / (1.0 - p)); }
inline double probability_from_logit(double l) { return 1.0 / (1.0 + std::exp(-l)); }

}  // namespace occ_improve
