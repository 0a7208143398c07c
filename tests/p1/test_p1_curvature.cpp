// P1's horizons on a curved Earth (Scene::curvature) against the exact point march (terrain/point_horizon,
// an independent march over every crossing that also takes each piece's inner maximum of the lowered
// slope), on rough fields of several seeds, square and rectangular texels, and on a field with a distant
// wall (closed form); and p1 on rectangular texels without curvature, exact.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "field/procedural.hpp"
#include "field/scene.hpp"
#include "methods/method_table.hpp"
#include "terrain/point_horizon.hpp"

namespace hfbake {
namespace {

Scene curved_scene(HeightField f, double c) {
  Scene s;
  s.name = "curved";
  s.field = std::move(f);
  s.environment = make_uniform_environment({1, 1, 1});
  s.curvature = c;
  return s;
}

// The point march's curvature whose coefficient is c at every azimuth, without refraction.
EarthCurvature coefficient(double c) {
  const double R = 1 / (2 * c);
  return {R, R, 0.0};
}

// p1's horizon layer (sin of the elevation) against the exact march from every texel centre, K = 8:
// the worst difference in elevation (radians) over the texels with a caster, with the curvature in p1's
// scene `c_p1` and in the march `c_truth`.
double worst_against_march(const HeightField& f, double c_p1, double c_truth) {
  constexpr int K = 8;
  const Scene scene = curved_scene(f, c_p1);
  const nlohmann::json entry = {{"directions", K}, {"layers", {"horizon"}}, {"horizon_tolerance", 0}};
  const LayerSet out = bake_method("p1", scene, entry, RunControl{});
  const Layer* h = out.find("horizon");
  EXPECT_NE(h, nullptr);
  double worst = 0;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      PointHorizonQuery q;
      q.x = i, q.y = j;
      q.directions = K;
      q.frame = {f.dx(), -f.dy(), 0};
      if (c_truth > 0) q.curvature = coefficient(c_truth);
      const std::vector<HorizonRay> rays = point_horizon(f, q);
      for (int k = 0; k < K; ++k) {
        // p1's phi_k = 360 k / K from +x (east) towards +y (south): compass azimuth 90 + phi_k.
        const HorizonRay& r = rays[std::size_t((k + K / 4) % K)];
        if (!r.found) continue;
        const double e =
            std::asin(std::clamp(double(h->data[f.index(i, j) * K + std::size_t(k)]), -1.0, 1.0));
        worst = std::max(worst, std::abs(e - r.elevation_deg * kPi / 180));
      }
    }
  return worst;
}

TEST(P1Curvature, RoughFieldsAgainstTheExactMarch) {
  const double c = 1e-3;  // per texel: a caster 40 texels away is lowered by 1.6, its slope by 0.04
  for (std::uint64_t seed : {3u, 8u, 21u}) {
    ProceduralSpec p;
    p.kind = ProceduralKind::fractal;
    p.width = 48, p.height = 40;
    p.seed = seed;
    HeightField f = make_procedural(p, 1.0, Wrap::clamp);
    if (seed == 8u) f.texel_size_y = 1.45;  // a geographic raster's rectangles
    if (seed == 21u) f.texel_size = 0.7;
    // p1 evaluates the crossings; the march also each piece's inner maximum and the first piece's limit
    // at the receiver, which exceed the crossings' by at most c times the piece's length (at most a
    // texel's diagonal); and p1's fast arctangent and float sine, 1e-5.
    EXPECT_LT(worst_against_march(f, c, c), c * std::hypot(f.dx(), f.dy()) + 1e-5) << seed;
    EXPECT_GT(worst_against_march(f, 0, c), 0.02) << "a flat p1 is far from the curved truth";
    // Flat, p1's crossings are the march's: the same horizons to p1's float arithmetic.
    EXPECT_LT(worst_against_march(f, 0, 0), 2e-5) << seed;
  }
}

TEST(P1Curvature, AWallBeyondTheCurve) {
  HeightField f;
  f.width = 400, f.height = 3;
  f.z.assign(f.texel_count(), 0.0f);
  const double H = 20, c = 1e-4;
  const int D = 300;
  for (int j = 0; j < 3; ++j)
    for (int i = 50 + D; i < f.width; ++i) f.z[f.index(i, j)] = float(H);
  const Scene scene = curved_scene(f, c);
  const nlohmann::json entry = {{"directions", 4}, {"layers", {"horizon"}}, {"horizon_tolerance", 0}};
  const LayerSet out = bake_method("p1", scene, entry, RunControl{});
  const double e = std::asin(out.find("horizon")->data[f.index(50, 1) * 4 + 0]);  // phi 0: towards the wall
  EXPECT_NEAR(e, std::atan((H - c * D * D) / D), 1e-5);
}

}  // namespace
}  // namespace hfbake
