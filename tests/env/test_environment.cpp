// Environment sampling, mip levels, the built-in sky and the cube view, against closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "env/environment.hpp"

namespace hfbake {
namespace {

constexpr double k4Pi = 4 * kPi;

Environment random_env(int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 10.f);
  std::vector<Rgb> t(std::size_t(2 * h) * h);
  for (Rgb& x : t) x = {u(rng), u(rng), u(rng)};
  return make_latlong_environment(2 * h, h, std::move(t));
}

TEST(Environment, UniformIsUniformEverywhere) {
  const Environment env = make_uniform_environment({0.5f, 1.0f, 2.0f});
  EXPECT_TRUE(env.uniform);
  for (Vec3 d : {Vec3{0, 0, 1}, Vec3{0, 0, -1}, Vec3{1, 2, 3}, Vec3{-1, 0.1, 0}}) {
    const Rgb a = env.radiance(d), b = env.radiance_filtered(d, 0.7);
    EXPECT_FLOAT_EQ(a.r, 0.5f);
    EXPECT_FLOAT_EQ(a.g, 1.0f);
    EXPECT_FLOAT_EQ(b.b, 2.0f);
  }
  // The stand-in lat-long integrates to 4 pi L.
  const Rgb total = integrate_sphere(env);
  EXPECT_NEAR(total.g, k4Pi, 1e-4);
}

TEST(Environment, LatLongSolidAnglesSumTo4Pi) {
  for (int h : {1, 3, 8, 64, 256}) {
    double sum = 0;
    for (int r = 0; r < h; ++r) sum += 2 * h * latlong_texel_solid_angle(2 * h, h, r);
    EXPECT_NEAR(sum, k4Pi, 1e-12) << h;
  }
}

TEST(Environment, TexelDirectionFollowsTheDocumentedLayout) {
  const Environment env = random_env(4, 1);  // 8 x 4
  // Texel (2, 1): theta = pi * 1.5 / 4 from +z, phi = 2 pi * 2.5 / 8 from +x towards +y.
  const double th = kPi * 1.5 / 4, ph = 2 * kPi * 2.5 / 8;
  const Vec3 d = env.texel_direction(2, 1);
  EXPECT_NEAR(d.x, std::sin(th) * std::cos(ph), 1e-12);
  EXPECT_NEAR(d.y, std::sin(th) * std::sin(ph), 1e-12);
  EXPECT_NEAR(d.z, std::cos(th), 1e-12);
  // Column 0 starts at +x: a direction just past +x towards +y is in column 0, just before is the last.
  EXPECT_EQ(env.texel_direction(0, 0).y > 0, true);
  EXPECT_EQ(env.texel_direction(7, 0).y < 0, true);
}

TEST(Environment, SinglePatchIsFoundInItsDirection) {
  const int h = 16, w = 32;
  std::vector<Rgb> t(std::size_t(w) * h, Rgb{0, 0, 0});
  const int pc = 5, pr = 3;
  t[std::size_t(pr) * w + pc] = {100, 100, 100};
  const Environment env = make_latlong_environment(w, h, t);
  // At the patch's center the bilinear lookup returns the texel (lookups compute angles in float with a
  // 1e-5 rad atan2: 5e-5 of a texel here, so within 0.01 of 100).
  EXPECT_NEAR(env.radiance(env.texel_direction(pc, pr)).r, 100.f, 0.01);
  // theta = pi * 3.5 / 16, phi = 2 pi * 5.5 / 32: an independent statement of where the patch is.
  const double th = kPi * 3.5 / 16, ph = 2 * kPi * 5.5 / 32;
  EXPECT_NEAR(env.radiance({std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)}).g, 100.f,
              0.01);
  // The opposite direction sees nothing.
  EXPECT_FLOAT_EQ(env.radiance(-env.texel_direction(pc, pr)).r, 0.f);
  // Half a texel off in azimuth, bilinear gives half.
  const double ph2 = 2 * kPi * 6.0 / 32;
  EXPECT_NEAR(env.radiance({std::sin(th) * std::cos(ph2), std::sin(th) * std::sin(ph2), std::cos(th)}).r,
              50.f, 0.01);
}

TEST(Environment, AzimuthWrapsAcrossTheSeam) {
  const int h = 8, w = 16;
  std::vector<Rgb> t(std::size_t(w) * h, Rgb{0, 0, 0});
  for (int r = 0; r < h; ++r) t[std::size_t(r) * w] = {1, 1, 1};  // column 0 bright
  const Environment env = make_latlong_environment(w, h, t);
  // Exactly on +x (phi = 0) lies between the last column and column 0: bilinear gives 1/2.
  EXPECT_NEAR(env.radiance({1, 0, 0}).r, 0.5f, 1e-6);
}

TEST(Environment, MipLevelsConserveTheIntegral) {
  const Environment env = random_env(64, 7);
  ASSERT_GE(env.levels.size(), 7u);  // 128x64 down to 2x1
  EXPECT_EQ(env.levels.back().width, 2);
  EXPECT_EQ(env.levels.back().height, 1);
  // Independent truth: sum of texel * solid angle at level 0, computed here.
  double truth = 0;
  const auto& l0 = env.levels[0];
  for (int r = 0; r < l0.height; ++r)
    for (int c = 0; c < l0.width; ++c)
      truth += l0.texels[std::size_t(r) * l0.width + c].r * latlong_texel_solid_angle(l0.width, l0.height, r);
  for (int m = 0; m < int(env.levels.size()); ++m)
    EXPECT_NEAR(integrate_sphere(env, m).r, truth, 1e-5 * truth) << m;
  // A huge cone returns the top level: the two hemispheres' means, whose average is the sphere mean.
  const Rgb a = env.radiance_filtered({1, 0.001, 0}, 10.0), b = env.radiance_filtered({-1, -0.001, 0}, 10.0);
  EXPECT_NEAR(0.5 * (a.r + b.r), truth / k4Pi, 1e-4 * truth);
  // A zero cone is the plain bilinear lookup.
  EXPECT_FLOAT_EQ(env.radiance_filtered({0.3, 0.4, 0.5}, 0).g, env.radiance({0.3, 0.4, 0.5}).g);
}

TEST(Environment, AzimuthWedgeProfile) {
  const Environment env = random_env(8, 11);  // 16 x 8, columns 2 pi / 16 wide
  const auto& l = env.levels[0];
  const auto at = [&](int c, int r) { return l.texels[std::size_t(r) * l.width + c]; };
  const double col = 2 * kPi / 16;
  // Exactly column 3: its texels.
  auto p = azimuth_wedge_profile(env, 3 * col, 4 * col);
  ASSERT_EQ(p.size(), 8u);
  for (int r = 0; r < 8; ++r) EXPECT_NEAR(p[r].g, at(3, r).g, 1e-5);
  // Half of column 5 and all of column 6: (0.5 c5 + c6) / 1.5.
  p = azimuth_wedge_profile(env, 5.5 * col, 7 * col);
  for (int r = 0; r < 8; ++r) EXPECT_NEAR(p[r].r, (0.5 * at(5, r).r + at(6, r).r) / 1.5, 1e-5);
  // Across the seam: half of column 15 and half of column 0, written as [-0.5, 0.5] columns.
  p = azimuth_wedge_profile(env, -0.5 * col, 0.5 * col);
  for (int r = 0; r < 8; ++r) EXPECT_NEAR(p[r].b, 0.5 * (at(15, r).b + at(0, r).b), 1e-5);
  // A full turn: the row mean.
  p = azimuth_wedge_profile(env, 1.0, 1.0 + 2 * kPi);
  for (int r = 0; r < 8; ++r) {
    double mean = 0;
    for (int c = 0; c < 16; ++c) mean += at(c, r).r / 16.0;
    EXPECT_NEAR(p[r].r, mean, 1e-5);
  }
  // Uniform: its radiance everywhere.
  const auto u = azimuth_wedge_profile(make_uniform_environment({2, 2, 2}), 0.1, 0.2);
  for (const Rgb& x : u) EXPECT_EQ(x.g, 2.0f);
}

TEST(Environment, SkyMatchesItsClosedForms) {
  SkySpec spec;
  spec.zenith = {0.2f, 0.4f, 1.0f};
  spec.horizon = {1.0f, 1.0f, 1.0f};
  spec.ground = {0.1f, 0.1f, 0.1f};
  spec.height = 128;
  const EnvironmentLighting sky = make_sky_environment(spec);
  const Environment& env = sky.environment;
  // Integral over the upper hemisphere of h + (zen - h) z is pi (h + zen); the lower is 2 pi ground.
  // Irradiance on a horizontal receiver: integral of L z dOmega = 2 pi (h / 2 + (zen - h) / 3).
  double upper = 0, lower = 0, irr = 0;
  const auto& l = env.levels[0];
  for (int r = 0; r < l.height; ++r)
    for (int c = 0; c < l.width; ++c) {
      const double L = l.texels[std::size_t(r) * l.width + c].r, w = env.texel_solid_angle(r);
      const double z0 = std::cos(kPi * r / l.height), z1 = std::cos(kPi * (r + 1) / l.height);
      if (r < l.height / 2) {
        upper += L * w;
        irr += L * w * 0.5 * (z0 + z1);  // mean of z over the row (dOmega is uniform in z)
      } else {
        lower += L * w;
      }
    }
  EXPECT_NEAR(upper, kPi * (1.0 + 0.2), 1e-5);
  EXPECT_NEAR(lower, 2 * kPi * 0.1, 1e-5);
  // The row-mean of L times the row-mean of z is not the mean of L z: allow the discretisation error.
  EXPECT_NEAR(irr, 2 * kPi * (0.5 + (0.2 - 1.0) / 3), 1e-3);
  // Straight up the radiance approaches the zenith; just above the horizon the horizon colour.
  EXPECT_NEAR(env.radiance({0, 0, 1}).b, 1.0f, 0.01f);
  EXPECT_NEAR(env.radiance({1, 0, 0.05}).r, 1.0f - 0.8f * 0.05f, 0.01f);  // above the half-texel blend
  EXPECT_NEAR(env.radiance({1, 0, -0.2}).r, 0.1f, 1e-6);
  // The sun: elevation 35, azimuth 135 by default.
  ASSERT_EQ(sky.lights.size(), 1u);
  const Vec3 d = sky.lights[0].direction;
  const double e = 35 * kPi / 180, a = 135 * kPi / 180;
  EXPECT_NEAR(d.x, std::cos(e) * std::cos(a), 1e-12);
  EXPECT_NEAR(d.y, std::cos(e) * std::sin(a), 1e-12);
  EXPECT_NEAR(d.z, std::sin(e), 1e-12);
  EXPECT_NEAR(sky.lights[0].angular_diameter, 0.53 * kPi / 180, 1e-12);
  EXPECT_FLOAT_EQ(sky.lights[0].irradiance.r, 3.0f);
}

TEST(Environment, SkyRotationIntensityAndSunBelowHorizon) {
  SkySpec spec;
  spec.sun_elevation_deg = 0;
  spec.sun_azimuth_deg = 90;
  spec.rotation_deg = 90;
  spec.intensity = 2;
  spec.sun_elevation_deg = 10;
  const EnvironmentLighting a = make_sky_environment(spec);
  ASSERT_EQ(a.lights.size(), 1u);
  EXPECT_NEAR(a.lights[0].direction.x, -std::cos(10 * kPi / 180), 1e-12);  // azimuth 180
  EXPECT_NEAR(a.lights[0].direction.y, 0, 1e-12);
  EXPECT_FLOAT_EQ(a.lights[0].irradiance.r, 6.0f);
  EXPECT_NEAR(a.environment.radiance({0, 0, -1}).r, 0.4f, 1e-6);  // 2 x ground
  spec.sun_elevation_deg = -5;
  EXPECT_TRUE(make_sky_environment(spec).lights.empty());
  spec.sun_elevation_deg = 20;
  spec.sun_irradiance = {0, 0, 0};
  EXPECT_TRUE(make_sky_environment(spec).lights.empty());
}

TEST(CubeView, SolidAnglesSumTo4Pi) {
  for (int n : {1, 2, 5, 32}) {
    CubeView v;
    v.size = n;
    double sum = 0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) sum += 6 * v.texel_solid_angle(i, j);
    EXPECT_NEAR(sum, k4Pi, 1e-12) << n;
  }
  // One face is a sixth of the sphere; the center texel of a 1-texel face is 4 pi / 6.
  CubeView one;
  one.size = 1;
  EXPECT_NEAR(one.texel_solid_angle(0, 0), k4Pi / 6, 1e-12);
}

TEST(CubeView, DirectionsFollowTheDocumentedFaces) {
  CubeView v;
  v.size = 3;
  const Vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int f = 0; f < 6; ++f) {
    const Vec3 c = v.texel_direction(f, 1, 1);
    EXPECT_NEAR(c.x, axes[f].x, 1e-12);
    EXPECT_NEAR(c.y, axes[f].y, 1e-12);
    EXPECT_NEAR(c.z, axes[f].z, 1e-12);
    // u x v = axis (right-handed faces).
    const Vec3 uv = cross(CubeView::face_u(f), CubeView::face_v(f));
    EXPECT_NEAR(dot(uv, axes[f]), 1, 1e-12);
  }
  // Face +x, texel (2, 0): a = 2/3, b = -2/3 -> normalize(1, 2/3, -2/3).
  const Vec3 d = v.texel_direction(0, 2, 0);
  const double n = std::sqrt(1 + 8.0 / 9);
  EXPECT_NEAR(d.x, 1 / n, 1e-12);
  EXPECT_NEAR(d.y, (2.0 / 3) / n, 1e-12);
  EXPECT_NEAR(d.z, (-2.0 / 3) / n, 1e-12);
  // Face +z (up), texel (0, 2): a = -2/3 along +x, b = 2/3 along +y.
  const Vec3 e = v.texel_direction(4, 0, 2);
  EXPECT_NEAR(e.x, (-2.0 / 3) / n, 1e-12);
  EXPECT_NEAR(e.y, (2.0 / 3) / n, 1e-12);
  EXPECT_NEAR(e.z, 1 / n, 1e-12);
}

TEST(CubeView, ConservesTheIntegralAndFindsAPatch) {
  const Environment env = random_env(32, 3);
  const CubeView view = make_cube_view(env, 16);
  double sum = 0;
  for (int f = 0; f < 6; ++f)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i) sum += view.at(f, i, j).r * view.texel_solid_angle(i, j);
  const double truth = integrate_sphere(env).r;
  EXPECT_NEAR(sum, truth, 0.01 * truth);

  // A bright patch towards -y, slightly up, lands in face -y (3) at the texel that contains it.
  const int h = 64, w = 128;
  std::vector<Rgb> t(std::size_t(w) * h, Rgb{0, 0, 0});
  // phi = 270 deg -> column 96 (texels 95/96 straddle it: brighten both), theta = 80 deg -> row 28.
  for (int r = 27; r <= 29; ++r)
    for (int c = 94; c <= 97; ++c) t[std::size_t(r) * w + c] = {1, 1, 1};
  const CubeView pv = make_cube_view(make_latlong_environment(w, h, t), 8);
  int bf = -1, bi = -1, bj = -1;
  float best = -1;
  for (int f = 0; f < 6; ++f)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i)
        if (pv.at(f, i, j).r > best) best = pv.at(f, i, j).r, bf = f, bi = i, bj = j;
  EXPECT_EQ(bf, 3);
  // Face -y has u = +x, v = +z: the patch (x ~ 0, z ~ +0.17) is at a ~ 0, b ~ +0.18 -> i in {3, 4}, j = 4.
  EXPECT_TRUE(bi == 3 || bi == 4) << bi;
  EXPECT_EQ(bj, 4);
}

}  // namespace
}  // namespace hfbake
