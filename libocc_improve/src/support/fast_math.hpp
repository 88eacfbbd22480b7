#pragma once
// Branch-free float exp and log that GCC vectorises inside the insertion kernel.
// Accuracy (checked in tests/test_fast_math.cpp against std::exp/std::log in double):
//   fast_exp: relative error < 2e-7 on [-87, 88]; fast_log: absolute error < 2e-7 on normal floats, and
//   relative error < 4e-7 for x in [0.5, 2] (log near 0). Neither divides: a division is the slowest
//   vector instruction of the kernel.
#include <cstdint>
#include <cstring>
#if defined(__x86_64__) || defined(__SSE__)
#include <xmmintrin.h>
#endif

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
  // log(1 + r), r = m - 1 in [-0.293, 0.414]: r - r^2/2 + r^3 P(r) with Cephes' minimax P (no division,
  // and accurate relative to r, so log of odds near 1 keeps tiny log-odds exact to float precision).
  const float r = m - 1.0f, r2 = r * r;
  float p = 7.0376836292e-2f;
  p = p * r - 1.1514610310e-1f;
  p = p * r + 1.1676998740e-1f;
  p = p * r - 1.2420140846e-1f;
  p = p * r + 1.4249322787e-1f;
  p = p * r - 1.6668057665e-1f;
  p = p * r + 2.0000714765e-1f;
  p = p * r - 2.4999993993e-1f;
  p = p * r + 3.3333331174e-1f;
  float y = p * r * r2 - 0.5f * r2;
  y += e * -2.12194440e-4f;  // ln 2 split in two, as in fast_exp
  return (r + y) + e * 0.693359375f;
}

/// While alive, the calling thread flushes denormal results and operands to zero (SSE FTZ + DAZ), and
/// restores its previous mode on destruction. The kernel's peak term e^-(t^2 + B) underflows far from a
/// measurement; a denormal there weighs < 1e-37 against terms >= 1e-7, but costs a microcode assist of
/// ~100 cycles per operation.
class FlushDenormals {
public:
#if defined(__x86_64__) || defined(__SSE__)
  FlushDenormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | 0x8040u); }
  ~FlushDenormals() { _mm_setcsr(saved_); }

private:
  unsigned saved_;
#endif
public:
  FlushDenormals(const FlushDenormals&) = delete;
  FlushDenormals& operator=(const FlushDenormals&) = delete;
};

}  // namespace occ_improve::detail
