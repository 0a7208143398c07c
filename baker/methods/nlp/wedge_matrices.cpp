#include "methods/nlp/wedge_matrices.hpp"

#include <cmath>

#include "core/vec.hpp"
#include "methods/nlp/nlp_basis.hpp"
#include "methods/nlp/quadrature.hpp"
#include "methods/nlp/sh.hpp"

namespace hfbake::nlp {

bool parse_azimuth_interpolation(const std::string& name, AzimuthInterpolation& out) {
  if (name == "linear") return out = AzimuthInterpolation::linear, true;
  if (name == "bspline") return out = AzimuthInterpolation::bspline, true;
  return false;
}

int wedge_taps(AzimuthInterpolation interp) {
  return interp == AzimuthInterpolation::linear ? 2 : 4;
}

double wedge_weight(AzimuthInterpolation interp, int b, double a) {
  if (interp == AzimuthInterpolation::linear) return b == 0 ? 1 - a : a;
  // Uniform cubic B-spline basis for the segment between control points 1 and 2.
  switch (b) {
    case 0:
      return (1 - a) * (1 - a) * (1 - a) / 6;
    case 1:
      return (3 * a * a * a - 6 * a * a + 4) / 6;
    case 2:
      return (-3 * a * a * a + 3 * a * a + 3 * a + 1) / 6;
    default:
      return a * a * a / 6;
  }
}

std::vector<double> wedge_matrix(AzimuthInterpolation interp, double dphi) {
  const int taps = wedge_taps(interp), cols = 4 * taps;
  std::vector<double> m(std::size_t(sh::kCount) * cols, 0.0);
  const QuadratureRule gt = gauss_legendre(32, 0, kPi), gp = gauss_legendre(16, 0, dphi);
  for (std::size_t a = 0; a < gt.x.size(); ++a) {
    const double th = gt.x[a], z = std::cos(th), st = std::sin(th);
    double p[4];
    basis4(z, p);
    for (std::size_t b = 0; b < gp.x.size(); ++b) {
      const double phi = gp.x[b], w = gt.w[a] * gp.w[b] * st;
      double y[sh::kCount];
      sh::eval(st * std::cos(phi), st * std::sin(phi), z, y);
      for (int t = 0; t < taps; ++t) {
        const double wt = w * wedge_weight(interp, t, phi / dphi);
        for (int r = 0; r < sh::kCount; ++r)
          for (int c = 0; c < 4; ++c) m[std::size_t(r) * cols + t * 4 + c] += wt * p[c] * y[r];
      }
    }
  }
  return m;
}

std::vector<std::array<float, 64>> sample_matrices(AzimuthInterpolation interp, int m) {
  const int taps = wedge_taps(interp), cols = 4 * taps;
  const double dphi = 2 * kPi / m;
  const std::vector<double> wm = wedge_matrix(interp, dphi);
  // Tap b of wedge w is sample w + b (linear) or w - 1 + b (B-spline).
  const int first = interp == AzimuthInterpolation::linear ? 0 : -1;
  std::vector<std::array<double, 64>> acc(m, std::array<double, 64>{});
  for (int w = 0; w < m; ++w) {
    for (int t = 0; t < taps; ++t) {
      const int j = ((w + first + t) % m + m) % m;
      for (int c = 0; c < 4; ++c) {
        double col[sh::kCount], rot[sh::kCount];
        for (int r = 0; r < sh::kCount; ++r) col[r] = wm[std::size_t(r) * cols + t * 4 + c];
        sh::rotate_z(col, rot, w * dphi);
        for (int r = 0; r < sh::kCount; ++r) acc[j][r * 4 + c] += rot[r];
      }
    }
  }
  std::vector<std::array<float, 64>> out(m);
  for (int j = 0; j < m; ++j)
    for (int k = 0; k < 64; ++k) out[j][k] = float(acc[j][k]);
  return out;
}

}  // namespace hfbake::nlp
