// P1's horizons against independent truth on terrain rough at the texel scale and on steps: the exact march
// over the reference's triangulated surface from every texel centre (truth::march_tri, every column, row and
// diagonal crossing; no hull, no sweep), and closed forms at the foot and the top of a step along a column.
// Directions that are not multiples of 45 degrees are where the sweep's lines miss the texel centres, so K =
// 16 and 24 have most of theirs off the diagonals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "methods/p1/p1.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

Scene make_scene(HeightField f) {
  Scene s;
  s.name = "rough";
  s.normals = compute_normals(f);
  s.field = std::move(f);
  s.environment = make_uniform_environment({1, 1, 1});
  return s;
}

P1Result horizons(const Scene& s, int K, double tolerance = 0) {
  P1Params p;
  p.directions = K;
  p.horizon_tolerance = tolerance;
  p.horizon = true;
  p.vsky = p.direct = false;
  return compute_p1(s, p, RunControl{});
}

struct Agreement {
  double p99 = 0, max = 0, above = 0;  // |sin h - sin h_exact|: 99th percentile, max, share above 0.05
  double max_inner = 0;                // max without the field's outermost texel ring
  double max_axes = 0, max_other = 0;  // max over multiples of 45 degrees, and over the other directions
  double ao_bias = 0;                  // mean of P1's ao minus the exact horizons' ao
};

Agreement against_exact_march(const Scene& s, int K) {
  const HeightField& f = s.field;
  const P1Result r = horizons(s, K);
  SweepSpec spec;
  spec.directions = K;
  std::vector<SweepDirection> dirs;
  for (int k = 0; k < K; ++k) dirs.push_back(plan_direction(f, spec, k));
  std::vector<float> err, h(K);
  double ao_diff = 0, inner = 0, axes = 0, other = 0;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      const std::size_t idx = f.index(i, j);
      truth::exact_horizons(f, dirs, i, j, h.data());
      const Vec3f n = s.normals[idx];
      double ao = 0;
      for (int k = 0; k < K; ++k) {
        err.push_back(std::fabs(r.horizon[idx * K + k] - h[k]));
        if (i > 0 && j > 0 && i < f.width - 1 && j < f.height - 1)
          inner = std::max(inner, double(err.back()));
        double& cls = (8 * k) % K == 0 ? axes : other;
        cls = std::max(cls, double(err.back()));
        ao += truth::ao_term(std::asin(std::clamp(double(h[k]), -1.0, 1.0)),
                             n.x * dirs[k].dx + n.y * dirs[k].dy, n.z);
      }
      ao_diff += r.ao[idx] - ao / K;
    }
  Agreement a;
  a.ao_bias = ao_diff / double(f.texel_count());
  a.above = double(std::count_if(err.begin(), err.end(), [](float e) { return e > 0.05f; })) / err.size();
  a.max = *std::max_element(err.begin(), err.end());
  a.max_inner = inner;
  a.max_axes = axes, a.max_other = other;
  std::nth_element(err.begin(), err.begin() + err.size() * 99 / 100, err.end());
  a.p99 = err[err.size() * 99 / 100];
  return a;
}

TEST(P1Rough, HorizonsMatchTheExactMarchOnRoughFields) {
  struct Case {
    const char* name;
    HeightField field;
  };
  const Case cases[] = {{"rough60", truth::rough_field(72, 64, 60, 0.7, 11)},
                        {"rough80", truth::rough_field(64, 72, 80, 0.7, 12)},
                        {"rough70 gain .5", truth::rough_field(64, 64, 70, 0.5, 13)}};
  for (const Case& c : cases)
    for (int K : {16, 24, 37}) {
      const Agreement a = against_exact_march(make_scene(c.field), K);
      std::printf(
          "[rough] %-16s K=%2d |sin h - exact|: p99 %.2g max %.2g (45deg %.2g, others %.2g); ao bias %+.2g\n",
          c.name, K, a.p99, a.max, a.max_axes, a.max_other, a.ao_bias);
      // Every texel (the border ring too) and every direction. The strip search is exact: measured max
      // 2e-6 (float heights); a blend of the two lines' casters gives p99 0.1-0.3, max 1.0-1.2 here.
      EXPECT_LE(a.p99, 0.005) << c.name << " K=" << K;
      EXPECT_LE(a.max, 0.02) << c.name << " K=" << K;
      EXPECT_LE(std::fabs(a.ao_bias), 0.001) << c.name << " K=" << K;
    }
}

TEST(P1Rough, HorizonsMatchTheExactMarchOnStepsAndSmoothFields) {
  struct Case {
    const char* name;
    HeightField field;
  };
  const Case cases[] = {{"step 20deg", truth::step_field(64, 64, 4, 20)},
                        {"terraces 30deg", truth::step_field(64, 64, 4, 30, 3, 12)},
                        {"fractal", truth::procedural(ProceduralKind::fractal, 64, 64, Wrap::clamp)},
                        // Thin fields: the sweep trims each line to its run across the field.
                        {"thin 300x4", truth::rough_field(300, 4, 60, 0.7, 14)},
                        {"thin 3x240", truth::rough_field(3, 240, 60, 0.7, 15)}};
  for (const Case& c : cases)
    for (int K : {16, 24}) {
      const Agreement a = against_exact_march(make_scene(c.field), K);
      std::printf(
          "[steps] %-16s K=%2d |sin h - exact|: p99 %.2g max %.2g (inside the border ring %.2g; 45deg %.2g, "
          "others %.2g); ao bias %+.2g\n",
          c.name, K, a.p99, a.max, a.max_inner, a.max_axes, a.max_other, a.ao_bias);
      EXPECT_LE(a.p99, 0.005) << c.name << " K=" << K;
      EXPECT_LE(a.max, 0.02) << c.name << " K=" << K;
      EXPECT_LE(std::fabs(a.ao_bias), 0.001) << c.name << " K=" << K;
    }
}

// The accuracy dial: at tolerance tau every horizon (the border ring and every direction included) lies
// within tau of the exact march's and never above it (to float rounding), on rough, stepped and smooth
// fields; larger tolerances must actually be used (some horizons differ: on every field at 0.05, on some
// at 0.01, where a small field's groups of lanes may leave no block to skip).
TEST(P1Tolerance, EveryHorizonWithinTheToleranceOfTheExactMarch) {
  struct Case {
    const char* name;
    HeightField field;
  };
  const Case cases[] = {{"rough70", truth::rough_field(61, 57, 70, 0.7, 32)},
                        {"rough65 gain .6", truth::rough_field(48, 40, 65, 0.6, 31)},
                        {"terraces 25deg", truth::step_field(58, 63, 3, 25, 5, 9)},
                        {"steps 40deg", truth::step_field(64, 50, 7, 40, 2, 6)},
                        {"fractal", truth::procedural(ProceduralKind::fractal, 60, 60, Wrap::clamp)}};
  constexpr double kRounding = 2e-5;  // float heights and the atan / sincos approximations
  long differ_at_1e2 = 0;
  for (const Case& c : cases) {
    const Scene s = make_scene(c.field);
    const HeightField& f = s.field;
    const int K = 19;  // mostly off the axes and diagonals
    SweepSpec spec;
    spec.directions = K;
    std::vector<SweepDirection> dirs;
    for (int k = 0; k < K; ++k) dirs.push_back(plan_direction(f, spec, k));
    std::vector<float> exact(f.texel_count() * K), h(K);
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) {
        truth::exact_horizons(f, dirs, i, j, h.data());
        std::copy(h.begin(), h.end(), exact.begin() + std::ptrdiff_t(f.index(i, j) * K));
      }
    for (double tau : {0.0, 1e-3, 1e-2, 0.05}) {
      const P1Result r = horizons(s, K, tau);
      double below = 0, above = 0;
      long differ = 0;
      for (std::size_t q = 0; q < exact.size(); ++q) {
        below = std::max(below, double(exact[q]) - r.horizon[q]);
        above = std::max(above, double(r.horizon[q]) - exact[q]);
        differ += std::fabs(double(r.horizon[q]) - exact[q]) > kRounding;
      }
      std::printf(
          "[tolerance] %-15s tau %.0e: exact - p1 at most %.2g, p1 - exact at most %.2g, %ld differ\n",
          c.name, tau, below, above, differ);
      EXPECT_LE(below, tau + kRounding) << c.name << " tau " << tau;
      EXPECT_LE(above, kRounding) << c.name << " tau " << tau;
      if (tau == 0) {
        EXPECT_EQ(differ, 0) << c.name;
      }
      if (tau >= 0.05) {
        EXPECT_GT(differ, 0) << c.name << ": the tolerance was not used";
      }
      if (tau == 1e-2) differ_at_1e2 += differ;
    }
  }
  EXPECT_GT(differ_at_1e2, 0) << "tolerance 0.01 was used on no field";
}

// A 4 m step along a column (x >= 32 high): on the triangulated surface the cell between the foot column
// (x = 31) and the top column (x = 32) is one plane rising 4 per texel, so from the foot, looking towards
// the step (cos phi > 0), tan h = 4 cos phi (the top edge casts it); from the top edge looking over the
// plateau the horizon is flat, and looking down the step the farthest point on the field casts it:
// tan h = -4 / (distance to the field's border along the ray).
// A horizon depends on height differences only, and P1 computes each crossing's rise before anything else:
// the same field 8192 units up (its heights multiples of 2^-10, so the raised copy holds them exactly) has
// the same horizons bit for bit, on clamp and repeat fields, and the raised clamp field's match the exact
// march to float rounding of the rises. (Lerping the absolute heights first rounds a crossing 8000 units up
// by up to 2.4e-4: 3e-4 in sin h at 0.7 texels.)
TEST(P1Rough, HorizonsAreTheSameAtAnyAbsoluteHeight) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    HeightField f = truth::rough_field(48, 40, 60, 0.6, 23);
    const float lo = *std::min_element(f.z.begin(), f.z.end());
    for (float& z : f.z) z = std::round((z - lo) * 1024.0f) / 1024.0f;
    f.wrap = wrap;
    HeightField up = f;
    for (float& z : up.z) z += 8192.0f;
    for (std::size_t t = 0; t < f.z.size(); ++t) ASSERT_EQ(double(up.z[t]) - 8192.0, double(f.z[t]));
    const Scene low_scene = make_scene(f), high_scene = make_scene(up);
    const P1Result a = horizons(low_scene, 16), b = horizons(high_scene, 16);
    ASSERT_EQ(a.horizon.size(), b.horizon.size());
    int differ = 0;
    for (std::size_t t = 0; t < a.horizon.size(); ++t) differ += a.horizon[t] != b.horizon[t];
    EXPECT_EQ(differ, 0) << (wrap == Wrap::clamp ? "clamp" : "repeat");
    if (wrap == Wrap::clamp) {
      const Agreement g = against_exact_march(high_scene, 16);
      EXPECT_LE(g.max, 1e-6);
    }
  }
}

// A repeat field's ray runs through the tiling to where its sweep line starts: wrap_periods whole periods
// beyond the texel's own along the direction's major axis (docs/methods/p1.md). The exact march over a clamp
// field holding that much of the tiling (periods either side along the major axis, and across it as far as
// a ray drifts, |g| <= 1) is the truth: every texel and direction of non-square rough and fractal tiles, at
// one and two periods, within float rounding of the rises.
TEST(P1Rough, RepeatHorizonsEqualTheExactMarchThroughTheTiling) {
  struct Case {
    const char* name;
    HeightField field;
  };
  std::vector<Case> cases;
  cases.push_back({"rough", truth::rough_field(37, 29, 60, 0.6, 31)});
  cases.push_back({"fractal", truth::procedural(ProceduralKind::fractal, 26, 34, Wrap::repeat)});
  const int K = 16;
  for (Case& c : cases)
    for (const int periods : {1, 2}) {
      HeightField& f = c.field;
      f.wrap = Wrap::repeat;
      Scene scene = make_scene(f);
      P1Params p;
      p.directions = K, p.wrap_periods = periods, p.horizon = true, p.vsky = p.direct = false;
      const P1Result r = compute_p1(scene, p, RunControl{});
      SweepSpec spec;
      spec.directions = K;
      double worst = 0;
      for (const bool x_major : {true, false}) {
        const int W = f.width, H = f.height, major = x_major ? W : H;
        const int along = periods * major, across = (periods + 1) * major + 2;
        HeightField big;
        big.texel_size = f.texel_size, big.wrap = Wrap::clamp;
        big.width = x_major ? 2 * along + W : 2 * across + W;
        big.height = x_major ? 2 * across + H : 2 * along + H;
        const int i0 = x_major ? along : across, j0 = x_major ? across : along;
        big.z.resize(big.texel_count());
        for (int j = 0; j < big.height; ++j)
          for (int i = 0; i < big.width; ++i)
            big.z[big.index(i, j)] = f.z[f.index(((i - i0) % W + W) % W, ((j - j0) % H + H) % H)];
        for (int k = 0; k < K; ++k) {
          const SweepDirection d = plan_direction(f, spec, k);
          if ((std::fabs(d.dx) >= std::fabs(d.dy)) != x_major) continue;
          for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
              const double exact = std::sin(truth::march_tri(big, i0 + i, j0 + j, d.dx, d.dy, 7));
              worst = std::max(worst, std::fabs(double(r.horizon[f.index(i, j) * K + k]) - exact));
            }
        }
      }
      EXPECT_LE(worst, 1e-5) << c.name << " periods " << periods;
    }
}

// Where a repeat tile is cut matters only through the occluders beyond its rays' wrap_periods periods: a
// rough 64 x 48 tile rolled by (13, 29) bakes the same ao at the rolled texels within what
// schemas/methods/p1.schema.json says (wrap_periods), less and less as the periods grow.
TEST(P1Rough, ARolledTileBakesTheSameAoWithinItsPeriods) {
  HeightField f = truth::rough_field(64, 48, 60, 0.6, 7);
  f.wrap = Wrap::repeat;
  HeightField rolled = f;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i)
      rolled.z[rolled.index((i + 13) % f.width, (j + 29) % f.height)] = f.z[f.index(i, j)];
  double worst[2] = {0, 0};
  for (const int periods : {1, 8}) {
    P1Params p;
    p.directions = 32, p.wrap_periods = periods, p.vsky = p.direct = false;
    const P1Result a = compute_p1(make_scene(f), p, RunControl{});
    const P1Result b = compute_p1(make_scene(rolled), p, RunControl{});
    double& w = worst[periods == 1 ? 0 : 1];
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i)
        w = std::max(w, double(std::fabs(a.ao[f.index(i, j)] -
                                         b.ao[rolled.index((i + 13) % f.width, (j + 29) % f.height)])));
  }
  std::printf("[rolled tile] max |d ao|: %.2g at 1 period, %.2g at 8\n", worst[0], worst[1]);
  EXPECT_LE(worst[0], 0.06);
  EXPECT_LE(worst[1], 0.001);
  EXPECT_LT(worst[1], worst[0] / 20);
}

TEST(P1Rough, StepAlongAColumnHasTheClosedFormHorizons) {
  const int W = 64, H = 64, K = 24;
  const Scene s = make_scene(truth::step_field(W, H, 4, 0));
  ASSERT_EQ(s.field.at(31, 10), 0.0f);
  ASSERT_EQ(s.field.at(32, 10), 4.0f);
  const P1Result r = horizons(s, K);
  SweepSpec spec;
  spec.directions = K;
  double worst_foot = 0, worst_top = 0, worst_down = 0;
  for (int k = 0; k < K; ++k) {
    const SweepDirection d = plan_direction(s.field, spec, k);
    for (int j = 16; j < 48; ++j) {
      if (d.dx > 0.2) {
        const double foot = std::sin(std::atan(4 * d.dx));
        worst_foot = std::max(worst_foot, std::fabs(r.horizon[s.field.index(31, j) * K + k] - foot));
        worst_top = std::max(worst_top, std::fabs(double(r.horizon[s.field.index(32, j) * K + k])));
      } else if (d.dx < -0.2) {
        const double tx = 32 / -d.dx;  // to x = 0
        const double ty = d.dy > 0 ? (H - 1 - j) / d.dy : (d.dy < 0 ? j / -d.dy : 1e300);
        const double down = std::sin(std::atan(-4 / std::min(tx, ty)));
        worst_down = std::max(worst_down, std::fabs(r.horizon[s.field.index(32, j) * K + k] - down));
      }
    }
  }
  std::printf(
      "[step] max |sin h - closed form|: foot %.2g, top over the plateau %.2g, top down the step %.2g\n",
      worst_foot, worst_top, worst_down);
  EXPECT_LE(worst_foot, 1e-5);
  EXPECT_LE(worst_top, 1e-5);
  EXPECT_LE(worst_down, 1e-4);
}

// The horizon layer by texel is the layer by direction transposed, bit for bit: the by-direction layer is
// written where the search's rows land, the by-texel one placed from a direction block's planes, four texels
// of four directions at a time with the rest one by one. Blocks of 1 to 8 directions (K = 10, 32, 40, 64 in
// 8 blocks) and a texel count that is no multiple of 4.
TEST(P1Rough, TheHorizonLayerByTexelIsTheLayerByDirectionTransposed) {
  const Scene s = make_scene(truth::rough_field(37, 29, 60, 0.7, 21));
  const std::size_t N = s.field.texel_count();
  for (const int K : {10, 32, 40, 64}) {
    P1Params p;
    p.directions = K;
    p.horizon = true;
    p.vsky = p.direct = false;
    const P1Result by_texel = compute_p1(s, p, RunControl{});
    p.horizon_by_direction = true;
    const P1Result by_direction = compute_p1(s, p, RunControl{});
    ASSERT_EQ(by_texel.horizon.size(), N * std::size_t(K));
    ASSERT_EQ(by_direction.horizon.size(), N * std::size_t(K));
    std::size_t differ = 0;
    for (std::size_t t = 0; t < N; ++t)
      for (int k = 0; k < K; ++k)
        differ += by_texel.horizon[t * std::size_t(K) + std::size_t(k)] !=
                          by_direction.horizon[std::size_t(k) * N + t]
                      ? 1
                      : 0;
    EXPECT_EQ(differ, 0u) << "K = " << K;
  }
}

}  // namespace
}  // namespace hfbake
