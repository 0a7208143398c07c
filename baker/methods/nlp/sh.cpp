#include "methods/nlp/sh.hpp"

#include <algorithm>

#include "methods/nlp/quadrature.hpp"

namespace hfbake::sh {

double evaluate(const Coeffs& c, Vec3 d) {
  const Coeffs y = eval(d);
  double s = 0;
  for (int i = 0; i < kCount; ++i) s += c[i] * y[i];
  return s;
}

Coeffs rotate_zonal(const std::array<double, kBands>& zh, Vec3 n) {
  const Coeffs y = eval(normalize(n));
  Coeffs c{};
  for (int i = 0; i < kCount; ++i) {
    const int l = band_of(i);
    c[i] = std::sqrt(4 * kPi / (2 * l + 1)) * zh[l] * y[i];
  }
  return c;
}

namespace {

// The product of three bands <= 3 is a polynomial of degree <= 9 in (x, y, z): a 12-point Gauss-Legendre
// rule in z and 24 equally spaced azimuths integrate it exactly (odd powers of sqrt(1 - z^2) come with odd
// azimuthal frequencies < 24 and vanish exactly).
ProductTensor make_product_tensor() {
  const QuadratureRule gz = gauss_legendre(12);
  const int nphi = 24;
  std::array<std::array<std::array<double, kCount>, kCount>, kCount> c{};
  for (std::size_t a = 0; a < gz.x.size(); ++a) {
    const double z = gz.x[a], r = std::sqrt(std::max(0.0, 1 - z * z));
    for (int p = 0; p < nphi; ++p) {
      const double phi = 2 * kPi * (p + 0.5) / nphi, w = gz.w[a] * 2 * kPi / nphi;
      double y[kCount];
      eval(r * std::cos(phi), r * std::sin(phi), z, y);
      for (int i = 0; i < kCount; ++i)
        for (int j = 0; j < kCount; ++j)
          for (int k = 0; k < kCount; ++k) c[i][j][k] += w * y[i] * y[j] * y[k];
    }
  }
  ProductTensor t;
  for (int i = 0; i < kCount; ++i)
    for (int j = 0; j < kCount; ++j)
      for (int k = 0; k < kCount; ++k)
        if (std::abs(c[i][j][k]) > 1e-12) t.entries.push_back({i, j, k, c[i][j][k]});
  return t;
}

}  // namespace

const ProductTensor& product_tensor() {
  static const ProductTensor t = make_product_tensor();
  return t;
}

Coeffs product(const Coeffs& a, const Coeffs& b) {
  Coeffs out{};
  for (const auto& e : product_tensor().entries) out[e.k] += e.c * a[e.i] * b[e.j];
  return out;
}

std::array<std::array<double, kCount>, kCount> product_matrix(const Coeffs& a) {
  std::array<std::array<double, kCount>, kCount> m{};
  for (const auto& e : product_tensor().entries) m[e.k][e.j] += e.c * a[e.i];
  return m;
}

}  // namespace hfbake::sh
