// The hull stack is exact: on every line of every direction, the horizon it returns equals a brute-force
// march over the same sample points (double atan2), on incoherent random heights and on the four P2 test
// surfaces, clamp and repeat. Also the float approximations used in the hot loops.
#include <gtest/gtest.h>

#include <cstdio>

#include "methods/p1/fast_math.hpp"
#include "methods/p1/horizon_sweep.hpp"
#include "methods/p1/hull_stack.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

struct Exactness {
  double hull_max = 0;     // |hull (double) - march|, radians
  double worker_max = 0;   // |worker output (float, fast atan) - march|
  double far_max = 0;      // |far worker (lagging near radius) - march over the samples that far behind|
  double cross_max = 0;    // the same with the row and diagonal crossings as extra points
  double surface_max = 0;  // |crossing height - triangulated surface there|
  long receivers = 0, none_mismatch = 0;
};

Exactness check_field(const HeightField& f, int K) {
  Exactness ex;
  SweepSpec spec;
  spec.directions = K;
  p1::HorizonLineWorker worker, far_worker, cross_worker;
  far_worker.far_radius = 2.0;  // texel size 1: samples >= 2 texels behind (the default near radius)
  cross_worker.far_radius = 2.0;
  cross_worker.crossings = &f;
  std::vector<float> z, out, out_far, out_cross, pz;
  std::vector<double> pos;
  for (int k = 0; k < K; ++k) {
    const SweepDirection d = plan_direction(f, spec, k);
    for (int l = d.line_begin; l < d.line_end; ++l) {
      const SweepLine line = truth::make_line(f, d, l, z);
      // The hull stack itself, with exact double elevations.
      p1::HullStack hull;
      hull.reset(line.count);
      out.assign(std::size_t(line.receivers()) * p1::HorizonLineWorker::channels(), 0.0f);
      worker(line, out.data());
      out_far.assign(out.size(), 0.0f);
      far_worker(line, out_far.data());
      const int lag = p1::far_lag(far_worker.far_radius, line.step);
      out_cross.assign(out.size(), 0.0f);
      cross_worker(line, out_cross.data());
      cross_worker.terrain_points(line, pos, pz);
      for (std::size_t q = 0; q < pos.size(); ++q) {  // every point lies on the triangulated surface
        const int n0 = int(std::floor(pos[q]));
        const double t = pos[q] - n0;
        const double x = line.x(n0) + (n0 + 1 < line.count ? line.x(n0 + 1) - line.x(n0) : 0) * t;
        const double y = line.y(n0) + (n0 + 1 < line.count ? line.y(n0 + 1) - line.y(n0) : 0) * t;
        const double xw = f.wrap == Wrap::repeat ? x - f.width * std::floor(x / f.width) : x;
        const double yw = f.wrap == Wrap::repeat ? y - f.height * std::floor(y / f.height) : y;
        ex.surface_max = std::max(ex.surface_max, std::fabs(pz[q] - truth::tri_height(f, xw, yw)));
      }
      for (int n = 0; n < line.count; ++n) {
        p1::HorizonCaster c;
        if (line.is_terrain(n))
          c = hull.add(n, line.z[n]);
        else if (line.inside_end > line.inside_begin && n >= line.inside_end)
          c = hull.query(n, line.z[n]);
        if (n < line.first_receiver) continue;
        const double truth = truth::march_same_points(line, n);
        const double got = !c.any ? truth::kNone : std::atan2(c.dz, c.dist * line.step);
        if (!c.any != (truth == truth::kNone)) ++ex.none_mismatch;
        ex.hull_max = std::max(ex.hull_max, std::fabs(got - truth));
        if (line.is_terrain(n)) {  // the worker skips points off a clamp field (never receivers)
          const float* o =
              out.data() + std::size_t(n - line.first_receiver) * p1::HorizonLineWorker::channels();
          const double layer = p1::caster_elevation(o[0], o[1]);
          ex.worker_max = std::max(ex.worker_max, std::fabs(layer - truth));
          const float* of =
              out_far.data() + std::size_t(n - line.first_receiver) * p1::HorizonLineWorker::channels();
          const double far_truth = truth::march_same_points(line, n, n - lag + 1);
          ex.far_max =
              std::max(ex.far_max, std::fabs(double(p1::caster_elevation(of[0], of[1])) - far_truth));
          // Crossings: the column samples plus the row and diagonal crossings (their heights checked
          // against the triangulated surface below); brute force over those at least 2 texels behind.
          double cross_truth = truth::kNone;
          for (std::size_t q = 0; q < pos.size(); ++q) {
            if (pos[q] > n - 2.0 / line.step + 1e-9) break;
            cross_truth =
                std::max(cross_truth, std::atan2(double(pz[q]) - line.z[n], (n - pos[q]) * line.step));
          }
          const float* oc =
              out_cross.data() + std::size_t(n - line.first_receiver) * p1::HorizonLineWorker::channels();
          ex.cross_max =
              std::max(ex.cross_max, std::fabs(double(p1::caster_elevation(oc[0], oc[1])) - cross_truth));
        }
        ++ex.receivers;
      }
    }
  }
  return ex;
}

TEST(HullStack, ExactAgainstSamePointsMarch) {
  struct Case {
    const char* name;
    HeightField field;
  };
  std::vector<Case> cases;
  for (Wrap w : {Wrap::clamp, Wrap::repeat}) {
    cases.push_back(
        {w == Wrap::clamp ? "random/clamp" : "random/repeat", truth::random_field(37, 29, 20.0, 9, w)});
    cases.push_back({w == Wrap::clamp ? "fractal/clamp" : "fractal/repeat",
                     truth::procedural(ProceduralKind::fractal, 40, 32, w)});
    cases.push_back({w == Wrap::clamp ? "bricks/clamp" : "bricks/repeat",
                     truth::procedural(ProceduralKind::bricks, 40, 32, w)});
    cases.push_back({w == Wrap::clamp ? "sines/clamp" : "sines/repeat",
                     truth::procedural(ProceduralKind::sines, 40, 32, w)});
    cases.push_back({w == Wrap::clamp ? "blocks/clamp" : "blocks/repeat",
                     truth::procedural(ProceduralKind::blocks, 48, 48, w)});
  }
  for (const Case& c : cases) {
    for (int K : {16, 13}) {
      const Exactness ex = check_field(c.field, K);
      std::printf(
          "[exactness] %-15s K=%2d receivers=%7ld  max|hull-march|=%.3g rad  max|layer-march|=%.3g rad  "
          "max|far-march|=%.3g rad  max|crossings-march|=%.3g rad (heights %.2g)\n",
          c.name, K, ex.receivers, ex.hull_max, ex.worker_max, ex.far_max, ex.cross_max, ex.surface_max);
      EXPECT_EQ(ex.none_mismatch, 0) << c.name;
      EXPECT_LE(ex.hull_max, 1e-12) << c.name;   // the same caster up to double rounding
      EXPECT_LE(ex.worker_max, 1e-6) << c.name;  // plus the float fast atan of the stored layer
      EXPECT_LE(ex.far_max, 1e-6) << c.name;     // the lagging hull (far field) is exact too
      EXPECT_LE(ex.cross_max, 1e-6) << c.name;   // and with the triangulation's crossings
      EXPECT_LE(ex.surface_max, 1e-4) << c.name;
    }
  }
}

TEST(HullStack, QueryMatchesMarchForPointsBeyondTheHull) {
  // Random hulls queried from random heights: binary search == linear scan over every point.
  std::uint64_t x = 12345;
  auto rnd = [&] {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    return double(x >> 11) / 9007199254740992.0;
  };
  for (int trial = 0; trial < 200; ++trial) {
    p1::HullStack hull;
    const int n = 1 + int(rnd() * 60);
    hull.reset(n);
    std::vector<float> z(n);
    for (int m = 0; m < n; ++m) {
      z[m] = float(rnd() * 10);
      hull.add(m, z[m]);
    }
    for (int q = 0; q < 5; ++q) {
      const int at = n + int(rnd() * 5);
      const float zq = float(rnd() * 14 - 2);
      double best = -10;
      for (int m = 0; m < n; ++m) best = std::max(best, (double(z[m]) - zq) / (at - m));
      const p1::HorizonCaster c = hull.query(at, zq);
      ASSERT_NEAR(c.dz / c.dist, best, 1e-12);
    }
  }
}

TEST(HullStack, GallopingQueryFromAnyHintFindsTheSteepestVertex) {
  // query_index_near (FarHorizonWorker's query, from the last texel's vertex) against a linear scan for the
  // steepest vertex, from every hint and beyond both ends, on random hulls with fractional positions.
  std::uint64_t x = 777;
  auto rnd = [&] {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    return double(x >> 11) / 9007199254740992.0;
  };
  long checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    p1::HullStackF hull;
    const int n = 1 + int(rnd() * 80);
    hull.reset(n);
    std::vector<double> pos(n);
    std::vector<float> z(n);
    double p = 0;
    for (int m = 0; m < n; ++m) {
      p += 0.05 + rnd();
      pos[m] = p, z[m] = float(rnd() * 10);
      hull.add(p, z[m]);
    }
    for (int q = 0; q < 4; ++q) {
      const double at = p + 0.5 + rnd() * 5;
      const float zq = float(rnd() * 14 - 2);
      double best = -1e300;
      for (int m = 0; m < n; ++m) best = std::max(best, (double(z[m]) - zq) / (at - pos[m]));
      const int by_search = hull.query_index(at, zq);
      for (int hint = -2; hint <= hull.size() + 1; ++hint) {
        const int i = hull.query_index_near(at, zq, hint);
        ASSERT_EQ(i, by_search) << "trial " << trial << " hint " << hint;
        ASSERT_NEAR((double(hull.height(i)) - zq) / (at - hull.position(i)), best, 1e-12);
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 10000);
}

TEST(FastMath, AtanAndSincosAccuracy) {
  double e_atan = 0, e_sin = 0, e_cos = 0;
  for (int i = -200000; i <= 200000; ++i) {
    const double x = std::sinh(i * 1e-4);  // covers +-5e8 densely near 0
    e_atan = std::max(e_atan, std::fabs(double(p1::fast_atan(float(x))) - std::atan(double(float(x)))));
    const double e = i * (kPi / 2) / 200000;
    float s, c;
    p1::fast_sincos(float(e), s, c);
    e_sin = std::max(e_sin, std::fabs(s - std::sin(double(float(e)))));
    e_cos = std::max(e_cos, std::fabs(c - std::cos(double(float(e)))));
  }
  std::printf("[fast_math] max error: atan %.3g, sin %.3g, cos %.3g\n", e_atan, e_sin, e_cos);
  EXPECT_LE(e_atan, 4e-7);
  EXPECT_LE(e_sin, 2e-7);
  EXPECT_LE(e_cos, 2e-7);
}

}  // namespace
}  // namespace hfbake
