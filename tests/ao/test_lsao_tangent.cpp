// lsao's receiver tangent (lsao_chain_hull.hpp): closed forms (planes, the wall and the pit
// with every falloff), the brute-force hbao march as a cross-check on gentle and rough fields, the hull
// against the brute force over the same line samples, and determinism across thread counts.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "ao_scenes.hpp"
#include "field/procedural.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/lsao.hpp"
#include "methods/ao/lsao_chain_hull.hpp"

namespace hfbake {
namespace {

LsaoOptions receiver(int K, Falloff rho, ObscuranceWeighting w = ObscuranceWeighting::cosine) {
  LsaoOptions o;
  o.directions = K;
  o.occlusion.rho = rho;
  o.occlusion.weighting = w;
  o.tangent = LsaoTangent::receiver;
  return o;
}

// The line samples alone (surface bilinear, no near field): the slab model's closed forms of a vertical face
// (the triangulated surface's face is a one-texel ramp: test_obscurance_surface.cpp has its truth).
LsaoOptions receiver_samples(int K, Falloff rho, ObscuranceWeighting w = ObscuranceWeighting::cosine) {
  LsaoOptions o = receiver(K, rho, w);
  o.surface = LsaoSurface::bilinear;
  o.near_radius = 0;
  return o;
}

const Falloff kFalloffs[] = {{FalloffKind::none, 0},     {FalloffKind::step, 7},
                             {FalloffKind::step, 40},    {FalloffKind::linear, 10},
                             {FalloffKind::smooth, 10},  {FalloffKind::smooth, 200},
                             {FalloffKind::rational, 5}, {FalloffKind::exponential, 4}};

// Float sums; exponential and rational bands by 2-point Gauss (lsao_chain_hull.cpp): 2e-4 relative measured.
double tolerance(const Falloff& rho, double want) {
  const bool gauss = rho.kind == FalloffKind::exponential || rho.kind == FalloffKind::rational;
  return gauss ? 5e-4 * want : 2e-6;
}

// A plane, level or tilted, occludes nothing seen from its own tangent: every direction gives 0 (P3's fixed
// tangent gives Wt < 0 per direction and needs the clamp).
TEST(LsaoTangent, PlanesAreOpen) {
  for (double angle : {0.0, 25.0, 60.0}) {
    ProceduralSpec s;
    s.kind = ProceduralKind::slope;
    s.width = s.height = 48;
    s.angle_deg = angle;
    s.aspect_deg = 30;
    const HeightField f = make_procedural(s, 1.0, Wrap::clamp);
    for (const Falloff& rho : kFalloffs)
      for (auto w : {ObscuranceWeighting::uniform, ObscuranceWeighting::cosine}) {
        const auto mean = lsao_mean_occlusion(f, receiver(16, rho, w), RunControl{});
        for (int j = 1; j < 47; ++j)
          for (int i = 1; i < 47; ++i)
            ASSERT_NEAR(mean[f.index(i, j)], 0.0, 1e-6)
                << angle << " " << falloff_kind_name(rho.kind) << " " << i << " " << j;
      }
  }
}

// The infinite wall in front of a level texel, K = 8: axes and diagonals sample texel centres,
// so the sweep meets the wall's top edge exactly and the obscurance is the closed form's discrete-K sum
// (every ray below the top hits the vertical face at x / cos e, weighted by rho there), for every falloff:
// the chain has one band per direction, and the windows of the falloffs that end must keep the wall exactly
// while it is within the radius (R = 7: the axis direction only, at 6; the diagonals meet it at 8.5).
TEST(LsaoTangent, WallClosedForm) {
  const int width = 64, height = 129, x0 = 40;
  const double h = 5, d = 6;
  const HeightField f = test::make_wall(width, height, x0, h);
  const std::size_t idx = f.index(x0 - int(d), height / 2);
  for (const Falloff& rho : kFalloffs)
    for (bool cosine : {true, false}) {
      const auto w = cosine ? ObscuranceWeighting::cosine : ObscuranceWeighting::uniform;
      const double got = lsao_mean_occlusion(f, receiver_samples(8, rho, w), RunControl{})[idx];
      const double want = test::wall_occlusion(d, h, 8, cosine, [&](double x) { return rho(x); });
      EXPECT_NEAR(got, want, tolerance(rho, want))
          << falloff_kind_name(rho.kind) << " R " << rho.radius << " cosine " << cosine;
    }
}

// The bowl: the centre of a cylindrical pit (radius 24, depth 10) sees the rim at 24 in every direction; its
// cosine-weighted obscurance for each falloff is the closed form's integral over the wall (K = 4: the axes
// meet the rim's top texel exactly). The fixed tangent (P3, -0.85) misses all of it with a falloff whose
// weight at the rim is below 1 - W(sin e)... the point of the receiver's tangent.
TEST(LsaoTangent, PitClosedForm) {
  const double rw = 24, depth = 10;
  const HeightField f = test::make_pit(97, rw, depth);
  const std::size_t idx = f.index(48, 48);
  for (const Falloff& rho : kFalloffs) {
    const double got = lsao_mean_occlusion(f, receiver_samples(4, rho), RunControl{})[idx];
    const double want = test::pit_occlusion(rw, depth, [&](double x) { return rho(x); });
    EXPECT_NEAR(got, want, tolerance(rho, want)) << falloff_kind_name(rho.kind) << " R " << rho.radius;
  }
  LsaoOptions fixed = receiver_samples(4, {FalloffKind::smooth, 200});
  fixed.tangent = LsaoTangent::fixed;
  const double want = test::pit_occlusion(rw, depth, [](double x) {
    return Falloff{FalloffKind::smooth, 200}(x);
  });
  EXPECT_GT(want, 0.1);
  EXPECT_LT(lsao_mean_occlusion(f, fixed, RunControl{})[idx], 0.5 * want);
}

struct Field {
  const char* name;
  HeightField f;
};
std::vector<Field> fields() {
  auto make = [](ProceduralKind kind, std::uint64_t seed, double amplitude, double feature) {
    ProceduralSpec s;
    s.kind = kind;
    s.width = s.height = 96;
    s.seed = seed;
    s.amplitude = amplitude;
    s.feature_size = feature;
    return make_procedural(s, 1.0, Wrap::clamp);
  };
  return {{"craters", make(ProceduralKind::craters, 9, 4, 10)},
          {"sines", make(ProceduralKind::sines, 1, 0, 0)},
          {"rough", make(ProceduralKind::rough, 3, 0, 0)}};
}

double rmse(const std::vector<float>& a, const std::vector<float>& b, double* mean = nullptr) {
  double s = 0, m = 0;
  for (std::size_t t = 0; t < a.size(); ++t) {
    const double e = double(a[t]) - double(b[t]);
    s += e * e;
    m += e;
  }
  if (mean) *mean = m / double(a.size());
  return std::sqrt(s / double(a.size()));
}

// Cross-check against hbao's march on the triangulated surface (its default: segment estimator over every
// crossing, the exact slice integral; tests/ao/test_hbao_triangles.cpp), same K and falloff. Bounds about
// 1.5x what was measured with lsao's surface triangles and near field (measured 0.0002 / 0.0003 craters,
// 0.0027 / 0.0029 sines, 0.0046 / 0.0077 rough for smooth R 32 / step R 8; the line samples alone were
// 0.06-0.08 on rough; a walk that stopped while the horizon was below the horizontal, 0.0082 / 0.0104 on
// rough); P3's fixed tangent is 5-30x beyond them on the gentle fields (the 0.9997 against 0.982).
TEST(LsaoTangent, AgainstHbaoMarch) {
  struct Bound {
    const char* field;
    Falloff rho;
    double receiver_rmse, fixed_rmse_above;
  };
  const Bound bounds[] = {{"craters", {FalloffKind::smooth, 32}, 0.0004, 0.02},
                          {"craters", {FalloffKind::step, 8}, 0.0005, 0.008},
                          {"sines", {FalloffKind::smooth, 32}, 0.004, 0.1},
                          {"sines", {FalloffKind::step, 8}, 0.0045, 0.05},
                          {"rough", {FalloffKind::smooth, 32}, 0.007, 0.2},
                          {"rough", {FalloffKind::step, 8}, 0.0115, 0.15}};
  for (const Field& fd : fields()) {
    for (const Bound& b : bounds) {
      if (std::string(b.field) != fd.name) continue;
      HbaoSettings s;
      s.falloff = b.rho;
      s.directions = uniform_directions(16);
      s.reach = default_reach(fd.f, b.rho);
      s.surface = MarchSurface::triangles;  // hbao's default: the exact slice integral of the surface
      s.estimator = HorizonEstimator::segment;
      s.bent = false;
      std::vector<float> march(fd.f.texel_count());
      hbao_field(fd.f, compute_normals(fd.f), s, RunControl{}, march.data(), nullptr);
      LsaoOptions o = receiver(16, b.rho);
      double bias = 0;
      const double e = rmse(lsao_obscurance(fd.f, o, RunControl{}), march, &bias);
      o.tangent = LsaoTangent::fixed;
      const double e_fixed = rmse(lsao_obscurance(fd.f, o, RunControl{}), march);
      std::printf("%-8s %-6s R %-3g: lsao - hbao rmse %.4f bias %+.4f (fixed tangent rmse %.4f)\n", fd.name,
                  falloff_kind_name(b.rho.kind), b.rho.radius, e, bias, e_fixed);
      EXPECT_LT(e, b.receiver_rmse) << fd.name;
      EXPECT_GT(e_fixed, b.fixed_rmse_above) << fd.name;
    }
  }
}

// The chain hull against its brute force over the same line samples (every visible sample's band): what
// the merging costs. Measured rmse 0.00001-0.00002 (craters), 0.00003-0.00004 (sines), 0.0002-0.0007
// (rough).
TEST(LsaoTangent, HullAgainstBruteForceChain) {
  for (const Field& fd : fields())
    for (const Falloff& rho : {Falloff{FalloffKind::smooth, 32}, Falloff{FalloffKind::rational, 8}}) {
      LsaoOptions o = receiver(8, rho);
      LsaoStats st;
      const auto hull = lsao_obscurance(fd.f, o, RunControl{}, &st);
      o.estimator = LsaoEstimator::brute_visible;
      const auto brute = lsao_obscurance(fd.f, o, RunControl{});
      const double e = rmse(hull, brute);
      std::printf("%-8s %-9s: hull - brute chain rmse %.5f, prune tests per sample %.3f\n", fd.name,
                  falloff_kind_name(rho.kind), e, double(st.iterations) / double(st.samples));
      EXPECT_LT(e, fd.name == std::string("craters") ? 0.0001 : 0.001) << fd.name;
      EXPECT_LE(st.iterations, 2 * st.samples);  // amortised O(1): one push and at most one pop a sample
    }
}

// Coalescing adjacent rising bands (LsaoOptions::band_tolerance, TangentChain::coalesce): exact for a step
// inside its radius; with a smooth falloff as close to hbao's exact slice march (the triangulated surface's
// slice integral at the same K) as the separate bands, and the bands a query adds no longer grow with the
// radius (P3's cost property). Measured on this field: step R 8 the same bits; smooth rmse against the
// march separate 0.00142, coalesced 0.00142 (R 8); 0.00246, 0.00255 (R 512); bands a query R 8 -> 512
// separate 3.12 -> 3.22, coalesced 2.96 -> 1.53.
TEST(LsaoTangent, CoalescedBandsKeepAccuracyAndFlattenTheWork) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::ridges;
  spec.width = spec.height = 112;
  spec.seed = 31;
  spec.amplitude = 24;
  const HeightField f = make_procedural(spec, 1.0, Wrap::clamp);
  const std::vector<Vec3f> normals = compute_normals(f);
  {
    LsaoOptions o = receiver(16, {FalloffKind::step, 8});
    const auto coalesced = lsao_obscurance(f, o, RunControl{});
    o.band_tolerance = 0;
    const auto separate = lsao_obscurance(f, o, RunControl{});
    double worst = 0;
    for (std::size_t t = 0; t < f.texel_count(); ++t)
      worst = std::max(worst, std::abs(double(coalesced[t]) - double(separate[t])));
    std::printf("step R 8: coalesced - separate worst %.2e\n", worst);
    EXPECT_LT(worst, 1e-5);
  }
  double bands[2][2] = {};  // [coalesced?][R 8, R 512]
  for (int r = 0; r < 2; ++r) {
    const Falloff rho{FalloffKind::smooth, r == 0 ? 8.0 : 512.0};
    HbaoSettings s;
    s.falloff = rho;
    s.directions = uniform_directions(16);
    s.reach = default_reach(f, rho);
    s.surface = MarchSurface::triangles;
    s.estimator = HorizonEstimator::segment;
    s.bent = false;
    std::vector<float> march(f.texel_count());
    hbao_field(f, normals, s, RunControl{}, march.data(), nullptr);
    double e[2];
    for (int c = 0; c < 2; ++c) {
      LsaoOptions o = receiver(16, rho);
      if (c == 0) o.band_tolerance = 0;
      LsaoStats st;
      e[c] = rmse(lsao_obscurance(f, o, RunControl{}, &st), march);
      bands[c][r] = double(st.bands) / double(st.queries);
    }
    std::printf("smooth R %3g: rmse against the march separate %.5f coalesced %.5f\n", rho.radius, e[0],
                e[1]);
    EXPECT_LT(e[1], 1.06 * e[0] + 1e-5) << rho.radius;
  }
  std::printf("bands a query, R 8 -> 512: separate %.2f -> %.2f, coalesced %.2f -> %.2f\n", bands[0][0],
              bands[0][1], bands[1][0], bands[1][1]);
  // The hull's merges (judged from the near field's edge, lsao.cpp) keep the separate bands flat too.
  EXPECT_LT(bands[0][1], 1.2 * bands[0][0]);
  EXPECT_LT(bands[1][1], 1.2 * bands[1][0]);
}

// The walk's block steps (lsao_chain_hull.cpp: blocks that cannot rise passed over in one test) and its
// lazily held bands against every point added one by one (brute_chain) over the same points, no merges: a
// long rising run seen from its foot (z = c d^1.5 behind the receiver, each point higher seen from it than
// the one before) and beyond it a lower, level stretch and one far peak that rises again. The sums agree to
// rounding, and the walk takes fewer steps than half the 400 points (measured: 179).
TEST(LsaoTangent, WalkBlocksAgainstEveryPointAddedOneByOne) {
  std::vector<SlicePoint> pts;  // walk order of the line: farthest first
  for (int d = 400; d >= 1; --d) {
    const double z = d > 300 ? (d == 390 ? 400.0 : 10.0) : d > 150 ? 5.0 : 0.05 * std::pow(double(d), 1.5);
    pts.push_back({-double(d), z});
  }
  const SlicePoint p{0, 0};
  for (const double radius : {2000.0, 600.0}) {  // every point inside the support (brute_chain has none)
    const Falloff rho{FalloffKind::smooth, radius};
    ChainHull hull;
    for (const SlicePoint& q : pts) hull.push(q);
    auto chain = [&] {
      TangentChain c(rho, Weighting::cosine, slice_frame(0.3, 1.0));
      c.want_direction = true;
      c.segments = true;
      c.coalesce = 0.01;
      return c;
    };
    TangentChain walked = chain(), each = chain();
    hull.query(p, rho.support(1e-4), walked);
    brute_chain(pts.data(), pts.size(), p, each);
    walked.finish();
    each.finish();
    std::printf("R %4g: sum walked %.12f one by one %.12f, steps %u, bands %u %u\n", radius, walked.sum,
                each.sum, walked.walked, walked.bands, each.bands);
    EXPECT_NEAR(walked.sum, each.sum, 1e-12);
    EXPECT_NEAR(walked.direction.h, each.direction.h, 1e-12);
    EXPECT_NEAR(walked.direction.v, each.direction.v, 1e-12);
    EXPECT_EQ(walked.bands, each.bands);
    EXPECT_GT(each.sum, 0.0);
    EXPECT_LT(walked.walked, 200u);
  }
}

// The chain hull with a near field (lsao.cpp: points pushed once they are near_radius behind the receivers,
// each after a prune judged from there) against every point added one by one (the brute force over the same
// line points, near field included), on families of fields: ridges of two periods and heights, rough fBm of
// two roughnesses, terraces (vertical steps), at a short and a long smooth falloff. Measured rmse hull -
// brute 0.0001-0.0007 (ridges, rough), 0.0008-0.0014 (terraces). Beside it the walk's steps per query against
// the radius on a ridged field: measured 4.3 (R 8) and 9.9 (R 256); merges judged from the adjacent sample (a
// hull that grows with the radius) take about 3x as many at R 256 as at R 8 (docs/performance-lsao.md).
TEST(LsaoTangent, NearFieldHullAgainstEveryPointAddedOneByOne) {
  struct Family {
    const char* name;
    ProceduralKind kind;
    double feature, amplitude, angle;
  };
  const Family families[] = {{"ridges 24/8", ProceduralKind::ridges, 24, 8, NAN},
                             {"ridges 64/24", ProceduralKind::ridges, 64, 24, NAN},
                             {"rough 45", ProceduralKind::rough, 0, 0, 45},
                             {"rough 70", ProceduralKind::rough, 0, 0, 70},
                             {"terraces", ProceduralKind::terraces, 0, 12, NAN}};
  for (const Family& fam : families) {
    ProceduralSpec spec;
    spec.kind = fam.kind;
    spec.width = spec.height = 72;
    spec.seed = 5;
    spec.feature_size = fam.feature;
    spec.amplitude = fam.amplitude;
    spec.angle_deg = fam.angle;
    const HeightField f = make_procedural(spec, 1.0, Wrap::clamp);
    for (const double radius : {12.0, 96.0}) {
      LsaoOptions o = receiver(8, {FalloffKind::smooth, radius});
      ASSERT_EQ(o.surface, LsaoSurface::triangles);
      ASSERT_GT(o.near_radius, 0.0);
      LsaoStats st;
      const auto hull = lsao_obscurance(f, o, RunControl{}, &st);
      o.estimator = LsaoEstimator::brute_visible;
      const auto brute = lsao_obscurance(f, o, RunControl{});
      const double e = rmse(hull, brute);
      std::printf("%-12s R %3g: hull - every point rmse %.5f, walk steps a query %.2f\n", fam.name, radius, e,
                  double(st.walked) / double(st.queries));
      EXPECT_LT(e, 0.002) << fam.name << " R " << radius;
    }
  }
  // The walk's steps per query from R 8 to R 256 on a ridged field wider than the radius.
  ProceduralSpec spec;
  spec.kind = ProceduralKind::ridges;
  spec.width = spec.height = 320;
  spec.seed = 23;
  spec.amplitude = 40;
  const HeightField f = make_procedural(spec, 1.0, Wrap::clamp);
  double steps[2];
  for (int r = 0; r < 2; ++r) {
    LsaoStats st;
    lsao_obscurance(f, receiver(4, {FalloffKind::smooth, r == 0 ? 8.0 : 256.0}), RunControl{}, &st);
    steps[r] = double(st.walked) / double(st.queries);
  }
  std::printf("ridges 320: walk steps a query R 8 %.2f, R 256 %.2f\n", steps[0], steps[1]);
  EXPECT_LT(steps[1], 2.5 * steps[0]);
}

// Same bits for any thread count (lines run in parallel; sums in direction order), with the bent normal.
TEST(LsaoTangent, DeterministicAcrossThreadCounts) {
  const HeightField f = fields()[0].f;
  for (const Falloff& rho : {Falloff{FalloffKind::smooth, 12}, Falloff{FalloffKind::rational, 4}}) {
    std::vector<std::vector<float>> runs;
    std::vector<std::vector<Vec3f>> bents;
    for (int threads : {1, 2, 4}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
      std::vector<Vec3f> bent;
      runs.push_back(lsao_obscurance(f, receiver(12, rho), RunControl{}, nullptr, &bent));
      bents.push_back(bent);
    }
    for (std::size_t r = 1; r < runs.size(); ++r) {
      EXPECT_EQ(runs[r], runs[0]);
      for (std::size_t t = 0; t < bents[0].size(); ++t) {
        ASSERT_EQ(bents[r][t].x, bents[0][t].x);
        ASSERT_EQ(bents[r][t].y, bents[0][t].y);
        ASSERT_EQ(bents[r][t].z, bents[0][t].z);
      }
    }
  }
}

}  // namespace
}  // namespace hfbake
