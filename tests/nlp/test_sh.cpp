// Order-4 real SH: basis, rotation, zonal harmonics, products, environment projection, each against an
// independent truth (orthonormality, associated Legendre functions, closed-form integrals).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "env/environment.hpp"
#include "methods/nlp/quadrature.hpp"
#include "methods/nlp/sh.hpp"
#include "methods/nlp/sh_lighting.hpp"

namespace hfbake {
namespace {

Vec3 dir(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// Integrates f(w) over the sphere with a product rule exact for polynomials of degree <= 2 * nz - 1 in z
// and azimuthal frequencies < nphi.
template <class F>
double sphere_integral(F f, int nz = 24, int nphi = 48) {
  const QuadratureRule g = gauss_legendre(nz);
  double s = 0;
  for (std::size_t a = 0; a < g.x.size(); ++a)
    for (int p = 0; p < nphi; ++p) {
      const double phi = 2 * kPi * (p + 0.5) / nphi;
      s += g.w[a] * 2 * kPi / nphi * f(dir(std::acos(g.x[a]), phi));
    }
  return s;
}

// Integrates over the sphere split at the plane through n (for clamped functions): theta about n.
template <class F>
double sphere_integral_about(Vec3 n, F f, int nt = 64, int nphi = 128) {
  n = normalize(n);
  const Vec3 t = normalize(std::abs(n.z) < 0.9 ? cross(n, Vec3{0, 0, 1}) : cross(n, Vec3{1, 0, 0}));
  const Vec3 b = cross(n, t);
  double s = 0;
  for (int half = 0; half < 2; ++half) {
    const QuadratureRule g = gauss_legendre(nt, half == 0 ? 0 : -1, half == 0 ? 1 : 0);
    for (std::size_t a = 0; a < g.x.size(); ++a) {
      const double c = g.x[a], r = std::sqrt(1 - c * c);
      for (int p = 0; p < nphi; ++p) {
        const double phi = 2 * kPi * (p + 0.5) / nphi;
        const Vec3 w = n * c + t * (r * std::cos(phi)) + b * (r * std::sin(phi));
        s += g.w[a] * 2 * kPi / nphi * f(w);
      }
    }
  }
  return s;
}

TEST(Sh, OrthonormalByQuadrature) {
  for (int i = 0; i < sh::kCount; ++i)
    for (int j = 0; j < sh::kCount; ++j) {
      const double v = sphere_integral([&](Vec3 w) { return sh::eval(w)[i] * sh::eval(w)[j]; });
      EXPECT_NEAR(v, i == j ? 1.0 : 0.0, 1e-12) << i << "," << j;
    }
}

// The closed-form polynomials against K_lm P_l^|m|(cos theta) {sqrt2 cos(m phi), sqrt2 sin(|m| phi)} with
// std::assoc_legendre (which has no Condon-Shortley phase: the documented convention).
TEST(Sh, MatchesAssociatedLegendreWithoutCondonShortley) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  auto fact = [](int n) {
    double f = 1;
    for (int k = 2; k <= n; ++k) f *= k;
    return f;
  };
  for (int trial = 0; trial < 50; ++trial) {
    const double theta = std::acos(2 * u(rng) - 1), phi = 2 * kPi * u(rng);
    const sh::Coeffs y = sh::eval(dir(theta, phi));
    for (int l = 0; l < 4; ++l)
      for (int m = -l; m <= l; ++m) {
        const int am = std::abs(m);
        const double k = std::sqrt((2 * l + 1) / (4 * kPi) * fact(l - am) / fact(l + am));
        const double p = std::assoc_legendre(l, am, std::cos(theta));
        const double want = m == 0 ? k * p
                                   : (m > 0 ? std::sqrt(2.0) * k * p * std::cos(m * phi)
                                            : std::sqrt(2.0) * k * p * std::sin(am * phi));
        EXPECT_NEAR(y[sh::index(l, m)], want, 1e-12) << l << " " << m;
      }
  }
  // Pinned signs: +y, +z, +x for band 1.
  const sh::Coeffs y = sh::eval(Vec3{0.6, 0, 0.8});
  EXPECT_GT(y[3], 0);
  EXPECT_NEAR(y[1], 0, 1e-15);
}

TEST(Sh, ProjectionOfConstantAndClampedCosine) {
  for (int i = 0; i < sh::kCount; ++i) {
    const double c = sphere_integral([&](Vec3 w) { return sh::eval(w)[i]; });
    EXPECT_NEAR(c, i == 0 ? std::sqrt(4 * kPi) : 0.0, 1e-12);
  }
  // max(z, 0): split at the equator so the quadrature is exact.
  for (int i = 0; i < sh::kCount; ++i) {
    const double c =
        sphere_integral_about({0, 0, 1}, [&](Vec3 w) { return std::max(w.z, 0.0) * sh::eval(w)[i]; });
    const int l = sh::band_of(i);
    const bool zonal = i == sh::index(l, 0);
    EXPECT_NEAR(c, zonal ? sh::kClampedCosine[l] : 0.0, 1e-12) << i;
  }
  // The paper's rounded vector (NS09 §7).
  EXPECT_NEAR(sh::kClampedCosine[0], 0.886227, 1e-6);
  EXPECT_NEAR(sh::kClampedCosine[1], 1.02333, 1e-5);
  EXPECT_NEAR(sh::kClampedCosine[2], 0.495416, 1e-6);
  EXPECT_EQ(sh::kClampedCosine[3], 0.0);
  for (int l = 0; l < 4; ++l)
    EXPECT_NEAR(sh::kCosineConvolution[l], std::sqrt(4 * kPi / (2 * l + 1)) * sh::kClampedCosine[l], 1e-12);
}

TEST(Sh, ZRotationMatchesDirectEvaluation) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  sh::Coeffs c;
  for (double& v : c) v = u(rng);
  for (double angle : {0.3, -1.2, 2.5, kPi}) {
    sh::Coeffs r;
    sh::rotate_z(c.data(), r.data(), angle);
    for (int t = 0; t < 20; ++t) {
      const Vec3 w = normalize(Vec3{u(rng), u(rng), u(rng)});
      // g(R w) = f(w): g at R w.
      const Vec3 rw{w.x * std::cos(angle) - w.y * std::sin(angle),
                    w.x * std::sin(angle) + w.y * std::cos(angle), w.z};
      EXPECT_NEAR(sh::evaluate(r, rw), sh::evaluate(c, w), 1e-12);
    }
  }
}

TEST(Sh, ZonalRotationToANormalIsTheProjectionOfTheRotatedLobe) {
  for (Vec3 n : {Vec3{0, 0, 1}, Vec3{0.3, -0.5, 0.8}, Vec3{-0.9, 0.1, 0.2}, Vec3{0, 0, -1}}) {
    n = normalize(n);
    const sh::Coeffs f = sh::rotate_zonal(sh::kClampedCosine, n);
    for (int i = 0; i < sh::kCount; ++i) {
      const double want =
          sphere_integral_about(n, [&](Vec3 w) { return std::max(dot(n, w), 0.0) * sh::eval(w)[i]; });
      EXPECT_NEAR(f[i], want, 1e-10) << i;
    }
  }
}

// Meaning of the diffuse vector: its rotated form dotted with a radiance's SH is the irradiance. For a
// radiance linear in w, L(w) = a + b (d . w), E(n) = pi a + (2 pi / 3) b (d . n) exactly.
TEST(Sh, DiffuseVectorGivesIrradiance) {
  const Vec3 d = normalize(Vec3{0.2, 0.7, -0.4});
  const double a = 1.3, b = 0.6;
  sh::Coeffs l{};
  l[0] = a * std::sqrt(4 * kPi);
  const sh::Coeffs yd = sh::eval(d);
  for (int i = 1; i < 4; ++i) l[i] = b * 4 * kPi / 3 * yd[i];  // projection of (d . w)
  for (Vec3 n : {Vec3{0, 0, 1}, Vec3{1, 0, 0}, Vec3{0.5, 0.5, 0.7}}) {
    n = normalize(n);
    const sh::Coeffs f = sh::rotate_zonal(sh::kClampedCosine, n);
    double e = 0;
    for (int i = 0; i < sh::kCount; ++i) e += f[i] * l[i];
    EXPECT_NEAR(e, kPi * a + 2 * kPi / 3 * b * dot(d, n), 1e-12);
  }
}

TEST(Sh, ProductMatchesProjectionOfPointwiseProduct) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  sh::Coeffs a, b;
  for (double& v : a) v = u(rng);
  for (double& v : b) v = u(rng);
  const sh::Coeffs p = sh::product(a, b);
  for (int k = 0; k < sh::kCount; ++k) {
    const double want =
        sphere_integral([&](Vec3 w) { return sh::evaluate(a, w) * sh::evaluate(b, w) * sh::eval(w)[k]; });
    EXPECT_NEAR(p[k], want, 1e-11) << k;
  }
  const auto m = sh::product_matrix(a);
  for (int k = 0; k < sh::kCount; ++k) {
    double s = 0;
    for (int j = 0; j < sh::kCount; ++j) s += m[k][j] * b[j];
    EXPECT_NEAR(s, p[k], 1e-12);
  }
}

TEST(ShLighting, UniformEnvironment) {
  const Environment env = make_uniform_environment({0.5f, 1.0f, 2.0f});
  const auto c = nlp::project_environment(env);
  const float rad[3] = {0.5f, 1.0f, 2.0f};
  for (int ch = 0; ch < 3; ++ch)
    for (int i = 0; i < sh::kCount; ++i)
      EXPECT_NEAR(c[ch][i], i == 0 ? rad[ch] * std::sqrt(4 * kPi) : 0, 1e-5);
}

// The built-in sky is linear in z above the horizon and constant below: closed-form bands 0 and 1.
TEST(ShLighting, SkyGradientClosedForm) {
  SkySpec spec;
  spec.height = 128;
  const Environment env = make_sky_environment(spec).environment;
  const auto c = nlp::project_environment(env);
  const double h = spec.horizon.g, zen = spec.zenith.g, gr = spec.ground.g;
  const double l00 = 0.28209479177387814 * 2 * kPi * (h + (zen - h) / 2 + gr);
  const double l10 = 0.4886025119029199 * 2 * kPi * (h / 2 + (zen - h) / 3 - gr / 2);
  EXPECT_NEAR(c[1][0], l00, 2e-4 * l00);
  EXPECT_NEAR(c[1][2], l10, 2e-3 * std::abs(l10));
  EXPECT_NEAR(c[1][1], 0, 1e-6);
  EXPECT_NEAR(c[1][3], 0, 1e-6);
}

// Orientation pin: one bright texel projects to about (solid angle) x Y(texel_direction), using the
// environment's own mapping functions.
TEST(ShLighting, SingleTexelFollowsTexelDirection) {
  const int w = 64, h = 32;
  for (auto [c0, r0] : {std::pair{5, 7}, std::pair{40, 20}, std::pair{17, 3}}) {
    std::vector<Rgb> t(std::size_t(w) * h, Rgb{0, 0, 0});
    t[std::size_t(r0) * w + c0] = Rgb{1, 1, 1};
    const Environment env = make_latlong_environment(w, h, t);
    const auto c = nlp::project_environment(env);
    const sh::Coeffs y = sh::eval(env.texel_direction(c0, r0));
    const double sa = env.texel_solid_angle(r0);
    for (int i = 0; i < sh::kCount; ++i) EXPECT_NEAR(c[0][i], sa * y[i], 0.02 * sa) << i;
  }
}

}  // namespace
}  // namespace hfbake
