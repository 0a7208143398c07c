// NLP basis, occlusion vector and the wedge matrices of NS09 Appendix A, against quadrature and brute force.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "methods/nlp/nlp_basis.hpp"
#include "methods/nlp/quadrature.hpp"
#include "methods/nlp/sh.hpp"
#include "methods/nlp/wedge_matrices.hpp"

namespace hfbake {
namespace {

TEST(Nlp, OrthonormalOnMinusOneOne) {
  const QuadratureRule g = gauss_legendre(16);
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) {
      double s = 0;
      for (std::size_t k = 0; k < g.x.size(); ++k)
        s += g.w[k] * nlp::basis(i, g.x[k]) * nlp::basis(j, g.x[k]);
      EXPECT_NEAR(s, i == j ? 1.0 : 0.0, 1e-13);
    }
}

TEST(Nlp, FourTermFormMatchesRodrigues) {
  for (double z = -1; z <= 1.0001; z += 0.125) {
    double p[4];
    nlp::basis4(z, p);
    // Rodrigues' formula expanded by hand: sqrt((2l+1)/2) P_l(z).
    EXPECT_NEAR(p[0], std::sqrt(0.5), 1e-15);
    EXPECT_NEAR(p[1], std::sqrt(1.5) * z, 1e-15);
    EXPECT_NEAR(p[2], std::sqrt(2.5) * (3 * z * z - 1) / 2, 1e-15);
    EXPECT_NEAR(p[3], std::sqrt(3.5) * (5 * z * z * z - 3 * z) / 2, 1e-15);
    for (int l = 0; l < 4; ++l) EXPECT_NEAR(p[l], nlp::basis(l, z), 1e-14);
  }
}

// Closed-form occlusion vector (NS09 order-4 form) against numerical projection of the step.
TEST(Nlp, OcclusionClosedFormMatchesQuadrature) {
  for (double sigma = -kPi / 2; sigma <= kPi / 2 + 1e-9; sigma += kPi / 17) {
    const double s = std::sin(sigma);
    double v[4];
    nlp::occlusion4(s, v);
    const QuadratureRule g = gauss_legendre(8, -1, s);
    for (int l = 0; l < 4; ++l) {
      double want = 0;
      for (std::size_t k = 0; k < g.x.size(); ++k) want += g.w[k] * nlp::basis(l, g.x[k]);
      EXPECT_NEAR(v[l], want, 1e-13) << sigma << " " << l;
    }
    // The paper's printed form.
    const double c = std::cos(sigma);
    EXPECT_NEAR(v[0], (s + 1) / std::sqrt(2.0), 1e-14);
    EXPECT_NEAR(v[1], -3 * c * c / (2 * std::sqrt(6.0)), 1e-14);
    EXPECT_NEAR(v[2], -5 * s * c * c / (2 * std::sqrt(10.0)), 1e-14);
    EXPECT_NEAR(v[3], 7 * c * c * (-4 + 5 * c * c) / (8 * std::sqrt(14.0)), 1e-14);
  }
  // Full occlusion (sigma = pi/2) is the projection of 1: (sqrt 2, 0, 0, 0).
  double v[4];
  nlp::occlusion4(1.0, v);
  EXPECT_NEAR(v[0], std::sqrt(2.0), 1e-15);
  for (int l = 1; l < 4; ++l) EXPECT_NEAR(v[l], 0, 1e-15);
}

// Brute force: the wedge's spherical function W(theta, phi) = I(alpha; w...) . P^(cos theta), projected on
// Y by a midpoint rule on a fine (theta, phi) grid.
void check_wedge(nlp::AzimuthInterpolation interp, double dphi) {
  const int taps = nlp::wedge_taps(interp), cols = 4 * taps;
  const std::vector<double> m = nlp::wedge_matrix(interp, dphi);
  ASSERT_EQ(m.size(), std::size_t(16 * cols));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> w(cols);
  for (double& x : w) x = u(rng);
  const int nt = 720, np = 360;
  std::vector<double> brute(16, 0.0);
  for (int a = 0; a < nt; ++a) {
    const double th = kPi * (a + 0.5) / nt, z = std::cos(th), st = std::sin(th);
    double p[4];
    nlp::basis4(z, p);
    for (int b = 0; b < np; ++b) {
      const double phi = dphi * (b + 0.5) / np, alpha = phi / dphi;
      double f = 0;
      for (int t = 0; t < taps; ++t)
        for (int c = 0; c < 4; ++c) f += nlp::wedge_weight(interp, t, alpha) * w[t * 4 + c] * p[c];
      double y[16];
      sh::eval(st * std::cos(phi), st * std::sin(phi), z, y);
      const double da = (kPi / nt) * (dphi / np) * st;
      for (int r = 0; r < 16; ++r) brute[r] += f * y[r] * da;
    }
  }
  for (int r = 0; r < 16; ++r) {
    double got = 0;
    for (int c = 0; c < cols; ++c) got += m[std::size_t(r) * cols + c] * w[c];
    EXPECT_NEAR(got, brute[r], 2e-5) << r;
  }
}

TEST(Wedge, LinearMatrixMatchesBruteForce) {
  check_wedge(nlp::AzimuthInterpolation::linear, 2 * kPi / 32);
  check_wedge(nlp::AzimuthInterpolation::linear, 2 * kPi / 5);
}

TEST(Wedge, BsplineMatrixMatchesBruteForce) {
  check_wedge(nlp::AzimuthInterpolation::bspline, 2 * kPi / 32);
  check_wedge(nlp::AzimuthInterpolation::bspline, 2 * kPi / 7);
}

TEST(Wedge, BsplineWeightsPartitionUnity) {
  for (double a = 0; a <= 1; a += 0.1) {
    double s = 0;
    for (int b = 0; b < 4; ++b) s += nlp::wedge_weight(nlp::AzimuthInterpolation::bspline, b, a);
    EXPECT_NEAR(s, 1, 1e-15);
  }
}

// Azimuth-independent upper hemisphere (a flat field's visibility) -> the hemisphere's SH in closed form:
// 2 pi Y00, pi Y10 / 1 ..., zero for m != 0.
TEST(Wedge, SampleMatricesReproduceTheUpperHemisphere) {
  double v[4];
  nlp::band4(0.0, 1.0, v);
  const double want_zonal[4] = {2 * kPi * 0.28209479177387814, kPi * 0.4886025119029199, 0.0,
                                2 * kPi * 0.3731763325901154 * (5.0 / 4 - 3.0 / 2)};
  for (auto interp : {nlp::AzimuthInterpolation::linear, nlp::AzimuthInterpolation::bspline})
    for (int m : {3, 8, 32, 100}) {
      const auto a = nlp::sample_matrices(interp, m);
      double V[16] = {};
      for (int j = 0; j < m; ++j)
        for (int r = 0; r < 16; ++r)
          for (int c = 0; c < 4; ++c) V[r] += a[j][r * 4 + c] * v[c];
      for (int r = 0; r < 16; ++r) {
        const int l = sh::band_of(r);
        EXPECT_NEAR(V[r], r == sh::index(l, 0) ? want_zonal[l] : 0.0, 2e-6) << m << " " << r;
      }
    }
}

// Azimuth-dependent slices: f(z, phi) = p(z) (1 + 0.5 cos phi + 0.3 sin 2 phi) with cubic p (exact in NLP);
// V converges to the quadrature projection of f as m grows.
TEST(Wedge, SampleMatricesConvergeForAzimuthalVariation) {
  auto pz = [](double z) { return 0.4 + 0.3 * z - 0.2 * z * z + 0.5 * z * z * z; };
  auto ang = [](double phi) { return 1 + 0.5 * std::cos(phi) + 0.3 * std::sin(2 * phi); };
  // NLP projection of p (exact with 4 terms).
  const QuadratureRule g = gauss_legendre(8);
  double pc[4] = {};
  for (std::size_t k = 0; k < g.x.size(); ++k)
    for (int l = 0; l < 4; ++l) pc[l] += g.w[k] * pz(g.x[k]) * nlp::basis(l, g.x[k]);
  // Truth by quadrature over the sphere.
  double truth[16] = {};
  const QuadratureRule gz = gauss_legendre(24);
  for (std::size_t a = 0; a < gz.x.size(); ++a) {
    const double z = gz.x[a], r = std::sqrt(1 - z * z);
    for (int p = 0; p < 64; ++p) {
      const double phi = 2 * kPi * (p + 0.5) / 64;
      double y[16];
      sh::eval(r * std::cos(phi), r * std::sin(phi), z, y);
      for (int i = 0; i < 16; ++i) truth[i] += gz.w[a] * 2 * kPi / 64 * pz(z) * ang(phi) * y[i];
    }
  }
  for (auto interp : {nlp::AzimuthInterpolation::linear, nlp::AzimuthInterpolation::bspline}) {
    double prev = 1e9;
    for (int m : {8, 32, 128}) {
      const auto a = nlp::sample_matrices(interp, m);
      double V[16] = {};
      for (int j = 0; j < m; ++j) {
        const double s = ang(2 * kPi * j / m);
        for (int r = 0; r < 16; ++r)
          for (int c = 0; c < 4; ++c) V[r] += a[j][r * 4 + c] * pc[c] * s;
      }
      double err = 0;
      for (int r = 0; r < 16; ++r) err = std::max(err, std::abs(V[r] - truth[r]));
      EXPECT_LT(err, prev);
      prev = err;
    }
    EXPECT_LT(prev, 2e-3);
  }
}

}  // namespace
}  // namespace hfbake
