#include "reference/sh_irradiance_reference.hpp"

#include <algorithm>
#include <cmath>

#include "core/azimuth.hpp"
#include "core/layers.hpp"
#include "methods/nlp/quadrature.hpp"
#include "reference/sh_environment.hpp"

namespace hfbake::reference {
namespace {

// Gauss-Legendre in elevation within one lat-long row (at most pi / rows wide; the uniform environment's
// stand-in has 8 rows of 22.5 degrees): the integrand Y_i cos e is a trigonometric polynomial of degree <= 3
// for bands 0..2, which 8 nodes integrate to rounding over such an interval.
constexpr int kNodes = 8;
constexpr int kMaxRows = 512;

const QuadratureRule& rule() {
  static const QuadratureRule gl = gauss_legendre(kNodes);
  return gl;
}

// out[i] (i < 9) += integral over e in [a, b] of Y_i(cos e c, cos e s, sin e) cos e de.
void add_basis_integral(double a, double b, double c, double s, double* out) {
  if (!(b > a)) return;
  const QuadratureRule& gl = rule();
  const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
  for (int n = 0; n < kNodes; ++n) {
    const double e = mid + half * gl.x[n], ce = std::cos(e);
    const auto y = sh_basis(Vec3{ce * c, ce * s, std::sin(e)});
    const double w = half * gl.w[n] * ce;
    for (int i = 0; i < 9; ++i) out[i] += w * y[i];
  }
}

}  // namespace

std::vector<std::string> sh_irradiance_channels() {
  std::vector<std::string> names;
  for (const std::string& c : indexed_channels(kShIrradianceCoefficients))
    for (const char* colour : {"R", "G", "B"}) names.push_back(c + "." + colour);
  return names;
}

ShEnvironmentTable make_sh_environment_table(const Environment& env, int azimuths) {
  ShEnvironmentTable t;
  t.azimuths = azimuths;
  azimuth_table(azimuths, t.cos_phi, t.sin_phi);
  std::vector<std::vector<Rgb>> profile(static_cast<std::size_t>(azimuths));
  for (int k = 0; k < azimuths; ++k) {
    const double phi = azimuth(k, azimuths);
    profile[std::size_t(k)] = azimuth_wedge_profile(env, phi - kPi / azimuths, phi + kPi / azimuths);
    if (profile[std::size_t(k)].empty()) profile[std::size_t(k)].assign(1, env.uniform_radiance);
  }
  // At most kMaxRows rows (an 8192 x 4096 map's table would take 113 MB): groups of `merge` rows, the
  // group's radiance the solid-angle-weighted mean of its rows (rows of pi / 512 = 0.35 degrees and finer).
  const int rows0 = int(profile[0].size());
  int merge = 1;
  for (int m = 2; rows0 / merge > kMaxRows && m <= rows0 / 64; ++m)
    if (rows0 % m == 0) merge = m;
  if (merge > 1) {
    for (std::vector<Rgb>& p : profile) {
      std::vector<Rgb> merged(std::size_t(rows0 / merge));
      for (int g = 0; g < rows0 / merge; ++g) {
        double sum[3] = {}, weight = 0;
        for (int r = g * merge; r < (g + 1) * merge; ++r) {
          const double w = std::sin(kPi / 2 - kPi * r / rows0) - std::sin(kPi / 2 - kPi * (r + 1) / rows0);
          sum[0] += w * p[std::size_t(r)].r, sum[1] += w * p[std::size_t(r)].g,
              sum[2] += w * p[std::size_t(r)].b;
          weight += w;
        }
        merged[std::size_t(g)] = {float(sum[0] / weight), float(sum[1] / weight), float(sum[2] / weight)};
      }
      p = std::move(merged);
    }
  }
  t.rows = int(profile[0].size());
  const int h = t.rows;
  t.edge.resize(std::size_t(h) + 1);
  for (int r = 0; r <= h; ++r) t.edge[std::size_t(r)] = kPi / 2 - kPi * r / h;
  t.radiance.resize(std::size_t(azimuths) * h * 3);
  t.cumulative.assign(std::size_t(azimuths) * (h + 1) * kShIrradianceSums, 0.0);
  for (int k = 0; k < azimuths; ++k) {
    double* C = &t.cumulative[std::size_t(k) * (h + 1) * kShIrradianceSums];
    for (int r = 0; r < h; ++r) {
      const Rgb L = profile[std::size_t(k)][std::size_t(r)];
      const double l[3] = {L.r, L.g, L.b};
      double I[9] = {};
      add_basis_integral(t.edge[std::size_t(r) + 1], t.edge[std::size_t(r)], t.cos_phi[k], t.sin_phi[k], I);
      for (int c = 0; c < 3; ++c) t.radiance[(std::size_t(k) * h + r) * 3 + c] = l[c];
      for (int i = 0; i < 9; ++i)
        for (int c = 0; c < 3; ++c)
          C[(r + 1) * kShIrradianceSums + i * 3 + c] = C[r * kShIrradianceSums + i * 3 + c] + l[c] * I[i];
    }
  }
  return t;
}

void add_sh_environment_above(const ShEnvironmentTable& t, const double* elevation, double* out) {
  const int h = t.rows;
  const double dphi = 2 * kPi / t.azimuths;
  for (int k = 0; k < t.azimuths; ++k) {
    const double e = std::clamp(elevation[k], -kPi / 2, kPi / 2);
    // The row holding e: rows above it whole (cumulative), its own part from e up to its upper edge.
    const int r = std::clamp(int(std::floor((kPi / 2 - e) / (kPi / h))), 0, h - 1);
    const double* C = &t.cumulative[(std::size_t(k) * (h + 1) + r) * kShIrradianceSums];
    const double* L = &t.radiance[(std::size_t(k) * h + r) * 3];
    double I[9] = {};
    add_basis_integral(e, t.edge[std::size_t(r)], t.cos_phi[k], t.sin_phi[k], I);
    for (int i = 0; i < 9; ++i)
      for (int c = 0; c < 3; ++c) out[i * 3 + c] += dphi * (C[i * 3 + c] + L[c] * I[i]);
  }
}

}  // namespace hfbake::reference
