// The reference's sh_irradiance (reference/sh_irradiance_reference.hpp) against closed forms (flat ground
// under a sky gradient and a sun with a disk; a tilted plane under a uniform sky) and against a brute force
// over a dense grid of directions on a rough emissive field; and traced for the jobs whose methods bake it.
#include <gtest/gtest.h>

#include <cmath>

#include "core/azimuth.hpp"
#include "env/environment.hpp"
#include "field/procedural.hpp"
#include "reference/bake_reference.hpp"
#include "reference/embree_field.hpp"
#include "reference/sh_environment.hpp"
#include "reference/sh_irradiance_reference.hpp"

namespace hfbake {
namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kY0 = 0.28209479177387814, kY1 = 0.4886025119029199, kY20 = 0.31539156525252005;

// A_l / pi of the clamped cosine (pi, 2 pi / 3, pi / 4, 0 over pi) for coefficient i.
double scale(int i) {
  return i < 1 ? 1.0 : i < 4 ? 2.0 / 3 : i < 9 ? 0.25 : 0.0;
}

Scene make_scene(const ProceduralSpec& spec, Rgb albedo, int bounces) {
  Scene s;
  s.name = "t";
  s.field = make_procedural(spec, 1.0, Wrap::clamp);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), albedo);
  s.environment = make_uniform_environment({1, 1, 1});
  s.bounces = bounces;
  return s;
}

// Coefficient i (0..15), colour c of texel (x, y), and its standard error.
struct Coefficient {
  double v = 0, se = 0;
};
Coefficient at(const LayerSet& r, int x, int y, int i, int c) {
  const Layer* l = r.find("sh_irradiance");
  const Layer* s = r.find("sh_irradiance_stderr");
  EXPECT_TRUE(l && s);
  EXPECT_EQ(l->channel_count(), 48);
  const std::size_t t = std::size_t(y) * r.width + x;
  return {l->data[t * 48 + i * 3 + c], s->data[t * 48 + i * 3 + c]};
}

ReferenceOptions sh_options(int samples) {
  ReferenceOptions o;
  o.layers = {"sh_irradiance"};
  o.samples = samples;
  return o;
}

Vec3 direction(double elevation_deg, double azimuth_deg) {
  const double e = elevation_deg * kDeg, a = azimuth_deg * kDeg;
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

// Flat ground sees the upper hemisphere and nothing of itself. Under L(w) = a + b z (a lat-long whose rows
// hold the row means, exact for z) the incident projection is L_00 = Y_0 pi (2a + b), L_10 = Y_1 pi (a +
// 2b / 3), L_20 = Y_20 pi b / 2, the rest zero; a sun of irradiance E whose disk (half-angle alpha, cos
// alpha = k) is all visible adds E Y_lm(d) times 2 / (1 + k), 1, k for l = 0, 1, 2 (the disk mean of the
// zonal P_l); c_lm = (A_l / pi) L_lm with A_l / pi = 1, 2/3, 1/4.
class FlatGround : public ::testing::TestWithParam<int> {};

// H = 1024 rows: the environment table merges them in pairs (at most 512 rows).
TEST_P(FlatGround, UnderASkyGradientAndASunIsTheClosedForm) {
  const double a = 0.7, b = 0.5;
  const int H = GetParam(), W = 2 * H;
  std::vector<Rgb> texels(std::size_t(W) * H);
  for (int r = 0; r < H; ++r) {
    const double z0 = std::cos(kPi * r / H), z1 = std::cos(kPi * (r + 1) / H);
    const float L = float(a + b * 0.5 * (z0 + z1));  // z is uniform in solid angle over a row
    for (int c = 0; c < W; ++c) texels[std::size_t(r) * W + c] = {L, L, L};
  }
  ProceduralSpec p;
  p.kind = ProceduralKind::flat;
  p.width = p.height = 9;
  Scene s = make_scene(p, {0.5f, 0.5f, 0.5f}, 1);
  s.environment = make_latlong_environment(W, H, std::move(texels));
  DirectionalLight sun;
  sun.direction = direction(35, 135);
  sun.angular_diameter = 10 * kDeg;  // large, so the disk's closed form differs from a point's
  sun.irradiance = {2, 3, 4};
  s.lights = {sun};
  const LayerSet r = bake_reference(s, sh_options(256), {});

  const double k = std::cos(5 * kDeg);
  const double disk[3] = {2 / (1 + k), 1, k};
  const auto y = reference::sh_basis(sun.direction);
  const double sky[9] = {
      kY0 * kPi * (2 * a + b), 0, kY1 * kPi * (a + 2 * b / 3), 0, 0, 0, kY20 * kPi * b / 2, 0, 0};
  const double E[3] = {2, 3, 4};
  for (auto [x, yy] : {std::pair{4, 4}, std::pair{1, 7}})
    for (int i = 0; i < 16; ++i)
      for (int c = 0; c < 3; ++c) {
        const int l = i < 1 ? 0 : i < 4 ? 1 : i < 9 ? 2 : 3;
        const double truth = l == 3 ? 0.0 : scale(i) * (sky[i] + E[c] * disk[l] * y[i]);
        const Coefficient v = at(r, x, yy, i, c);
        EXPECT_LE(std::abs(v.v - truth), 3 * v.se + 2e-4)
            << "texel " << x << "," << yy << " coefficient " << i << " colour " << c << ": " << v.v << " +- "
            << v.se << ", truth " << truth;
      }
}

INSTANTIATE_TEST_SUITE_P(ShIrradianceReference, FlatGround, ::testing::Values(256, 1024));

// V = [w . n > 0] on a plane of normal n, which never sees itself: under a uniform sky of radiance 1 the
// incident projection is the hemisphere's zonal coefficients sqrt(pi), sqrt(3 pi) / 2, 0 rotated to n.
TEST(ShIrradianceReference, TiltedPlaneIsTheRotatedHemisphere) {
  ProceduralSpec p;
  p.kind = ProceduralKind::slope;
  p.width = p.height = 33;
  p.angle_deg = 35;
  p.aspect_deg = 40;
  const Scene s = make_scene(p, {0.5f, 0.5f, 0.5f}, 2);
  const LayerSet r = bake_reference(s, sh_options(64), {});
  const Vec3 n = direction(90 - 35, 40);
  const auto y = reference::sh_basis(n);
  const double z[3] = {std::sqrt(kPi), std::sqrt(3 * kPi) / 2, 0};
  for (auto [x, yy] : {std::pair{16, 16}, std::pair{5, 25}, std::pair{27, 8}})
    for (int i = 0; i < 16; ++i) {
      const int l = i < 1 ? 0 : i < 4 ? 1 : i < 9 ? 2 : 3;
      const double truth = l == 3 ? 0.0 : scale(i) * std::sqrt(4 * kPi / (2 * l + 1)) * z[l] * y[i];
      const Coefficient v = at(r, x, yy, i, 1);
      EXPECT_NEAR(v.v, truth, 2e-4) << "texel " << x << "," << yy << " coefficient " << i;
      EXPECT_EQ(v.se, 0.0);  // the plane sees no terrain: no Monte Carlo term
    }
}

// A rough field that emits a known radiance and reflects nothing, so the terrain's light is exact: the
// reference against a midpoint rule over 1440 x 720 equal-area cells of the sphere, one Embree ray per cell
// from the receiver (escape: the sky; a hit in the normal's hemisphere: the emission; below it: nothing),
// plus the point sun's shadow ray.
TEST(ShIrradianceReference, MatchesABruteForceOverTheSphere) {
  ProceduralSpec p;
  p.kind = ProceduralKind::fractal;
  p.width = p.height = 24;
  p.seed = 3;
  p.amplitude = 6;
  Scene s = make_scene(p, {0, 0, 0}, 1);
  s.surface.emission.assign(s.field.texel_count(), Rgb{0.3f, 0.2f, 0.1f});
  s.environment = make_uniform_environment({1.0f, 0.8f, 0.6f});
  DirectionalLight sun;
  sun.direction = direction(25, 200);
  sun.irradiance = {2, 2, 2};
  s.lights = {sun};
  const LayerSet r = bake_reference(s, sh_options(4096), {});

  const reference::EmbreeField geometry(s.field, reference::GeometryKind::quads, 1);
  const Rgb sky{1.0f, 0.8f, 0.6f}, emission{0.3f, 0.2f, 0.1f};
  const int NZ = 720, NP = 1440;
  const double cell = 4 * kPi / (double(NZ) * NP);
  auto blocked = [&](Vec3 o, Vec3 w) {
    RTCRay ray{};
    ray.org_x = float(o.x), ray.org_y = float(o.y), ray.org_z = float(o.z);
    ray.dir_x = float(w.x), ray.dir_y = float(w.y), ray.dir_z = float(w.z);
    ray.tnear = 0, ray.tfar = std::numeric_limits<float>::infinity(), ray.mask = 0xffffffffu;
    RTCIntersectContext c;
    rtcInitIntersectContext(&c);
    rtcOccluded1(geometry.scene(), &c, &ray);
    return ray.tfar < 0;
  };
  int terrain_texels = 0;
  for (auto [x, y] : {std::pair{12, 12}, std::pair{6, 17}, std::pair{18, 5}}) {
    const Vec3 n = s.normals[s.field.index(x, y)].d();
    const Vec3 o = s.field.position(x, y) + Vec3{0, 0, geometry.epsilon()};
    double L[9][3] = {};
    double seen = 0;
    for (int iz = 0; iz < NZ; ++iz)
      for (int ip = 0; ip < NP; ++ip) {
        const double z = -1 + 2 * (iz + 0.5) / NZ, rr = std::sqrt(1 - z * z), phi = 2 * kPi * (ip + 0.5) / NP;
        const Vec3 w{rr * std::cos(phi), rr * std::sin(phi), z};
        Rgb v{};
        if (!blocked(o, w))
          v = sky;
        else if (dot(n, w) > 0)
          v = emission, seen += cell;
        const auto yb = reference::sh_basis(w);
        for (int i = 0; i < 9; ++i)
          L[i][0] += cell * v.r * yb[i], L[i][1] += cell * v.g * yb[i], L[i][2] += cell * v.b * yb[i];
      }
    terrain_texels += seen > 0.3;  // the test must see terrain light, or it proves nothing about it
    const bool sun_free = !blocked(o, sun.direction);
    const auto ys = reference::sh_basis(sun.direction);
    for (int i = 0; i < 9; ++i)
      for (int c = 0; c < 3; ++c) {
        const double truth = scale(i) * (L[i][c] + (sun_free ? 2.0 * ys[i] : 0.0));
        const Coefficient v = at(r, x, y, i, c);
        EXPECT_LE(std::abs(v.v - truth), 4 * v.se + 3e-3)
            << "texel " << x << "," << y << " coefficient " << i << " colour " << c << ": " << v.v << " +- "
            << v.se << ", brute force " << truth;
      }
  }
  EXPECT_GE(terrain_texels, 2);
}

TEST(ShIrradianceReference, TracedWhenAMethodBakesIt) {
  MethodContext context;
  context.field.width = context.field.height = 16;
  context.bounces = 1;
  const nlohmann::json with = {{"bake", {{{"method", "nlp"}}}}};
  const ReferenceOptions a = read_reference_options(with, context, "job.json");
  EXPECT_NE(std::find(a.layers.begin(), a.layers.end(), "sh_irradiance"), a.layers.end());
  const nlohmann::json without = {{"bake", {{{"method", "nlp"}, {"layers", {"direct", "total"}}}}}};
  const ReferenceOptions b = read_reference_options(without, context, "job.json");
  EXPECT_EQ(std::find(b.layers.begin(), b.layers.end(), "sh_irradiance"), b.layers.end());
}

}  // namespace
}  // namespace hfbake
