// Float approximations for the per-sample and per-texel hot loops of the horizon methods.
// Errors (measured over their whole domains in tests/p1): fast_atan < 4e-8 rad, fast_sincos < 2e-7.
// Always inlined, and built on compiler builtins rather than std:: wrappers: the per-instruction-set
// kernels (row_shading_*.cpp) include them, and an out-of-line copy compiled for AVX-512 must never be the
// one the linker keeps for every caller.
#pragma once

#include <cmath>

namespace hfbake::p1 {

inline constexpr float kHalfPiF = 1.57079632679489661923f;
inline constexpr float kQuarterPiF = 0.78539816339744830962f;

// atan(x) for |x| <= tan(pi/8) (Taylor series to x^15; the remainder is below 2e-8).
[[gnu::always_inline]] inline float atan_small(float x) {
  const float t = x * x;
  float p = -1.0f / 15;
  p = p * t + 1.0f / 13;
  p = p * t - 1.0f / 11;
  p = p * t + 1.0f / 9;
  p = p * t - 1.0f / 7;
  p = p * t + 1.0f / 5;
  p = p * t - 1.0f / 3;
  p = p * t + 1.0f;
  return x * p;
}

// atan2(y, x) for x >= 0 (x, y not both 0), one division: with lo = min(|y|, x), hi = max(|y|, x),
// atan(lo / hi) = pi/4 + atan((lo - hi) / (lo + hi)) when lo / hi > tan(pi/8), and atan(|y| / x) =
// pi/2 - atan(x / |y|) when |y| > x. Branch-free (selects): loops vectorise, random inputs do not
// mispredict, and there is a single division on the dependency chain.
[[gnu::always_inline]] inline float fast_atan2_pos(float y, float x) {
  const float a = __builtin_fabsf(y);
  const float lo = a < x ? a : x, hi = a < x ? x : a;
  const bool big = lo > 0.41421356f * hi;
  const float num = big ? lo - hi : lo, den = big ? lo + hi : hi;
  float r = atan_small(num / den) + (big ? kQuarterPiF : 0.0f);
  r = a > x ? kHalfPiF - r : r;
  return __builtin_copysignf(r, y);
}

// atan(x) for any finite x.
[[gnu::always_inline]] inline float fast_atan(float x) {
  return fast_atan2_pos(x, 1.0f);
}

// Elevation angle of a vector with rise dz over horizontal run h > 0: atan2(dz, h) in (-pi/2, pi/2).
[[gnu::always_inline]] inline float fast_elevation(float dz, float h) {
  return fast_atan2_pos(dz, h);
}

// sin and cos of e for |e| <= pi/2 (Taylor to e^13 / e^14).
[[gnu::always_inline]] inline void fast_sincos(float e, float& s, float& c) {
  const float t = e * e;
  float ps = 1.0f / 6227020800.0f;  // 1/13!
  ps = ps * t - 1.0f / 39916800.0f;
  ps = ps * t + 1.0f / 362880.0f;
  ps = ps * t - 1.0f / 5040.0f;
  ps = ps * t + 1.0f / 120.0f;
  ps = ps * t - 1.0f / 6.0f;
  ps = ps * t + 1.0f;
  s = e * ps;
  float pc = 1.0f / 87178291200.0f;  // 1/14!
  pc = pc * t - 1.0f / 479001600.0f;
  pc = pc * t + 1.0f / 3628800.0f;
  pc = pc * t - 1.0f / 40320.0f;
  pc = pc * t + 1.0f / 720.0f;
  pc = pc * t - 1.0f / 24.0f;
  pc = pc * t + 0.5f;
  c = 1.0f - t * pc;
}

}  // namespace hfbake::p1
