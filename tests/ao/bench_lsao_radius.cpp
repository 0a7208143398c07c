// lsao's cost against its radius on its defaults (receiver tangent, surface triangles, near_radius 4),
// K = 16, smooth falloff, its default layers (obscurance and bent_normal): P3's property is a cost per
// texel-direction that does not grow with the radius (docs/performance-lsao.md holds the current table).
//
//   build/tests/ao/ao_bench_lsao_radius [google-benchmark flags]
//
// Args {field size, radius in texels}, R = 4 ... 1024 at 256^2 and 512^2 (a clamp field: beyond the field's
// size the radius reaches no farther). One thread (texel-directions per CPU-second hold on a loaded
// machine; the sweep parallelises over lines). Counters: texel_dirs_per_s (texels x K / CPU time), and per
// texel-direction query the steps its walks over the hulls took (walked; a skipped block of points one step)
// and the bands it added (bands, near field included): the work that must stay flat as R grows.
#include <benchmark/benchmark.h>

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>

#include "field/procedural.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/lsao.hpp"

namespace hfbake {
namespace {

const HeightField& ridges(int n) {
  static std::map<int, HeightField> cache;
  auto it = cache.find(n);
  if (it == cache.end()) {
    ProceduralSpec spec;
    spec.kind = ProceduralKind::ridges;
    spec.width = spec.height = n;
    spec.seed = 23;
    spec.amplitude = 40;
    it = cache.emplace(n, make_procedural(spec, 1.0, Wrap::clamp)).first;
  }
  return it->second;
}

void BM_LsaoRadius(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int n = int(state.range(0)), K = 16;
  LsaoOptions o;  // the defaults: receiver tangent, surface triangles, near_radius 4
  o.directions = K;
  o.occlusion.rho = {FalloffKind::smooth, double(state.range(1))};
  const HeightField& f = ridges(n);
  LsaoStats st;
  std::vector<Vec3f> bent;  // the default layers: obscurance and bent_normal
  for (auto _ : state) benchmark::DoNotOptimize(lsao_obscurance(f, o, RunControl{}, &st, &bent));
  const double texel_dirs = double(n) * double(n) * K;
  state.counters["texel_dirs_per_s"] =
      benchmark::Counter(texel_dirs * double(state.iterations()), benchmark::Counter::kIsRate);
  const double queries = double(std::max<std::uint64_t>(st.queries, 1));
  state.counters["walked"] = double(st.walked) / queries;
  state.counters["bands"] = double(st.bands) / queries;
}

void Radii(benchmark::internal::Benchmark* b) {
  for (int n : {256, 512})
    for (int r : {4, 8, 16, 32, 64, 128, 256, 512, 1024}) b->Args({n, r});
  b->ArgNames({"size", "R"})->Unit(benchmark::kMillisecond)->Iterations(1);
}
BENCHMARK(BM_LsaoRadius)->Apply(Radii);

// --measure: per radius, lsao (defaults) against hbao's march on the triangulated surface (segment
// estimator: the exact slice integral of that surface at the same K = 16 azimuths, an independent truth for
// what the line sweep approximates) on a 160^2 crop of the benchmark's field, with the work counters.
int measure(double tolerance) {
  const HeightField& f = ridges(160);
  const std::vector<Vec3f> normals = compute_normals(f);
  std::printf("| R | rmse | bias | walked | bands | lsao s | hbao s |\n|---|---|---|---|---|---|---|\n");
  for (int r : {8, 32, 128, 512}) {
    const Falloff rho{FalloffKind::smooth, double(r)};
    HbaoSettings s;
    s.falloff = rho;
    s.directions = uniform_directions(16);
    s.reach = default_reach(f, rho);
    s.surface = MarchSurface::triangles;
    s.estimator = HorizonEstimator::segment;
    s.bent = false;
    std::vector<float> march(f.texel_count());
    const auto t0 = std::chrono::steady_clock::now();
    hbao_field(f, normals, s, RunControl{}, march.data(), nullptr);
    const auto t1 = std::chrono::steady_clock::now();
    LsaoOptions o;
    o.directions = 16;
    o.occlusion.rho = rho;
    if (tolerance > 0) o.near_rho_tolerance = tolerance;
    LsaoStats st;
    std::vector<Vec3f> bent;
    const std::vector<float> l = lsao_obscurance(f, o, RunControl{}, &st, &bent);
    const auto t2 = std::chrono::steady_clock::now();
    double sq = 0, bias = 0;
    for (std::size_t t = 0; t < l.size(); ++t) {
      const double d = double(l[t]) - double(march[t]);
      sq += d * d, bias += d;
    }
    const double n = double(l.size()), q = double(std::max<std::uint64_t>(st.queries, 1));
    std::printf("| %d | %.5f | %+.5f | %.1f | %.2f | %.2f | %.2f |\n", r, std::sqrt(sq / n), bias / n,
                double(st.walked) / q, double(st.bands) / q, std::chrono::duration<double>(t2 - t1).count(),
                std::chrono::duration<double>(t1 - t0).count());
  }
  return 0;
}

}  // namespace
}  // namespace hfbake

int main(int argc, char** argv) {
  for (int a = 1; a < argc; ++a)
    if (std::strcmp(argv[a], "--measure") == 0)
      return hfbake::measure(a + 1 < argc ? std::atof(argv[a + 1]) : 0.0);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
