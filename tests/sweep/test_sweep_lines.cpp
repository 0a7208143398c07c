// The sweep driver's geometry against its documented rules: walk order, heights equal to the field's
// bilinear surface, results reaching texel centers with weights that reproduce the texel position,
// coverage (every texel's weights sum to 1), repeat-mode warm-up, determinism and cancellation.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <atomic>
#include <cmath>

#include "field/procedural.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake {
namespace {

HeightField test_field(int w, int h, Wrap wrap) {
  ProceduralSpec s;
  s.kind = ProceduralKind::fractal;
  s.width = w;
  s.height = h;
  s.seed = 3;
  return make_procedural(s, 0.5, wrap);
}

// A worker writing each receiver's texel coordinates (x, y) and height: gathered, they must give back the
// texel center (linear in the minor coordinate) and the field height exactly where a sample hits a texel.
struct PositionWorker {
  void operator()(const SweepLine& line, float* out) const {
    for (int n = line.first_receiver; n < line.count; ++n) {
      float* o = out + std::size_t(n - line.first_receiver) * 3;
      o[0] = float(line.x(n));
      o[1] = float(line.y(n));
      o[2] = line.z[n];
    }
  }
};

TEST(SweepLines, GatheredPositionsAreTexelCenters) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    for (int K : {1, 3, 8, 12, 16}) {
      const HeightField f = test_field(23, 17, wrap);
      SweepSpec spec;
      spec.directions = K;
      spec.channels = 3;
      spec.batch = 3;
      std::vector<int> visits(f.texel_count() * K, 0);
      sweep_lines(
          f, spec, RunControl{}, [] { return PositionWorker{}; },
          [&](int k, int i, int j, const TexelTaps& t) {
            ++visits[f.index(i, j) * K + k];
            const float x = t.value(0), y = t.value(1);
            if (wrap == Wrap::repeat) {
              // lo and hi can be periodic copies one period apart: compare each tap modulo the period.
              for (const float* p : {t.lo, t.hi}) {
                const float dxp = p[0] - i - std::round((p[0] - i) / f.width) * f.width;
                const float dyp = p[1] - j - std::round((p[1] - j) / f.height) * f.height;
                EXPECT_LE(std::hypot(dxp, dyp), 1.5f);
              }
              return;
            }
            // Every tap lies on the field (clamp: points off the field are never receivers).
            for (const float* p : {t.lo, t.hi}) {
              if (p == t.hi && t.w_hi == 0) continue;  // a tap with no weight
              EXPECT_GE(p[0], -1e-5f);
              EXPECT_GE(p[1], -1e-5f);
              EXPECT_LE(p[0], f.width - 1 + 1e-5f);
              EXPECT_LE(p[1], f.height - 1 + 1e-5f);
            }
            const SweepDirection d = plan_direction(f, spec, k);
            const int v0 = d.x_major ? j : i;
            if (t.w_hi == 0 && (v0 == 0 || v0 == d.n_minor - 1)) {  // border rows: the inside tap alone
              EXPECT_LT(std::hypot(x - i, y - j), 1.0f);
              return;
            }
            EXPECT_NEAR(x, i, 2e-5) << "K " << K << " k " << k << " texel " << i << "," << j;
            EXPECT_NEAR(y, j, 2e-5) << "K " << K << " k " << k << " texel " << i << "," << j;
            if (t.w_hi == 0) {
              EXPECT_EQ(t.value(2), f.z[f.index(i, j)]);
            }
          });
      for (int v : visits) ASSERT_EQ(v, 1);
    }
  }
}

TEST(SweepLines, WalkOrderHeightsAndInsideRun) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    const HeightField f = test_field(19, 26, wrap);
    SweepSpec spec;
    spec.directions = 24;
    for (int k = 0; k < spec.directions; ++k) {
      const SweepDirection d = plan_direction(f, spec, k);
      std::vector<float> z(d.count);
      for (int l = d.line_begin; l < d.line_end; ++l) {
        const SweepLine line = sampled_line(f, d, l, z.data());
        // Reading a transposed copy (what the driver does for y-major lines) gives the same bits.
        std::vector<float> zt(d.count), transposed(f.texel_count());
        for (int j = 0; j < f.height; ++j)
          for (int i = 0; i < f.width; ++i) transposed[std::size_t(i) * f.height + j] = f.z[f.index(i, j)];
        int tb, te;
        sample_line(f, d, l, zt.data(), &tb, &te, transposed.data());
        ASSERT_EQ(zt, z);
        ASSERT_EQ(tb, line.inside_begin);
        ASSERT_EQ(te, line.inside_end);
        for (int n = 0; n < d.count; ++n) {
          // Heights are the field's own bilinear surface, bit for bit.
          ASSERT_EQ(z[n], f.bilinear(line.x(n), line.y(n))) << k << " " << l << " " << n;
          const bool on_field =
              line.x(n) >= 0 && line.x(n) <= f.width - 1 && line.y(n) >= 0 && line.y(n) <= f.height - 1;
          if (wrap == Wrap::clamp) {
            ASSERT_EQ(line.is_terrain(n), on_field) << k << " " << l << " " << n;
          }
          if (n > 0) {  // sample n - 1 lies towards phi_k from sample n, one step away
            const double ex = (line.x(n - 1) - line.x(n)) * f.texel_size;
            const double ey = (line.y(n - 1) - line.y(n)) * f.texel_size;
            ASSERT_NEAR(std::hypot(ex, ey), d.step, 1e-9);
            ASSERT_NEAR(ex * d.dx + ey * d.dy, d.step, 1e-9);
            ASSERT_NEAR(line.s(n) - line.s(n - 1), d.step, 1e-9);
          }
          const Vec3 p = line.position(n);
          ASSERT_EQ(p.z, double(z[n]));
          // height_taps interpolate the height exactly like the sampler.
          const TexelPair hp = line.height_taps(n, f);
          ASSERT_EQ(z[n], f.z[hp.texel[0]] * hp.weight[0] + f.z[hp.texel[1]] * hp.weight[1]);
        }
        if (wrap == Wrap::repeat) {
          ASSERT_EQ(d.first_receiver, d.n_major);  // wrap_periods = 1
          ASSERT_EQ(line.inside_begin, 0);
          ASSERT_EQ(line.inside_end, d.count);
        }
      }
    }
  }
}

// Scattering with receiver_texels is the transpose of the gather: every texel's weights sum to 1, and the
// gather's weights are the same numbers.
TEST(SweepLines, ReceiverTexelsCoverEveryTexelOnce) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    const HeightField f = test_field(21, 14, wrap);
    SweepSpec spec;
    spec.directions = 20;
    for (int k = 0; k < spec.directions; ++k) {
      const SweepDirection d = plan_direction(f, spec, k);
      std::vector<double> wsum(f.texel_count(), 0.0);
      std::vector<float> z(d.count);
      for (int l = d.line_begin; l < d.line_end; ++l) {
        const SweepLine line = sampled_line(f, d, l, z.data());
        for (int n = d.first_receiver; n < d.count; ++n) {
          const TexelPair p = line.receiver_texels(n, f);
          for (int e = 0; e < 2; ++e)
            if (p.texel[e] >= 0) wsum[p.texel[e]] += p.weight[e];
        }
      }
      for (std::size_t t = 0; t < wsum.size(); ++t)
        ASSERT_NEAR(wsum[t], 1.0, 1e-6) << "k " << k << " texel " << t;
    }
  }
}

// The scatter rule (receiver_texels) and the gather rule (texel_taps) are the same weights.
TEST(SweepLines, ScatterEqualsGather) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    const HeightField f = test_field(21, 14, wrap);
    SweepSpec spec;
    spec.directions = 11;
    spec.channels = 3;
    std::vector<double> gathered(f.texel_count() * spec.directions, 0.0);
    sweep_lines(
        f, spec, RunControl{}, [] { return PositionWorker{}; },
        [&](int k, int i, int j, const TexelTaps& t) {
          gathered[f.index(i, j) * spec.directions + k] = t.value(2);
        });
    for (int k = 0; k < spec.directions; ++k) {
      const SweepDirection d = plan_direction(f, spec, k);
      std::vector<double> scattered(f.texel_count(), 0.0);
      std::vector<float> z(d.count);
      for (int l = d.line_begin; l < d.line_end; ++l) {
        const SweepLine line = sampled_line(f, d, l, z.data());
        for (int n = d.first_receiver; n < d.count; ++n) {
          const TexelPair p = line.receiver_texels(n, f);
          for (int e = 0; e < 2; ++e)
            if (p.texel[e] >= 0) scattered[p.texel[e]] += double(p.weight[e]) * z[n];
        }
      }
      for (std::size_t t = 0; t < scattered.size(); ++t)
        ASSERT_NEAR(scattered[t], gathered[t * spec.directions + k], 1e-4) << "k " << k << " texel " << t;
    }
  }
}

TEST(SweepLines, ExplicitAzimuths) {
  const HeightField f = test_field(20, 20, Wrap::clamp);
  SweepSpec spec;
  spec.azimuths = {0.3, kPi / 4, 2.0, -kPi / 2};
  spec.channels = 3;
  std::vector<int> seen(4, 0);
  sweep_lines(
      f, spec, RunControl{}, [] { return PositionWorker{}; },
      [&](int k, int i, int j, const TexelTaps& t) {
        ++seen[k];
        if (k == 1 || k == 3) {  // a diagonal and an axis: exact
          EXPECT_EQ(t.w_hi, 0.0f);
          EXPECT_EQ(t.lo[0], float(i));
          EXPECT_EQ(t.lo[1], float(j));
        }
      });
  for (int c : seen) EXPECT_EQ(c, 400);
  const SweepDirection d = plan_direction(f, spec, 2);
  EXPECT_NEAR(d.dx, std::cos(2.0), 1e-15);
  EXPECT_NEAR(d.dy, std::sin(2.0), 1e-15);
}

TEST(SweepLines, AxisAndDiagonalDirectionsHitTexelsExactly) {
  const HeightField f = test_field(16, 16, Wrap::clamp);
  SweepSpec spec;
  spec.directions = 8;
  spec.channels = 3;
  sweep_lines(
      f, spec, RunControl{}, [] { return PositionWorker{}; },
      [&](int, int i, int j, const TexelTaps& t) {
        ASSERT_EQ(t.w_hi, 0.0f);
        ASSERT_EQ(t.lo[0], float(i));
        ASSERT_EQ(t.lo[1], float(j));
        ASSERT_EQ(t.lo[2], f.z[f.index(i, j)]);
      });
}

// A line-order-dependent worker (a running max along the walk) gives the same bits for 1 and 2 threads.
struct RunningMax {
  void operator()(const SweepLine& line, float* out) const {
    float m = -1e30f;
    for (int n = 0; n < line.count; ++n) {
      if (n >= line.first_receiver) out[n - line.first_receiver] = m - line.z[n];
      if (line.is_terrain(n)) m = std::max(m, line.z[n]);
    }
  }
};

TEST(SweepLines, DeterministicForAnyThreadCount) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    const HeightField f = test_field(64, 48, wrap);
    SweepSpec spec;
    spec.directions = 13;
    auto run = [&](int threads) {
      std::vector<float> acc(f.texel_count(), 0.0f);
      tbb::task_arena arena(threads);
      arena.execute([&] {
        sweep_lines(
            f, spec, RunControl{}, [] { return RunningMax{}; },
            [&](int, int i, int j, const TexelTaps& t) { acc[f.index(i, j)] += t.value(0); });
      });
      return acc;
    };
    EXPECT_EQ(run(1), run(2));
  }
}

TEST(SweepLines, CancelThrows) {
  const HeightField f = test_field(32, 32, Wrap::clamp);
  std::atomic<bool> cancel{true};
  RunControl rc;
  rc.cancel = &cancel;
  SweepSpec spec;
  EXPECT_THROW(sweep_lines(
                   f, spec, rc, [] { return RunningMax{}; }, [](int, int, int, const TexelTaps&) {}),
               Cancelled);
}

TEST(SweepLines, ProgressReachesOne) {
  const HeightField f = test_field(16, 16, Wrap::clamp);
  std::atomic<int> calls{0};
  double last = 0;
  RunControl rc;
  rc.progress = [&](double p) {
    ++calls;
    last = p;
  };
  SweepSpec spec;
  spec.directions = 10;
  spec.batch = 4;
  sweep_lines(
      f, spec, rc, [] { return RunningMax{}; }, [](int, int, int, const TexelTaps&) {});
  EXPECT_EQ(calls.load(), 3);
  EXPECT_DOUBLE_EQ(last, 1.0);
}

}  // namespace
}  // namespace hfbake
