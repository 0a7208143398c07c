// One table of every method of this folder on the closed-form scenes (ao_scenes.hpp), with the
// tolerance each must meet; printed for the closing note. Truths come from ao_scenes.hpp (independent
// quadrature of the closed forms), never from the code under test.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

#include "ao_scenes.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/hsao.hpp"
#include "methods/ao/vo.hpp"

namespace hfbake {
namespace {

struct Row {
  std::string method, scene;
  double truth, got, tol;
};

void check(const Row& r) {
  std::printf("| %-22s | %-34s | %8.5f | %8.5f | %+9.5f | %6.3f |\n", r.method.c_str(), r.scene.c_str(),
              r.truth, r.got, r.got - r.truth, r.tol);
  EXPECT_NEAR(r.got, r.truth, r.tol) << r.method << " " << r.scene;
}

Falloff falloff(FalloffKind k, double R) {
  Falloff f;
  f.kind = k, f.radius = R;
  return f;
}

TEST(ClosedFormTable, EveryMethod) {
  const HeightField pit = test::make_pit(81, 32, 32);         // rw = 32, D = 32, receiver (40, 40)
  const HeightField wall = test::make_wall(96, 257, 64, 32);  // x0 = 32, H = 32, receiver (32, 128)
  const HeightField flat = test::make_plane(33, 0, 0), tilted = test::make_plane(33, 0.3, -0.2);
  const auto up = Vec3{0, 0, 1};
  const auto tilted_n = compute_normals(tilted)[tilted.index(16, 16)].d();
  auto rho = [](Falloff f) { return [f](double d) { return f(d); }; };
  auto one = [](double) { return 1.0; };
  const Falloff none{}, rat32 = falloff(FalloffKind::rational, 32), step40 = falloff(FalloffKind::step, 40),
                        lin64 = falloff(FalloffKind::linear, 64);

  std::printf(
      "| method                 | scene                              |    truth |      got |     error |    "
      "tol |\n");
  // hbao: K = 16, step 0.5 texel.
  auto hbao = [&](const HeightField& f, Vec3 n, int i, int j, Falloff fo, Weighting w) {
    HbaoSettings s;
    s.falloff = fo, s.weighting = w, s.directions = uniform_directions(16), s.step = 0.5, s.reach = 1e6;
    return hbao_texel(f, n, i, j, s).occluded;
  };
  const Weighting cos = Weighting::cosine, uni = Weighting::uniform;
  check({"hbao cos K16", "pit rw=D=32 none (sin^2 e)", 0.5, hbao(pit, up, 40, 40, none, cos), 0.01});
  check({"hbao cos K16", "pit rational R=32 (r=R^2)", test::pit_occlusion(32, 32, rho(rat32)),
         hbao(pit, up, 40, 40, rat32, cos), 0.006});
  check({"hbao cos K16", "pit step R=40", test::pit_occlusion(32, 32, rho(step40)),
         hbao(pit, up, 40, 40, step40, cos), 0.02});
  check({"hbao cos K16", "pit linear R=64", test::pit_occlusion(32, 32, rho(lin64)),
         hbao(pit, up, 40, 40, lin64, cos), 0.01});
  check({"hbao uni K16", "pit none (sin e)", std::sqrt(0.5), hbao(pit, up, 40, 40, none, uni), 0.01});
  check({"hbao cos K16", "wall a=1 none (discrete K)", test::wall_occlusion(32, 32, 16, true, one),
         hbao(wall, up, 32, 128, none, cos), 0.004});
  check({"hbao uni K16", "wall a=1 none (discrete K)", test::wall_occlusion(32, 32, 16, false, one),
         hbao(wall, up, 32, 128, none, uni), 0.006});
  check({"hbao cos K16", "wall a=1 rational R=32", test::wall_occlusion(32, 32, 16, true, rho(rat32)),
         hbao(wall, up, 32, 128, rat32, cos), 0.003});
  check({"hbao cos K16", "flat plane, rational R=8", 0,
         hbao(flat, up, 16, 16, falloff(FalloffKind::rational, 8), cos), 1e-6});
  check(
      {"hbao cos K16", "tilted plane (0.3, -0.2), none", 0, hbao(tilted, tilted_n, 16, 16, none, cos), 1e-6});
  check(
      {"hbao uni K16", "tilted plane (0.3, -0.2), none", 0, hbao(tilted, tilted_n, 16, 16, none, uni), 1e-6});

  // hbao on the reference's triangulated surface (every profile vertex, segment bands).
  auto hbao_tri = [&](const HeightField& f, Vec3 n, int i, int j, Falloff fo) {
    HbaoSettings s;
    s.falloff = fo, s.directions = uniform_directions(16), s.reach = 1e6;
    s.surface = MarchSurface::triangles, s.estimator = HorizonEstimator::segment;
    return hbao_texel(f, n, i, j, s).occluded;
  };
  check({"hbao triangles K16", "pit rw=D=32 none (sin^2 e)", 0.5, hbao_tri(pit, up, 40, 40, none), 0.01});
  check({"hbao triangles K16", "pit step R=40", test::pit_occlusion(32, 32, rho(step40)),
         hbao_tri(pit, up, 40, 40, step40), 0.02});
  check({"hbao triangles K16", "pit rational R=32 (r=R^2)", test::pit_occlusion(32, 32, rho(rat32)),
         hbao_tri(pit, up, 40, 40, rat32), 0.006});
  check({"hbao triangles K16", "wall a=1 none (discrete K)", test::wall_occlusion(32, 32, 16, true, one),
         hbao_tri(wall, up, 32, 128, none), 0.004});
  check({"hbao triangles K16", "wall a=1 rational R=32", test::wall_occlusion(32, 32, 16, true, rho(rat32)),
         hbao_tri(wall, up, 32, 128, rat32), 0.003});
  check({"hbao triangles K16", "tilted plane (0.3, -0.2), none", 0, hbao_tri(tilted, tilted_n, 16, 16, none),
         1e-6});

  // hsao: N_d = 16, N_s = R / 0.5, N_n = 4 (cosine weighting; radius-bounded falloffs).
  auto hsao = [&](const HeightField& f, Vec3 n, int i, int j, Falloff fo) {
    HsaoSettings s;
    s.falloff = fo, s.directions = 16, s.steps = int(fo.radius / 0.5), s.normal_rays = 4;
    return hsao_texel(f, n, i, j, s).occluded();
  };
  const Falloff step128 = falloff(FalloffKind::step, 128);
  check({"hsao K16", "pit step R=128 (= none)", 0.5, hsao(pit, up, 40, 40, step128), 0.01});
  check({"hsao K16", "pit step R=40", test::pit_occlusion(32, 32, rho(step40)), hsao(pit, up, 40, 40, step40),
         0.02});
  check({"hsao K16", "pit linear R=64", test::pit_occlusion(32, 32, rho(lin64)), hsao(pit, up, 40, 40, lin64),
         0.01});
  check({"hsao K16", "wall a=1 step R=128 (discrete K)", test::wall_occlusion(32, 32, 16, true, one),
         hsao(wall, up, 32, 128, step128), 0.005});
  check(
      {"hsao K16", "flat plane step R=12", 0, hsao(flat, up, 16, 16, falloff(FalloffKind::step, 12)), 1e-9});
  check({"hsao K16", "tilted plane step R=12", 0,
         hsao(tilted, tilted_n, 16, 16, falloff(FalloffKind::step, 12)), 1e-9});

  // vo: its own quantity, box volumetric obscurance (closed forms by counting footprint texels).
  auto vo = [&](const HeightField& f, int i, int j, double b, double h, double F) {
    VoSettings s;
    s.radius = b, s.box_height = h, s.fade = F, s.levels = 2;
    return double(vo_occlusion(f, compute_normals(f), s, RunControl{})[f.index(i, j)]);
  };
  const HeightField vpit = test::make_pit(49, 8, 6);
  int ground = 0;
  for (int y = -12; y <= 12; ++y)
    for (int x = -12; x <= 12; ++x) ground += std::hypot(x, y) >= 8 ? 1 : 0;
  check({"vo 4 layers", "pit rw=8 D=6, b=12 h=F=10 (box VO)", ground / 625.0 * 0.6,
         vo(vpit, 24, 24, 12, 10, 10), 1e-6});
  check({"vo 4 layers", "wall x0=4 H=5, b=10 h=F=8 (box VO)", 7.0 / 21.0 * 5.0 / 8.0,
         vo(test::make_wall(64, 64, 36, 5), 32, 32, 10, 8, 8), 1e-6});
  check({"vo 4 layers", "flat plane b=4", 0, vo(flat, 16, 16, 4, 2, 2), 1e-6});
  check({"vo 4 layers", "tilted plane b=4", 0, vo(tilted, 16, 16, 4, 2, 2), 1e-6});
}

}  // namespace
}  // namespace hfbake
