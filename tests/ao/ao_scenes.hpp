// Closed-form test scenes as height fields, and their expected
// values computed here independently of the code under test.
#pragma once

#include <cmath>
#include <functional>

#include "core/vec.hpp"
#include "field/height_field.hpp"

namespace hfbake::test {

// A cylindrical pit of radius rw and depth d (texels, texel_size 1) centred in an n x n field (n odd): texels
// with distance < rw are the floor (-d), the rest ground (0). The bilinear wall rises over one texel, its top
// at distance rw +- the raster.
inline HeightField make_pit(int n, double rw, double d, double texel = 1.0) {
  HeightField f;
  f.width = f.height = n;
  f.texel_size = texel;
  f.z.resize(f.texel_count());
  const int c = n / 2;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      f.z[f.index(i, j)] = float((std::hypot(i - c, j - c) < rw ? -d : 0.0) * texel);
  return f;
}

// An infinite wall parallel to y: ground 0 for i < x0, plateau h for i >= x0 (the wall top at x = x0 exactly;
// the bilinear ramp spans [x0 - 1, x0]). Put the receiver at row n / 2, some texels left of x0.
inline HeightField make_wall(int width, int n, int x0, double h) {
  HeightField f;
  f.width = width;
  f.height = n;
  f.z.resize(f.texel_count());
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < width; ++i) f.z[f.index(i, j)] = float(i >= x0 ? h : 0.0);
  return f;
}

// A plane z = gx x + gy y.
inline HeightField make_plane(int n, double gx, double gy, Wrap wrap = Wrap::clamp) {
  HeightField f;
  f.width = f.height = n;
  f.wrap = wrap;
  f.z.resize(f.texel_count());
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) f.z[f.index(i, j)] = float(gx * i + gy * j);
  return f;
}

// Simpson's rule with n (even) intervals: an independent quadrature for the expectations.
inline double simpson(const std::function<double(double)>& g, double a, double b, int n = 4000) {
  const double h = (b - a) / n;
  double s = g(a) + g(b);
  for (int k = 1; k < n; ++k) s += g(a + k * h) * (k % 2 ? 4 : 2);
  return s * h / 3;
}

// Cosine-weighted occluded fraction at the centre of a pit (receiver normal up) with falloff rho(d): every
// ray below the rim elevation hits the wall at distance rw / cos e.
inline double pit_occlusion(double rw, double d, const std::function<double(double)>& rho) {
  const double top = std::atan2(d, rw);
  return 2 * simpson([&](double e) { return rho(rw / std::cos(e)) * std::sin(e) * std::cos(e); }, 0, top);
}

// Cosine- or uniform-weighted occluded fraction at distance x0 from an infinite wall of height h, K
// directions phi_k = 2 pi k / K (K = 0: the exact azimuthal integral).
// half_length: the wall's extent either side of the receiver (a finite field), infinite by default.
inline double wall_occlusion(double x0, double h, int K, bool cosine,
                             const std::function<double(double)>& rho, double half_length = INFINITY) {
  auto slice = [&](double phi) {
    if (std::cos(phi) <= 1e-12 || x0 * std::abs(std::tan(phi)) > half_length) return 0.0;
    const double X = x0 / std::cos(phi), top = std::atan2(h, X);
    return simpson(
        [&](double e) { return rho(X / std::cos(e)) * (cosine ? std::sin(e) : 1.0) * std::cos(e); }, 0, top,
        2000);
  };
  const double f = cosine ? 2.0 : 1.0;
  if (K == 0) return f * simpson(slice, -kPi / 2, kPi / 2, 4000) / (2 * kPi);
  double s = 0;
  for (int k = 0; k < K; ++k) s += slice(2 * kPi * k / K);
  return f * s / K;
}

}  // namespace hfbake::test
