// The reference against closed forms and brute force: flat ground, planes, a V-trench floor, a pit, a sun
// with angular size, a lat-long sky, the white furnace; the surface split, the skirt; determinism.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <map>
#include <span>

#include "../p1/p1_truth.hpp"
#include "core/azimuth.hpp"
#include "env/environment.hpp"
#include "field/procedural.hpp"
#include "reference/bake_reference.hpp"
#include "reference/embree_field.hpp"
#include "reference/env_sampler.hpp"
#include "reference/horizon_reference.hpp"
#include "reference/sampling.hpp"
#include "reference/sh_environment.hpp"

namespace hfbake {
namespace {

constexpr double kDeg = kPi / 180.0;

Scene make_scene(const ProceduralSpec& spec, Wrap wrap = Wrap::clamp, Rgb albedo = {0.5f, 0.5f, 0.5f},
                 Rgb sky = {1, 1, 1}) {
  Scene s;
  s.name = "t";
  s.field = make_procedural(spec, 1.0, wrap);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), albedo);
  s.environment = make_uniform_environment(sky);
  s.bounces = 0;
  return s;
}

ProceduralSpec spec_of(ProceduralKind kind, int size) {
  ProceduralSpec p;
  p.kind = kind;
  p.width = p.height = size;
  return p;
}

ReferenceOptions options(std::vector<std::string> layers, int samples) {
  ReferenceOptions o;
  o.layers = std::move(layers);
  o.samples = samples;
  return o;
}

struct Value {
  double v = 0, se = 0;
};
Value at(const LayerSet& l, const std::string& name, int i, int j, int c = 0) {
  const Layer* a = l.find(name);
  const Layer* s = l.find(name + "_stderr");
  EXPECT_TRUE(a && s) << name;
  const std::size_t t = std::size_t(j) * l.width + i;
  return {a->data[t * a->channel_count() + c], s->data[t * s->channel_count() + c]};
}

// |estimate - truth| <= 3 standard errors (+ a float-rounding allowance).
#define EXPECT_WITHIN_3SE(value, truth, extra)                              \
  do {                                                                      \
    const Value v_ = (value);                                               \
    EXPECT_LE(std::abs(v_.v - (truth)), 3 * v_.se + (extra))                \
        << "estimate " << v_.v << " +- " << v_.se << ", truth " << (truth); \
  } while (0)

// Height on the triangulation of docs/contract.md (split from (i+1, j) to (i, j+1)), an independent
// evaluation.
double triangulated_height(const HeightField& f, double x, double y) {
  const int i = std::clamp(int(std::floor(x)), 0, f.width - 2),
            j = std::clamp(int(std::floor(y)), 0, f.height - 2);
  const double fx = x - i, fy = y - j;
  const double h00 = f.at(i, j), h10 = f.at(i + 1, j), h01 = f.at(i, j + 1), h11 = f.at(i + 1, j + 1);
  if (fx + fy <= 1) return h00 + (h10 - h00) * fx + (h01 - h00) * fy;
  return h11 + (h01 - h11) * (1 - fx) + (h10 - h11) * (1 - fy);
}

// Brute-force horizon elevation (radians) from texel (i, j) in azimuth phi by marching the triangulation.
double horizon(const HeightField& f, int i, int j, double phi) {
  const double h0 = f.at(i, j);
  double best = -kPi / 2;
  for (double s = 0.01;; s += 0.01) {
    const double x = i + s * std::cos(phi), y = j + s * std::sin(phi);
    if (x < 0 || y < 0 || x > f.width - 1 || y > f.height - 1) break;
    best = std::max(best, std::atan2(triangulated_height(f, x, y) - h0, s));
  }
  return best;
}

// The table forms of the Sobol generator and the bit reversal against their definitions, bit by bit.
TEST(Sampling, SobolAndBitReversalMatchTheirDefinitions) {
  std::uint64_t x = 12345;
  for (int n = 0; n < 200000; ++n) {
    x = reference::mix64(x);
    const std::uint32_t index = n < 1000 ? std::uint32_t(n) : std::uint32_t(x);
    std::uint32_t dim1 = 0, v = 1u << 31, reversed = 0;
    for (int k = 0; k < 32; ++k, v ^= v >> 1) {
      if (index & (1u << k)) dim1 ^= v;
      if (index & (1u << k)) reversed |= 1u << (31 - k);
    }
    ASSERT_EQ(reference::sobol_dim1(index), dim1) << index;
    ASSERT_EQ(reference::reverse_bits(index), reversed) << index;
  }
}

TEST(Sampling, PrefixesAreNets) {
  // The first 2^m points of a scrambled sequence: one point in every elementary interval of area 2^-m.
  for (std::uint64_t stream : {1ull, 77ull, 123456789ull}) {
    const auto seq = reference::Sequence2::make(stream);
    const int m = 6, n = 1 << m;
    for (int a = 0; a <= m; ++a) {
      std::vector<int> count(n, 0);
      for (int k = 0; k < n; ++k) {
        const auto p = seq(std::uint32_t(k));
        const int cx = int(p.u * (1 << a)), cy = int(p.v * (1 << (m - a)));
        ++count[cx * (1 << (m - a)) + cy];
      }
      for (int c : count) ASSERT_EQ(c, 1) << "stream " << stream << " split " << a;
    }
  }
}

TEST(Sampling, SequenceIsTheScrambledSobolPairAsDefined) {
  // Sequence2's point k, written out from its definition (scrambled index, each Sobol dimension scrambled
  // with its own seed): the sampler may take shortcuts, never other bits.
  for (std::uint64_t stream : {3ull, 4242ull, 987654321ull}) {
    const auto seq = reference::Sequence2::make(stream);
    for (std::uint32_t k : {0u, 1u, 2u, 7u, 31u, 32u, 1000u, 65535u, 123456789u, 4294967295u}) {
      const std::uint32_t s = reference::owen_scramble(k, seq.index_seed);
      const auto p = seq(k);
      ASSERT_EQ(p.u, reference::to_unit(reference::owen_scramble(reference::sobol_dim0(s), seq.seed_u))) << k;
      ASSERT_EQ(p.v, reference::to_unit(reference::owen_scramble(reference::sobol_dim1(s), seq.seed_v))) << k;
    }
  }
}

TEST(Geometry, SurfaceSplitAndSkirt) {
  HeightField f;
  f.width = f.height = 2;
  f.z = {0, 0, 0, 1};  // h(1,1) = 1: the split decides the height at (0.7, 0.7)
  for (auto kind :
       {reference::GeometryKind::grid, reference::GeometryKind::triangles, reference::GeometryKind::quads}) {
    reference::EmbreeField g(f, kind, 1);
    auto down = [&](double x, double y) {
      RTCRayHit rh{};
      rh.ray.org_x = float(x), rh.ray.org_y = float(y), rh.ray.org_z = 5;
      rh.ray.dir_z = -1;
      rh.ray.tfar = 100;
      rh.ray.mask = ~0u;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      RTCIntersectContext c;
      rtcInitIntersectContext(&c);
      rtcIntersect1(g.scene(), &c, &rh);
      return 5.0 - rh.ray.tfar;
    };
    EXPECT_NEAR(down(0.3, 0.3), 0.0, 1e-6);
    EXPECT_NEAR(down(0.7, 0.7), 0.4, 1e-6);  // on the triangle (1,0) (1,1) (0,1)
    EXPECT_NEAR(down(0.9, 0.2), 0.1, 1e-6);
    // A ray from outside, below the border edge, heading in: the skirt stops it.
    RTCRay r{};
    r.org_x = -1, r.org_y = 0.5f, r.org_z = -0.2f, r.dir_x = 1, r.tfar = 100, r.mask = ~0u;
    RTCIntersectContext c;
    rtcInitIntersectContext(&c);
    rtcOccluded1(g.scene(), &c, &r);
    EXPECT_LT(r.tfar, 0) << "a ray passed under the border";
    // Above the border it passes.
    RTCRay above{};
    above.org_x = -1, above.org_y = 0.5f, above.org_z = 1.2f, above.dir_x = 1, above.tfar = 100,
    above.mask = ~0u;
    rtcOccluded1(g.scene(), &c, &above);
    EXPECT_GT(above.tfar, 0);
  }
}

TEST(Reference, FlatGroundUnderUniformSky) {
  const Rgb L{0.5f, 1.0f, 2.0f};
  Scene s = make_scene(spec_of(ProceduralKind::flat, 33), Wrap::clamp, {0.5f, 0.5f, 0.5f}, L);
  const LayerSet r = bake_reference(s, options({"ao", "vsky", "direct"}, 64), {});
  for (int j = 0; j < 33; j += 8)
    for (int i = 0; i < 33; i += 8) {  // the border too: the skirt must not occlude
      EXPECT_WITHIN_3SE(at(r, "ao", i, j), 1.0, 1e-6);
      EXPECT_WITHIN_3SE(at(r, "vsky", i, j), 1.0, 1e-6);
      for (int c = 0; c < 3; ++c) EXPECT_WITHIN_3SE(at(r, "direct", i, j, c), (&L.r)[c], 1e-5);
    }
}

TEST(Reference, TiltedPlane) {
  ProceduralSpec p = spec_of(ProceduralKind::slope, 41);
  p.angle_deg = 35;
  p.aspect_deg = 40;  // faces 40 degrees: rises towards 220 degrees
  Scene s = make_scene(p);
  const LayerSet r = bake_reference(s, options({"ao", "vsky"}, 256), {});
  // vsky closed form: tan h = tan S cos(phi - uphill), vsky = 1 - mean sin(max(h, 0)).
  const double S = p.angle_deg * kDeg, uphill = (p.aspect_deg + 180) * kDeg;
  double mean_sin = 0;
  const int K = 100000;
  for (int k = 0; k < K; ++k) {
    const double phi = 2 * kPi * (k + 0.5) / K;
    mean_sin += std::sin(std::max(0.0, std::atan(std::tan(S) * std::cos(phi - uphill)))) / K;
  }
  for (auto [i, j] : {std::pair{20, 20}, std::pair{0, 0}, std::pair{40, 20}, std::pair{10, 33}})
    EXPECT_WITHIN_3SE(at(r, "ao", i, j), 1.0, 1e-6);  // a plane does not occlude its own hemisphere
  // vsky where the plane extends uphill in every direction: the mean over a block of texels (independent
  // estimates, so its standard error is sqrt(sum se^2) / n; single texels carry a noisy 7-dof stderr).
  Value block;
  int n = 0;
  for (int j = 12; j <= 28; ++j)
    for (int i = 12; i <= 28; ++i, ++n) {
      const Value v = at(r, "vsky", i, j);
      block.v += v.v, block.se += v.se * v.se;
    }
  block.v /= n, block.se = std::sqrt(block.se) / n;
  EXPECT_WITHIN_3SE(block, 1.0 - mean_sin, 1e-4);
}

TEST(Reference, TrenchFloor) {
  ProceduralSpec p = spec_of(ProceduralKind::trench, 33);
  p.angle_deg = 40;
  Scene s = make_scene(p);
  const LayerSet r = bake_reference(s, options({"ao"}, 1024), {});
  for (int j : {8, 16, 24}) EXPECT_WITHIN_3SE(at(r, "ao", 16, j), std::cos(p.angle_deg * kDeg), 1e-4);
}

TEST(Reference, PitCenter) {
  ProceduralSpec p = spec_of(ProceduralKind::pit, 49);
  p.radius = 16;
  p.depth = 10;
  Scene s = make_scene(p);
  const LayerSet r = bake_reference(s, options({"ao", "vsky"}, 1024), {});
  // Brute-force horizons of the triangulated pit (its rim is a one-texel ramp, not a circle).
  double sin2 = 0, sin1 = 0;
  const int K = 720;
  for (int k = 0; k < K; ++k) {
    const double e = std::max(0.0, horizon(s.field, 24, 24, 2 * kPi * (k + 0.5) / K));
    sin2 += std::sin(e) * std::sin(e) / K, sin1 += std::sin(e) / K;
  }
  EXPECT_WITHIN_3SE(at(r, "ao", 24, 24), 1 - sin2, 2e-3);
  EXPECT_WITHIN_3SE(at(r, "vsky", 24, 24), 1 - sin1, 2e-3);
  // The closed form of the ideal cylinder, 1 - D^2 / (D^2 + R^2), within the rim's discretisation.
  const double D = p.depth, R = p.radius;
  EXPECT_NEAR(at(r, "ao", 24, 24).v, 1 - D * D / (D * D + R * R), 0.03);
}

// A notch between two straight walls, extruded along y: z = 3 (c - x) on the left, 13 (x - c) on the right, c
// = 4 on a 9 x 9 field, albedo rho, under a uniform sky of radiance 1.
Scene notch_scene(double rho) {
  Scene s;
  s.name = "notch";
  HeightField& f = s.field;
  f.width = f.height = 9;
  f.texel_size = 1;
  f.wrap = Wrap::clamp;
  f.z.resize(f.texel_count());
  for (int j = 0; j < 9; ++j)
    for (int i = 0; i < 9; ++i) f.z[f.index(i, j)] = float(i < 4 ? 3 * (4 - i) : 13 * (i - 4));
  s.normals = compute_normals(f);
  s.surface.albedo.assign(f.texel_count(), Rgb{float(rho), float(rho), float(rho)});
  s.environment = make_uniform_environment({1, 1, 1});
  return s;
}

TEST(Reference, ReceiverInANotchSeesTheWedgeBetweenItsWalls) {
  // From the notch (notch_scene) the free sky is the dihedral wedge between the wall planes, opening alpha =
  // pi - atan 3 - atan 13: vsky = 2 alpha / (2 pi). The texel's normal, from central differences, leans far
  // to the left, over the left wall: a receiver offset along it started under that wall and saw nothing (vsky
  // 0 instead of 0.127). Receivers are lifted vertically, which is above the surface wherever the surface is
  // a height field.
  Scene s = notch_scene(0.5);
  const HeightField& f = s.field;
  const int c = 4;
  const LayerSet r = bake_reference(s, options({"vsky", "ao", "bent_normal"}, 4096), {});
  const double alpha = kPi - std::atan(3.0) - std::atan(13.0);
  EXPECT_WITHIN_3SE(at(r, "vsky", c, 4), alpha / kPi, 1e-3);
  // ao and the bent normal about the texel's normal N = (cos nu, 0, sin nu) (in the xz plane by symmetry):
  // a direction at angle psi in the xz plane and beta out of it has N.w = cos(beta) cos(psi - nu) and
  // dw = cos(beta) dbeta dpsi, over the wedge psi in [atan 13, pi - atan 3] (inside N's hemisphere here).
  const Vec3 n = s.normals[f.index(c, 4)].d();
  ASSERT_NEAR(n.y, 0, 1e-6);
  const double nu = std::atan2(n.z, n.x), psi0 = std::atan(13.0), psi1 = kPi - std::atan(3.0);
  ASSERT_GT(psi0, nu - kPi / 2);
  ASSERT_LT(psi1, nu + kPi / 2);
  // ao = (1/pi) int cos^2 beta dbeta int cos(psi - nu) dpsi = (1/2) [sin(psi - nu)] over the wedge.
  EXPECT_WITHIN_3SE(at(r, "ao", c, 4), 0.5 * (std::sin(psi1 - nu) - std::sin(psi0 - nu)), 1e-3);
  // The bent normal: the x and z components are (4/3) int (cos psi, sin psi) cos(psi - nu) dpsi, y is 0.
  double bx = 0, bz = 0;
  const int steps = 20000;
  for (int k = 0; k < steps; ++k) {
    const double psi = psi0 + (psi1 - psi0) * (k + 0.5) / steps;
    bx += std::cos(psi) * std::cos(psi - nu);
    bz += std::sin(psi) * std::cos(psi - nu);
  }
  const double len = std::hypot(bx, bz);
  const Value x = at(r, "bent_normal", c, 4, 0), y = at(r, "bent_normal", c, 4, 1),
              z = at(r, "bent_normal", c, 4, 2);
  EXPECT_WITHIN_3SE(x, bx / len, 2e-3);
  EXPECT_WITHIN_3SE(y, 0.0, 2e-3);
  EXPECT_WITHIN_3SE(z, bz / len, 2e-3);
}

// The first bounce at the bottom of the same notch under a uniform sky (radiance 1, albedo rho): every
// direction of the receiver's that the sky wedge does not hold enters a wall at the crease, so it sees each
// wall's light there, rho E_w / pi, with E_w / pi the wall's own cosine-weighted view of the wedge,
// (1/2) [sin(psi - nu_w)] over it (nu_w the angle of the wall's normal in the xz plane). The paths' next rays
// start eps off their hits, and the hits lie within a few eps of the crease: started eps along the wall's
// normal they began under the other wall and read it dark (0.0013 here instead of 0.0184).
TEST(Reference, FirstBounceInANotchIsTheWallsLightAtTheCrease) {
  const double rho = 0.5;
  Scene s = notch_scene(rho);
  const HeightField& f = s.field;
  const int c = 4;
  s.bounces = 1;
  const LayerSet r = bake_reference(s, options({"indirect_b1"}, 65536), {});
  // The sky wedge psi in [psi0, psi1]; the right wall (z = 13 (x - c)) lies below psi0, the left above psi1.
  const double psi0 = std::atan(13.0), psi1 = kPi - std::atan(3.0);
  const double nu_left = std::atan2(1.0, 3.0), nu_right = std::atan2(1.0, -13.0);
  const auto cosine_view = [](double nu, double a, double b) {
    return 0.5 * (std::sin(b - nu) - std::sin(a - nu));
  };
  const double left = rho * cosine_view(nu_left, psi0, psi1), right = rho * cosine_view(nu_right, psi0, psi1);
  const Vec3 n = s.normals[f.index(c, 4)].d();
  const double nu = std::atan2(n.z, n.x);
  const double b1 = right * cosine_view(nu, nu - kPi / 2, psi0) + left * cosine_view(nu, psi1, nu + kPi / 2);
  ASSERT_GT(b1, 0.01);
  EXPECT_WITHIN_3SE(at(r, "indirect_b1", c, 4), b1, 1e-4);
}

TEST(ReferenceHorizons, AgreeWithTheExactMarchOnRoughTerrain) {
  // Two independent computations of the same horizons of the triangulated surface: bisection with Embree
  // rays, and the exact march over every column, row and diagonal crossing (tests/p1/p1_truth.hpp). The
  // border ring included, where the azimuths 0, 90, 180 and 270 degrees run along the border, in the plane
  // of the mesh's outer edges (the march has no crossing looking out of the field: those are skipped).
  ProceduralSpec p = spec_of(ProceduralKind::rough, 40);
  p.angle_deg = 75;
  const HeightField f = make_procedural(p, 1.0, Wrap::clamp);
  const int K = 12;
  const ReferenceHorizons h = trace_reference_horizons(f, K, true, {});
  double worst = 0, worst_border = 0;
  int distance_misses = 0, along_border = 0;
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i)
      for (int k = 0; k < K; ++k) {
        const double phi = azimuth(k, K);
        const double c = std::cos(phi), s = std::sin(phi);
        const bool border = i == 0 || j == 0 || i == 39 || j == 39;
        double dz, run;
        const bool seen = truth::march_from(f, i, j, c, s, 7, 0, &dz, &run);
        if (!border) {
          ASSERT_TRUE(seen);
        }
        if (!seen) continue;
        const double e = std::atan2(dz, run);
        const std::size_t t = f.index(i, j) * K + k;
        const double error = std::abs(std::asin(double(h.sin_elevation[t])) - e);
        (border ? worst_border : worst) = std::max(border ? worst_border : worst, error);
        along_border += border && (std::abs(c) < 1e-9 || std::abs(s) < 1e-9);
        if (!border)
          distance_misses += std::abs(h.distance[t] - std::hypot(run, dz)) > 1e-3 * std::hypot(run, dz);
      }
  EXPECT_LT(worst, 2e-4);  // radians: the receivers' lift and float rays
  EXPECT_GT(along_border, 4 * 38);
  EXPECT_LT(worst_border, 2e-4);
  // Distances: where two casters' elevations differ by less than the rays resolve (about 1e-4 rad for a
  // caster a twentieth of a texel away) either may be hit; on this field that is about 1 % of the
  // texel-directions. A wrong distance rule (horizontal instead of 3D, the wrong hit) misses most of them.
  EXPECT_LT(distance_misses, 38 * 38 * K / 50);
  // Bisection steps shown to matter: 6 halvings of pi leave errors of about pi / 128.
  const ReferenceHorizons coarse = trace_reference_horizons(f, K, false, {}, 6);
  double coarse_worst = 0;
  for (std::size_t t = 0; t < coarse.sin_elevation.size(); ++t)
    coarse_worst = std::max(coarse_worst, double(std::abs(coarse.sin_elevation[t] - h.sin_elevation[t])));
  EXPECT_GT(coarse_worst, 1e-3);
}

TEST(ReferenceHorizons, AddedForTheMethodsThatBakeThem) {
  const HeightField f = make_procedural(spec_of(ProceduralKind::cone, 9), 1.0, Wrap::clamp);
  LayerSet method;
  method.width = method.height = 9;
  std::vector<std::string> names;
  for (int k = 0; k < 5; ++k) names.push_back(std::string(1, 'k') + std::to_string(k));
  method.add("horizon", names);
  LayerSet reference;
  reference.width = reference.height = 9;
  add_reference_horizons(f, {&method}, reference, {});
  ASSERT_TRUE(reference.find("horizon"));
  EXPECT_EQ(reference.find("horizon")->channels, names);
  EXPECT_FALSE(reference.find("horizon_distance"));  // nobody baked it
  // The cone's apex sees its flanks fall at 30 degrees in every direction (the triangulated flanks between
  // the grid's exact heights sag below the cone by up to 1e-3 in sin).
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(reference.find("horizon")->data[f.index(4, 4) * 5 + k], -0.5, 1e-3);
}

TEST(Reference, SunWithAngularSizeOnFlatGround) {
  Scene s = make_scene(spec_of(ProceduralKind::flat, 17), Wrap::clamp, {0.5f, 0.5f, 0.5f}, {0, 0, 0});
  const double zenith = 50 * kDeg;
  DirectionalLight sun;
  sun.direction = {std::sin(zenith) * std::cos(0.3), std::sin(zenith) * std::sin(0.3), std::cos(zenith)};
  sun.angular_diameter = 12 * kDeg;
  sun.irradiance = {2, 3, 4};
  s.lights = {sun};
  DirectionalLight point = sun;
  point.angular_diameter = 0;
  point.irradiance = {1, 1, 1};
  const LayerSet r = bake_reference(s, options({"direct"}, 64), {});
  s.lights = {point};
  const LayerSet rp = bake_reference(s, options({"direct"}, 8), {});
  for (int c = 0; c < 3; ++c) {
    EXPECT_WITHIN_3SE(at(r, "direct", 8, 8, c), (&sun.irradiance.r)[c] * std::cos(zenith) / kPi, 1e-5);
    EXPECT_WITHIN_3SE(at(rp, "direct", 8, 8, c), std::cos(zenith) / kPi, 1e-6);
  }
  EXPECT_GT(at(r, "direct", 8, 8).se, 0);  // the disk is sampled: there is noise, and it is reported
}

// A lat-long sky (importance sampled with MIS): on flat ground, direct = (1/pi) int L cos over the upper
// hemisphere = horizon + 2 (zenith - horizon) / 3 for the built-in sky's gradient L = horizon + (zenith -
// horizon) sin e.
TEST(Reference, LatLongSkyWithMis) {
  SkySpec spec;
  spec.sun_irradiance = {0, 0, 0};
  spec.height = 128;
  const EnvironmentLighting sky = make_sky_environment(spec);
  Scene s = make_scene(spec_of(ProceduralKind::flat, 9));
  s.environment = sky.environment;
  const LayerSet r = bake_reference(s, options({"direct"}, 256), {});
  for (int c = 0; c < 3; ++c) {
    const double h = (&spec.horizon.r)[c], z = (&spec.zenith.r)[c];
    // 2e-3: the bilinear lookup blends the ground into the lowest half-row of sky.
    EXPECT_WITHIN_3SE(at(r, "direct", 4, 4, c), h + 2 * (z - h) / 3, 2e-3);
  }
}

// Emission: a V-trench whose walls glow with radiance E, black sky, albedo 0. The floor sees the walls in
// the cosine-weighted fraction 1 - cos(beta), so indirect = indirect_b1 = E (1 - cos beta), b2 = 0.
TEST(Reference, EmittingTrenchWalls) {
  ProceduralSpec p = spec_of(ProceduralKind::trench, 33);
  p.angle_deg = 50;
  Scene s = make_scene(p, Wrap::clamp, {0, 0, 0}, {0, 0, 0});
  const Rgb E{2, 1, 0.5f};
  s.surface.emission.assign(s.field.texel_count(), E);
  s.bounces = 2;
  const LayerSet r =
      bake_reference(s, options({"indirect", "indirect_b1", "indirect_b2", "direct"}, 512), {});
  const double open = std::cos(p.angle_deg * kDeg);
  for (int c = 0; c < 3; ++c) {
    EXPECT_WITHIN_3SE(at(r, "indirect", 16, 16, c), (&E.r)[c] * (1 - open), 1e-4);
    EXPECT_WITHIN_3SE(at(r, "indirect_b1", 16, 16, c), (&E.r)[c] * (1 - open), 1e-4);
    EXPECT_EQ(at(r, "indirect_b2", 16, 16, c).v, 0);
    EXPECT_EQ(at(r, "direct", 16, 16, c).v, 0);
  }
}

// The SH-band-limited sky on flat ground: E / pi = sum_l (A_l / pi) L_l0 Y_l0(+z) with the clamped-cosine
// coefficients A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4, A_3 = 0 (Ramamoorthi & Hanrahan 2001).
TEST(Reference, ShBandLimitedSkyOnFlatGround) {
  SkySpec spec;
  spec.sun_irradiance = {0, 0, 0};
  spec.height = 64;
  const EnvironmentLighting sky = make_sky_environment(spec);
  Scene s = make_scene(spec_of(ProceduralKind::flat, 9));
  s.environment = sky.environment;
  ReferenceOptions o = options({"direct"}, 256);
  o.sh_environment = true;
  const LayerSet r = bake_reference(s, o, {});
  const auto c = reference::project_sh(sky.environment);
  const auto y = reference::sh_basis({0, 0, 1});
  const double a[4] = {1.0, 2.0 / 3.0, 0.25, 0.0};
  for (int ch = 0; ch < 3; ++ch) {
    double expected = 0;
    for (int l = 0; l < 4; ++l) expected += a[l] * (&c[l * (l + 1)].r)[ch] * y[l * (l + 1)];
    EXPECT_WITHIN_3SE(at(r, "direct", 4, 4, ch), expected, 2e-3);
  }
}

// A sun in one texel of a lat-long map (60000 over a sky of 0.2) lights flat ground with E / pi = 0.2 plus
// the sun texel's 60000 Omega cos(theta) / pi (the bilinear lookup spreads it over its neighbours, keeping
// its integral to first order). The sampler must put samples where the lookup puts that light: at 256 samples
// the noise is under a tenth of the value and the estimate agrees with the closed form. (A sampler weighting
// each texel by its own luminance alone seldom samples the neighbours: a heavy-tailed estimate, 40 % low
// here with a small reported noise.)
TEST(EnvSampler, OneBrightTexelIsSampledWhereTheLookupSpreadsIt) {
  const int W = 64, H = 32, row = 8, col = 21;
  std::vector<Rgb> texels(std::size_t(W) * H, Rgb{0.2f, 0.2f, 0.2f});
  texels[std::size_t(row) * W + col] = Rgb{60000, 60000, 60000};
  Scene s = make_scene(spec_of(ProceduralKind::flat, 9));
  s.environment = make_latlong_environment(W, H, texels);
  const LayerSet r = bake_reference(s, options({"direct"}, 256), {});
  const double theta = kPi * (row + 0.5) / H;
  const double omega = s.environment.texel_solid_angle(row);
  const double expected = 0.2 + (60000 - 0.2) * omega * std::cos(theta) / kPi;
  for (int c = 0; c < 3; ++c) {
    const Value e = at(r, "direct", 4, 4, c);
    EXPECT_LT(e.se, 0.1 * expected) << c;
    EXPECT_WITHIN_3SE(e, expected, 0.01 * expected);
  }
}

TEST(EnvSampler, PdfIsNormalisedAndMatchesSampling) {
  SkySpec spec;
  spec.height = 32;
  const Environment env = make_sky_environment(spec).environment;
  const reference::EnvSampler sampler(env);
  double total = 0;
  for (int r = 0; r < 32; ++r)
    for (int c = 0; c < 64; ++c) total += sampler.pdf(env.texel_direction(c, r)) * env.texel_solid_angle(r);
  EXPECT_NEAR(total, 1.0, 1e-9);
  const auto seq = reference::Sequence2::make(5);
  for (std::uint32_t k = 0; k < 100; ++k) {
    double pdf = 0;
    const Vec3 d = sampler.sample(seq(k), pdf);
    EXPECT_NEAR(length(d), 1.0, 1e-9);
    EXPECT_NEAR(sampler.pdf(d), pdf, 1e-9 * pdf);
  }
}

TEST(ShEnvironment, BandLimitedKeepsLowOrderFunctions) {
  // L = 1 + 0.5 z + 0.25 x y lies in bands 0..2: the band-limited environment reproduces it.
  const int H = 64, W = 128;
  std::vector<Rgb> texels(W * H);
  Environment probe = make_uniform_environment({1, 1, 1});
  probe = make_latlong_environment(W, H, std::vector<Rgb>(W * H, Rgb{1, 1, 1}));
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c) {
      const Vec3 d = probe.texel_direction(c, r);
      const float v = float(1 + 0.5 * d.z + 0.25 * d.x * d.y);
      texels[r * W + c] = {v, 2 * v, 0.5f};
    }
  const Environment env = make_latlong_environment(W, H, texels);
  const Environment bl = reference::band_limited_environment(env);
  double worst = 0;
  for (int k = 0; k < W * H; ++k)
    worst = std::max(worst, double(std::abs(bl.levels[0].texels[k].g - texels[k].g)));
  EXPECT_LT(worst, 2e-3);
}

// White furnace: albedo 1 under a uniform sky L on a rough, tiling field. Light is never lost, so
// total -> L as bounces grow; the part still missing after N bounces is the light that would need more.
TEST(Reference, WhiteFurnace) {
  ProceduralSpec p = spec_of(ProceduralKind::fractal, 24);
  p.amplitude = 8;
  p.feature_size = 12;
  Scene s = make_scene(p, Wrap::repeat, {1, 1, 1}, {1, 1, 1});
  s.bounces = 12;
  std::vector<std::string> layers = {"total", "direct"};
  for (int b = 1; b <= s.bounces; ++b) layers.push_back("indirect_b" + std::to_string(b));
  // 32 replicates: (estimate - truth) / stderr follows Student's t with 31 degrees of freedom, so a
  // per-texel check at 4.5 stderr is meaningful even for the heavy-tailed path contributions.
  ReferenceOptions o = options(layers, 512);
  o.replicates = 32;
  const LayerSet r = bake_reference(s, o, {});
  double mean = 0, var = 0, direct = 0;
  int beyond3 = 0;
  std::vector<double> bounce(s.bounces + 1, 0.0);
  const int n = 24 * 24;
  for (int j = 0; j < 24; ++j)
    for (int i = 0; i < 24; ++i) {
      const Value v = at(r, "total", i, j);
      mean += v.v / n, var += v.se * v.se / (double(n) * n);
      direct += at(r, "direct", i, j).v / n;
      for (int b = 1; b <= s.bounces; ++b) bounce[b] += at(r, "indirect_b" + std::to_string(b), i, j).v / n;
      EXPECT_LE(std::abs(v.v - 1.0), 4.5 * v.se + 1e-3) << i << "," << j << " se " << v.se;
      beyond3 += std::abs(v.v - 1.0) > 3 * v.se + 1e-3;
    }
  EXPECT_LE(beyond3, n / 50);
  // Geometric convergence: each bounce carries a fraction of the previous one.
  EXPECT_LT(direct, 0.99);
  EXPECT_GT(bounce[1], 0.005);
  for (int b = 2; b <= 5; ++b) EXPECT_LT(bounce[b], bounce[b - 1] * 0.7) << b;  // later ones are noise-sized
  EXPECT_LE(std::abs(mean - 1.0), 3 * std::sqrt(var) + 2e-4) << "mean total " << mean;
  std::printf(
      "white furnace: direct %.5f, b1 %.5f, b2 %.5f, b3 %.5f, ..., b%d %.2e; mean total %.6f +- %.6f\n",
      direct, bounce[1], bounce[2], bounce[3], s.bounces, bounce[s.bounces], mean, std::sqrt(var));
}

TEST(Reference, DeterministicForAnyThreadCount) {
  ProceduralSpec p = spec_of(ProceduralKind::fractal, 32);
  Scene s = make_scene(p, Wrap::clamp, {0.6f, 0.5f, 0.4f});
  s.bounces = 2;
  SkySpec spec;
  spec.height = 16;
  const EnvironmentLighting sky = make_sky_environment(spec);
  s.environment = sky.environment;
  s.lights = sky.lights;
  ReferenceOptions o =
      options({"ao", "vsky", "obscurance", "direct", "indirect", "total", "indirect_b2"}, 16);
  o.falloff.kind = FalloffKind::smooth;
  o.falloff.radius = 6;
  o.tile_size = 8;
  LayerSet one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = bake_reference(s, o, {});
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = bake_reference(s, o, {});
  }
  ASSERT_EQ(one.layers.size(), two.layers.size());
  for (std::size_t k = 0; k < one.layers.size(); ++k) {
    ASSERT_EQ(one.layers[k].data.size(), two.layers[k].data.size());
    EXPECT_EQ(
        0, std::memcmp(one.layers[k].data.data(), two.layers[k].data.data(), one.layers[k].data.size() * 4))
        << one.layers[k].name;
  }
}

// Resuming (ReferenceResume): bands handed out by one bake and given back to another are taken as they are,
// and the bands traced afresh are the same bits as in a whole bake (rows of 7 and a shorter last band, a
// row range as the farm cuts it, the adaptive "samples" layer included).
TEST(Reference, ResumedBandsGiveTheBitsOfAWholeBake) {
  Scene s = make_scene(spec_of(ProceduralKind::fractal, 30));
  ReferenceOptions o = options({"ao", "vsky"}, 32);
  o.target_stderr = 0.05;
  o.tile_size = 7;
  o.row_begin = 3;
  o.row_end = 27;  // 24 rows: bands of 7, 7, 7, 3
  ASSERT_EQ(reference_band_count(o, 24), 4);
  std::map<int, std::vector<float>> stored;
  ReferenceResume first;
  first.store = [&](int band, std::span<const float> v) { stored[band].assign(v.begin(), v.end()); };
  const LayerSet whole = bake_reference(s, o, {}, &first);
  EXPECT_EQ(first.bands_traced, 4);
  EXPECT_EQ(first.bands_resumed, 0);
  ASSERT_EQ(stored.size(), 4u);
  // Bands 1 and 3 come back (band 2 with the wrong size is refused by the loader, as a damaged file is).
  ReferenceResume second;
  second.load = [&](int band, std::span<float> v) {
    if (band % 2 == 0 || stored[band].size() != v.size()) return false;
    std::copy(stored[band].begin(), stored[band].end(), v.begin());
    return true;
  };
  int stores = 0;
  second.store = [&](int, std::span<const float>) { ++stores; };
  const LayerSet resumed = bake_reference(s, o, {}, &second);
  EXPECT_EQ(second.bands_resumed, 2);
  EXPECT_EQ(second.bands_traced, 2);
  EXPECT_EQ(stores, 2);  // only what it traced
  ASSERT_EQ(whole.layers.size(), resumed.layers.size());
  for (std::size_t k = 0; k < whole.layers.size(); ++k)
    EXPECT_EQ(0, std::memcmp(whole.layers[k].data.data(), resumed.layers[k].data.data(),
                             whole.layers[k].data.size() * 4))
        << whole.layers[k].name;
  // A band given back with other values is taken as given: the loader is the one that checks.
  ReferenceResume third;
  third.load = [&](int band, std::span<float> v) {
    std::fill(v.begin(), v.end(), 0.25f);
    return band == 3;
  };
  const LayerSet odd = bake_reference(s, o, {}, &third);
  EXPECT_EQ(odd.find("ao")->data[std::size_t(30) * 21], 0.25f);  // row 3 + 21: band 3
  EXPECT_NE(odd.find("ao")->data[std::size_t(30) * 20], 0.25f);
}

// The quad mesh (with its quad skirt) and the grid are the same surface traced by the same robust
// intersector: every layer, hit distances included (obscurance, the paths), has the same bits, with single
// rays or streams (rtcOccluded1M / rtcIntersect1M), on a rough field under a sky with a sun, 2 bounces.
TEST(Reference, QuadsGridAndStreamsGiveTheSameBits) {
  Scene s = make_scene(spec_of(ProceduralKind::fractal, 40), Wrap::clamp, {0.6f, 0.5f, 0.4f});
  s.bounces = 2;
  const EnvironmentLighting sky = make_sky_environment(SkySpec{});
  s.environment = sky.environment;
  s.lights = sky.lights;
  ReferenceOptions o = options({"ao", "vsky", "obscurance", "direct", "indirect", "bent_normal"}, 32);
  o.falloff.kind = FalloffKind::smooth;
  o.falloff.radius = 6;
  o.geometry = reference::GeometryKind::grid;
  o.ray_streams = false;
  const LayerSet grid = bake_reference(s, o, {});
  for (const bool streams : {false, true}) {
    o.geometry = reference::GeometryKind::quads;
    o.ray_streams = streams;
    const LayerSet quads = bake_reference(s, o, {});
    ASSERT_EQ(grid.layers.size(), quads.layers.size());
    for (std::size_t k = 0; k < grid.layers.size(); ++k)
      EXPECT_EQ(0, std::memcmp(grid.layers[k].data.data(), quads.layers[k].data.data(),
                               grid.layers[k].data.size() * 4))
          << grid.layers[k].name << (streams ? ", streams" : ", single rays");
  }
}

TEST(Reference, TargetStderrSpendsSamplesWhereTheNoiseIs) {
  ProceduralSpec p = spec_of(ProceduralKind::pit, 17);
  p.radius = 5;
  p.depth = 4;
  Scene s = make_scene(p);
  ReferenceOptions o = options({"ao"}, 8192);
  o.target_stderr = 0.01;
  const LayerSet r = bake_reference(s, o, {});
  const Layer* n = r.find("samples");
  ASSERT_TRUE(n);
  // Open flat ground: every pilot sample escapes; the floor 1 / 64 still asks for a few hundred samples.
  EXPECT_EQ(at(r, "ao", 0, 0).v, 1.0);
  EXPECT_LE(n->data[0], 512);
  // Inside the pit the estimate is noisy: more samples, and a stderr near the target.
  const float inside = n->data[8 * 17 + 8];
  EXPECT_GT(inside, n->data[0]);
  EXPECT_LT(inside, 8192);
  EXPECT_LE(at(r, "ao", 8, 8).se, 0.02);
}

TEST(Reference, ObscuranceStepIsAoLimitedToRadius) {
  // Pit center with a step falloff beyond the pit's reach equals ao; well inside, it sees less occlusion.
  ProceduralSpec p = spec_of(ProceduralKind::pit, 33);
  p.radius = 8;
  p.depth = 8;
  Scene s = make_scene(p);
  ReferenceOptions o = options({"ao", "obscurance"}, 512);
  o.falloff = {FalloffKind::step, 100};
  LayerSet r = bake_reference(s, o, {});
  EXPECT_EQ(at(r, "ao", 16, 16).v, at(r, "obscurance", 16, 16).v);  // same rays, same hits
  o.falloff = {FalloffKind::step, 4};                               // the wall is 8+ away: nothing within 4
  r = bake_reference(s, o, {});
  EXPECT_WITHIN_3SE(at(r, "obscurance", 16, 16), 1.0, 1e-6);
}

// The reference's ao must not depend on what else the job asks of it. With an obscurance method
// and no path tracing, ao must not be counted from rays shortened to the falloff radius (it would equal
// the obscurance). Every combination of bounces 0/1, with/without an obscurance method and default/explicit
// reference layers must give the ao of an ao-only reference.
TEST(Reference, AoIsTheSameWhateverElseTheJobTraces) {
  ProceduralSpec p = spec_of(ProceduralKind::fractal, 24);
  p.amplitude = 6;
  Scene s = make_scene(p);
  const LayerSet ao_only = bake_reference(s, options({"ao"}, 64), {});
  const Layer* truth = ao_only.find("ao");
  const Layer* truth_se = ao_only.find("ao_stderr");
  ASSERT_TRUE(truth && truth_se);
  double mean_truth = 0;
  for (float v : truth->data) mean_truth += v;
  mean_truth /= double(truth->data.size());
  ASSERT_LT(mean_truth, 0.97);  // rough enough that a radius of 2 leaves much of the occlusion out
  for (int bounces : {0, 1})
    for (bool obscurance_method : {false, true})
      for (bool explicit_layers : {false, true}) {
        SCOPED_TRACE("bounces " + std::to_string(bounces) + (obscurance_method ? ", hbao" : "") +
                     (explicit_layers ? ", explicit layers" : ", default layers"));
        s.bounces = bounces;
        nlohmann::json job = {{"bake", {{{"method", "p1"}}}}, {"reference", {{"samples", 64}}}};
        if (obscurance_method)
          job["bake"].push_back({{"method", "hbao"}, {"radius", 2}, {"falloff", "step"}});
        if (explicit_layers) {
          job["reference"]["layers"] = {"ao"};
          if (obscurance_method) job["reference"]["layers"].push_back("obscurance");
        }
        const LayerSet r = bake_reference(s, parse_reference_options(s, job), {});
        const Layer* ao = r.find("ao");
        ASSERT_TRUE(ao);
        double mean = 0;
        int off = 0;
        for (std::size_t t = 0; t < ao->data.size(); ++t) {
          mean += ao->data[t];
          off += std::abs(ao->data[t] - truth->data[t]) > 3 * truth_se->data[t] + 1e-6;
        }
        mean /= double(ao->data.size());
        EXPECT_NEAR(mean, mean_truth, 1e-4);
        EXPECT_EQ(off, 0);
        if (obscurance_method) {  // and obscurance is still limited to the radius: more open than ao
          const Layer* ob = r.find("obscurance");
          ASSERT_TRUE(ob);
          double mean_ob = 0;
          for (float v : ob->data) mean_ob += v;
          EXPECT_GT(mean_ob / double(ob->data.size()), mean_truth + 0.01);
        }
      }
}

TEST(Reference, OptionsFromTheJob) {
  Scene s = make_scene(spec_of(ProceduralKind::flat, 8));
  s.bounces = 2;
  nlohmann::json job = {
      {"bake", {{{"method", "p1"}}, {{"method", "lsao"}, {"radius", 12}, {"falloff", "smooth"}}}},
      {"reference", {{"samples", 64}, {"seed", 3}}}};
  ReferenceOptions o = parse_reference_options(s, job);
  EXPECT_EQ(o.falloff.kind, FalloffKind::smooth);
  EXPECT_EQ(o.falloff.radius, 12);
  // Only what the methods are scored against: p1's ao, vsky, direct and lsao's obscurance and bent normal
  // (lsao's default layers).
  EXPECT_EQ(o.layers, (std::vector<std::string>{"ao", "vsky", "obscurance", "direct", "bent_normal"}));
  EXPECT_EQ(o.resolved["layers"], nlohmann::json(o.layers));
  EXPECT_EQ(o.resolved["samples"], 64);
  EXPECT_EQ(o.resolved["replicates"], 8);      // a default, recorded
  EXPECT_EQ(o.resolved["geometry"], "quads");  // small fields: the faster geometry
  MethodContext big;
  big.field.width = 4096, big.field.height = 4097;  // beyond 4096² texels: the grid's third of the memory
  EXPECT_EQ(read_reference_options(job, big, "j.json").resolved["geometry"], "grid");
  big.field.height = 4096;
  EXPECT_EQ(read_reference_options(job, big, "j.json").resolved["geometry"], "quads");
  job["bake"].push_back({{"method", "p2"}});  // p2 adds indirect and total
  EXPECT_EQ(
      parse_reference_options(s, job).layers,
      (std::vector<std::string>{"ao", "vsky", "obscurance", "direct", "indirect", "total", "bent_normal"}));
  job["bake"] = nlohmann::json::array();  // a reference-only job traces everything
  EXPECT_EQ(parse_reference_options(s, job).layers,
            (std::vector<std::string>{"ao", "vsky", "direct", "indirect", "total"}));
  job["bake"] = {{{"method", "p1"}}};
  job["reference"]["layers"] = {"ao", "indirect_b3"};
  EXPECT_THROW(parse_reference_options(s, job), InputError);
  job["reference"]["layers"] = {"ao", "indirect_b2"};
  EXPECT_NO_THROW(parse_reference_options(s, job));
}

}  // namespace
}  // namespace hfbake
