// P1 throughput in texel-directions per second of CPU time (process CPU: all threads), the whole bake and
// its parts, on the smooth built-in fractal (field 0) and rough fBm, 60 degrees at the texel scale (field 1),
// at 256², 512² and 1024², K = 16 and 64:
//   BM_P1Bake     compute_p1: ao + direct under a uniform sky (bench/p1_speed_1024.json's layers), everything
//   BM_P1Tolerance compute_p1 (ao + vsky) at horizon_tolerance = arg * 1e-4, with its ao error against
//                 tolerance 0 (counters ao_err_mean, ao_err_max)
//   BM_FarField   the sweep, FarHorizonWorker's strip search (starting from each texel's near field, as
//                 compute_p1 runs it) and the strip gather; counter bands/texel: bands searched per texel
//   BM_NearField  the near field alone: near_slopes_row over every row, per direction
//   BM_Gather     the sweep driver and the strip gather alone (a line worker that only writes "none")
// plus the hull stack alone and the brute-force march for scale. Args: field, size, K (BM_P1Bake: and
// threads). For docs/performance.md:
//   build/tests/p1/bench_p1 --benchmark_filter='BM_P1Bake/0/' --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "methods/p1/far_horizons.hpp"
#include "methods/p1/horizon_sweep.hpp"
#include "methods/p1/p1.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

const HeightField& field_of(int kind, int size) {  // 0: the smooth fractal, 1: rough fBm (60 degrees)
  static std::map<std::pair<int, int>, HeightField> cache;
  auto it = cache.find({kind, size});
  if (it != cache.end()) return it->second;
  HeightField f = kind == 0 ? truth::procedural(ProceduralKind::fractal, size, size, Wrap::clamp)
                            : truth::rough_field(size, size, 60, 0.7, 3);
  return cache.emplace(std::make_pair(kind, size), std::move(f)).first->second;
}

double peak_rss_mb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0;
}

void set_counters(benchmark::State& state, double work) {
  state.counters["texdir/s"] = benchmark::Counter(work, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["ns/texdir"] = benchmark::Counter(
      work * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["peak_rss_MB"] = peak_rss_mb();
}

// The whole bake as `hfbake bake` runs it for layers ao + direct under a uniform sky (no lights).
void BM_P1Bake(benchmark::State& state) {
  const int kind = int(state.range(0)), size = int(state.range(1)), K = int(state.range(2));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, int(state.range(3)));
  Scene s;
  s.field = field_of(kind, size);
  P1Params p;
  p.directions = K;
  p.ao = p.direct = true;
  p.vsky = false;
  for (auto _ : state) {
    P1Result r = compute_p1(s, p, RunControl{});
    benchmark::DoNotOptimize(r.ao.data());
  }
  set_counters(state, double(s.field.texel_count()) * K);
}

// The accuracy dial: compute_p1 for ao + vsky (the speed job's layers) at horizon_tolerance = range(3) *
// 1e-4, one thread; with the mean and max |ao - ao at tolerance 0| as counters.
void BM_P1Tolerance(benchmark::State& state) {
  const int kind = int(state.range(0)), size = int(state.range(1)), K = int(state.range(2));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
  Scene s;
  s.field = field_of(kind, size);
  P1Params p;
  p.directions = K;
  p.ao = p.vsky = true;
  p.direct = false;
  const std::vector<float> exact = compute_p1(s, p, RunControl{}).ao;
  p.horizon_tolerance = double(state.range(3)) * 1e-4;
  std::vector<float> ao;
  for (auto _ : state) {
    P1Result r = compute_p1(s, p, RunControl{});
    benchmark::DoNotOptimize(r.ao.data());
    ao = std::move(r.ao);
  }
  set_counters(state, double(s.field.texel_count()) * K);
  double sum = 0, worst = 0;
  for (std::size_t t = 0; t < ao.size(); ++t) {
    const double e = std::fabs(double(ao[t]) - exact[t]);
    sum += e, worst = std::max(worst, e);
  }
  state.counters["ao_err_mean"] = sum / double(std::max<std::size_t>(1, ao.size()));
  state.counters["ao_err_max"] = worst;
}

// The sweep as compute_p1 runs its far field (p1_sweep_spec): the strip gather, no line heights, 8 directions
// a batch.
SweepSpec strip_sweep_spec(int K) {
  P1Params p;
  p.directions = K;
  return p1_sweep_spec(p);
}

// P1's far field alone (the strip search, FarHorizonWorker, as compute_p1 runs it with near_radius 2) and
// the strip gather, summed per texel; counters: texel-directions/s and the bands searched per texel.
void BM_FarField(benchmark::State& state) {
  const int kind = int(state.range(0)), size = int(state.range(1)), K = int(state.range(2));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
  const HeightField& f = field_of(kind, size);
  std::vector<float> acc(f.texel_count());
  const SweepSpec spec = strip_sweep_spec(K);
  std::atomic<std::uint64_t> texels{0}, bands{0};
  struct Counting : p1::FarHorizonWorker {
    std::atomic<std::uint64_t>*t = nullptr, *b = nullptr;
    ~Counting() {
      if (t) *t += texels, *b += bands;
    }
  };
  for (auto _ : state) {
    sweep_lines_tiled(
        f, spec, RunControl{},
        [&] {
          Counting w;
          w.field = &f;
          w.far_radius = 2 * f.texel_size;
          w.beat_near = true;
          w.t = &texels, w.b = &bands;
          return w;
        },
        [&](const SweepTile& t) {
          const std::size_t plane = std::size_t(t.width) * t.height;
          for (int y = 0; y < t.height; ++y)
            for (int x = 0; x < t.width; ++x)
              acc[f.index(t.i0 + x, t.j0 + y)] += t.strip[plane + std::size_t(y) * t.width + x];
        });
    benchmark::DoNotOptimize(acc.data());
  }
  set_counters(state, double(f.texel_count()) * K);
  state.counters["bands/texel"] = double(bands) / std::max<double>(1, double(texels));
}

// The near field alone: every texel's steepest near crossing (near_radius 2) for each of K directions.
void BM_NearField(benchmark::State& state) {
  const int kind = int(state.range(0)), size = int(state.range(1)), K = int(state.range(2));
  const HeightField& f = field_of(kind, size);
  SweepSpec probe;
  probe.directions = K;
  std::vector<p1::NearStencil> near;
  for (int k = 0; k < K; ++k) near.push_back(p1::near_stencil(f, plan_direction(f, probe, k), 2.0));
  std::vector<float> acc(f.texel_count()), row(std::size_t(f.width));
  for (auto _ : state) {
    for (int k = 0; k < K; ++k)
      for (int j = 0; j < f.height; ++j) {
        p1::near_slopes_row(f, near[k], 0, j, f.width, row.data());
        float* a = acc.data() + f.index(0, j);
        for (int i = 0; i < f.width; ++i) a[i] += row[i];
      }
    benchmark::DoNotOptimize(acc.data());
  }
  set_counters(state, double(f.texel_count()) * K);
}

// The sweep driver and the strip gather alone: every line sampled, its receivers written "none" (no
// search), every texel's strip result gathered and summed.
void BM_Gather(benchmark::State& state) {
  const int kind = int(state.range(0)), size = int(state.range(1)), K = int(state.range(2));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
  const HeightField& f = field_of(kind, size);
  std::vector<float> acc(f.texel_count());
  const SweepSpec spec = strip_sweep_spec(K);
  struct NoSearch {
    void operator()(const SweepLine& line, float* out) const {
      for (int n = line.first_receiver; n < line.count; ++n)
        out[2 * (n - line.first_receiver)] = 0, out[2 * (n - line.first_receiver) + 1] = line.z[n];
    }
  };
  for (auto _ : state) {
    sweep_lines_tiled(
        f, spec, RunControl{}, [] { return NoSearch{}; },
        [&](const SweepTile& t) {
          const std::size_t plane = std::size_t(t.width) * t.height;
          for (int y = 0; y < t.height; ++y)
            for (int x = 0; x < t.width; ++x)
              acc[f.index(t.i0 + x, t.j0 + y)] += t.strip[plane + std::size_t(y) * t.width + x];
        });
    benchmark::DoNotOptimize(acc.data());
  }
  set_counters(state, double(f.texel_count()) * K);
}

// The hull stack alone: push every sample of random lines (the worst input: no coherence) and query
// from a point beyond each, per sample.
void BM_HullStack(benchmark::State& state) {
  const int n = int(state.range(0));
  std::vector<float> z(n);
  std::uint64_t x = 12345;
  for (float& v : z) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    v = float(double(x >> 11) / 9007199254740992.0 * 100.0);
  }
  p1::HullStackF h;
  double sum = 0;
  for (auto _ : state) {
    h.reset(n);
    for (int i = 0; i < n; ++i) {
      h.add(i, z[i]);
      sum += h.query_index(i + 1.5, z[i]);
    }
    benchmark::DoNotOptimize(sum);
  }
  state.counters["samples/s"] = benchmark::Counter(double(n), benchmark::Counter::kIsIterationInvariantRate);
}

// Brute force: march from every texel center over every crossing to the border, one direction (0.3 rad).
void BM_BruteForceMarch(benchmark::State& state) {
  const HeightField& f = field_of(0, int(state.range(0)));
  SweepSpec spec;
  spec.azimuths = {0.3};
  const SweepDirection d = plan_direction(f, spec, 0);
  double sum = 0;
  for (auto _ : state) {
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) sum += truth::march_tri(f, i, j, d.dx, d.dy, 7);
    benchmark::DoNotOptimize(sum);
  }
  set_counters(state, double(f.texel_count()));
}

// field x size x K (x threads for the whole bake: 1, and 2 at 1024²).
void PartArgs(benchmark::internal::Benchmark* b) {
  for (int kind : {0, 1})
    for (int size : {256, 512, 1024})
      for (int K : {16, 64}) b->Args({kind, size, K});
}
void BakeArgs(benchmark::internal::Benchmark* b) {
  for (int kind : {0, 1})
    for (int size : {256, 512, 1024})
      for (int K : {16, 64}) {
        b->Args({kind, size, K, 1});
        if (size == 1024) b->Args({kind, size, K, 2});
      }
}

BENCHMARK(BM_P1Bake)->Apply(BakeArgs)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();
void ToleranceArgs(benchmark::internal::Benchmark* b) {
  for (int kind : {0, 1})
    for (int tol : {0, 10, 30, 100, 300, 1000}) b->Args({kind, 1024, 64, tol});
}
BENCHMARK(BM_P1Tolerance)->Apply(ToleranceArgs)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();
BENCHMARK(BM_FarField)->Apply(PartArgs)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();
BENCHMARK(BM_NearField)->Apply(PartArgs)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();
BENCHMARK(BM_Gather)->Apply(PartArgs)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();
BENCHMARK(BM_HullStack)->Arg(1024)->Arg(16384);
BENCHMARK(BM_BruteForceMarch)->Arg(256)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace hfbake

BENCHMARK_MAIN();
