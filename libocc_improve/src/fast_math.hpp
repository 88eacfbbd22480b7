#pragma once
// Branch-free float exp and log that GCC vectorises inside the insertion kernel.
// Accuracy (checked in tests/test_fast_math.cpp against std::exp/std::log in double):
//   fast_exp: relative error < 2e-7 on [-87, 88]; fast_log: absolute error < 2e-7 on normal floats.
#include <cstdint>
#include <cstring>

namespace occ_improve::detail {

inline float bits_to_float(std::uint32_t b) {
  float f;
  std::memcpy(&f, &b, sizeof f);
  return f;
}
inline std::uint32_t float_to_bits(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  return b;
}

inline float fast_exp(float x) {
  x = x < -87.0f ? -87.0f : (x > 88.0f ? 88.0f : x);
  // round(x / ln2) via truncation of a positive number: floorf would be a libm call on baseline x86-64
  // and would stop the loop from vectorising.
  const std::int32_t ni = static_cast<std::int32_t>(x * 1.44269504088896341f + 128.5f) - 128;
  const float n = static_cast<float>(ni);
  // x - n ln2 with ln2 split in two so the reduction is exact to float precision.
  float r = x - n * 0.693359375f;
  r = r - n * -2.12194440e-4f;
  // e^r on [-0.35, 0.35]: Taylor to degree 7 (truncation < 1e-8).
  float p = 1.0f / 5040.0f;
  p = p * r + 1.0f / 720.0f;
  p = p * r + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  const std::int32_t e = ni + 127;
  return p * bits_to_float(static_cast<std::uint32_t>(e) << 23);
}

inline float fast_log(float x) {
  x = x < 1.17549435e-38f ? 1.17549435e-38f : x;
  const std::uint32_t bits = float_to_bits(x);
  float e = static_cast<float>(static_cast<std::int32_t>(bits >> 23) - 127);
  float m = bits_to_float((bits & 0x007fffffu) | 0x3f800000u);  // [1, 2)
  const bool high = m > 1.41421356f;
  m = high ? m * 0.5f : m;
  e = high ? e + 1.0f : e;
  // log(m) = 2 atanh(s), s = (m - 1)/(m + 1) in [-0.172, 0.172]; series to s^9 (truncation < 1e-9).
  const float s = (m - 1.0f) / (m + 1.0f), s2 = s * s;
  float p = 1.0f / 9.0f;
  p = p * s2 + 1.0f / 7.0f;
  p = p * s2 + 1.0f / 5.0f;
  p = p * s2 + 1.0f / 3.0f;
  p = p * s2 + 1.0f;
  return 2.0f * s * p + e * 0.693147180559945f;
}

}  // namespace occ_improve::detail
