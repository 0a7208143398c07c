// P1 throughput: horizons alone (sweep + hull stack + gather) and horizons + lighting (compute_p1: ao, vsky,
// direct from the built-in sky through the exact tables, plus its sun), by size, K and threads, in
// texel-directions per second; and the brute-force march from every texel (one direction) for the ratio.
//   ./bench_p1 --benchmark_filter=...   (see tests/p1/README of the closing note for the table)
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <string>

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
