// Throughput of the obscurance methods through their entry points: texel-directions per second (items =
// texels x K; vo has no directions: items = texels) on a fractal field, 512^2 and 1024^2, K = 8, 16, 32,
// one thread (oneTBB limited to 1), so items_per_second is per CPU-second and holds on a loaded machine; the
// methods parallelise over rows (2 threads: about 2x). Radius 16 world units (= texels), step falloff for the
// radius-bounded methods.
//   build-ao/tests/ao/ao_bench_ao
#include <benchmark/benchmark.h>

#include <tbb/global_control.h>

#include <map>

#include "field/procedural.hpp"
#include "methods/ao/bake_ao.hpp"

namespace hfbake {
namespace {

const Scene& scene(int n) {
  static std::map<int, Scene> cache;
  auto it = cache.find(n);
  if (it == cache.end()) {
    ProceduralSpec spec;
    spec.kind = ProceduralKind::fractal;
    spec.width = spec.height = n;
    spec.seed = 7;
    Scene s;
    s.field = make_procedural(spec, 1.0, Wrap::clamp);
    s.normals = compute_normals(s.field);
    it = cache.emplace(n, std::move(s)).first;
  }
  return it->second;
}

// Bakes `params` as method `method`'s entry (its reader, then its bake) in every iteration.
void run(benchmark::State& state, const char* method, nlohmann::json params, bool directional) {
  const int n = int(state.range(0)), K = int(state.range(1));
  if (directional) params["directions"] = K;
  const Scene& s = scene(n);
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  for (auto _ : state) benchmark::DoNotOptimize(bake_method(method, s, params, RunControl{}));
  state.SetItemsProcessed(state.iterations() * std::int64_t(n) * n * (directional ? K : 1));
}

void Args(benchmark::internal::Benchmark* b) {
  for (int n : {512, 1024})
    for (int K : {8, 16, 32}) b->Args({n, K});
  b->Unit(benchmark::kMillisecond)->Iterations(1);
}

void BM_HbaoStepR16(benchmark::State& st) {
  run(st, "hbao", {{"method", "hbao"}, {"radius", 16}, {"layers", {"obscurance"}}}, true);
}
BENCHMARK(BM_HbaoStepR16)->Apply(Args);
void BM_HbaoRationalR16(benchmark::State& st) {  // marches out to 100 R (rho < 1e-4) or the border
  run(st, "hbao", {{"method", "hbao"}, {"radius", 16}, {"falloff", "rational"}, {"layers", {"obscurance"}}},
      true);
}
BENCHMARK(BM_HbaoRationalR16)->Args({512, 8})->Unit(benchmark::kMillisecond)->Iterations(1);
void BM_HsaoStepR16(benchmark::State& st) {
  run(st, "hsao", {{"method", "hsao"}, {"radius", 16}, {"normal_rays", 2}, {"layers", {"obscurance"}}}, true);
}
BENCHMARK(BM_HsaoStepR16)->Apply(Args);
void BM_VoR16(benchmark::State& st) {
  run(st, "vo", {{"method", "vo"}, {"radius", 16}}, false);
}
BENCHMARK(BM_VoR16)->Args({512, 0})->Args({1024, 0})->Unit(benchmark::kMillisecond)->Iterations(1);
void BM_LsaoRationalR16(benchmark::State& st) {
  run(st, "lsao", {{"method", "lsao"}, {"radius", 16}, {"falloff", "rational"}}, true);
}
BENCHMARK(BM_LsaoRationalR16)->Apply(Args);
void BM_FarfieldRationalR16(benchmark::State& st) {
  run(st, "farfield", {{"method", "farfield"}, {"radius", 16}, {"falloff", "rational"}}, true);
}
BENCHMARK(BM_FarfieldRationalR16)->Apply(Args);

}  // namespace
}  // namespace hfbake

BENCHMARK_MAIN();
