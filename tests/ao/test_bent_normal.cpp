// Bent normals of the horizon-based methods against an independent quadrature of the cosine-weighted mean
// open direction next to a wall, and the entry points' layer handling.
#include <gtest/gtest.h>

#include <cmath>

#include "ao_scenes.hpp"
#include "core/error.hpp"
#include "field/procedural.hpp"
#include "methods/ao/bake_ao.hpp"
#include "methods/ao/farfield.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/hsao.hpp"
#include "methods/ao/lsao.hpp"

namespace hfbake {
namespace {

// Cosine-weighted mean open direction at distance x0 from a wall of height h (wall towards +x), n = up,
// K azimuths phi_k = 2 pi k / K: per azimuth the directions above the wall's elevation (or above 0) are open.
Vec3 wall_bent(double x0, double h, int K) {
  Vec3 sum{0, 0, 0};
  for (int k = 0; k < K; ++k) {
    const double phi = 2 * kPi * k / K;
    const double lo = std::cos(phi) > 1e-12 ? std::atan2(h, x0 / std::cos(phi)) : 0.0;
    const double bh =
        test::simpson([](double e) { return std::sin(e) * std::cos(e) * std::cos(e); }, lo, kPi / 2);
    const double bv =
        test::simpson([](double e) { return std::sin(e) * std::sin(e) * std::cos(e); }, lo, kPi / 2);
    sum += Vec3{bh * std::cos(phi), bh * std::sin(phi), bv};
  }
  return normalize(sum);
}

double angle_deg(Vec3 a, Vec3 b) {
  return std::acos(std::min(1.0, dot(normalize(a), normalize(b)))) * 180 / kPi;
}

TEST(BentNormal, WallHbaoAndHsao) {
  const HeightField f = test::make_wall(96, 257, 64, 32);  // x0 = 32, a = 1
  const Vec3 expect = wall_bent(32, 32, 16);
  EXPECT_LT(expect.x, -0.1);  // leans away from the wall
  HbaoSettings h;
  h.directions = uniform_directions(16);
  h.reach = 1e6;
  h.step = 0.5;
  EXPECT_LT(angle_deg(hbao_texel(f, {0, 0, 1}, 32, 128, h).bent_normal, expect), 0.5);
  HbaoSettings tri = h;  // on the triangulated surface, segment bands (rational falloff: the Gauss path)
  tri.surface = MarchSurface::triangles, tri.estimator = HorizonEstimator::segment;
  EXPECT_LT(angle_deg(hbao_texel(f, {0, 0, 1}, 32, 128, tri).bent_normal, expect), 0.5);
  tri.falloff = {FalloffKind::rational, 1e5};
  EXPECT_LT(angle_deg(hbao_texel(f, {0, 0, 1}, 32, 128, tri).bent_normal, expect), 0.5);
  HsaoSettings s;
  s.falloff.kind = FalloffKind::step;
  s.falloff.radius = 128;
  s.directions = 16;
  s.steps = 256;
  EXPECT_LT(angle_deg(hsao_texel(f, {0, 0, 1}, 32, 128, s).bent_normal, expect), 0.5);
}

// LSAO's largest occluder with rho = 1 and cosine weighting is the highest horizon, so its bent normal is the
// same closed form; farfield's slabs are exact on a vertical wall.
TEST(BentNormal, WallLsaoAndFarfield) {
  const HeightField f = test::make_wall(96, 257, 64, 32);  // x0 = 32, a = 1
  const Vec3 expect = wall_bent(32, 32, 16);
  const std::size_t idx = f.index(32, 128);
  LsaoOptions l;
  l.directions = 16;
  l.occlusion.rho.kind = FalloffKind::none;
  std::vector<Vec3f> lb;
  lsao_obscurance(f, l, {}, nullptr, &lb);
  EXPECT_LT(angle_deg(lb[idx].d(), expect), 0.5);
  FarfieldOptions o;
  o.directions = 16;
  std::vector<Vec3f> fb;
  farfield_obscurance(f, compute_normals(f), o, {}, nullptr, &fb);
  EXPECT_LT(angle_deg(fb[idx].d(), expect), 0.5);
  // With a radius the bent normal straightens: the wall at 32 is beyond R = 16.
  l.occlusion.rho = {FalloffKind::step, 16};
  o.rho = {FalloffKind::step, 16};
  lsao_obscurance(f, l, {}, nullptr, &lb);
  farfield_obscurance(f, compute_normals(f), o, {}, nullptr, &fb);
  EXPECT_LT(angle_deg(lb[idx].d(), {0, 0, 1}), 1e-3);
  EXPECT_LT(angle_deg(fb[idx].d(), {0, 0, 1}), 1e-3);
}

// On rough terrain the three horizon methods agree on the bent normal (same K, falloff, radius): lsao keeps
// one occluder per direction, farfield averages far intervals over its sector, hbao marches every sample.
TEST(BentNormal, FractalAgainstHbao) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = spec.height = 96;
  spec.seed = 5;
  const HeightField f = make_procedural(spec, 1.0, Wrap::clamp);
  const std::vector<Vec3f> normals = compute_normals(f);
  const Falloff rho{FalloffKind::step, 16};
  HbaoSettings h;
  h.falloff = rho;
  h.reach = 16;
  h.directions = uniform_directions(16);
  std::vector<float> hb_xyz(3 * f.texel_count());
  hbao_field(f, normals, h, {}, nullptr, hb_xyz.data());
  std::vector<Vec3f> hb(f.texel_count());
  for (std::size_t t = 0; t < hb.size(); ++t) hb[t] = {hb_xyz[3 * t], hb_xyz[3 * t + 1], hb_xyz[3 * t + 2]};
  LsaoOptions l;
  l.directions = 16;
  l.occlusion.rho = rho;
  std::vector<Vec3f> lb, fb;
  lsao_obscurance(f, l, {}, nullptr, &lb);
  FarfieldOptions o;
  o.directions = 16;
  o.rho = rho;
  farfield_obscurance(f, normals, o, {}, nullptr, &fb);
  double lsum = 0, fsum = 0, nsum = 0;
  int count = 0;
  for (int j = 16; j < 80; ++j)
    for (int i = 16; i < 80; ++i) {
      const std::size_t t = f.index(i, j);
      lsum += angle_deg(lb[t].d(), hb[t].d());
      fsum += angle_deg(fb[t].d(), hb[t].d());
      nsum += angle_deg(normals[t].d(), hb[t].d());
      ++count;
    }
  std::printf("mean angle to hbao's bent normal: lsao %.2f deg, farfield %.2f deg, the normal %.2f deg\n",
              lsum / count, fsum / count, nsum / count);
  EXPECT_GT(nsum / count, 3.0);                 // the bent normals do bend
  EXPECT_LT(fsum / count, 0.2 * nsum / count);  // farfield: the same slabs within R (near field 12 texels)
  EXPECT_LT(lsum / count, 0.5 * nsum / count);  // lsao: one occluder per direction
}

Scene scene_of(HeightField f) {
  Scene s;
  s.field = std::move(f);
  s.normals = compute_normals(s.field);
  return s;
}

TEST(BakeAo, LayersAndErrors) {
  const Scene scene = scene_of(test::make_pit(21, 5, 4));
  const RunControl rc;
  const LayerSet a = bake_method("hbao", scene, {{"method", "hbao"}, {"directions", 8}}, rc);
  ASSERT_NE(a.find("ao"), nullptr);
  ASSERT_NE(a.find("obscurance"), nullptr);
  ASSERT_NE(a.find("bent_normal"), nullptr);
  EXPECT_EQ(a.find("ao")->data, a.find("obscurance")->data);
  EXPECT_EQ(a.find("bent_normal")->channels.size(), 3u);
  for (float v : a.find("ao")->data) EXPECT_TRUE(v >= 0 && v <= 1);
  // The centre of the pit is darker than the ground.
  EXPECT_LT(a.find("ao")->data[scene.field.index(10, 10)], a.find("ao")->data[scene.field.index(0, 0)]);
  // With a falloff there is no "ao" layer (it is unlimited AO by definition).
  const LayerSet b =
      bake_method("hbao", scene, {{"method", "hbao"}, {"radius", 4}, {"falloff", "smooth"}}, rc);
  EXPECT_EQ(b.find("ao"), nullptr);
  EXPECT_THROW(bake_method("hbao", scene, {{"method", "hbao"}, {"radius", 4}, {"layers", {"ao"}}}, rc),
               InputError);
  EXPECT_THROW(bake_method("hbao", scene, {{"method", "hbao"}, {"tangent", -0.5}}, rc), InputError);
  const LayerSet c =
      bake_method("hsao", scene, {{"method", "hsao"}, {"radius", 6}, {"layers", {"obscurance"}}}, rc);
  ASSERT_EQ(c.layers.size(), 1u);
  EXPECT_THROW(bake_method("hsao", scene, {{"method", "hsao"}}, rc), InputError);
  const LayerSet d = bake_method("vo", scene, {{"method", "vo"}, {"radius", 3}}, rc);
  ASSERT_NE(d.find("obscurance"), nullptr);
  EXPECT_THROW(bake_method("vo", scene, {{"method", "vo"}, {"radius", 3}, {"depth_layers", 3}}, rc),
               InputError);
}

TEST(BakeAo, DeterministicAndCancellable) {
  const Scene scene = scene_of(test::make_pit(31, 8, 6));
  const nlohmann::json p = {{"method", "hbao"}, {"directions", 8}, {"radius", 6}, {"falloff", "rational"}};
  EXPECT_EQ(bake_method("hbao", scene, p, {}).layers[0].data,
            bake_method("hbao", scene, p, {}).layers[0].data);
  std::atomic<bool> cancel{true};
  RunControl rc;
  rc.cancel = &cancel;
  EXPECT_THROW(bake_method("hbao", scene, p, rc), Cancelled);
  EXPECT_THROW(bake_method("hsao", scene, {{"method", "hsao"}, {"radius", 6}}, rc), Cancelled);
  EXPECT_THROW(bake_method("vo", scene, {{"method", "vo"}, {"radius", 6}}, rc), Cancelled);
}

}  // namespace
}  // namespace hfbake
