// P1 lighting against closed forms (flat, slope, trench floor, pit center, cone apex, sky and sun on flat
// ground), the lighting tables against direct integration and against the analytic uniform-sky formula,
// the mapping error against marches from the texel centers, repeat mode against a 3 x 3 clamp tiling,
// the normal-bin error of P1 Figure 7, determinism and the bake entry.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdio>

#include "core/error.hpp"
#include "methods/p1/bake_p1.hpp"
#include "methods/p1/lighting_table.hpp"
#include "methods/p1/p1.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

constexpr double kDeg = kPi / 180;

Scene make_scene(HeightField f, Environment env = make_uniform_environment({1, 1, 1}),
                 std::vector<DirectionalLight> lights = {}) {
  Scene s;
  s.name = "test";
  s.normals = compute_normals(f);
  s.surface.albedo.assign(f.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
  s.field = std::move(f);
  s.environment = std::move(env);
  s.lights = std::move(lights);
  return s;
}

P1Params params(int K, bool horizon = false) {
  P1Params p;
  p.directions = K;
  p.horizon = horizon;
  p.bent_normal = true;
  return p;
}

HeightField shape(ProceduralKind kind, int size, double angle_deg = 30, double radius = 0, double depth = 0,
                  double aspect = 0) {
  ProceduralSpec s;
  s.kind = kind;
  s.width = s.height = size;
  s.angle_deg = angle_deg;
  s.radius = radius;
  s.depth = depth;
  s.aspect_deg = aspect;
  return make_procedural(s, 1.0, Wrap::clamp);
}

TEST(P1Analytic, FlatIsOpen) {
  const Scene s = make_scene(shape(ProceduralKind::flat, 33));
  const P1Result r = compute_p1(s, params(16), RunControl{});
  for (std::size_t i = 0; i < r.ao.size(); ++i) {
    ASSERT_NEAR(r.ao[i], 1.0, 1e-6);
    ASSERT_NEAR(r.vsky[i], 1.0, 1e-6);
    ASSERT_NEAR(r.bent_normal_at(i).z, 1.0, 1e-6);
  }
}

TEST(P1Analytic, SlopeGivesAoOneAndClosedFormVsky) {
  for (double aspect : {0.0, 60.0, 200.0}) {
    const double S = 30 * kDeg, A = aspect * kDeg;
    const int K = 32;
    const Scene s = make_scene(shape(ProceduralKind::slope, 41, 30, 0, 0, aspect));
    const P1Result r = compute_p1(s, params(K, true), RunControl{});
    // Along azimuth phi the plane rises by -tan S cos(phi - A) per unit distance.
    double vsky = 1;
    std::vector<double> sin_e(K);
    for (int k = 0; k < K; ++k) {
      const double e = std::atan(-std::tan(S) * std::cos(2 * kPi * k / K - A));
      sin_e[k] = std::sin(e);
      vsky -= std::max(sin_e[k], 0.0) / K;
    }
    double max_ao = 0, max_h = 0;
    for (int j = 0; j < 41; ++j)
      for (int i = 0; i < 41; ++i) {
        const std::size_t t = s.field.index(i, j);
        max_ao = std::max(max_ao, std::fabs(r.ao[t] - 1.0));  // every texel, borders included
        if (i < 2 || j < 2 || i > 38 || j > 38) continue;
        ASSERT_NEAR(r.vsky[t], vsky, 1e-5) << i << "," << j;
        for (int k = 0; k < K; ++k) max_h = std::max(max_h, std::fabs(r.horizon[t * K + k] - sin_e[k]));
      }
    std::printf("[slope] aspect %5.1f: max|ao - 1| = %.3g, max|sin h - exact| = %.3g, vsky = %.6f\n", aspect,
                max_ao, max_h, vsky);
    EXPECT_LE(max_ao, 2e-6);
    EXPECT_LE(max_h, 2e-6);
  }
}

TEST(P1Analytic, TrenchFloor) {
  const double A = 35 * kDeg;
  for (int K : {16, 64}) {
    const Scene s = make_scene(shape(ProceduralKind::trench, 65, 35));
    const P1Result r = compute_p1(s, params(K, true), RunControl{});
    // Floor (normal up): horizon atan(tan A |cos phi|) in every direction; ao = mean cos^2 e -> cos A.
    double ao = 0;
    for (int k = 0; k < K; ++k) {
      const double c = std::cos(2 * kPi * k / K);
      ao += 1 / (1 + std::tan(A) * std::tan(A) * c * c) / K;
    }
    double max_ao = 0, max_h = 0;
    for (int j = 16; j <= 48; ++j) {
      const std::size_t t = s.field.index(32, j);
      max_ao = std::max(max_ao, std::fabs(r.ao[t] - ao));
      for (int k = 0; k < K; ++k) {
        const double e = std::atan(std::tan(A) * std::fabs(std::cos(2 * kPi * k / K)));
        max_h = std::max(max_h, std::fabs(std::asin(r.horizon[t * K + k]) - e));
      }
    }
    std::printf("[trench] K=%d floor ao exact %.6f (cos A %.6f): max|err| %.3g; max horizon err %.3g deg\n",
                K, ao, std::cos(A), max_ao, max_h / kDeg);
    // The floor is a crease: a far caster on the wall behind the texel is transferred from a tap on the
    // other wall (it lies above the texel's plane there, its caster below the texel's ray): the known
    // residual of the far-field transfer (about 0.5 % of ao here).
    EXPECT_LE(max_ao, 5e-3);
  }
}

// The two facets at the trench floor (P1Params::facet_direct): each is a wall's plane, tilted by A away
// from its own wall. Under a uniform sky the trench's cross-section gives the closed form: the opening
// spans the in-plane angles (-(90 - A), 90 - A) from the zenith, i.e. (-(90 - 2A), 90) from the facet's
// normal, so E/pi = (1 + cos 2A) / 2 = cos^2 A (the smoothed, upward normal gets cos A). The same horizons
// in P1's K-direction sum (Eq. 5 with the facet's normal) give the finite-K value; and a sun across the
// trench lights each facet with its own cosine.
TEST(P1Analytic, TrenchFloorFacets) {
  const double A = 35 * kDeg;
  const int K = 64;
  P1Params p = params(K);
  p.facet_direct = true;
  const Scene s = make_scene(shape(ProceduralKind::trench, 65, 35));
  const P1Result r = compute_p1(s, p, RunControl{});
  ASSERT_EQ(r.direct_facets.size(), kCornerFacets * s.field.texel_count());
  double sum[2] = {0, 0};
  for (int q = 0; q < 2; ++q) {
    const double nx = q == 0 ? -std::sin(A) : std::sin(A), nz = std::cos(A);
    for (int k = 0; k < K; ++k) {
      const double c = std::cos(2 * kPi * k / K);
      const double e = std::atan(std::tan(A) * std::fabs(c)), np = nx * c;
      const double th = std::min(kPi / 2 - e, kPi / 2 + std::atan(np / nz));
      sum[q] += (nz * std::sin(th) * std::sin(th) + np * (th - std::sin(th) * std::cos(th))) / K;
    }
  }
  const double limit = std::cos(A) * std::cos(A);
  std::printf("[trench facets] K=%d Eq.5 sums %.6f %.6f, limit cos^2 A %.6f\n", K, sum[0], sum[1], limit);
  EXPECT_NEAR(sum[0], limit, 2e-3);  // the quadrature itself
  double worst = 0;
  // The floor texel's corner facets (field/triangulation.hpp): 0, 3 and 4 lie on the +x side of the
  // crease, 1, 2 and 5 on the -x side.
  const int side[kCornerFacets] = {0, 1, 1, 0, 0, 1};
  for (int j = 16; j <= 48; ++j) {
    const std::size_t t = s.field.index(32, j);
    for (int c = 0; c < kCornerFacets; ++c)
      worst = std::max(worst, std::fabs(r.direct_facets[kCornerFacets * t + c].g - sum[side[c]]));
    // On the walls every facet is the wall's plane: the texel's own direct light.
    const std::size_t w = s.field.index(40, j);
    for (int c = 0; c < kCornerFacets; ++c)
      EXPECT_NEAR(r.direct_facets[kCornerFacets * w + c].g, r.direct_at(w).g, 1e-4);
  }
  EXPECT_LE(worst, 5e-3);  // the floor's crease residual of TrenchFloor
  EXPECT_GT(r.direct_at(s.field.index(32, 32)).g - limit, 0.05);  // the smoothed normal is far off

  DirectionalLight sun;
  sun.direction = direction_from_elevation_azimuth(50, 0);  // across the trench, above its walls
  sun.irradiance = {3, 3, 3};
  const Scene lit =
      make_scene(shape(ProceduralKind::trench, 65, 35), make_uniform_environment({0, 0, 0}), {sun});
  const P1Result rl = compute_p1(lit, p, RunControl{});
  const std::size_t t = lit.field.index(32, 32);
  for (int c = 0; c < kCornerFacets; ++c)  // the +x side faces away from it, the -x side faces it
    EXPECT_NEAR(rl.direct_facets[kCornerFacets * t + c].r,
                3 * std::sin((side[c] == 0 ? 15 : 85) * kDeg) / kPi, 1e-5);
}

TEST(P1Analytic, PitCenter) {
  const double R = 20, D = 20;
  const Scene s = make_scene(shape(ProceduralKind::pit, 81, 30, R, D));
  const P1Result r = compute_p1(s, params(64, true), RunControl{});
  const std::size_t c = s.field.index(40, 40);
  // The wall is a bilinear ramp between the last texel inside (r < R) and the first outside: the rim top
  // lies between R and R + sqrt(2) from the center.
  const double lo = R * R / (R * R + D * D), hi = (R + 1.5) * (R + 1.5) / ((R + 1.5) * (R + 1.5) + D * D);
  std::printf("[pit] center ao %.5f, bounds [%.5f, %.5f], ideal cylinder %.5f\n", r.ao[c], lo, hi, lo);
  EXPECT_GE(r.ao[c], lo - 1e-4);
  EXPECT_LE(r.ao[c], hi);
  for (int k = 0; k < 64; ++k) {
    const double e = std::asin(r.horizon[c * 64 + k]);
    EXPECT_GE(e, std::atan(D / (R + 1.5)) - 1e-4);
    EXPECT_LE(e, std::atan(D / (R - 1)) + 1e-4);
  }
}

TEST(P1Analytic, PitRimSeesTheOpenSky) {
  // A cylindrical pit (radius 16, depth 10) in a flat plateau: a plateau texel at the rim has nothing above
  // its horizontal (the only depression is the pit), so vsky = 1 exactly, whatever its normal (tilted by
  // the drop). Its ao against the exact triangle-surface march from the texel center (brute force). The
  // earlier tangent-plane lift gave vsky 0.888 at (48, 32) (the normal's gradient straddles the drop).
  const Scene s = make_scene(shape(ProceduralKind::pit, 65, 30, 16, 10));
  const int K = 64;
  const P1Result r = compute_p1(s, params(K, true), RunControl{});
  double max_vsky = 0, max_ao = 0;
  int rim = 0;
  for (int j = 0; j < 65; ++j)
    for (int i = 0; i < 65; ++i) {
      const double d = std::hypot(i - 32.0, j - 32.0);
      const std::size_t t = s.field.index(i, j);
      if (d < 16 || d > 18 || s.field.z[t] != 0.0f) continue;  // plateau texels on the rim ring
      ++rim;
      max_vsky = std::max(max_vsky, std::fabs(r.vsky[t] - 1.0));
      const Vec3f n = s.normals[t];
      double ao = 0;
      for (int k = 0; k < K; ++k) {
        const double phi = 2 * kPi * k / K, dx = std::cos(phi), dy = std::sin(phi);
        const double e = truth::march_tri(s.field, i, j, dx, dy, 7);
        const double np = n.x * dx + n.y * dy, nz = n.z;
        const double th = std::min(kPi / 2 - e, kPi / 2 + std::atan(np / nz));
        ao += (nz * std::sin(th) * std::sin(th) + np * (th - std::sin(th) * std::cos(th))) / K;
      }
      max_ao = std::max(max_ao, std::fabs(ao - r.ao[t]));
    }
  std::printf(
      "[pit rim] %d plateau rim texels: max |vsky - 1| %.2e, max |ao - exact march| %.2e; (48,32) vsky "
      "%.4f\n",
      rim, max_vsky, max_ao, r.vsky[s.field.index(48, 32)]);
  EXPECT_GT(rim, 50);
  EXPECT_LE(max_vsky, 1e-3);
  EXPECT_LE(max_ao, 0.02);
}

TEST(P1Analytic, ConeApexHasNegativeHorizonsAndFullAo) {
  const double A = 30 * kDeg;
  for (int K : {8, 64}) {
    const Scene s = make_scene(shape(ProceduralKind::cone, 65, 30));
    const P1Result r = compute_p1(s, params(K, true), RunControl{});
    const std::size_t c = s.field.index(32, 32);
    EXPECT_NEAR(r.ao[c], 1.0, 1e-6);
    EXPECT_NEAR(r.vsky[c], 1.0, 1e-6);
    double max_err = 0;
    for (int k = 0; k < K; ++k) {
      const double e = std::asin(r.horizon[c * K + k]);
      EXPECT_LT(e, 0) << k;
      max_err = std::max(max_err, std::fabs(e + A));
    }
    std::printf("[cone] K=%d apex: ao %.7f, max |horizon - (-slope)| = %.3g deg\n", K, r.ao[c],
                max_err / kDeg);
    if (K == 8) {
      EXPECT_LE(max_err, 1e-5);  // axes and diagonals: the apex is a sample of every line
    }
  }
}

TEST(P1Lighting, DiskFraction) {
  EXPECT_DOUBLE_EQ(disk_fraction_above(0.3, 0.3, 0.01), 0.5);
  EXPECT_DOUBLE_EQ(disk_fraction_above(0.31, 0.3, 0.01), 1.0);
  EXPECT_DOUBLE_EQ(disk_fraction_above(0.29, 0.3, 0.01), 0.0);
  // Chord at half the radius below the center: segment area of a unit disk above y = -0.5.
  const double x = 0.5, seg = std::acos(x) - x * std::sqrt(1 - x * x);
  EXPECT_NEAR(disk_fraction_above(0.3, 0.3 - 0.005, 0.01), 1 - seg / kPi, 1e-12);
  EXPECT_EQ(disk_fraction_above(0.1, 0.0, 0.0), 1.0);
  EXPECT_EQ(disk_fraction_above(-0.1, 0.0, 0.0), 0.0);
}

TEST(P1Lighting, SunOnFlatAndInATrench) {
  DirectionalLight sun;
  sun.direction = direction_from_elevation_azimuth(30, 45);
  sun.angular_diameter = 0.53 * kDeg;
  sun.irradiance = {3, 2, 1};
  const Environment black = make_uniform_environment({0, 0, 0});
  {
    const Scene s = make_scene(shape(ProceduralKind::flat, 17), black, {sun});
    const P1Result r = compute_p1(s, params(16), RunControl{});
    const std::size_t c = s.field.index(8, 8);
    EXPECT_NEAR(r.direct_at(c).r, 3 * 0.5 / kPi, 1e-6);
    EXPECT_NEAR(r.direct_at(c).b, 1 * 0.5 / kPi, 1e-6);
  }
  // Trench floor, walls at 35 degrees: a sun across the trench (azimuth 0) at 20 degrees is hidden, at 50
  // degrees it shines; at 35 degrees exactly half the disk shows.
  for (double el : {20.0, 35.0, 50.0}) {
    DirectionalLight l = sun;
    l.direction = direction_from_elevation_azimuth(el, 0);
    const Scene s = make_scene(shape(ProceduralKind::trench, 33, 35), black, {l});
    const P1Result r = compute_p1(s, params(16), RunControl{});
    const double v = r.direct_at(s.field.index(16, 16)).r;
    const double full = 3 * std::sin(el * kDeg) / kPi;
    if (el < 35) {
      EXPECT_EQ(v, 0.0);
    } else if (el > 35) {
      EXPECT_NEAR(v, full, 1e-6);
    } else {
      EXPECT_NEAR(v, full / 2, full * 0.02);
    }
  }
}

TEST(P1Lighting, TablesMatchDirectIntegration) {
  const EnvironmentLighting sky = make_sky_environment(SkySpec{});
  const int K = 16;
  const p1::LightingTables t = p1::build_lighting_tables(sky.environment, K, 15, 256);
  double worst = 0;
  for (int k = 0; k < K; k += 3)
    for (int i = 0; i < 15; ++i)
      for (int j = 0; j <= 256; j += 7) {
        const double tn = -kPi / 2 + kPi * i / 14, th = kPi * j / 256;
        const Rgb a = t.lookup(k, float(tn), float(th));
        const Rgb b = p1::lighting_table_exact(sky.environment, K, k, tn, th);
        worst = std::max(worst, double(std::fabs(a.g - b.g)));
      }
  EXPECT_LE(worst, 1e-6);  // at the table's own nodes the lookup is the exact integral
}

TEST(P1Lighting, SkyOnFlatGroundIsTheHemisphereIntegral) {
  // L(e) = H + (Z - H) sin e above the horizon: E/pi on an open flat receiver = H + 2 (Z - H) / 3.
  SkySpec spec;
  spec.sun_irradiance = {0, 0, 0};
  const EnvironmentLighting sky = make_sky_environment(spec);
  const Scene s = make_scene(shape(ProceduralKind::flat, 17), sky.environment, {});
  const P1Result r = compute_p1(s, params(16), RunControl{});
  const Rgb got = r.direct_at(s.field.index(8, 8));
  const double expect_g = spec.horizon.g + 2 * (spec.zenith.g - spec.horizon.g) / 3;
  std::printf("[sky/flat] direct.g %.6f expected %.6f\n", got.g, expect_g);
  EXPECT_NEAR(got.g, expect_g, 1e-3 * expect_g);
}

TEST(P1Lighting, TablesAgreeWithUniformSkyFormula) {
  // A constant lat-long environment goes through the tables; a uniform one through the uniform-sky formula:
  // the same light (exactly for the factorised tables, within the bin error for P1's binned tables).
  const int K = 32;
  const Environment flat_latlong = make_latlong_environment(32, 16, std::vector<Rgb>(32 * 16, Rgb{1, 1, 1}));
  const HeightField f = truth::procedural(ProceduralKind::fractal, 64, 64, Wrap::clamp);
  const P1Result b = compute_p1(make_scene(f), params(K), RunControl{});
  for (int bins : {0, 15}) {
    P1Params p = params(K);
    p.normal_bins = bins;
    const P1Result a = compute_p1(make_scene(f, flat_latlong), p, RunControl{});
    double max_d = 0, mean_d = 0;
    for (std::size_t i = 0; i < (a.direct.size() / 3); ++i) {
      const double d = std::fabs(a.direct_at(i).g - b.direct_at(i).g);
      max_d = std::max(max_d, d);
      mean_d += d / (a.direct.size() / 3);
    }
    std::printf("[tables vs uniform sky] normal_bins %2d: mean |diff| %.3g, max %.3g\n", bins, mean_d, max_d);
    EXPECT_LE(mean_d, bins == 0 ? 1e-6 : 5e-3);
    EXPECT_LE(max_d, bins == 0 ? 1e-5 : 2e-2);
  }
}

TEST(P1Measure, NormalBinError) {
  // P1 Figure 7: error of normal_bins 7 and 15 against 255 (P1: 0.16 % / 1.66 % avg / max for 8 bins,
  // 0.03 % / 0.42 % for 16), relative to the mean direct light; and every binned table against the exact
  // factorised evaluation (normal_bins 0).
  SkySpec spec;
  spec.sun_irradiance = {0, 0, 0};
  const EnvironmentLighting sky = make_sky_environment(spec);
  const Scene s =
      make_scene(truth::procedural(ProceduralKind::fractal, 96, 96, Wrap::clamp), sky.environment);
  auto run = [&](int bins) {
    P1Params p = params(32);
    p.normal_bins = bins;
    return compute_p1(s, p, RunControl{});
  };
  const P1Result ref = run(255), exact = run(0);
  double mean_ref = 0;
  for (std::size_t i = 0; i < ref.direct.size() / 3; ++i)
    mean_ref += ref.direct_at(i).luminance() / double(ref.direct.size() / 3);
  auto error = [&](const P1Result& r, const P1Result& against, double& avg, double& mx) {
    avg = 0, mx = 0;
    for (std::size_t i = 0; i < (r.direct.size() / 3); ++i) {
      const double e = std::fabs(r.direct_at(i).luminance() - against.direct_at(i).luminance()) / mean_ref;
      avg += e / (r.direct.size() / 3);
      mx = std::max(mx, e);
    }
  };
  double avg7 = 0, avg15 = 0, avg255 = 0, mx;
  for (int bins : {7, 15, 255}) {
    const P1Result r = run(bins);
    double avg, avg_x, mx_x;
    error(r, ref, avg, mx);
    error(r, exact, avg_x, mx_x);
    std::printf(
        "[normal bins] %3d: vs 255 avg %.3f %% max %.3f %%; vs exact avg %.3f %% max %.3f %% (of the mean)\n",
        bins, 100 * avg, 100 * mx, 100 * avg_x, 100 * mx_x);
    (bins == 7 ? avg7 : bins == 15 ? avg15 : avg255) = avg_x;
  }
  EXPECT_LE(avg7, 0.03);
  EXPECT_LT(avg15, avg7);
  EXPECT_LT(avg255, avg15);
  EXPECT_LE(avg255, 2e-3);
}

TEST(P1Measure, MappingErrorAgainstTexelCenterMarch) {
  // The gathered horizon of each texel against the exact horizon marched from the texel center itself on
  // the reference's triangulated surface (every column, row and diagonal crossing), in the interior
  // (>= 2 texels from the border) and on the border ring, and the ao difference that results (ao from the
  // marched horizons with the same formula): the whole error of bringing line results to texel centers.
  const int K = 16;
  for (ProceduralKind kind : {ProceduralKind::fractal, ProceduralKind::sines, ProceduralKind::blocks}) {
    const HeightField f = truth::procedural(kind, 64, 64, Wrap::clamp);
    const Scene s = make_scene(f);
    const P1Result r = compute_p1(s, params(K, true), RunControl{});
    SweepSpec spec;
    spec.directions = K;
    struct Stats {
      double sum = 0, sq = 0, mx = 0, ao_sum = 0, ao_max = 0;
      long n = 0, texels = 0;
    } in, border;
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) {
        Stats& st = (i < 2 || j < 2 || i > 61 || j > 61) ? border : in;
        const std::size_t t = f.index(i, j);
        const Vec3f n = s.normals[t];
        double ao = 0;
        for (int k = 0; k < K; ++k) {
          const SweepDirection d = plan_direction(f, spec, k);
          const double e = truth::march_tri(f, i, j, d.dx, d.dy, 7);
          const double err = std::fabs(std::asin(double(r.horizon[t * K + k])) - e);
          st.sum += err, st.sq += err * err, st.mx = std::max(st.mx, err), ++st.n;
          const double np = n.x * std::cos(d.phi) + n.y * std::sin(d.phi), nz = n.z;
          const double th = std::min(kPi / 2 - e, kPi / 2 + std::atan(np / nz));
          ao += (nz * std::sin(th) * std::sin(th) + np * (th - std::sin(th) * std::cos(th))) / K;
        }
        st.ao_sum += std::fabs(ao - r.ao[t]);
        st.ao_max = std::max(st.ao_max, std::fabs(ao - r.ao[t]));
        ++st.texels;
      }
    for (const Stats* st : {&in, &border})
      std::printf(
          "[mapping] %-8s K=%d %-8s horizon vs texel-center march: mean %.3f deg, rms %.3f, max %.2f; "
          "|d ao| mean %.2e, max %.2e\n",
          procedural_kind_name(kind), K, st == &in ? "interior" : "border", st->sum / st->n / kDeg,
          std::sqrt(st->sq / st->n) / kDeg, st->mx / kDeg, st->ao_sum / st->texels, st->ao_max);
    // (before the exact near field: fractal 0.77 deg / 3.3e-3, sines 1.39 / 4.1e-3, blocks 0.85 / 4.9e-3)
    EXPECT_LE(in.sum / in.n / kDeg, 0.7);
    EXPECT_LE(in.ao_sum / in.texels, 5e-3);
    EXPECT_LE(border.ao_sum / border.texels, 6e-3);
  }
}

TEST(P1Wrap, RepeatEqualsCenterOfClampTilingAndIsSeamless) {
  const int W = 48;
  const HeightField tile = truth::procedural(ProceduralKind::fractal, W, W, Wrap::repeat);
  HeightField big;
  big.width = big.height = 3 * W;
  big.texel_size = tile.texel_size;
  big.wrap = Wrap::clamp;
  big.z.resize(big.texel_count());
  for (int j = 0; j < 3 * W; ++j)
    for (int i = 0; i < 3 * W; ++i) big.z[big.index(i, j)] = tile.z[tile.index(i % W, j % W)];
  const P1Result a = compute_p1(make_scene(tile), params(32), RunControl{});
  const P1Result b = compute_p1(make_scene(big), params(32), RunControl{});
  double mean = 0, mx = 0, mean_ao = 0;
  for (int j = 0; j < W; ++j)
    for (int i = 0; i < W; ++i) {
      const double d = std::fabs(a.ao[tile.index(i, j)] - b.ao[big.index(W + i, W + j)]);
      mean += d / (W * W), mx = std::max(mx, d), mean_ao += a.ao[tile.index(i, j)] / (W * W);
    }
  // Seams: differences across the tile edge against differences between interior neighbours.
  double seam = 0, interior = 0;
  for (int j = 0; j < W; ++j) {
    seam = std::max({seam, double(std::fabs(a.ao[tile.index(W - 1, j)] - a.ao[tile.index(0, j)])),
                     double(std::fabs(a.ao[tile.index(j, W - 1)] - a.ao[tile.index(j, 0)]))});
    for (int i = 0; i + 1 < W; ++i)
      interior = std::max({interior, double(std::fabs(a.ao[tile.index(i, j)] - a.ao[tile.index(i + 1, j)])),
                           double(std::fabs(a.ao[tile.index(j, i)] - a.ao[tile.index(j, i + 1)]))});
  }
  std::printf(
      "[repeat] vs 3x3 clamp center: mean |d ao| %.2e, max %.2e (mean ao %.4f); max seam step %.3g, "
      "max interior step %.3g\n",
      mean, mx, mean_ao, seam, interior);
  EXPECT_LE(mean, 2e-3);
  EXPECT_LE(seam, interior);
}

TEST(P1, DeterministicForAnyThreadCount) {
  const EnvironmentLighting sky = make_sky_environment(SkySpec{});
  const Scene s =
      make_scene(truth::procedural(ProceduralKind::bricks, 80, 70, Wrap::clamp), sky.environment, sky.lights);
  P1Params p = params(24, true);
  p.horizon_distance = true;
  auto run = [&](int threads) {
    P1Result r;
    tbb::task_arena(threads).execute([&] { r = compute_p1(s, p, RunControl{}); });
    return r;
  };
  const P1Result a = run(1), b = run(2);
  EXPECT_EQ(a.ao, b.ao);
  EXPECT_EQ(a.vsky, b.vsky);
  EXPECT_EQ(a.horizon, b.horizon);
  EXPECT_EQ(a.horizon_distance, b.horizon_distance);
  ASSERT_EQ((a.direct.size() / 3), (b.direct.size() / 3));
  for (std::size_t i = 0; i < (a.direct.size() / 3); ++i) {
    ASSERT_EQ(a.direct_at(i).r, b.direct_at(i).r);
    ASSERT_EQ(a.direct_at(i).b, b.direct_at(i).b);
  }
}

TEST(P1, HorizonDistanceOnAPit) {
  // From the pit's center the rim casts every horizon: distance ~ sqrt(R^2 + D^2).
  const Scene s = make_scene(shape(ProceduralKind::pit, 41, 30, 10, 10));
  P1Params p = params(16);
  p.horizon_distance = true;
  const P1Result r = compute_p1(s, p, RunControl{});
  const std::size_t c = s.field.index(20, 20);
  for (int k = 0; k < 16; ++k) {
    EXPECT_GE(r.horizon_distance[c * 16 + k], std::hypot(10.0, 10.0) - 0.5);
    EXPECT_LE(r.horizon_distance[c * 16 + k], std::hypot(11.5, 10.0) + 0.5);
  }
  // A corner texel looking out of the field has no caster.
  EXPECT_TRUE(std::isinf(r.horizon_distance[s.field.index(0, 0) * 16 + 8]));
}

// Where nothing casts a horizon (a border texel looking out of the field), its sine is -1 exactly, as
// docs/contract.md says; elsewhere it is above -1.
TEST(P1, NothingAboveIsMinusOneExactly) {
  for (const ProceduralKind kind : {ProceduralKind::fractal, ProceduralKind::pit, ProceduralKind::flat}) {
    const Scene s = make_scene(shape(kind, 33, 30, 10, 10));
    P1Params p = params(16);
    p.horizon = true, p.horizon_distance = true;
    const P1Result r = compute_p1(s, p, RunControl{});
    std::size_t nothing = 0;
    for (std::size_t i = 0; i < r.horizon.size(); ++i) {
      if (std::isinf(r.horizon_distance[i])) {
        ++nothing;
        ASSERT_EQ(r.horizon[i], -1.0f) << int(kind) << " at " << i;
      } else {
        ASSERT_GT(r.horizon[i], -1.0f) << int(kind) << " at " << i;
      }
    }
    EXPECT_GT(nothing, 0u) << int(kind);
  }
}

TEST(BakeP1, LayersAndErrors) {
  const Scene s = make_scene(shape(ProceduralKind::flat, 9));
  nlohmann::json e = {{"method", "p1"}, {"directions", 8}};
  LayerSet l = bake_method("p1", s, e, RunControl{});
  ASSERT_EQ(l.layers.size(), 3u);
  EXPECT_NE(l.find("ao"), nullptr);
  EXPECT_NE(l.find("vsky"), nullptr);
  ASSERT_NE(l.find("direct"), nullptr);
  EXPECT_EQ(l.find("direct")->channel_count(), 3);
  e["layers"] = {"horizon", "bent_normal", "horizon_distance"};
  l = bake_method("p1", s, e, RunControl{});
  ASSERT_EQ(l.layers.size(), 3u);
  EXPECT_EQ(l.layers[0].name, "horizon");
  EXPECT_EQ(l.layers[0].channel_count(), 8);
  EXPECT_EQ(l.layers[0].data.size(), 81u * 8);
  e["layers"] = {"ao", "obscurance"};
  try {
    bake_method("p1", s, e, RunControl{});
    FAIL();
  } catch (const InputError& err) {
    EXPECT_EQ(err.where(), "/layers/1");
  }
  e.erase("layers");
  e["normal_bins"] = 16;
  EXPECT_THROW(bake_method("p1", s, e, RunControl{}), InputError);
}

// A directional light's own sweep direction is at any azimuth, not one of the K: its shadows against the
// exact march over the triangulated surface (truth::march_tri) on a field rough at the texel scale. The
// slopes 2/3, 1/2, 3/4, 1/3, 3/5 and 2/5 put some columns' u * slope on an integer up to rounding: there
// a texel the rounding moves to the next strip must not make the strip search look for it forever (a 67x53
// fractal with a light at [0.3, 0.2, 1]), and row and diagonal crossings 1e-15 from a column must not make
// the strip's hull non-concave, or its binary search misses the caster (the light at [-0.4, 0.3]).
// With horizon_tolerance tau a light's own horizon may lie up to tau (in sine) below the exact one: a texel
// is then lit or shadowed as the exact march says unless the sun's sine lies within tau below the exact
// horizon's.
void lights_shadow_as_the_exact_march(double tau) {
  const Environment black = make_uniform_environment({0, 0, 0});
  const HeightField field = truth::rough_field(67, 53, 70, 0.7, 21);
  const Vec3 dirs[] = {{0.3, 0.2, 1}, {1, 0.5, 0.8}, {-0.4, 0.3, 0.5}, {0.25, -1, 1.2},
                       {-2, -3, 2.5}, {3, 1, 1.2},   {-5, 3, 2.5},     {2, -5, 3}};
  for (const Vec3& v : dirs) {
    DirectionalLight l;
    l.direction = v;
    l.irradiance = {2, 2, 2};
    const Scene s = make_scene(field, black, {l});
    P1Params p = params(12);
    p.bent_normal = false;
    p.horizon_tolerance = tau;
    const P1Result r = compute_p1(s, p, RunControl{});
    const Vec3 d = normalize(v);
    const double el = std::asin(d.z), az = std::atan2(d.y, d.x);
    int lit = 0, shadowed = 0, wrong = 0;
    for (int j = 0; j < field.height; ++j)
      for (int i = 0; i < field.width; ++i) {
        const std::size_t idx = field.index(i, j);
        const double ndl = dot(s.normals[idx].d(), d);
        if (ndl <= 0) continue;
        const double e = truth::march_tri(field, i, j, std::cos(az), std::sin(az), 7);
        if (std::fabs(e - el) < 1e-4) continue;  // grazing: either answer is right to float precision
        if (std::sin(el) < std::sin(e) && std::sin(el) >= std::sin(e) - tau - 1e-4)
          continue;  // tau allows both
        const bool expect_lit = e < el;
        const double want = expect_lit ? 2 * ndl / kPi : 0;
        (expect_lit ? lit : shadowed) += 1;
        if (std::fabs(r.direct_at(idx).r - want) > 1e-5 * (1 + want)) ++wrong;
      }
    EXPECT_EQ(wrong, 0) << "light [" << v.x << ", " << v.y << ", " << v.z << "] tolerance " << tau;
    // Both outcomes well represented (fewer with a tolerance: the texels it leaves open are not counted).
    EXPECT_GT(lit, tau > 0 ? 50 : 100);
    EXPECT_GT(shadowed, tau > 0 ? 50 : 100);
  }
}

TEST(P1Lighting, LightsAtAnyAzimuthShadowAsTheExactMarch) {
  lights_shadow_as_the_exact_march(0);
}
TEST(P1Lighting, LightsShadowWithinTheHorizonTolerance) {
  lights_shadow_as_the_exact_march(0.01);
  lights_shadow_as_the_exact_march(0.05);
}

}  // namespace
}  // namespace hfbake
