// hsao with tilted normals, where the (n, T) planes are not vertical and the rays above the horizon matter,
// against an independent brute-force cosine-weighted ray march with the same binary radius.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "ao_scenes.hpp"
#include "methods/ao/hsao.hpp"

namespace hfbake {
namespace {

// Gentle slope with a ridge and a bump: receivers on the flanks have normals tilted by 10-35 degrees.
HeightField hills() {
  HeightField f;
  f.width = f.height = 48;
  f.z.resize(f.texel_count());
  for (int j = 0; j < 48; ++j)
    for (int i = 0; i < 48; ++i)
      f.z[f.index(i, j)] = float(0.15 * i + 5 * std::exp(-((i - 28) * (i - 28)) / 18.0) +
                                 4 * std::exp(-((i - 18) * (i - 18) + (j - 30) * (j - 30)) / 20.0));
  return f;
}

// Occluded fraction within R (binary): stratified cosine-weighted directions (s x s cells, cell centres),
// each ray marched in steps of 0.05 texel; a ray is blocked when it goes below the bilinear surface.
double brute_force(const HeightField& f, Vec3 n, int i, int j, double R, int strata) {
  Vec3 t1 = normalize(cross(std::abs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}, n));
  const Vec3 t2 = cross(n, t1);
  const Vec3 p = f.position(i, j) + n * 1e-4;
  int blocked = 0;
  for (int a = 0; a < strata; ++a)
    for (int b = 0; b < strata; ++b) {
      const double u = (a + 0.5) / strata, v = (b + 0.5) / strata;
      const double r = std::sqrt(u), phi = 2 * kPi * v;  // cosine-weighted (Malley)
      const Vec3 w = t1 * (r * std::cos(phi)) + t2 * (r * std::sin(phi)) + n * std::sqrt(1 - u);
      for (double d = 0.05; d < R; d += 0.05) {
        const Vec3 q = p + w * d;
        if (q.x < 0 || q.y < 0 || q.x > 47 || q.y > 47) break;
        if (q.z < f.bilinear(q.x, q.y)) {
          ++blocked;
          break;
        }
      }
    }
  return double(blocked) / (strata * strata);
}

TEST(HsaoTilted, ConvergesToBinaryRayMarch) {
  const HeightField f = hills();
  const auto normals = compute_normals(f);
  HsaoSettings s;
  s.falloff.kind = FalloffKind::step;
  s.falloff.radius = 8;
  s.directions = 64;
  s.steps = 160;
  s.normal_rays = 16;
  double worst = 0, sum_rays = 0;
  int count = 0;
  for (auto [i, j] : {std::pair{22, 24}, std::pair{25, 10}, std::pair{31, 20}, std::pair{14, 30},
                      std::pair{21, 33}, std::pair{34, 40}}) {
    const Vec3 n = normals[f.index(i, j)].d();
    const HsaoTexel t = hsao_texel(f, n, i, j, s);
    const double truth = brute_force(f, n, i, j, 8, 96);
    std::printf("hsao tilted (%d,%d) tilt %.1f deg: O_T %.4f O_N %.4f total %.4f, ray march %.4f\n", i, j,
                std::acos(n.z) * 180 / kPi, t.horizon_occlusion, t.normal_occlusion, t.occluded(), truth);
    worst = std::max(worst, std::abs(t.occluded() - truth));
    sum_rays += t.normal_occlusion;
    ++count;
  }
  EXPECT_LT(worst, 0.03);
  std::printf("hsao tilted: worst |error| %.4f, mean O_N %.4f\n", worst, sum_rays / count);
}

// Thin spikes the horizon walk steps over at a coarse N_s: the normal rays above the horizon catch part of
// what the walk missed, so adding them brings hsao closer to the ray march (their role in the paper).
TEST(HsaoTilted, NormalRaysRecoverWhatACoarseWalkMisses) {
  HeightField f = test::make_plane(48, 0, 0);
  for (int j = 2; j < 48; j += 5)
    for (int i = 3; i < 48; i += 4) f.z[f.index(i, j)] = 6;
  const auto normals = compute_normals(f);
  HsaoSettings s;
  s.falloff.kind = FalloffKind::step;
  s.falloff.radius = 8;
  s.directions = 16;
  s.steps = 6;
  double err_horizon = 0, err_rays = 0;
  for (auto [i, j] : {std::pair{20, 20}, std::pair{25, 23}, std::pair{17, 30}, std::pair{30, 15}}) {
    const Vec3 n = normals[f.index(i, j)].d();
    const double truth = brute_force(f, n, i, j, 8, 64);
    s.normal_rays = 0;
    err_horizon += std::abs(hsao_texel(f, n, i, j, s).occluded() - truth);
    s.normal_rays = 8;
    const HsaoTexel t = hsao_texel(f, n, i, j, s);
    err_rays += std::abs(t.occluded() - truth);
    std::printf("hsao spikes (%d,%d): O_T %.4f O_N %.4f, ray march %.4f\n", i, j, t.horizon_occlusion,
                t.normal_occlusion, truth);
  }
  std::printf("hsao spikes, N_s = 6: mean |error| horizon only %.4f, with 8 normal rays %.4f\n",
              err_horizon / 4, err_rays / 4);
  EXPECT_LT(err_rays, err_horizon);
}

}  // namespace
}  // namespace hfbake
