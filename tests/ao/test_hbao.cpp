// hbao against closed-form scenes (wall, pit, trench), computed independently in ao_scenes.hpp.
#include <gtest/gtest.h>

#include <cmath>

#include "ao_scenes.hpp"
#include "field/procedural.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/slice_integral.hpp"

namespace hfbake {
namespace {

using test::make_pit;
using test::make_plane;
using test::make_wall;

Falloff falloff(FalloffKind k, double r) {
  Falloff f;
  f.kind = k;
  f.radius = r;
  return f;
}

HbaoSettings settings(int K, Falloff f, Weighting w = Weighting::cosine, double step = 0.5) {
  HbaoSettings s;
  s.falloff = f;
  s.weighting = w;
  s.directions = uniform_directions(K);
  s.step = step;
  s.reach = 1e6;
  return s;
}

double occluded_at(const HeightField& f, int i, int j, const HbaoSettings& s) {
  return hbao_texel(f, compute_normals(f)[f.index(i, j)].d(), i, j, s).occluded;
}

// One or two directions on steep ridges (a 80 x 2 ridges field, texels 0.1 apart, 20 units of relief): the
// estimate of a normal whose lobe lies mostly in one direction stays a share, in [0, 1].
TEST(Hbao, FewDirectionsOnSteepRidgesStayInRange) {
  for (std::uint64_t seed : {1, 2, 3, 4, 5}) {
    ProceduralSpec spec;
    spec.kind = ProceduralKind::ridges, spec.width = 80, spec.height = 2, spec.seed = seed;
    HeightField f = make_procedural(spec, 0.1, Wrap::clamp);
    for (float& z : f.z) z *= 20;
    const auto normals = compute_normals(f);
    for (int K : {1, 2})
      for (FalloffKind k : {FalloffKind::none, FalloffKind::linear})
        for (int j = 0; j < f.height; ++j)
          for (int i = 0; i < f.width; ++i) {
            const double o =
                hbao_texel(f, normals[f.index(i, j)].d(), i, j, settings(K, falloff(k, 8.0))).occluded;
            EXPECT_GE(o, 0.0) << seed << " K " << K << " texel " << i << " " << j;
            EXPECT_LE(o, 1.0) << seed << " K " << K << " texel " << i << " " << j;
          }
  }
}

// The expectations themselves against tables computed by hand (guards the independent quadrature).
TEST(AoScenes, ClosedFormsMatchTheDigest) {
  auto rational = [](double r) { return [r](double d) { return r / (r + d * d); }; };
  EXPECT_NEAR(test::pit_occlusion(1, 1, [](double) { return 1.0; }), 0.5, 1e-6);
  EXPECT_NEAR(test::pit_occlusion(1, 1, rational(1)), 0.212318, 1e-6);
  EXPECT_NEAR(test::pit_occlusion(1, 1, rational(4)), 0.372294, 1e-6);
  EXPECT_NEAR(test::pit_occlusion(1, 2, rational(1)), 0.289174, 1e-6);
  EXPECT_NEAR(test::pit_occlusion(2, 1, rational(1)), 0.036712, 1e-6);
  auto one = [](double) { return 1.0; };
  EXPECT_NEAR(test::wall_occlusion(1, 1, 8, true, one), 0.145833, 1e-6);
  EXPECT_NEAR(test::wall_occlusion(1, 2, 16, true, one), 0.276190, 1e-6);
  EXPECT_NEAR(test::wall_occlusion(1, 0.5, 8, false, one), 0.139235, 1e-6);
  EXPECT_NEAR(test::wall_occlusion(1, 1, 0, false, one), 0.25, 1e-5);
  EXPECT_NEAR(test::wall_occlusion(1, 1, 8, true, rational(1)), 0.050982, 1e-6);
  EXPECT_NEAR(test::wall_occlusion(1, 2, 16, true, rational(1)), 0.075693, 1e-6);
  EXPECT_NEAR(test::wall_occlusion(1, 1, 16, true, rational(4)), 0.096322, 1e-6);
}

// The slice integrals against brute-force quadrature, every falloff, both weightings, a tilted normal.
TEST(SliceIntegral, BandsMatchQuadrature) {
  const SliceFrame s = slice_frame(0.4, std::sqrt(1 - 0.16));
  for (FalloffKind k : {FalloffKind::none, FalloffKind::step, FalloffKind::linear, FalloffKind::smooth,
                        FalloffKind::exponential, FalloffKind::rational}) {
    const Falloff f = falloff(k, 3.0);
    for (Weighting w : {Weighting::cosine, Weighting::uniform}) {
      for (double x : {0.5, 2.0, 5.0}) {
        const double a = -1.2, b = 1.1;
        const double expect = test::simpson(
            [&](double e) {
              const double c = std::cos(e);
              if (e < s.tangent) return 0.0;
              const double wt = w == Weighting::cosine ? (s.nt * c + s.nz * std::sin(e)) * c : c;
              return f(x / c) * wt;
            },
            a, b, 200000);
        EXPECT_NEAR(band_occlusion(f, w, s, a, b, x), expect, 2e-6) << int(k) << " " << int(w) << " " << x;
      }
    }
  }
}

TEST(Hbao, PitWithoutFalloff) {
  const HeightField f = make_pit(81, 32, 32);
  for (int K : {8, 16, 32}) EXPECT_NEAR(occluded_at(f, 40, 40, settings(K, Falloff{})), 0.5, 0.01) << K;
  // Uniform weighting: sin e.
  EXPECT_NEAR(occluded_at(f, 40, 40, settings(16, Falloff{}, Weighting::uniform)), std::sqrt(0.5), 0.01);
}

TEST(Hbao, PitWithFalloff) {
  const HeightField f = make_pit(81, 32, 32);
  // Rational falloff r / (r + d^2) with r = R^2: the closed forms (1, 1, 1) and (1, 1, 4) scaled by 32.
  EXPECT_NEAR(occluded_at(f, 40, 40, settings(16, falloff(FalloffKind::rational, 32))), 0.212318, 0.006);
  EXPECT_NEAR(occluded_at(f, 40, 40, settings(16, falloff(FalloffKind::rational, 64))), 0.372294, 0.008);
  // Step at R = 40: rays below acos(32 / 40) hit the wall within R. The rastered rim lies at 32..33 texels
  // depending on the azimuth, and the step cut-off makes that visible: 0.02.
  for (FalloffKind k :
       {FalloffKind::step, FalloffKind::linear, FalloffKind::smooth, FalloffKind::exponential}) {
    const Falloff fo = falloff(k, 40);
    const double expect = test::pit_occlusion(32, 32, [&](double d) { return fo(d); });
    EXPECT_NEAR(occluded_at(f, 40, 40, settings(16, fo)), expect, 0.02) << int(k);
  }
}

TEST(Hbao, WallMatchesDiscreteK) {
  const HeightField f = make_wall(96, 257, 64, 32);  // receiver at x = 32: x0 = 32, a = 1
  auto one = [](double) { return 1.0; };
  for (int K : {8, 16}) {
    EXPECT_NEAR(occluded_at(f, 32, 128, settings(K, Falloff{})), test::wall_occlusion(32, 32, K, true, one),
                0.004)
        << K;
    EXPECT_NEAR(occluded_at(f, 32, 128, settings(K, Falloff{}, Weighting::uniform)),
                test::wall_occlusion(32, 32, K, false, one), 0.006)
        << K;
    const Falloff r = falloff(FalloffKind::rational, 32);
    EXPECT_NEAR(occluded_at(f, 32, 128, settings(K, r)),
                test::wall_occlusion(32, 32, K, true, [&](double d) { return r(d); }), 0.003)
        << K;
  }
}

TEST(Hbao, PlanesAreOpen) {
  for (auto [gx, gy] : {std::pair{0.0, 0.0}, std::pair{0.3, -0.2}, std::pair{-1.5, 0.7}}) {
    const HeightField f = make_plane(33, gx, gy);
    const auto normals = compute_normals(f);
    for (FalloffKind k : {FalloffKind::none, FalloffKind::step, FalloffKind::rational}) {
      for (Weighting w : {Weighting::cosine, Weighting::uniform}) {
        const HbaoSettings s = settings(16, falloff(k, 8), w, 1.0);
        for (auto [i, j] : {std::pair{16, 16}, std::pair{3, 29}}) {
          const HorizonTexel t = hbao_texel(f, normals[f.index(i, j)].d(), i, j, s);
          EXPECT_NEAR(t.occluded, 0.0, 1e-6) << gx << " " << gy << " " << int(k) << " " << int(w);
        }
      }
      // The bent normal of an open plane is its normal (directions closed under negation).
      const HorizonTexel t = hbao_texel(f, normals[f.index(16, 16)].d(), 16, 16, settings(16, falloff(k, 8)));
      const Vec3 n = normals[f.index(16, 16)].d();
      EXPECT_GT(dot(t.bent_normal, n), 0.999) << gx << " " << gy;
    }
  }
}

TEST(Hbao, ConvergesWithDirectionsAndSteps) {
  // Wall: the error against the exact azimuthal integral shrinks with K (8 -> 16 -> 64).
  const HeightField wall = make_wall(96, 513, 64, 64);  // a = 2, 256 texels either side
  auto one = [](double) { return 1.0; };
  const double exact = test::wall_occlusion(32, 64, 0, false, one, 256);
  double prev = 1;
  for (int K : {8, 16, 32, 64}) {
    const double err =
        std::abs(occluded_at(wall, 32, 256, settings(K, Falloff{}, Weighting::uniform)) - exact);
    if (K < 64) {
      EXPECT_LT(err, prev) << K;
    }  // K = 64 is at the raster floor (wall ramp, step)
    prev = err;
  }
  EXPECT_LT(prev, 0.003);
  // Pit with a smooth falloff: the error against the closed form shrinks with the step.
  const HeightField pit = make_pit(81, 32, 32);
  const Falloff r = falloff(FalloffKind::rational, 32);
  const double expect = test::pit_occlusion(32, 32, [&](double d) { return r(d); });
  const double e4 = std::abs(occluded_at(pit, 40, 40, settings(8, r, Weighting::cosine, 4.0)) - expect);
  const double e1 = std::abs(occluded_at(pit, 40, 40, settings(8, r, Weighting::cosine, 1.0)) - expect);
  const double e025 = std::abs(occluded_at(pit, 40, 40, settings(8, r, Weighting::cosine, 0.25)) - expect);
  EXPECT_LT(e1, e4);
  EXPECT_LE(e025, e1 + 1e-9);
}

TEST(Hbao, LargestOccluderIsTheGlobalHorizonWithoutFalloff) {
  // P3's estimator with rho = 1 and sinT = -1 is the mean sine of the horizon.
  const HeightField f = make_pit(81, 32, 32);
  HbaoSettings s = settings(16, Falloff{}, Weighting::uniform);
  s.estimator = HorizonEstimator::largest_occluder;
  s.sin_tangent = -1;
  EXPECT_NEAR(occluded_at(f, 40, 40, s), std::sqrt(0.5), 0.01);
  // Flat ground, fixed tangent -0.85 and a falloff: every direction gives -0.85 (1 - rho(step)), clamped to
  // 0.
  const HeightField flat = make_plane(33, 0, 0);
  s.falloff = falloff(FalloffKind::rational, 4);
  s.sin_tangent = -0.85;
  EXPECT_EQ(occluded_at(flat, 16, 16, s), 0.0);
}

}  // namespace
}  // namespace hfbake

namespace hfbake {
namespace {

// A box-pattern direction (2, 1) with its own step |(2, 1)| samples texel centres only: the horizon equals
// the brute-force maximum over the texels (i + 2m, j + m).
TEST(Hbao, BoxPatternDirectionSamplesTexelCentres) {
  HeightField f;
  f.width = f.height = 40;
  f.z.resize(f.texel_count());
  for (std::size_t t = 0; t < f.z.size(); ++t) f.z[t] = float((t * 7919) % 13);
  const double L = std::hypot(2.0, 1.0);
  HbaoSettings s;
  s.weighting = Weighting::uniform;
  s.estimator = HorizonEstimator::largest_occluder;
  s.sin_tangent = -1;
  s.directions = {MarchDirection{2 / L, 1 / L, 1, L}};
  s.reach = 1e6;
  double best = -1;
  for (int m = 1; 5 + 2 * m < 40; ++m) {
    const double dz = f.z[f.index(5 + 2 * m, 7 + m)] - f.z[f.index(5, 7)], x = m * L;
    best = std::max(best, dz / std::hypot(x, dz));
  }
  EXPECT_NEAR(hbao_texel(f, {0, 0, 1}, 5, 7, s).occluded, std::max(0.0, best), 1e-6);
}

}  // namespace
}  // namespace hfbake
