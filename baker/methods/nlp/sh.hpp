// Real spherical harmonics of order 4 (bands l = 0..3, 16 coefficients) in the world frame, the basis of
// NLP/SH (Nowrouzezahrai & Snyder 2009, "NS09") and of the sh_visibility / sh_irradiance layers.
//
// Convention (written into every EXR hfbake's nlp method produces, attribute "hfbake:sh_convention"):
//   - index i = l * (l + 1) + m, m = -l..l: 0 = (0,0); 1..3 = (1,-1), (1,0), (1,1); 4..8 = (2,-2)..(2,2);
//     9..15 = (3,-3)..(3,3).
//   - orthonormal on the unit sphere: integral over the sphere of Y_i Y_j = delta_ij.
//   - no Condon-Shortley phase: m > 0 goes with cos(m phi), m < 0 with sin(|m| phi), every polynomial below
//     has a positive constant.
//   - direction (x, y, z) = (sin theta cos phi, sin theta sin phi, cos theta): world frame, +z up, phi from
//   +x
//     towards +y (the azimuth of docs/contract.md).
//   Y0 = 0.282095
//   Y1 = 0.488603 y,  Y2 = 0.488603 z,  Y3 = 0.488603 x
//   Y4 = 1.092548 xy, Y5 = 1.092548 yz, Y6 = 0.315392 (3z^2 - 1), Y7 = 1.092548 xz, Y8 = 0.546274 (x^2 - y^2)
//   Y9 = 0.590044 y (3x^2 - y^2), Y10 = 2.890611 xyz, Y11 = 0.457046 y (5z^2 - 1), Y12 = 0.373176 z (5z^2 -
//   3), Y13 = 0.457046 x (5z^2 - 1), Y14 = 1.445306 z (x^2 - y^2), Y15 = 0.590044 x (x^2 - 3y^2)
#pragma once

#include <array>
#include <cmath>
#include <vector>

#include "core/vec.hpp"

namespace hfbake::sh {

inline constexpr int kBands = 4;   // SH order n = 4 (bands 0..3)
inline constexpr int kCount = 16;  // n^2 coefficients

using Coeffs = std::array<double, kCount>;

inline constexpr int index(int l, int m) {
  return l * (l + 1) + m;
}
inline constexpr int band_of(int i) {
  return i < 1 ? 0 : (i < 4 ? 1 : (i < 9 ? 2 : 3));
}

// The basis at a unit direction (closed-form polynomials above).
template <class T>
inline void eval(T x, T y, T z, T* out) {
  const T x2 = x * x, y2 = y * y, z2 = z * z;
  out[0] = T(0.28209479177387814);
  out[1] = T(0.4886025119029199) * y;
  out[2] = T(0.4886025119029199) * z;
  out[3] = T(0.4886025119029199) * x;
  out[4] = T(1.0925484305920792) * x * y;
  out[5] = T(1.0925484305920792) * y * z;
  out[6] = T(0.31539156525252005) * (3 * z2 - 1);
  out[7] = T(1.0925484305920792) * x * z;
  out[8] = T(0.5462742152960396) * (x2 - y2);
  out[9] = T(0.5900435899266435) * y * (3 * x2 - y2);
  out[10] = T(2.890611442640554) * x * y * z;
  out[11] = T(0.4570457994644658) * y * (5 * z2 - 1);
  out[12] = T(0.3731763325901154) * z * (5 * z2 - 3);
  out[13] = T(0.4570457994644658) * x * (5 * z2 - 1);
  out[14] = T(1.445305721320277) * z * (x2 - y2);
  out[15] = T(0.5900435899266435) * x * (x2 - 3 * y2);
}
inline Coeffs eval(Vec3 d) {
  Coeffs c;
  eval(d.x, d.y, d.z, c.data());
  return c;
}

// Value of the expansion `c` in direction d.
double evaluate(const Coeffs& c, Vec3 d);

// Rotation about +z by `angle` (radians): the result g satisfies g(R_z(angle) w) = f(w), i.e. the function is
// turned by +angle (from +x towards +y). Works in place (in == out allowed).
template <class T>
inline void rotate_z(const T* in, T* out, double angle) {
  out[0] = in[0];
  out[2] = in[2];
  out[6] = in[6];
  out[12] = in[12];
  for (int m = 1; m <= 3; ++m) {
    const T c = T(std::cos(m * angle)), s = T(std::sin(m * angle));
    for (int l = m; l <= 3; ++l) {
      const T a = in[index(l, m)], b = in[index(l, -m)];
      out[index(l, m)] = a * c - b * s;
      out[index(l, -m)] = a * s + b * c;
    }
  }
}

// Zonal harmonics: a function g(n . w) symmetric about the axis n with ZH coefficients zh[l] (the
// coefficient of Y_l0 when n = +z). Its SH coefficients: sqrt(4 pi / (2l + 1)) zh[l] Y_lm(n).
Coeffs rotate_zonal(const std::array<double, kBands>& zh, Vec3 n);

// ZH coefficients of the clamped cosine max(cos theta, 0) (NS09 §7's diffuse vector): sqrt(pi)/2,
// sqrt(pi/3), sqrt(5 pi)/8, 0 = {0.886227, 1.02333, 0.495416, 0}. The dot product of
// rotate_zonal(kClampedCosine, n) with the SH of a radiance function is the irradiance E at normal n
// (of the band-limited radiance); E / pi is what a white Lambertian surface reflects.
inline const std::array<double, kBands> kClampedCosine = {0.88622692545275801, 1.0233267079464885,
                                                          0.49541591220075137, 0.0};

// Convolution with the clamped cosine: E_lm = a_l L_lm with a_l = sqrt(4 pi / (2l + 1)) zh_l
// = {pi, 2 pi / 3, pi / 4, 0}: the SH of the irradiance E(n) as a function of the normal.
inline constexpr std::array<double, kBands> kCosineConvolution = {3.14159265358979324, 2.09439510239319549,
                                                                  0.78539816339744831, 0.0};

// The SH triple product: (a * b)_k = sum_ij C_ijk a_i b_j, C_ijk = integral of Y_i Y_j Y_k (Gaunt
// coefficients), truncated to order 4. The nonzero entries, computed by exact quadrature.
struct ProductTensor {
  struct Entry {
    int i, j, k;
    double c;
  };
  std::vector<Entry> entries;
};
const ProductTensor& product_tensor();
Coeffs product(const Coeffs& a, const Coeffs& b);

// The 16 x 16 matrix of "multiply by a": (a * b)_k = sum_j M[k][j] b_j.
std::array<std::array<double, kCount>, kCount> product_matrix(const Coeffs& a);

}  // namespace hfbake::sh
