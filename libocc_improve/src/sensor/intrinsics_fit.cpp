#include "occ_improve/sensor/intrinsics_fit.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace occ_improve {
namespace {

template <typename Visit>
void for_each_valid(const float* xyz, int width, int height, std::size_t stride, Visit&& visit) {
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const float* p = xyz + (static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u)) * stride;
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]) || !(p[2] > 0)) continue;
      visit(u, v, static_cast<double>(p[0]) / p[2], static_cast<double>(p[1]) / p[2]);
    }
}

}  // namespace

IntrinsicsFit fit_intrinsics(const float* xyz, int width, int height, std::size_t stride_floats) {
  if (xyz == nullptr || width <= 0 || height <= 1 || stride_floats < 3)
    throw InvalidInput("intrinsics can only be estimated from an organized cloud (height > 1)");
  // Normal equations of the two line fits u = fx a + cx (a = x/z), v = fy b + cy (b = y/z).
  double saa = 0, sa = 0, sau = 0, su = 0, sbb = 0, sb = 0, sbv = 0, sv = 0;
  std::size_t n = 0;
  for_each_valid(xyz, width, height, stride_floats, [&](int u, int v, double a, double b) {
    saa += a * a, sa += a, sau += a * u, su += u;
    sbb += b * b, sb += b, sbv += b * v, sv += v;
    ++n;
  });
  if (n < 100) throw InvalidInput("too few valid points (" + std::to_string(n) + ") to estimate the camera intrinsics");
  const double dn = static_cast<double>(n);
  const double det_u = dn * saa - sa * sa, det_v = dn * sbb - sb * sb;
  if (!(det_u > 0) || !(det_v > 0))
    throw InvalidInput("the valid points do not span the image: cannot estimate intrinsics");
  IntrinsicsFit fit;
  PinholeIntrinsics& k = fit.intrinsics;
  k.fx = (dn * sau - sa * su) / det_u;
  k.cx = (su - k.fx * sa) / dn;
  k.fy = (dn * sbv - sb * sv) / det_v;
  k.cy = (sv - k.fy * sb) / dn;
  k.width = width;
  k.height = height;
  try {
    k.validate();
  } catch (const InvalidParameter& e) {
    throw InvalidInput(std::string("the estimated intrinsics are not a camera: ") + e.what());
  }
  double sum2 = 0;
  for_each_valid(xyz, width, height, stride_floats, [&](int u, int v, double a, double b) {
    const double du = k.fx * a + k.cx - u, dv = k.fy * b + k.cy - v;
    const double r2 = du * du + dv * dv;
    sum2 += r2;
    fit.max_residual_px = std::max(fit.max_residual_px, std::sqrt(r2));
  });
  fit.rms_residual_px = std::sqrt(sum2 / dn);
  fit.points_used = n;
  return fit;
}

IntrinsicsFit fit_intrinsics_checked(const float* xyz, int width, int height, std::size_t stride_floats,
                                     double max_rms_px) {
  // Before the fit: a limit no fit can meet (<= 0, NaN) is the caller's mistake, not the cloud's.
  detail::require_parameter(std::isfinite(max_rms_px) && max_rms_px > 0, "max_rms_px", max_rms_px, "finite and > 0");
  const IntrinsicsFit fit = fit_intrinsics(xyz, width, height, stride_floats);
  if (!(fit.rms_residual_px <= max_rms_px)) {
    // No hint how to give the camera: that is the caller's (a tool's flag, a Python argument).
    std::ostringstream m;
    m << "the cloud is not a pinhole range image: intrinsics fitted from its points miss their pixels by "
      << fit.rms_residual_px << " px RMS (at most " << max_rms_px << " accepted)";
    throw InvalidInput(m.str());
  }
  return fit;
}

}  // namespace occ_improve
