// hsao against the closed-form scenes and the height-field fact that the sampled term above the
// horizon vanishes for an upward normal.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ao_scenes.hpp"
#include "methods/ao/hsao.hpp"

namespace hfbake {
namespace {

HsaoSettings settings(FalloffKind k, double R, int dirs = 16, int steps = 128, int rays = 4) {
  HsaoSettings s;
  s.falloff.kind = k;
  s.falloff.radius = R;
  s.directions = dirs;
  s.steps = steps;
  s.normal_rays = rays;
  return s;
}

HsaoTexel at(const HeightField& f, int i, int j, const HsaoSettings& s) {
  return hsao_texel(f, compute_normals(f)[f.index(i, j)].d(), i, j, s);
}

TEST(Hsao, PitHorizonTermIsExactAndRaysFindNothing) {
  const HeightField f = test::make_pit(81, 32, 32);
  const HsaoTexel t = at(f, 40, 40, settings(FalloffKind::step, 64));
  EXPECT_NEAR(t.horizon_occlusion, 0.5, 0.01);  // sin^2 e
  EXPECT_EQ(t.normal_occlusion, 0.0);
  // R = 40 < the rim distance 45: the wall is seen up to acos(32 / 40); linear attenuation over 64.
  for (auto [k, R] : {std::pair{FalloffKind::step, 40.0}, std::pair{FalloffKind::linear, 64.0},
                      std::pair{FalloffKind::smooth, 64.0}}) {
    Falloff fo;
    fo.kind = k, fo.radius = R;
    const double expect = test::pit_occlusion(32, 32, [&](double d) { return fo(d); });
    EXPECT_NEAR(at(f, 40, 40, settings(k, R)).occluded(), expect, 0.02) << int(k);
  }
}

TEST(Hsao, WallMatchesDiscreteK) {
  const HeightField f = test::make_wall(96, 257, 64, 32);
  auto one = [](double) { return 1.0; };
  for (int K : {8, 16}) {
    const HsaoTexel t = at(f, 32, 128, settings(FalloffKind::step, 128, K, 256));
    EXPECT_NEAR(t.occluded(), test::wall_occlusion(32, 32, K, true, one), 0.005) << K;
    EXPECT_EQ(t.normal_occlusion, 0.0);
  }
}

TEST(Hsao, PlanesAreOpen) {
  for (auto [gx, gy] : {std::pair{0.0, 0.0}, std::pair{0.3, -0.2}, std::pair{-1.5, 0.7}}) {
    const HeightField f = test::make_plane(33, gx, gy);
    for (auto [i, j] : {std::pair{16, 16}, std::pair{3, 29}}) {
      const HsaoTexel t = at(f, i, j, settings(FalloffKind::step, 12, 16, 24, 4));
      EXPECT_NEAR(t.occluded(), 0.0, 1e-9) << gx << " " << gy;
      EXPECT_GT(dot(t.bent_normal, compute_normals(f)[f.index(i, j)].d()), 0.999);
    }
  }
}

// Random flat-topped blocks: at every receiver whose normal is exactly up, the rays above the horizon
// find nothing once the horizon search is fine enough (the sampled term converges to zero with N_s).
TEST(Hsao, NormalRaysVanishForUpwardNormals) {
  HeightField f;
  f.width = f.height = 64;
  f.z.assign(f.texel_count(), 0.0f);
  std::mt19937 rng(7);
  for (int b = 0; b < 24; ++b) {
    const int x0 = rng() % 56, y0 = rng() % 56, w = 2 + rng() % 8, h = 2 + rng() % 8;
    const float z = float(rng() % 12);
    for (int j = y0; j < std::min(64, y0 + h); ++j)
      for (int i = x0; i < std::min(64, x0 + w); ++i) f.z[f.index(i, j)] = std::max(f.z[f.index(i, j)], z);
  }
  const auto normals = compute_normals(f);
  double coarse = 0, fine = 0;
  int up = 0;
  for (int j = 0; j < 64; j += 3)
    for (int i = 0; i < 64; i += 3) {
      const Vec3 n = normals[f.index(i, j)].d();
      if (n.z < 1.0) continue;
      ++up;
      coarse += hsao_texel(f, n, i, j, settings(FalloffKind::step, 16, 8, 16, 4)).normal_occlusion;
      fine += hsao_texel(f, n, i, j, settings(FalloffKind::step, 16, 8, 256, 4)).normal_occlusion;
    }
  ASSERT_GT(up, 100);
  EXPECT_LT(fine / up, 2e-3);
  EXPECT_LE(fine, coarse);
  std::printf("hsao normal occlusion at %d upward receivers: mean %.2e (N_s = 16), %.2e (N_s = 256)\n", up,
              coarse / up, fine / up);
}

}  // namespace
}  // namespace hfbake
