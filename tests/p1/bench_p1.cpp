// P1 throughput: horizons alone (sweep + hull stack + gather) and horizons + lighting (compute_p1: ao, vsky,
// direct from the built-in sky through the exact tables, plus its sun), by size, K and threads, in
// texel-directions per second; and the brute-force march from every texel (one direction) for the ratio.
//   ./bench_p1 --benchmark_filter=...   (see tests/p1/README of the closing note for the table)
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>

#include "methods/p1/far_horizons.hpp"
#include "methods/p1/horizon_sweep.hpp"
#include "methods/p1/p1.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

const Scene& scene_of(int size) {
  static std::map<int, Scene> cache;
  auto it = cache.find(size);
  if (it != cache.end()) return it->second;
  Scene s;
  s.field = truth::procedural(ProceduralKind::fractal, size, size, Wrap::clamp);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
  EnvironmentLighting sky = make_sky_environment(SkySpec{});
  s.environment = std::move(sky.environment);
  s.lights = std::move(sky.lights);
  return cache.emplace(size, std::move(s)).first->second;
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

// Horizons alone: the sweep, the hull stack (far field with crossings) and the gather of every texel's
// far caster (summed per texel so the compiler keeps it; no near field, no lighting).
void BM_Horizons(benchmark::State& state) {
  const int size = int(state.range(0)), K = int(state.range(1)), threads = int(state.range(2));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
  const Scene& s = scene_of(size);
  std::vector<float> acc(s.field.texel_count());
  SweepSpec spec;
  spec.directions = K;
  spec.channels = p1::HorizonLineWorker::channels();
  for (auto _ : state) {
    sweep_lines(
        s.field, spec, RunControl{},
        [&] {  // as compute_p1 runs it: lagging the default near radius, with the triangulation's crossings
          p1::HorizonLineWorker w;
          w.far_radius = 2 * s.field.texel_size;
          w.crossings = &s.field;
          return w;
        },
        [&](int, int i, int j, const TexelTaps& t) { acc[s.field.index(i, j)] += t.value(0); });
    benchmark::DoNotOptimize(acc.data());
  }
  set_counters(state, double(s.field.texel_count()) * K);
}

const HeightField& field_of(int kind, int size) {  // 0: the smooth fractal, 1: rough fBm (60 degrees)
  static std::map<std::pair<int, int>, HeightField> cache;
  auto it = cache.find({kind, size});
  if (it != cache.end()) return it->second;
  HeightField f = kind == 0 ? truth::procedural(ProceduralKind::fractal, size, size, Wrap::clamp)
                            : truth::rough_field(size, size, 60, 0.7, 3);
  return cache.emplace(std::make_pair(kind, size), std::move(f)).first->second;
}

// P1's far field alone (the strip search, FarHorizonWorker, as compute_p1 runs it with near_radius 2) and
// the strip gather, summed per texel; counters: texel-directions/s and the bands searched per texel.
// Args: field (0 fractal, 1 rough), size, K, threads.
void BM_FarField(benchmark::State& state) {
  const int kind = int(state.range(0)), size = int(state.range(1)), K = int(state.range(2));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, int(state.range(3)));
  const HeightField& f = field_of(kind, size);
  std::vector<float> acc(f.texel_count());
  SweepSpec spec;
  spec.directions = K;
  spec.channels = p1::FarHorizonWorker::channels();
  spec.tile_nearest = spec.tile_values = false;
  spec.tile_strip = true;
  spec.zero_buffers = false;
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

// Horizons + lighting: ao, vsky and direct (sky through the exact tables + sun).
void BM_P1Lighting(benchmark::State& state) {
  const int size = int(state.range(0)), K = int(state.range(1)), threads = int(state.range(2));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
  const Scene& s = scene_of(size);
  P1Params p;
  p.directions = K;
  for (auto _ : state) {
    P1Result r = compute_p1(s, p, RunControl{});
    benchmark::DoNotOptimize(r.ao.data());
  }
  set_counters(state, double(s.field.texel_count()) * K);
}

// Brute force: march from every texel center over every sample to the border, one direction (0.3 rad).
void BM_BruteForceMarch(benchmark::State& state) {
  const int size = int(state.range(0));
  const Scene& s = scene_of(size);
  const HeightField& f = s.field;
  SweepSpec spec;
  spec.azimuths = {0.3};
  const SweepDirection d = plan_direction(f, spec, 0);
  double sum = 0;
  for (auto _ : state) {
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i)
        sum += truth::march_from_texel(f, i, j, d.phi, d.step / f.texel_size, 0);
    benchmark::DoNotOptimize(sum);
  }
  set_counters(state, double(f.texel_count()));
}

void HorizonArgs(benchmark::internal::Benchmark* b) {
  for (int size : {256, 512, 1024, 2048})
    for (int K : {16, 64, 256})
      for (int t : {1, 2}) {
        if (size >= 2048 && K > 64) continue;
        b->Args({size, K, t});
      }
  b->Args({4096, 16, 2});
}

BENCHMARK(BM_FarField)
    ->Args({0, 512, 64, 1})
    ->Args({1, 512, 64, 1})
    ->Args({0, 1024, 64, 1})
    ->Args({0, 1024, 64, 2})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime();
BENCHMARK(BM_HullStack)->Arg(1024)->Arg(16384);
BENCHMARK(BM_Horizons)->Apply(HorizonArgs)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_P1Lighting)->Apply(HorizonArgs)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BruteForceMarch)
    ->Arg(512)
    ->Arg(1024)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->UseRealTime();

}  // namespace
}  // namespace hfbake

BENCHMARK_MAIN();
