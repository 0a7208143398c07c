// Normals against the analytic normals of planes and of the sine grid.
#include <gtest/gtest.h>

#include <cmath>

#include "field/height_field.hpp"
#include "field/procedural.hpp"

namespace hfbake {
namespace {

TEST(Normals, SlopeIsExactEverywhereIncludingBorders) {
  for (double texel : {1.0, 0.25, 3.0}) {
    for (double aspect : {0.0, 30.0, 135.0, 270.0}) {
      ProceduralSpec s;
      s.kind = ProceduralKind::slope;
      s.width = 17;
      s.height = 12;
      s.angle_deg = 35;
      s.aspect_deg = aspect;
      const HeightField f = make_procedural(s, texel, Wrap::clamp);
      const auto n = compute_normals(f);
      // The plane faces azimuth `aspect`, tilted 35 degrees from +z.
      const double t = 35 * kPi / 180, a = aspect * kPi / 180;
      const Vec3 expect{std::sin(t) * std::cos(a), std::sin(t) * std::sin(a), std::cos(t)};
      for (int j = 0; j < f.height; ++j)
        for (int i = 0; i < f.width; ++i) {
          const Vec3 got = n[f.index(i, j)].d();
          ASSERT_NEAR(dot(got, expect), 1.0, 1e-6) << i << "," << j << " texel " << texel;
        }
    }
  }
}

TEST(Normals, SineGridMatchesAnalyticGradient) {
  // h = A sin(kx) sin(ky): the 3x3 quad-sum stencil is a second-order accurate gradient estimate, so the
  // angular error must fall ~4x when the period doubles.
  double previous_error = 0;
  for (int period : {16, 32, 64}) {
    ProceduralSpec s;
    s.kind = ProceduralKind::sines;
    s.width = s.height = period * 2;
    s.feature_size = period;
    s.amplitude = period / 8.0;
    const HeightField f = make_procedural(s, 1.0, Wrap::repeat);
    const auto n = compute_normals(f);
    const double k = 2 * kPi / period, A = s.amplitude;
    double max_err = 0;
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) {
        const Vec3 expect = normalize(
            {-A * k * std::cos(k * i) * std::sin(k * j), -A * k * std::sin(k * i) * std::cos(k * j), 1.0});
        max_err = std::max(max_err, std::acos(std::min(1.0, dot(n[f.index(i, j)].d(), expect))));
      }
    EXPECT_LT(max_err, 0.05) << "period " << period;
    if (previous_error > 0) {
      EXPECT_LT(max_err, previous_error / 3) << "period " << period;
    }
    previous_error = max_err;
  }
}

TEST(Normals, RepeatWrapsAcrossTheBorder) {
  // A periodic sine grid: the normal at column 0 must equal the one a shifted copy has in its interior.
  ProceduralSpec s;
  s.kind = ProceduralKind::sines;
  s.width = s.height = 32;
  s.feature_size = 16;
  const HeightField f = make_procedural(s, 1.0, Wrap::repeat);
  const auto n = compute_normals(f);
  for (int j = 0; j < 32; ++j) {
    const Vec3 a = n[f.index(0, j)].d(), b = n[f.index(16, j)].d();
    // sin(k(x+16)) = sin(kx + 2pi): identical heights around column 0 and column 16.
    EXPECT_NEAR(a.x, b.x, 1e-5);
    EXPECT_NEAR(a.y, b.y, 1e-5);
  }
}

}  // namespace
}  // namespace hfbake
