// The sweep driver's geometry against its documented rules: walk order, heights equal to the field's
// bilinear surface, results reaching texel centers with weights that reproduce the texel position,
// coverage (every texel's weights sum to 1), repeat-mode warm-up, determinism and cancellation.
#include <gtest/gtest.h>

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>

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
      spec.buffers.batch = 3;
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

// sampling.heights off (P1's far field): the lines reach the visitor with the same geometry and results
// slots, without heights; the gathered results are the same bits. Fails if the unsampled line loses a field
// (its distances s(n), positions or receivers) or still carries heights.
TEST(SweepLines, UnsampledLinesKeepTheirGeometry) {
  struct GeometryWorker {
    bool expect_heights = true;
    void operator()(const SweepLine& line, float* out) const {
      EXPECT_EQ(line.z != nullptr, expect_heights);
      for (int n = line.first_receiver; n < line.count; ++n) {
        float* o = out + std::size_t(n - line.first_receiver) * 3;
        o[0] = float(line.x(n)), o[1] = float(line.y(n)), o[2] = float(line.s(n));
      }
    }
  };
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat})
    for (int height : {48, 3}) {  // 64 x 3: thin, trimmed lines
      const HeightField f = test_field(64, height, wrap);
      auto run = [&](bool sample) {
        SweepSpec spec;
        spec.directions = 13;
        spec.channels = 3;
        spec.sampling.heights = sample;
        std::vector<float> acc(f.texel_count() * 13 * 9);  // per texel and direction: lo, hi, strip
        sweep_lines(
            f, spec, RunControl{}, [&] { return GeometryWorker{sample}; },
            [&](int k, int i, int j, const TexelTaps& t) {
              float* a = acc.data() + (f.index(i, j) * 13 + std::size_t(k)) * 9;
              for (int c = 0; c < 3; ++c) a[c] = t.lo[c], a[3 + c] = t.hi[c], a[6 + c] = t.strip[c];
            });
        return acc;
      };
      const std::vector<float> sampled = run(true), unsampled = run(false);
      ASSERT_FALSE(sampled.empty());
      EXPECT_EQ(sampled, unsampled) << (wrap == Wrap::clamp ? "clamp " : "repeat ") << height;
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
  spec.buffers.batch = 4;
  sweep_lines(
      f, spec, rc, [] { return RunningMax{}; }, [](int, int, int, const TexelTaps&) {});
  EXPECT_EQ(calls.load(), 3);
  EXPECT_DOUBLE_EQ(last, 1.0);
}

// ---- Streaming: windows of lines give the visitors the same values as whole buffers ----------------------

// A worker whose every result depends on the line, the receiver and the walk so far: a result read from the
// wrong line, column or slot of the ring changes what the visitor records.
struct TagWorker {
  int channels = 1;
  void operator()(const SweepLine& line, float* out) const {
    float m = -1e30f;
    for (int n = 0; n < line.count; ++n) {
      if (n >= line.first_receiver)
        for (int c = 0; c < channels; ++c)
          out[std::size_t(n - line.first_receiver) * channels + c] = float(line.line) * 4096.0f +
                                                                     float(n - line.first_receiver) +
                                                                     0.125f * float(c) + (m - line.z[n]);
      if (line.is_terrain(n)) m = std::max(m, line.z[n]);
    }
  }
};

// Everything the tile visitor gets, per (k, texel) in the order it arrived, and the texels' k order.
struct TileRecord {
  std::vector<float> data;    // [(texel * K + k) * stride ...]
  std::vector<int> order_ok;  // per texel: 1 while its directions arrived in ascending k
  std::vector<double> progress;
};

TileRecord record_tiled(const HeightField& f, SweepSpec spec) {
  const int K = spec.azimuths.empty() ? spec.directions : int(spec.azimuths.size()), C = spec.channels;
  spec.tile.taps = true;
  spec.tile.nearest = true;
  spec.buffers.zero = false;
  const std::size_t stride = std::size_t(4 * C + 3);
  TileRecord rec;
  rec.data.assign(f.texel_count() * K * stride, -7.0f);
  rec.order_ok.assign(f.texel_count(), 1);
  std::vector<int> last(f.texel_count(), -1);
  RunControl rc;
  rc.progress = [&](double p) { rec.progress.push_back(p); };
  sweep_lines_tiled(
      f, spec, rc, [&] { return TagWorker{C}; },
      [&](const SweepTile& t) {
        const std::size_t plane = std::size_t(t.width) * t.height;
        for (int y = 0; y < t.height; ++y)
          for (int x = 0; x < t.width; ++x) {
            const std::size_t texel = f.index(t.i0 + x, t.j0 + y), at = std::size_t(y) * t.width + x;
            if (t.k <= last[texel]) rec.order_ok[texel] = 0;
            last[texel] = t.k;
            float* o = rec.data.data() + (texel * K + t.k) * stride;
            for (int c = 0; c < C; ++c) {
              o[4 * c + 0] = t.value[c * plane + at];
              o[4 * c + 1] = t.nearest[c * plane + at];
              o[4 * c + 2] = t.lo[c * plane + at];
              o[4 * c + 3] = t.hi[c * plane + at];
            }
            o[4 * C + 0] = t.w_hi[at];
            o[4 * C + 1] = t.off_lo[at];
            o[4 * C + 2] = t.off_hi[at];
          }
      });
  return rec;
}

// The per-texel visitor's taps, per (k, texel).
std::vector<float> record_texels(const HeightField& f, SweepSpec spec) {
  const int K = spec.azimuths.empty() ? spec.directions : int(spec.azimuths.size()), C = spec.channels;
  const std::size_t stride = std::size_t(2 * C + 1);
  std::vector<float> data(f.texel_count() * K * stride, -7.0f);
  sweep_lines(
      f, spec, RunControl{}, [&] { return TagWorker{C}; },
      [&](int k, int i, int j, const TexelTaps& t) {
        float* o = data.data() + (f.index(i, j) * K + k) * stride;
        for (int c = 0; c < C; ++c) o[2 * c] = t.lo[c], o[2 * c + 1] = t.hi[c];
        o[2 * C] = t.w_hi;
      });
  return data;
}

bool any_stream(const HeightField& f, const SweepSpec& spec) {
  const int K = spec.azimuths.empty() ? spec.directions : int(spec.azimuths.size());
  std::vector<SweepDirection> dirs;
  for (int k = 0; k < K; ++k) dirs.push_back(plan_direction(f, spec, k));
  for (const detail::SweepBatch& b : detail::plan_sweep(f, spec, dirs).batches)
    if (b.stream) return true;
  return false;
}

TEST(SweepStream, WindowsGiveTheSameVisitorData) {
  const std::vector<double> azimuths = {0.0,      1e-3,        kPi / 4,       kPi / 2 - 1e-3, 2.0, kPi,
                                        -kPi / 4, 3 * kPi / 4, kPi / 2 + 0.3, -0.2,           4.5};
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat})
    for (auto [w, h] : {std::pair{37, 91}, std::pair{200, 13}, std::pair{64, 64}})
      for (int C : {1, 4})
        for (int set = 0; set < 3; ++set) {
          const HeightField f = test_field(w, h, wrap);
          SweepSpec whole;
          whole.channels = C;
          if (set == 0) whole.directions = 1;
          if (set == 1) whole.directions = 37;
          if (set == 2) whole.azimuths = azimuths;
          whole.buffers.batch = 8;
          whole.buffers.max_bytes = std::size_t(1) << 40;
          ASSERT_FALSE(any_stream(f, whole));
          const TileRecord a = record_tiled(f, whole);
          const std::vector<float> ta = record_texels(f, whole);
          // Tiny (one line a chunk, window = a tile's span) and medium (chunks of several lines) budgets.
          std::size_t largest = 0;  // the largest direction's whole buffer
          for (int k = 0; k < (set == 2 ? int(azimuths.size()) : whole.directions); ++k) {
            const SweepDirection d = plan_direction(f, whole, k);
            largest = std::max(largest, std::size_t(d.lines()) * d.stride() * C * sizeof(float));
          }
          for (std::size_t bytes : {std::size_t(1), largest / 3}) {
            SweepSpec small = whole;
            small.buffers.max_bytes = bytes;
            ASSERT_TRUE(any_stream(f, small));
            const TileRecord b = record_tiled(f, small);
            const std::string what = std::string(wrap == Wrap::clamp ? "clamp " : "repeat ") +
                                     std::to_string(w) + "x" + std::to_string(h) + " C " + std::to_string(C) +
                                     " set " + std::to_string(set) + " bytes " + std::to_string(bytes);
            ASSERT_EQ(a.data.size(), b.data.size());
            EXPECT_EQ(std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)), 0) << what;
            for (std::size_t t = 0; t < b.order_ok.size(); ++t)
              ASSERT_TRUE(b.order_ok[t] && a.order_ok[t]) << what;
            for (float v : b.data) ASSERT_NE(v, -7.0f) << what;  // every (k, texel) visited
            for (std::size_t p = 1; p < b.progress.size(); ++p) ASSERT_GE(b.progress[p], b.progress[p - 1]);
            ASSERT_FALSE(b.progress.empty());
            EXPECT_DOUBLE_EQ(b.progress.back(), 1.0) << what;
            const std::vector<float> tb = record_texels(f, small);
            EXPECT_EQ(std::memcmp(ta.data(), tb.data(), ta.size() * sizeof(float)), 0) << what;
          }
        }
}

// The tile's line range against every texel's taps read from a buffer (texel_taps' own arithmetic).
TEST(SweepStream, TileLinesAreExactlyTheTapsLines) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat})
    for (auto [w, h] : {std::pair{37, 91}, std::pair{200, 13}, std::pair{70, 70}, std::pair{5, 40}}) {
      const HeightField f = test_field(w, h, wrap);
      SweepSpec spec;
      spec.azimuths = {0.0, 1e-3, kPi / 4, kPi / 2 - 1e-3, 2.0, kPi, -kPi / 4, 3 * kPi / 4, 1.1, -2.9, 4.5};
      for (int k = 0; k < int(spec.azimuths.size()); ++k) {
        const SweepDirection d = plan_direction(f, spec, k);
        std::vector<float> buffer(std::size_t(d.lines()) * d.stride());
        for (int j0 = 0; j0 < h; j0 += 32)
          for (int i0 = 0; i0 < w; i0 += 32) {
            std::vector<char> read(std::size_t(d.lines()), 0);
            for (int j = j0; j < std::min(h, j0 + 32); ++j)
              for (int i = i0; i < std::min(w, i0 + 32); ++i) {
                const TexelTaps t = texel_taps(d, buffer.data(), 1, i, j);
                read[std::size_t(t.lo - buffer.data()) / d.stride()] = 1;
                read[std::size_t(t.hi - buffer.data()) / d.stride()] = 1;
              }
            int lo, hi;
            sweep_tile_lines(d, i0, std::min(w, i0 + 32), j0, std::min(h, j0 + 32), &lo, &hi);
            // Tight: the last line is read, the first too unless a clamp border row kept its inside tap
            // alone.
            ASSERT_TRUE(read[lo] || (!d.repeat && (d.x_major ? j0 : i0) == 0 && read[lo + 1]))
                << k << " tile " << i0 << "," << j0;
            ASSERT_TRUE(read[hi]) << k << " tile " << i0 << "," << j0;
            for (int l = 0; l < d.lines(); ++l) {
              const bool inside = lo <= hi ? (l >= lo && l <= hi) : (l >= lo || l <= hi);
              if (read[l]) {
                ASSERT_TRUE(inside) << k << " tile " << i0 << "," << j0 << " line " << l;
              }
            }
          }
      }
    }
}

// A worker recording, per direction, the span of addresses its outputs occupy (one allocation each).
struct SpanWorker {
  std::vector<std::atomic<std::uintptr_t>>* lo;
  std::vector<std::atomic<std::uintptr_t>>* hi;
  int channels;
  void operator()(const SweepLine& line, float* out) const {
    const std::size_t n = std::size_t(line.receivers()) * channels;
    const std::uintptr_t a = std::uintptr_t(out), b = std::uintptr_t(out + n);
    std::atomic<std::uintptr_t>&l = (*lo)[line.dir->k], &h = (*hi)[line.dir->k];
    for (std::uintptr_t v = l.load(); a < v && !l.compare_exchange_weak(v, a);) {
    }
    for (std::uintptr_t v = h.load(); b > v && !h.compare_exchange_weak(v, b);) {
    }
    std::fill_n(out, n, 0.0f);
  }
};

// A tall field (48 wide): x-major directions have a line per row, y-major ones a sample per row, so clamp
// mode's whole untrimmed buffers would grow with the height (y-major: with its square); the driver's (lines
// trimmed to the field, streamed) stay within the budget (which batching fills: whole buffers of several
// directions) and grow no faster than the texels.
TEST(SweepStream, BufferBytesBoundTheResultsAndStayFlatForTallFields) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    SweepSpec spec;
    spec.directions = 16;
    spec.channels = 4;
    spec.buffers.batch = 8;
    spec.buffers.max_bytes = std::size_t(32) << 20;
    std::size_t previous = 0;
    for (int h : {4096, 16384}) {
      const HeightField f = test_field(48, h, wrap);
      std::size_t whole = 0;  // the largest direction's whole buffer, were its lines not trimmed
      for (int k = 0; k < spec.directions; ++k) {
        const SweepDirection d = plan_direction(f, spec, k);
        whole = std::max(whole, std::size_t(d.lines()) * d.n_major * spec.channels * sizeof(float));
      }
      const std::size_t bound = sweep_buffer_bytes(f, spec);
      // Within the budget plus the small parts (line tables, tile orders, per-thread heights and tiles).
      EXPECT_LT(bound, spec.buffers.max_bytes + (std::size_t(2) << 20)) << h;
      if (wrap == Wrap::clamp) {
        if (h == 16384) {
          EXPECT_LT(bound, whole / 16);  // the whole buffer: about 1.8 GB
        }
        if (previous) {  // 16384 - 4096 rows more: at most 16 bytes a texel more (transposed copy: 4)
          EXPECT_LT(double(bound), double(previous) + 16.0 * 48 * (16384 - 4096)) << h;
        }
        previous = bound;
      }
      std::vector<std::atomic<std::uintptr_t>> lo(spec.directions), hi(spec.directions);
      for (auto& v : lo) v = UINTPTR_MAX;
      for (auto& v : hi) v = 0;
      sweep_lines(
          f, spec, RunControl{},
          [&] {
            return SpanWorker{&lo, &hi, spec.channels};
          },
          [](int, int, int, const TexelTaps&) {});
      for (int k = 0; k < spec.directions; ++k)
        EXPECT_LE(hi[k].load() - lo[k].load(), bound) << h << " " << k;
    }
  }
}

// The strip gather (SweepSpec::tile.strip, what P1's far field reads): every texel of every direction gets
// the result of the line just above it on its column, line l with l - 1 <= v0 - u * slope < l (checked in
// long double from the direction's slope, not with strip_line), also on the clamp border rows where one
// of its two lines runs off the field, and the same whether the lines stream or not.
struct LineColumnWorker {
  static constexpr int channels() { return 2; }
  void operator()(const SweepLine& line, float* out) const {
    for (int n = line.first_receiver; n < line.count; ++n) {
      out[2 * (n - line.first_receiver)] = float(line.line);
      out[2 * (n - line.first_receiver) + 1] = float(line.dir->u(n));
    }
  }
};

TEST(SweepLines, StripGatherGivesEachTexelTheLineAboveIt) {
  int checked = 0, bad = 0;
  for (const Wrap wrap : {Wrap::clamp, Wrap::repeat})
    for (const auto& [w, h] : {std::pair{37, 91}, std::pair{64, 64}, std::pair{200, 13}})
      for (const std::size_t budget : {std::size_t(1), std::size_t(256) << 20}) {
        const HeightField f = test_field(w, h, wrap);
        SweepSpec spec;
        spec.directions = 37;
        spec.channels = 2;
        spec.tile.strip = true;
        spec.tile.values = spec.tile.nearest = false;
        spec.buffers.max_bytes = budget;
        sweep_lines_tiled(
            f, spec, RunControl{}, [] { return LineColumnWorker{}; },
            [&](const SweepTile& t) {
              const SweepDirection d = plan_direction(f, spec, t.k);
              const std::size_t plane = std::size_t(t.width) * t.height;
              for (int y = 0; y < t.height; ++y)
                for (int x = 0; x < t.width; ++x) {
                  const int i = t.i0 + x, j = t.j0 + y, u = d.x_major ? i : j, v0 = d.x_major ? j : i;
                  const float line = t.strip[std::size_t(y) * t.width + x];
                  const float col = t.strip[plane + std::size_t(y) * t.width + x];
                  const long double g = (long double)v0 - (long double)u * (long double)d.slope;
                  long double below = g - ((long double)line - 1);  // in [0, 1) (repeat: modulo n_minor)
                  if (d.repeat) below -= d.n_minor * std::floor(below / d.n_minor);
                  ++checked;
                  if (!(below >= 0 && below < 1) || int(col) != u) ++bad;
                }
            });
      }
  EXPECT_GT(checked, 0);
  EXPECT_EQ(bad, 0) << "of " << checked;
}

// ---- Thin fields: trimmed lines ---------------------------------------------------------------------------

// A worker whose results depend on what a real one reads: the sample's position and distance along the walk,
// its height, and the terrain before it (the steepest slope up to the last 48 terrain samples, as a horizon
// sweep sees it); off-field receivers too (a tap with no weight may read them).
struct SlopeWorker {
  void operator()(const SweepLine& line, float* out) const {
    for (int n = line.first_receiver; n < line.count; ++n) {
      float* o = out + std::size_t(n - line.first_receiver) * 4;
      double best = -1e30;
      for (int m = std::max(line.inside_begin, n - 48); m < std::min(n, line.inside_end); ++m)
        best = std::max(best, (double(line.z[m]) - line.z[n]) / (line.s(n) - line.s(m)));
      o[0] = float(line.x(n));
      o[1] = float(line.y(n));
      o[2] = line.z[n] + float(line.s(n));
      o[3] = float(best);
    }
  }
};

// Everything sweep_lines_tiled hands the visitor with both taps apart, per (texel, k).
std::vector<float> record_slopes(const HeightField& f, SweepSpec spec) {
  const int K = spec.azimuths.empty() ? spec.directions : int(spec.azimuths.size());
  spec.channels = 4;
  spec.tile.taps = true;
  const std::size_t stride = 4 * 4 + 3;
  std::vector<float> data(f.texel_count() * K * stride, -7.0f);
  sweep_lines_tiled(
      f, spec, RunControl{}, [] { return SlopeWorker{}; },
      [&](const SweepTile& t) {
        const std::size_t plane = std::size_t(t.width) * t.height;
        for (int y = 0; y < t.height; ++y)
          for (int x = 0; x < t.width; ++x) {
            const std::size_t at = std::size_t(y) * t.width + x;
            float* o = data.data() + (f.index(t.i0 + x, t.j0 + y) * K + t.k) * stride;
            for (int c = 0; c < 4; ++c) {
              o[4 * c + 0] = t.value[c * plane + at];
              o[4 * c + 1] = t.nearest[c * plane + at];
              o[4 * c + 2] = t.lo[c * plane + at];
              // A tap with no weight: only whether it is finite matters (it may be off the field).
              o[4 * c + 3] =
                  t.w_hi[at] > 0 ? t.hi[c * plane + at] : float(std::isfinite(t.hi[c * plane + at]));
            }
            o[16] = t.w_hi[at], o[17] = t.off_lo[at], o[18] = t.off_hi[at];
          }
      });
  return data;
}

// Lines trimmed to a thin field's run give the visitors the same bits as whole lines, for either long axis,
// whole buffers or streamed.
TEST(SweepThin, TrimmedLinesGiveTheSameBitsAsWholeLines) {
  const std::vector<double> azimuths = {0.0,  1e-3, 0.05,     kPi / 4,     kPi / 2 - 1e-3,
                                        2.0,  kPi,  -kPi / 4, 3 * kPi / 4, kPi / 2 + 0.3,
                                        -0.2, 4.5,  3.0};
  for (auto [w, h] : {std::pair{700, 2}, std::pair{3, 500}, std::pair{400, 5}, std::pair{61, 13}})
    for (std::size_t budget : {std::size_t(1) << 30, std::size_t(4096)}) {
      const HeightField f = test_field(w, h, Wrap::clamp);
      SweepSpec spec;
      spec.azimuths = azimuths;
      spec.buffers.max_bytes = budget;
      int trimmed = 0;
      for (int k = 0; k < int(azimuths.size()); ++k) trimmed += plan_direction(f, spec, k).span > 0;
      if (w * h != 61 * 13) {
        EXPECT_GE(trimmed, 3) << w << "x" << h;
      }
      SweepSpec whole = spec;
      whole.sampling.trim_thin = false;
      const std::vector<float> a = record_slopes(f, whole), b = record_slopes(f, spec);
      ASSERT_EQ(a.size(), b.size());
      for (float v : b) ASSERT_NE(v, -7.0f);
      EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0)
          << w << "x" << h << " budget " << budget;
    }
}

// Counts the samples handed to the line workers.
struct CountWorker {
  std::atomic<std::uint64_t>* samples;
  void operator()(const SweepLine& line, float*) const { *samples += std::uint64_t(line.count); }
};

std::uint64_t sweep_samples(const HeightField& f, const SweepSpec& spec) {
  std::atomic<std::uint64_t> samples{0};
  sweep_lines(
      f, spec, RunControl{}, [&] { return CountWorker{&samples}; }, [](int, int, int, const TexelTaps&) {});
  return samples;
}

// A W x 2 field costs what a 2 x W field costs, linear in W: the work (samples the workers walk) and the
// buffers (sweep_buffer_bytes, the memory estimate's part). Untrimmed, W x 2 walked about K W^2 / 4 samples.
TEST(SweepThin, WorkAndBuffersOfThinFieldsAreLinearInTheTexels) {
  SweepSpec spec;
  spec.directions = 64;
  spec.channels = 2;
  std::uint64_t previous[2] = {0, 0};
  std::size_t previous_bytes[2] = {0, 0};
  for (int W : {4000, 16000}) {
    const HeightField wide = test_field(W, 2, Wrap::clamp), tall = test_field(2, W, Wrap::clamp);
    const std::uint64_t sw = sweep_samples(wide, spec), st = sweep_samples(tall, spec);
    const double texels = 2.0 * W, K = spec.directions;
    // Axis directions walk every texel once; the others at most 2 n_major (n_minor + 2) + span per line end.
    EXPECT_GE(double(sw), K * texels * 0.5) << W;
    EXPECT_LE(double(sw), 12 * K * texels) << W;
    EXPECT_LE(double(st), 12 * K * texels) << W;
    EXPECT_LT(std::max(sw, st), 3 * std::min(sw, st)) << W << ": " << sw << " vs " << st;
    const std::size_t bw = sweep_buffer_bytes(wide, spec), bt = sweep_buffer_bytes(tall, spec);
    EXPECT_LT(std::max(bw, bt), 3 * std::min(bw, bt)) << W << ": " << bw << " vs " << bt;
    if (previous[0]) {  // 4 x the texels: 4 x the work, not 16 x
      EXPECT_LT(double(sw), 5.0 * double(previous[0])) << sw << " after " << previous[0];
      EXPECT_LT(double(st), 5.0 * double(previous[1])) << st << " after " << previous[1];
      EXPECT_LT(double(bw), 5.0 * double(previous_bytes[0]));
      EXPECT_LT(double(bt), 5.0 * double(previous_bytes[1]));
    }
    previous[0] = sw, previous[1] = st, previous_bytes[0] = bw, previous_bytes[1] = bt;
  }
}

// The estimate's per-thread part counts the threads a bake may run (--threads caps TBB's parallelism), not
// every core: each thread more adds one thread's line and tile buffers.
TEST(SweepStream, BufferBytesCountTheThreadsTheBakeMayRun) {
  const HeightField f = test_field(300, 200, Wrap::clamp);
  SweepSpec spec;
  spec.directions = 16;
  spec.channels = 2;
  auto bytes_with = [&](std::size_t threads) {
    tbb::global_control cap(tbb::global_control::max_allowed_parallelism, threads);
    return sweep_buffer_bytes(f, spec);
  };
  const std::size_t one = bytes_with(1), two = bytes_with(2), eight = bytes_with(8);
  // One thread's part: at least its tile of 4 C + 3 channels of 32 x 32 floats.
  ASSERT_GT(two, one);
  const std::size_t per_thread = two - one;
  EXPECT_GE(per_thread, std::size_t(4 * spec.channels + 3) * 32 * 32 * sizeof(float));
  EXPECT_EQ(eight - one, 7 * per_thread);
  // Without a cap: the machine's threads.
  EXPECT_EQ(sweep_buffer_bytes(f, spec) - one,
            per_thread * std::size_t(tbb::info::default_concurrency() - 1));
}

}  // namespace
}  // namespace hfbake
