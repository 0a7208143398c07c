// Normalized Legendre polynomials (NLP) in z = cos theta = sin(elevation), the 1D basis in which NS09
// (§4) stores visibility and indirect radiance along one azimuth, and the closed-form occlusion vector.
#pragma once

#include <array>
#include <cmath>

namespace hfbake::nlp {

inline constexpr int kOrder = 4;  // basis functions P^_0..P^_3 (matches order-4 SH)

// P^_l(z) = sqrt((2l + 1) / 2) P_l(z), orthonormal on [-1, 1]; any l >= 0 (three-term recurrence).
double basis(int l, double z);

// The first four, evaluated together (hot loops).
template <class T>
inline void basis4(T z, T* out) {
  out[0] = T(0.70710678118654752);                        // sqrt(1/2)
  out[1] = T(1.22474487139158905) * z;                    // sqrt(3/2) z
  out[2] = T(0.79056941504209483) * (3 * z * z - 1);      // sqrt(5/2) (3z^2 - 1) / 2
  out[3] = T(0.93541434669348535) * z * (5 * z * z - 3);  // sqrt(7/2) (5z^3 - 3z) / 2
}

// Occlusion vector (NS09 Eq. 10 and its order-4 closed form): the NLP coefficients of the indicator of
// elevations below sigma, nu(sigma)_l = integral_{-1}^{sin sigma} P^_l(z) dz, as a function of
// s = sin(sigma) (c^2 = 1 - s^2):
//   [(s + 1)/sqrt 2, -3 c^2/(2 sqrt 6), -5 s c^2/(2 sqrt 10), 7 c^2 (5 c^2 - 4)/(8 sqrt 14)].
template <class T>
inline void occlusion4(T s, T* out) {
  const T c2 = 1 - s * s;
  out[0] = (s + 1) * T(0.70710678118654752);
  out[1] = c2 * T(-0.61237243569579452);                // -3 / (2 sqrt 6)
  out[2] = s * c2 * T(-0.79056941504209483);            // -5 / (2 sqrt 10)
  out[3] = c2 * (5 * c2 - 4) * T(0.23385358667337134);  // 7 / (8 sqrt 14)
}

// Visibility of elevations in (lo, hi) (sines of the elevations, lo <= hi): nu(hi) - nu(lo).
template <class T>
inline void band4(T s_lo, T s_hi, T* out) {
  T a[4], b[4];
  occlusion4(s_lo, a);
  occlusion4(s_hi, b);
  for (int l = 0; l < 4; ++l) out[l] = b[l] - a[l];
}

}  // namespace hfbake::nlp
