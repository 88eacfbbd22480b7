#pragma once
// Pinhole intrinsics recovered from an organized cloud (CONVENTIONS 2c needs the camera of every frame; it is
// never assumed): two independent least-squares lines u = fx x/z + cx and v = fy y/z + cy over the valid
// pixels, with the residual that says whether the cloud really is a pinhole range image.
#include "occ_improve/geometry/geometry.hpp"

#include <cstddef>

namespace occ_improve {

struct IntrinsicsFit {
  PinholeIntrinsics intrinsics;
  double rms_residual_px = 0;  ///< RMS of the fitted pixel position against the pixel's own (u, v)
  double max_residual_px = 0;
  std::size_t points_used = 0;
};

/// A fit worse than this (RMS) is not a pinhole range image. Back-projected Kinect frames fit to < 4e-5 px
/// RMS (float rounding; measured on every cloud in shared/data), a rectified stereo cloud to 4e-3 px; a
/// resampled or registered cloud misses by pixels. 0.01 px is 3% of a pixel-native column's angular sigma.
constexpr double kMaxIntrinsicsFitResidualPx = 0.01;

/// Fits the intrinsics of an organized cloud of width x height points, the point of pixel (u, v) at
/// xyz[(v * width + u) * stride_floats]. Points with z <= 0 or a coordinate not finite are left out.
/// Throws InvalidInput when fewer than 100 points are valid or they do not span the image.
IntrinsicsFit fit_intrinsics(const float* xyz, int width, int height, std::size_t stride_floats);

/// fit_intrinsics that also refuses a poor fit (RMS above max_rms_px) with InvalidInput naming the
/// residual, so that callers tell the user to give the intrinsics instead (the message names no way to
/// give them: the caller knows its own). max_rms_px not finite or <= 0 is InvalidParameter.
IntrinsicsFit fit_intrinsics_checked(const float* xyz, int width, int height, std::size_t stride_floats,
                                     double max_rms_px = kMaxIntrinsicsFitResidualPx);

}  // namespace occ_improve
