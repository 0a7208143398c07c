// Method p2 on whole fields: white furnace (identity and convergence), flat ground, closed forms for an
// emitting ramp and a V-trench, per-bounce means against the Embree reference, tree == naive bits,
// thread-count determinism, layers and parameters.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <utility>

#include "core/error.hpp"
#include "env/environment.hpp"
#include "field/procedural.hpp"
#include "field/scene.hpp"
#include "methods/p1/p1.hpp"
#include "methods/p2/bake_p2.hpp"
#include "methods/p2/indirect_gather.hpp"
#include "p2_test_scenes.hpp"
#include "reference/bake_reference.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake {
namespace {

Scene make_scene(HeightField f, Rgb sky, float albedo, float emission, int bounces) {
  Scene s;
  s.name = "test";
  s.field = std::move(f);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{albedo, albedo, albedo});
  if (emission > 0) s.surface.emission.assign(s.field.texel_count(), Rgb{emission, emission, emission});
  s.environment = make_uniform_environment(sky);
  s.bounces = bounces;
  return s;
}

HeightField procedural(ProceduralKind kind, int n, Wrap wrap, std::uint64_t seed = 2) {
  ProceduralSpec spec;
  spec.kind = kind;
  spec.width = n;
  spec.height = n;
  spec.seed = seed;
  return make_procedural(spec, 1.0, wrap);
}

P2Params params(int K, int bounces) {
  P2Params p;
  p.directions = K;
  p.bounces = bounces;
  return p;
}

// The cosine lobe as the K wedges integrate it (midpoint rule in azimuth, like P1): 1 for an upward
// normal, 1 - O(spectral) for a tilted one (2e-2 at K = 4 and 50 degrees).
double lobe(Vec3 n, int K) {
  double sum = 0;
  for (int k = 0; k < K; ++k) {
    const double phi = 2 * kPi * k / K;
    const double np = n.x * std::cos(phi) + n.y * std::sin(phi);
    const double et = std::atan(-np / n.z);  // tangent plane elevation
    sum += n.z * std::cos(et) * std::cos(et) + np * (kPi / 2 - et - std::sin(et) * std::cos(et));
  }
  return sum / K;
}

// max over texels of |direct + indirect - lobe|
double max_abs_dev(const Scene& s, const P2Result& r, int K) {
  double m = 0;
  for (std::size_t i = 0; i < r.direct.size(); ++i)
    m = std::max(m, std::fabs(double(r.direct[i].g + r.indirect[i].g) - lobe(s.normals[i].d(), K)));
  return m;
}

// Emission 1 everywhere, albedo 0, sky 1: every direction above the tangent plane brings radiance 1,
// from the sky (P1's direct) or from the terrain (one bounce), so direct + indirect = the cosine lobe
// (1 up to the azimuthal quadrature, lobe() above) at every texel: the two methods split each texel's
// lobe at the same horizon (indirect_sweep.cpp), so this holds to float rounding for every K.
TEST(P2Bake, EmittingFurnaceDirectPlusIndirectIsTheLobe) {
  for (auto kind : {ProceduralKind::fractal, ProceduralKind::blocks}) {
    for (Wrap wrap : {Wrap::repeat, Wrap::clamp}) {
      const Scene s = make_scene(procedural(kind, 48, wrap), {1, 1, 1}, 0, 1, 1);
      for (int K : {4, 16}) {
        const P2Result r = compute_p2(s, params(K, 1), RunControl{});
        EXPECT_LT(max_abs_dev(s, r, K), 1e-5) << procedural_kind_name(kind) << " K " << K;
        double terrain = 0;
        for (const Rgb& v : r.indirect) terrain += v.g;
        EXPECT_GT(terrain / double(r.indirect.size()), 0.02);  // the test is not vacuous
      }
    }
  }
}

// White furnace: albedo 1, sky 1, no emission. Bounce b + 1 gathers bounce b; the gather is linear and
// brings at most tau = max_x (lobe(x) - direct(x)) of a uniform radiance, where x runs over the texels
// and the facets (the senders), so max indirect_b <= tau^b (geometric convergence), and total -> 1 (the
// fixed point of total = direct + gather(total) when direct + gather(1) = 1, the identity tested
// above): after B bounces 1 - total <= tau^(B+1) / (1 - tau).
TEST(P2Bake, WhiteFurnaceConverges) {
  const int K = 32, B = 8;
  const Scene s = make_scene(procedural(ProceduralKind::fractal, 48, Wrap::repeat), {1, 1, 1}, 1, 0, 1);
  const P2Result r = compute_p2(s, params(K, B), RunControl{});
  double tau = 0;
  for (std::size_t i = 0; i < r.direct.size(); ++i)
    tau = std::max(tau, lobe(s.normals[i].d(), K) - r.direct[i].g);
  // The facets' share of terrain (P1's facet light, as compute_p2 lights its senders).
  P1Params p1;
  p1.directions = K;
  p1.facet_direct = true;
  const P1Result d = compute_p1(s, p1, RunControl{});
  for (int j = 0; j < s.field.height; ++j)
    for (int i = 0; i < s.field.width; ++i) {
      Vec3f fn[2];
      facet_normals(s.field, i, j, fn);
      for (int q = 0; q < 2; ++q)
        tau = std::max(tau, lobe(fn[q].d(), K) - d.direct_facets[2 * s.field.index(i, j) + q].g);
    }
  ASSERT_GT(tau, 0.05);
  ASSERT_LT(tau, 0.9);
  std::vector<double> total(r.direct.size());
  for (std::size_t i = 0; i < total.size(); ++i) total[i] = r.direct[i].g;
  double dev = 0, mean_dev = 0;
  for (int b = 0; b < B; ++b) {
    double m = 0;
    for (std::size_t i = 0; i < total.size(); ++i) {
      total[i] += r.indirect_b[b][i].g;
      m = std::max(m, double(r.indirect_b[b][i].g));
    }
    EXPECT_LE(m, std::pow(tau, b + 1) * 1.001 + 1e-6) << "bounce " << b + 1;  // (the exits start <= 1)
  }
  for (double t : total) {
    dev = std::max(dev, std::fabs(1 - t));
    mean_dev += (t - 1) / double(total.size());
  }
  std::printf("white furnace K %d, %d bounces: tau %.3f, max |1 - total| %.2e, mean(total - 1) %.2e\n", K, B,
              tau, dev, mean_dev);
  EXPECT_LT(dev, std::pow(tau, B + 1) / (1 - tau) + 1e-5);
  EXPECT_LT(std::fabs(mean_dev), 1e-5);
}

TEST(P2Bake, FlatGroundHasNoIndirectLight) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::flat;
  spec.width = spec.height = 32;
  const Scene s = make_scene(make_procedural(spec, 1.0, Wrap::clamp), {1, 1, 1}, 0.5f, 2, 1);
  const P2Result r = compute_p2(s, params(16, 2), RunControl{});
  for (const Rgb& v : r.indirect) ASSERT_EQ(v.g, 0.0f);
  for (const Rgb& v : r.direct) ASSERT_NEAR(v.g, 1.0f, 1e-5);
}

// An emitting ramp (plane rising at angle a from a crease at x0, emission 1, floor 0, black sky,
// albedo 0), seen from the floor with an upward normal: along azimuth phi (towards +x) the ramp points'
// elevations increase with the distance, so the terrain fills elevations from 0 to that of the point
// where the line leaves the field, e(phi) = atan((x + rho cos phi - x0) tan a / rho) with rho the
// distance to the border; the wedge integral is (1/K) sum_k sin^2 e(phi_k).
TEST(P2Bake, EmittingRampClosedForm) {
  const int W = 96, Hgt = 128, x0 = 40;
  const double tan_a = std::tan(40 * kPi / 180);
  HeightField f;
  f.width = W;
  f.height = Hgt;
  f.z.resize(f.texel_count());
  for (int j = 0; j < Hgt; ++j)
    for (int i = 0; i < W; ++i) f.z[f.index(i, j)] = float(std::max(0, i - x0) * tan_a);
  Scene s = make_scene(f, {0, 0, 0}, 0, 0, 1);
  s.surface.emission.assign(f.texel_count(), Rgb{});
  for (int j = 0; j < Hgt; ++j)
    for (int i = x0 + 1; i < W; ++i) s.surface.emission[f.index(i, j)] = {1, 1, 1};
  const int y = Hgt / 2;
  for (int K : {8, 32}) {
    const P2Result r = compute_p2(s, params(K, 1), RunControl{});
    for (int x : {x0 - 24, x0 - 12}) {
      double expect = 0;
      for (int k = 0; k < K; ++k) {
        const double phi = 2 * kPi * k / K, c = std::cos(phi), sn = std::sin(phi);
        if (c <= 1e-12) continue;
        double rho = (W - 1 - x) / c;
        if (std::fabs(sn) > 1e-12) rho = std::min(rho, (sn > 0 ? Hgt - 1 - y : y) / std::fabs(sn));
        const double rise = (x + rho * c - x0) * tan_a;
        if (rise <= 0) continue;
        const double e = std::atan(rise / rho);
        expect += std::sin(e) * std::sin(e) / K;
      }
      const double got = r.indirect[f.index(x, y)].g;
      // The crease segment (emission 0 -> 1 over one texel) accounts for the tolerance.
      EXPECT_NEAR(got, expect, 1e-3 + 0.005 * expect) << "K " << K << " x " << x;
      EXPECT_GT(got, 0.05);
    }
  }
}

// V-trench along y with walls at angle a, repeat mode (ridges on the walls' planes): from the floor,
// terrain fills elevations up to atan(tan a |cos phi|). With emission 1 everywhere and a black sky the
// floor gets (1/K) sum_k sin^2(atan(tan a |cos phi_k|)) -> 1 - cos a as K -> infinity.
TEST(P2Bake, EmittingVTrenchFloor) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::trench;
  spec.width = 65;
  spec.height = 64;
  spec.angle_deg = 30;
  const Scene s = make_scene(make_procedural(spec, 1.0, Wrap::repeat), {0, 0, 0}, 0, 1, 1);
  const double a = 30 * kPi / 180;
  for (int K : {4, 16, 64}) {
    const P2Result r = compute_p2(s, params(K, 1), RunControl{});
    double expect = 0;
    for (int k = 0; k < K; ++k) {
      const double e = std::atan(std::tan(a) * std::fabs(std::cos(2 * kPi * k / K)));
      expect += std::sin(e) * std::sin(e) / K;
    }
    const double got = r.indirect[s.field.index(32, 20)].g;
    // K = 4: axis samples are texels: exact. Oblique lines pass beside the apex and blend two samples on
    // the walls (see sweep_lines.hpp).
    EXPECT_NEAR(got, expect, K == 4 ? 1e-5 : 0.02) << "K " << K;
    if (K == 64) {
      EXPECT_NEAR(got, 1 - std::cos(a), 0.02);
    }
  }
}

// Reflected light between the walls of V-trenches, bounces 1..3, against an independent 2D radiosity
// integral. Repeat mode tiles the trench along x into a sawtooth (walls at angle a, a one-texel flat top
// between periods); the field does not vary along y, so the light does not either and the 3D irradiance
// from the extruded profile is the 2D form: a profile piece seen under the in-plane angles alpha_0..alpha_1
// from the normal contributes L (sin alpha_1 - sin alpha_0) / 2 to E / pi. A wall point sees the sky and
// exactly the opposite wall (the flat tops face away from it, the neighbouring trenches hide behind the
// ridges), so with a uniform sky 1 and albedo rho:
//   direct(p) = (1 - sin alpha_R) / 2,   alpha_R: the opposite ridge top (the sky reaches up to alpha = 90),
//   E_b(p)/pi = sum over the opposite wall's elements of rho E_{b-1}/pi (midpoint) (sin a1 - sin a0) / 2,
// with E_0 = direct, evaluated on 2048 elements per wall (mirror symmetry gives the opposite wall's
// values). This checks the bounce iteration itself (exit radiance rho * indirect_{b-1} at the senders,
// their weights, normalisation): a sender or weighting error of a few percent in bounce 2 or 3 fails it.
TEST(P2Bake, VTrenchBouncesMatch2DRadiosity) {
  const double a = 45 * kPi / 180, ta = std::tan(a), rho = 0.8;
  const int W = 65, cx = 32, B = 3;
  ProceduralSpec spec;
  spec.kind = ProceduralKind::trench;
  spec.width = W;
  spec.height = 64;
  spec.angle_deg = 45;
  const Scene s = make_scene(make_procedural(spec, 1.0, Wrap::repeat), {1, 1, 1}, float(rho), 0, B);

  // Truth on the left wall, x in [0, cx] (z = ta (cx - x), normal (sin a, cos a) in the xz-plane); the
  // right wall is its mirror image about x = cx.
  const int M = 2048;
  const double H = ta * cx;
  auto sin_from_normal = [&](double px, double pz, double qx, double qz) {  // n x (q - p) / |q - p|
    const double dx = qx - px, dz = qz - pz, d = std::hypot(dx, dz);
    return (std::sin(a) * dz - std::cos(a) * dx) / d;
  };
  // E_{b}/pi at left-wall point x from the right wall's elements carrying L(x') (x' on the left wall).
  auto gather = [&](double x, const std::vector<double>& L) {
    const double pz = ta * (cx - x);
    double e = 0;
    for (int m = 0; m < M; ++m) {  // right-wall element m: x from cx + m dx to cx + (m + 1) dx
      const double x0 = cx + double(m) * cx / M, x1 = cx + double(m + 1) * cx / M;
      const double s0 = sin_from_normal(x, pz, x0, ta * (x0 - cx));
      const double s1 = sin_from_normal(x, pz, x1, ta * (x1 - cx));
      e += L[M - 1 - m] * std::fabs(s1 - s0) / 2;  // mirror: right element m is left element M - 1 - m
    }
    return e;
  };
  auto direct_at = [&](double x) { return (1 - sin_from_normal(x, ta * (cx - x), 2 * cx, H)) / 2; };
  std::vector<double> L(M);  // exit radiance at the left wall's element midpoints
  for (int m = 0; m < M; ++m) L[m] = rho * direct_at((m + 0.5) * cx / M);
  const std::vector<int> probe = {6, 12, 18, 24, 28};
  std::vector<std::vector<double>> truth(B);
  for (int b = 0; b < B; ++b) {
    for (int x : probe) truth[b].push_back(gather(x, L));
    std::vector<double> next(M);
    for (int m = 0; m < M; ++m) next[m] = rho * gather((m + 0.5) * cx / M, L);
    L = std::move(next);
  }

  // The trench is infinite along y; the sweep sees wrap_periods * 64 texels of it along a line, so the
  // opposite ridge is missed only within 6 degrees of the y axis, where its elevation is below 0.6 deg.
  P2Params p = params(64, B);
  p.wrap_periods = 8;
  const P2Result r = compute_p2(s, p, RunControl{});
  std::vector<double> worst(B, 0.0);
  for (std::size_t q = 0; q < probe.size(); ++q) {
    const int x = probe[q];
    for (int side = 0; side < 2; ++side) {
      const int i = side == 0 ? x : 2 * cx - x;
      const std::size_t t = s.field.index(i, 32);
      EXPECT_NEAR(r.direct[t].g, direct_at(x), 0.005) << "x " << i;
      for (int b = 0; b < B; ++b) {
        const double got = r.indirect_b[b][t].g;
        worst[b] = std::max(worst[b], std::fabs(got / truth[b][q] - 1));
        // K = 64 azimuths and the crease/ridge texels' averaged normals: about 1 %.
        EXPECT_NEAR(got, truth[b][q], 0.02 * truth[b][q]) << "x " << i << " bounce " << b + 1;
      }
    }
  }
  std::printf("V-trench, max relative error over %zu wall texels: bounce 1 %.4f, 2 %.4f, 3 %.4f\n",
              2 * probe.size(), worst[0], worst[1], worst[2]);
}

// An emission map (P2 Figure 12): a glowing raised strip (height 3) on flat ground and a wall (height 12,
// full length along y) between it and the receivers on the far side. Exact intervisibility: those
// receivers get exactly nothing (black sky, albedo 0, wall not emitting), while the ground between the
// strip and the wall sees the strip's top and edge.
// Per bounce against the Embree reference on a field rough at the texel scale (the white furnace of
// tests/accuracy/p2_furnace.json: its finest octave is per-texel noise). The reference shades every hit with
// its facet's normal; with facet senders P2 does too, and each bounce's field mean agrees within a few %.
// Texel senders (the smoothed normal, as published) miss by 10-20 %: the facets a receiver sees lean
// towards it, so they see less sky and more of the terrain's light than their texels' normals say.
TEST(P2Bake, BouncesOnARoughFieldMatchTheReference) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = spec.height = 64;
  spec.seed = 3;
  spec.amplitude = 16;
  spec.feature_size = 32;
  const int B = 4;
  const Scene s = make_scene(make_procedural(spec, 1.0, Wrap::repeat), {1, 1, 1}, 1, 0, B);
  ReferenceOptions o;
  o.samples = 128;
  for (int b = 1; b <= B; ++b) o.layers.push_back("indirect_b" + std::to_string(b));
  const LayerSet ref = bake_reference(s, o, RunControl{});
  auto mean_of = [](const std::vector<Rgb>& v) {
    double m = 0;
    for (const Rgb& x : v) m += x.g;
    return m / double(v.size());
  };
  P2Params p = params(32, B);
  const P2Result facets = compute_p2(s, p, RunControl{});
  p.facet_senders = false;
  const P2Result texels = compute_p2(s, p, RunControl{});
  for (int b = 1; b <= B; ++b) {
    const Layer* l = ref.find("indirect_b" + std::to_string(b));
    ASSERT_NE(l, nullptr);
    double mr = 0;
    for (std::size_t i = 0; i < s.field.texel_count(); ++i) mr += l->data[3 * i + 1];
    mr /= double(s.field.texel_count());
    const double ef = mean_of(facets.indirect_b[b - 1]) / mr - 1,
                 et = mean_of(texels.indirect_b[b - 1]) / mr - 1;
    std::printf("bounce %d: reference mean %.4f, facet senders %+.1f %%, texel senders %+.1f %%\n", b, mr,
                100 * ef, 100 * et);
    EXPECT_LT(std::fabs(ef), b < 4 ? 0.03 : 0.07) << "bounce " << b;
    if (b == 1 || b >= 3) {
      EXPECT_GT(std::fabs(et), 0.08) << "bounce " << b;  // the test tells them apart
    }
  }
}

// Ground rough at the texel scale (white noise of 1.8 texels: 60-70 degrees between neighbours), against
// the Embree reference: under a uniform sky, and lit by an emission map that rises with the heights. A
// facet's light differs at its three corners (its pits see far less sky than its crests), and the crease
// below a texel's first crossing is the facet at the texel itself: taking each facet's light at one vertex
// puts the first bounce 18 % high under the sky and 10 % high under the emission.
TEST(P2Bake, WhiteNoiseGroundMatchesTheReference) {
  const HeightField f = white_noise_field(40);
  float lo = f.z[0], hi = f.z[0];
  for (float z : f.z) lo = std::min(lo, z), hi = std::max(hi, z);
  for (int lit = 0; lit < 2; ++lit) {
    Scene s = make_scene(f, lit == 0 ? Rgb{1, 1, 1} : Rgb{0, 0, 0}, 0.5f, lit == 0 ? 0 : 1, 1);
    if (lit == 1)
      for (std::size_t t = 0; t < f.texel_count(); ++t) {
        const float e = (f.z[t] - lo) / (hi - lo);
        s.surface.emission[t] = {e, e, e};
      }
    ReferenceOptions o;
    o.samples = 256;
    o.layers = {"indirect_b1"};
    const LayerSet ref = bake_reference(s, o, RunControl{});
    const Layer* l = ref.find("indirect_b1");
    ASSERT_NE(l, nullptr);
    const P2Result r = compute_p2(s, params(64, 1), RunControl{});
    double mr = 0, mp = 0;
    int n = 0;
    for (int j = 4; j < f.height - 4; ++j)  // the border ring reads dark in the reference (reference.md)
      for (int i = 4; i < f.width - 4; ++i, ++n) {
        const std::size_t t = f.index(i, j);
        mr += l->data[3 * t + 1], mp += r.indirect[t].g;
      }
    const double bias = mp / mr - 1;
    std::printf("white noise, %s: reference mean %.4f, P2 %+.1f %%\n", lit == 0 ? "uniform sky" : "emission",
                mr / n, 100 * bias);
    EXPECT_LT(std::fabs(bias), 0.04);
  }
}

// Brute force for the exact near field: E/pi of one bounce at texel (i, j), marched from the texel centre
// over every column, row and diagonal crossing of the triangulated surface (clamp field, to the border;
// beyond it the nearest texels, as the reference), each piece between crossings visible over the elevations
// above everything nearer, weighted over each of the K wedges at the texel normal.
// point_L(ci, cj, lower, x, y): the radiance of quad (ci, cj)'s lower (fx + fy <= 1) or upper triangle at
// the point (x, y) of it. The crease below the first piece radiates the first triangle's light at the texel;
// a piece radiates the light at the middle of its visible part (docs/methods/p2.md), or, with `split` > 1,
// each of `split` equal parts of the piece its own middle's light: the gather of light that varies
// linearly over each triangle, to the quadrature's accuracy.
template <class PointL>
double centre_gather(const Scene& s, int i, int j, int K, PointL&& point_L, int split = 1) {
  const HeightField& f = s.field;
  const Vec3 n = s.normals[f.index(i, j)].d();
  const double z0 = f.z[f.index(i, j)], ts = f.texel_size;
  double sum = 0;
  for (int k = 0; k < K; ++k) {
    const double phi = 2 * kPi * k / K, dx = std::cos(phi), dy = std::sin(phi);
    const WedgeWeights w = WedgeWeights::make(n, dx, dy, 2 * kPi / K);
    std::vector<double> cuts;
    auto family = [&](double origin, double d) {
      if (std::fabs(d) < 1e-12) return;
      for (double c = d > 0 ? std::floor(origin) + 1 : std::ceil(origin) - 1;; c += d > 0 ? 1 : -1) {
        const double t = (c - origin) / d, x = i + t * dx, y = j + t * dy;
        if (x < -1e-9 || y < -1e-9 || x > f.width - 1 + 1e-9 || y > f.height - 1 + 1e-9) break;
        cuts.push_back(t);
      }
    };
    family(i, dx), family(j, dy), family(i + j, dx + dy);
    std::sort(cuts.begin(), cuts.end());
    auto height = [&](double t) {
      return f.triangle_height(std::clamp(i + t * dx, 0.0, f.width - 1.0),
                               std::clamp(j + t * dy, 0.0, f.height - 1.0));
    };
    // The light at parameter u of the ray, on the triangle under the piece around um; a piece along an edge
    // (the axis and diagonal directions run along columns, rows or diagonals) sees the triangles on both
    // sides, half each.
    auto light = [&](double um, double u) {
      const double mx = i + um * dx, my = j + um * dy, x = i + u * dx, y = j + u * dy;
      auto side = [&](double px, double py) {
        const int ci = int(std::floor(px)), cj = int(std::floor(py));
        return double(point_L(ci, cj, (px - ci) + (py - cj) <= 1, x, y));
      };
      return 0.5 * (side(mx - 1e-6 * dy, my + 1e-6 * dx) + side(mx + 1e-6 * dy, my - 1e-6 * dx));
    };
    double prev = 0, m = -1e300;
    bool first = true;
    for (double t : cuts) {
      if (t - prev < 1e-9) continue;
      const double parts = first ? 1 : split;
      for (int q = 0; q < parts; ++q) {
        const double a = prev + (t - prev) * q / parts, b = prev + (t - prev) * (q + 1) / parts;
        const double dza = height(a) - z0, dzb = height(b) - z0, sa = a * ts, sb = b * ts;
        const double slope = dzb / sb;
        const double lo = first ? w.t_n : std::max(m, w.t_n);
        if (slope > lo) {
          double L;
          if (first) {
            L = light(0.5 * (a + b), 0.0);  // the crease: at the texel
          } else {
            const double den = (dzb - dza) - m * (sb - sa);
            const double t0 = std::clamp(den > 0 ? (m * sa - dza) / den : 0.0, 0.0, 1.0);
            L = light(0.5 * (a + b), a + 0.5 * (t0 + 1) * (b - a));
          }
          sum += L * (w.F(slope) - w.F(lo));
        }
        m = std::max(m, slope);
      }
      prev = t, first = false;
    }
  }
  return sum / kPi;
}

// The emission map's light at (x, y) on quad (ci, cj)'s lower or upper triangle: linear between its corners.
double emission_at(const Scene& s, int ci, int cj, bool lower, double x, double y) {
  const HeightField& f = s.field;
  auto em = [&](int a, int b) { return double(s.surface.emission[f.index(f.wrap_i(a), f.wrap_j(b))].g); };
  const double fx = std::clamp(x - ci, 0.0, 1.0), fy = std::clamp(y - cj, 0.0, 1.0);
  if (lower) return em(ci, cj) * (1 - fx - fy) + em(ci + 1, cj) * fx + em(ci, cj + 1) * fy;
  return em(ci + 1, cj) * (1 - fy) + em(ci + 1, cj + 1) * (fx + fy - 1) + em(ci, cj + 1) * (1 - fx);
}

// A near radius that covers the whole field turns P2 (and P1's horizons) into the exact gather from every
// texel centre over the triangulated surface: against the brute force above, rough field, emission map; and
// the rule's error against the gather of the emission as it varies over each triangle.
TEST(P2Bake, NearFieldCoveringTheFieldIsTheExactCentreGather) {
  HeightField f;
  f.width = f.height = 11;
  f.z.resize(f.texel_count());
  std::uint64_t x = 7;
  for (float& z : f.z) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    z = float((x >> 33) % 1000) / 250.0f;  // 0..4 texels of noise
  }
  Scene s = make_scene(f, {0, 0, 0}, 0, 1, 1);
  for (std::size_t t = 0; t < s.field.texel_count(); ++t) {
    const float e = 0.2f + 0.8f * float((t * 37) % 11) / 10.0f;
    s.surface.emission[t] = {e, e, e};
  }
  const int K = 16;
  P2Params p = params(K, 1);
  p.near_radius = 16;  // > the field's diagonal
  const P2Result r = compute_p2(s, p, RunControl{});
  auto em = [&](int ci, int cj, bool lower, double px, double py) {
    return emission_at(s, ci, cj, lower, px, py);
  };
  double worst = 0, mean = 0, linear_err = 0;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      const double bf = centre_gather(s, i, j, K, em), fine = centre_gather(s, i, j, K, em, 64);
      worst = std::max(worst, std::fabs(r.indirect[s.field.index(i, j)].g - bf));
      mean += fine / double(f.texel_count());
      linear_err += (r.indirect[s.field.index(i, j)].g - fine) / double(f.texel_count());
    }
  std::printf(
      "near field over the whole field: mean E/pi %.4f, max |P2 - brute force| %.2e, P2 against the "
      "linear emission's gather %+.2f %%\n",
      mean, worst, 100 * linear_err / mean);
  EXPECT_GT(mean, 0.1);
  EXPECT_LT(worst, 2e-5);
  EXPECT_LT(std::fabs(linear_err / mean), 0.02);
}

// Stepped terrain: P2 at its defaults against the brute-force gather from every texel
// centre over the triangulated surface (centre_gather above), with the same senders: every facet's exit
// radiance from P1's facet direct light (albedo 0.5, the built-in sky and sun at 35 degrees). Terraces with
// cliffs 2.5 texels high, one bounce. Lines that see the terrain only at their column samples take the
// straight segment between two columns for the surface, missing its bends at the rows and diagonals in
// between -- on a cliff, its top edge and its foot: field mean +2.3 %, rms 0.0028 (line_profile "columns",
// K = 32); with every crossing on the lines (the default) -0.1 %, rms 0.0013.
TEST(P2Bake, SteppedFieldMatchesTheExactCentreGather) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::terraces;
  spec.width = spec.height = 48;
  spec.seed = 5;
  spec.amplitude = 8;
  spec.step = 2.5;
  Scene s = make_scene(make_procedural(spec, 1.0, Wrap::clamp), {0, 0, 0}, 0.5f, 0, 1);
  EnvironmentLighting sky = make_sky_environment(SkySpec{});
  s.environment = std::move(sky.environment);
  s.lights = sky.lights;
  const int K = 32;
  const HeightField& f = s.field;
  // The senders exactly as compute_p2 lights them: P1's facet direct light times the albedo.
  P1Params p1 = p2_direct_params(params(K, 1), false);
  const P1Result d = compute_p1(s, p1, RunControl{});
  // Each triangle's light at a point: its three corners' (P1's light of that triangle at each corner,
  // field/triangulation.hpp kWeightCornerFacet), linear between them.
  auto facet_L = [&](int ci, int cj, bool lower, double px, double py) {
    const double fx = std::clamp(px - ci, 0.0, 1.0), fy = std::clamp(py - cj, 0.0, 1.0);
    const int q = lower ? 0 : 1;
    const double wt[2][3] = {{1 - fx - fy, fx, fy}, {1 - fy, fx + fy - 1, 1 - fx}};
    double L = 0;
    for (int c = 0; c < 3; ++c) {
      const int ti = std::clamp(ci + kWeightCorner[q][c][0], 0, f.width - 1),
                tj = std::clamp(cj + kWeightCorner[q][c][1], 0, f.height - 1);
      L += wt[q][c] * d.direct_facets[kCornerFacets * f.index(ti, tj) + kWeightCornerFacet[q][c]].g;
    }
    return 0.5 * L;
  };
  std::vector<double> bf(f.texel_count());
  double mean_bf = 0;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      bf[f.index(i, j)] = centre_gather(s, i, j, K, facet_L);
      mean_bf += bf[f.index(i, j)] / double(f.texel_count());
    }
  double bias[2], rms[2];
  for (int exact = 0; exact < 2; ++exact) {
    P2Params p = params(K, 1);
    p.exact_profile = exact == 1;
    const P2Result r = compute_p2(s, p, RunControl{});
    double d1 = 0, d2 = 0;
    for (std::size_t t = 0; t < f.texel_count(); ++t) {
      const double e = r.indirect[t].g - bf[t];
      d1 += e, d2 += e * e;
    }
    bias[exact] = d1 / double(f.texel_count()) / mean_bf;
    rms[exact] = std::sqrt(d2 / double(f.texel_count()));
  }
  std::printf("terraces, mean E/pi %.4f: columns bias %+.2f %% rms %.5f, exact bias %+.2f %% rms %.5f\n",
              mean_bf, 100 * bias[0], rms[0], 100 * bias[1], rms[1]);
  EXPECT_GT(mean_bf, 0.02);
  EXPECT_LT(std::fabs(bias[1]), 0.005);
  EXPECT_LT(rms[1], 0.7 * rms[0]);
  EXPECT_GT(bias[0], 0.015);  // the test tells the two apart
}

TEST(P2Bake, EmitterBehindAWallIsInvisible) {
  const int W = 80, Hgt = 64, xw = 50;
  HeightField f;
  f.width = W;
  f.height = Hgt;
  f.z.assign(f.texel_count(), 0.0f);
  Scene s = make_scene(f, {0, 0, 0}, 0, 0, 1);
  s.surface.emission.assign(f.texel_count(), Rgb{});
  for (int j = 0; j < Hgt; ++j) {
    s.field.z[f.index(xw, j)] = 12;
    for (int i = 10; i < 30; ++i) {
      s.field.z[f.index(i, j)] = 3;
      s.surface.emission[f.index(i, j)] = {2, 2, 2};
    }
  }
  s.normals = compute_normals(s.field);
  const P2Result r = compute_p2(s, params(32, 1), RunControl{});
  for (int j = 0; j < Hgt; ++j)
    for (int i = xw + 1; i < W; ++i) ASSERT_EQ(r.indirect[f.index(i, j)].g, 0.0f) << i << " " << j;
  for (int i = 32; i < xw - 2; ++i) EXPECT_GT(r.indirect[f.index(i, Hgt / 2)].g, 0.005f) << i;
}

// (Both line profiles, exact and columns; with and without the near field: the lagging tree's queries and
// the receivers' own pushes.)
TEST(P2Bake, TreeAndNaiveGiveIdenticalBits) {
  for (auto kind : {ProceduralKind::fractal, ProceduralKind::bricks, ProceduralKind::sines,
                    ProceduralKind::blocks, ProceduralKind::terraces})
    for (int variant = 0; variant < 3; ++variant)
      for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
        const Scene s = make_scene(procedural(kind, 40, wrap), {0.3f, 0.5f, 0.9f}, 0.6f, 0, 2);
        P2Params p = params(12, 2);
        p.exact_profile = variant != 2;
        if (variant == 1) p.near_radius = 0;
        const P2Result a = compute_p2(s, p, RunControl{});
        p.visibility = P2Visibility::naive;
        const P2Result b = compute_p2(s, p, RunControl{});
        for (std::size_t i = 0; i < a.indirect.size(); ++i) {
          ASSERT_EQ(a.indirect[i].r, b.indirect[i].r) << procedural_kind_name(kind) << " texel " << i;
          ASSERT_EQ(a.indirect[i].b, b.indirect[i].b) << procedural_kind_name(kind) << " texel " << i;
        }
        EXPECT_EQ(a.stats.run_starts, b.stats.run_starts);
        EXPECT_LT(a.stats.iterations, b.stats.iterations);
        EXPECT_LE(a.stats.iterations, 2 * a.stats.horizons_pushed + a.stats.pushed);  // P2: t <= 2m + n
      }
}

// Supersampling along the lines: tree == naive still, the furnace split stays within the sub-sample
// horizon change, and S = 1 is the default path.
TEST(P2Bake, SupersamplingAlongLines) {
  const Scene s = make_scene(procedural(ProceduralKind::fractal, 40, Wrap::clamp), {1, 1, 1}, 0, 1, 1);
  P2Params p = params(8, 1);
  p.supersampling = 3;
  const P2Result a = compute_p2(s, p, RunControl{});
  p.visibility = P2Visibility::naive;
  const P2Result b = compute_p2(s, p, RunControl{});
  for (std::size_t i = 0; i < a.indirect.size(); ++i) ASSERT_EQ(a.indirect[i].g, b.indirect[i].g);
  double mean = 0;
  for (std::size_t i = 0; i < a.indirect.size(); ++i)
    mean += (a.direct[i].g + a.indirect[i].g - lobe(s.normals[i].d(), 8)) / double(a.indirect.size());
  EXPECT_LT(std::fabs(mean), 2e-3);
  EXPECT_LT(max_abs_dev(s, a, 8), 0.1);
  p.supersampling = 1;
  p.visibility = P2Visibility::tree;
  EXPECT_LT(max_abs_dev(s, compute_p2(s, p, RunControl{}), 8), 1e-5);
}

// P1's horizons kept whole from stage 0 or recomputed per direction block in every bounce
// (p2_keeps_horizons): the same bits, for direction blocks of one and of two directions, clamp and repeat,
// facet and texel senders, with a sun (P1's direct reads its own sweep either way).
TEST(P2Bake, RecomputedHorizonsGiveTheKeptBits) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat})
    for (int K : {8, 12, 16})
      for (bool facets : {true, false}) {
        Scene s =
            make_scene(procedural(ProceduralKind::fractal, 37, wrap, 5), {0.4f, 0.6f, 0.9f}, 0.7f, 0, 2);
        DirectionalLight sun;
        sun.direction = normalize(Vec3{0.4, -0.3, 0.8});
        sun.irradiance = {2, 2, 1.5f};
        s.lights.push_back(sun);
        P2Params p = params(K, 2);
        p.facet_senders = facets;
        p.keep_horizons = 1;
        const P2Result kept = compute_p2(s, p, RunControl{});
        p.keep_horizons = 0;
        const P2Result again = compute_p2(s, p, RunControl{});
        ASSERT_EQ(kept.indirect_b.size(), 2u);
        for (std::size_t i = 0; i < kept.indirect.size(); ++i)
          for (int c = 0; c < 3; ++c) {
            auto at = [&](const Rgb& v) { return c == 0 ? v.r : c == 1 ? v.g : v.b; };
            ASSERT_EQ(at(kept.direct[i]), at(again.direct[i])) << "K " << K << " texel " << i;
            ASSERT_EQ(at(kept.indirect[i]), at(again.indirect[i])) << "K " << K << " texel " << i;
            ASSERT_EQ(at(kept.indirect_b[0][i]), at(again.indirect_b[0][i])) << "K " << K << " texel " << i;
          }
        EXPECT_EQ(kept.stats.iterations, again.stats.iterations);
        EXPECT_GT(kept.indirect[100].g, 0.0f);
      }
}

// The rule: kept while P1's horizons of every direction take at most 1 GiB, never without bounces.
TEST(P2Bake, HorizonsKeptOnlyWhileSmall) {
  auto shape = [](int n) {
    FieldShape f;
    f.width = f.height = n;
    return f;
  };
  EXPECT_TRUE(p2_keeps_horizons(shape(2048), params(64, 1), 0));  // 4 * 64 * 2048^2 = 1 GiB
  EXPECT_FALSE(p2_keeps_horizons(shape(2049), params(64, 1), 0));
  EXPECT_FALSE(p2_keeps_horizons(shape(64), params(64, 0), 3));
  EXPECT_TRUE(p2_keeps_horizons(shape(64), params(64, -1), 3));
  P2Params forced = params(64, 1);
  forced.keep_horizons = 0;
  EXPECT_FALSE(p2_keeps_horizons(shape(64), forced, 0));
  // Recomputing holds one block's horizons (8 of 64 directions) instead of all 64.
  forced.layers = {"indirect", "total", "direct"};
  P2Params kept = forced;
  kept.keep_horizons = 1;
  const double saved = p2_working_bytes(shape(1024), kept) - p2_working_bytes(shape(1024), forced);
  EXPECT_GT(saved, 4.0 * 56 * 1024 * 1024 * 0.9);
}

// p2's line worker leaves unread the receivers of a clamp field's lines that lie more than a texel (plus
// kReadMargin, 1e-6) off the field on the minor axis (indirect_sweep.cpp). That holds only while the
// driver's texel taps read no such receiver: every receiver slot holds its own minor coordinate (NaN where
// no receiver is), and every tap a texel reads must lie within a texel of the field. Square, thin (trimmed
// lines) and non-unit fields, directions of every octant.
TEST(P2Bake, TexelTapsReadOnlyReceiversNearTheField) {
  for (const auto& [w, h] : {std::pair{48, 48}, std::pair{97, 13}, std::pair{13, 97}, std::pair{40, 29}}) {
    ProceduralSpec ps;
    ps.kind = ProceduralKind::fractal;
    ps.width = w, ps.height = h;
    const HeightField f = make_procedural(ps, 0.7, Wrap::clamp);
    IndirectSweepSpec is;
    is.directions = 37;
    const SweepSpec spec = indirect_sweep_spec(is);
    for (int k = 0; k < is.directions; ++k) {
      const SweepDirection d = plan_direction(f, spec, k);
      const std::size_t stride = std::size_t(d.stride());
      std::vector<float> buffer(std::size_t(d.lines()) * stride, std::nanf(""));
      for (int l = d.line_begin; l < d.line_end; ++l)
        for (int u = 0; u < d.n_major; ++u) {
          const int slot = line_slot(d, l, u);
          if (slot >= 0 && std::size_t(slot) < stride)
            buffer[std::size_t(l - d.line_begin) * stride + std::size_t(slot)] =
                float(l + double(u) * d.slope);
        }
      int bad = 0;
      for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
          const TexelTaps t = texel_taps(d, buffer.data(), 1, i, j);
          for (const float* tap : {t.lo, t.w_hi > 0 ? t.hi : t.lo}) {
            const float v = tap[0];
            if (!(v > -1.0f - 1e-5f && v < float(d.n_minor) + 1e-5f) && bad++ < 3)
              ADD_FAILURE() << w << "x" << h << " k=" << k << " texel (" << i << ", " << j
                            << ") reads v=" << v;
          }
        }
      EXPECT_EQ(bad, 0) << w << "x" << h << " k=" << k;
    }
  }
}

TEST(P2Bake, SameBitsForAnyThreadCount) {
  const Scene s =
      make_scene(procedural(ProceduralKind::fractal, 48, Wrap::clamp), {1, 0.8f, 0.6f}, 0.7f, 0, 2);
  P2Result one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = compute_p2(s, params(8, 2), RunControl{});
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = compute_p2(s, params(8, 2), RunControl{});
  }
  for (std::size_t i = 0; i < one.indirect.size(); ++i) ASSERT_EQ(one.indirect[i].g, two.indirect[i].g);
}

TEST(P2Bake, LayersAndParameters) {
  const Scene s = make_scene(procedural(ProceduralKind::sines, 24, Wrap::clamp), {1, 1, 1}, 0.5f, 0, 2);
  const LayerSet def = bake_method("p2", s, {{"method", "p2"}, {"directions", 4}}, RunControl{});
  ASSERT_EQ(def.layers.size(), 3u);
  EXPECT_EQ(def.layers[0].name, "indirect");
  EXPECT_EQ(def.layers[1].name, "total");
  EXPECT_EQ(def.layers[2].name, "direct");
  const LayerSet b = bake_method(
      "p2", s, {{"method", "p2"}, {"directions", 4}, {"layers", {"indirect_b1", "indirect_b2", "indirect"}}},
      RunControl{});
  ASSERT_EQ(b.layers.size(), 3u);
  for (std::size_t i = 0; i < b.layers[2].data.size(); ++i)
    ASSERT_NEAR(b.layers[2].data[i], b.layers[0].data[i] + b.layers[1].data[i], 1e-6);
  EXPECT_THROW(bake_method("p2", s, {{"method", "p2"}, {"layers", {"indirect_b3"}}}, RunControl{}),
               InputError);
  EXPECT_THROW(bake_method("p2", s, {{"method", "p2"}, {"layers", {"ao"}}}, RunControl{}), InputError);
  EXPECT_THROW(bake_method("p2", s, {{"method", "p2"}, {"visibility", "fast"}}, RunControl{}), InputError);
  EXPECT_THROW(bake_method("p2", s, {{"method", "p2"}, {"senders", "vertices"}}, RunControl{}), InputError);
  EXPECT_THROW(bake_method("p2", s, {{"method", "p2"}, {"near_radius", 0.5}}, RunControl{}), InputError);
  EXPECT_EQ(read_method_config("p2", {{"method", "p2"}}, {}).get<P2Params>().near_radius, 4.0);
  EXPECT_TRUE(read_method_config("p2", {{"method", "p2"}}, {}).get<P2Params>().facet_senders);
  EXPECT_FALSE(
      read_method_config("p2", {{"method", "p2"}, {"senders", "texels"}}, {}).get<P2Params>().facet_senders);
  EXPECT_EQ(read_method_config("p2", {{"method", "p2"}, {"near_radius", 0}}, {}).get<P2Params>().near_radius,
            0.0);
  const LayerSet none =
      bake_method("p2", s, {{"method", "p2"}, {"directions", 4}, {"bounces", 0}}, RunControl{});
  for (float v : none.layers[0].data) ASSERT_EQ(v, 0.0f);
}

TEST(P2Bake, CancelStopsTheBake) {
  const Scene s = make_scene(procedural(ProceduralKind::fractal, 32, Wrap::clamp), {1, 1, 1}, 0.5f, 0, 1);
  std::atomic<bool> cancel{true};
  RunControl rc;
  rc.cancel = &cancel;
  EXPECT_THROW(compute_p2(s, params(8, 1), rc), Cancelled);
}

}  // namespace
}  // namespace hfbake
