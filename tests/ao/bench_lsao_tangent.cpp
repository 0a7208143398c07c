// lsao's tangent strategies: cost and a decomposition of the error.
//
//   build/tests/ao/ao_bench_lsao_tangent [google-benchmark flags]   texel-directions per CPU-second, one
//       thread, 512^2 fractal, K = 16: the receiver tangent and P3's fixed tangent, step and smooth falloffs
//       at R = 4, 64 and 1024 texels, rational at 16 (it never ends) and none.
//   build/tests/ao/ao_bench_lsao_tangent --measure   per field (96^2, K = 16; smooth R = 32 and step R = 8):
//       mean and rmse of lsao - hbao (slab estimator, one-texel bilinear steps) for the fixed tangent, the
//       receiver tangent's chain hull and its brute force over the same line samples (every visible band:
//       what the hull's chain approximates). Isolates the hull's error from the sampling's; the error against
//       the Embree reference is in the jobs' report.json (README).
#include <benchmark/benchmark.h>

#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>

#include "ao_truth.hpp"
#include "field/procedural.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/lsao.hpp"

namespace hfbake {
namespace {

HeightField field_of(ProceduralKind kind, int n, std::uint64_t seed, double amplitude = 0,
                     double feature = 0) {
  ProceduralSpec spec;
  spec.kind = kind;
  spec.width = spec.height = n;
  spec.seed = seed;
  spec.amplitude = amplitude;
  spec.feature_size = feature;
  return make_procedural(spec, 1.0, Wrap::clamp);
}

const HeightField& fractal(int n) {
  static std::map<int, HeightField> cache;
  auto it = cache.find(n);
  if (it == cache.end()) it = cache.emplace(n, field_of(ProceduralKind::fractal, n, 7)).first;
  return it->second;
}

// Args: {tangent (0: P3's fixed -0.85, 1: the receiver's), falloff kind, radius}.
void BM_LsaoTangent(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int n = 512, K = 16;
  LsaoOptions o;
  o.directions = K;
  o.tangent = state.range(0) == 0 ? LsaoTangent::fixed : LsaoTangent::receiver;
  o.occlusion.rho = {FalloffKind(state.range(1)), double(state.range(2))};
  for (auto _ : state) benchmark::DoNotOptimize(lsao_obscurance(fractal(n), o, RunControl{}));
  state.SetItemsProcessed(state.iterations() * std::int64_t(n) * n * K);
}
void TangentArgs(benchmark::internal::Benchmark* b) {
  for (int t : {0, 1}) {
    for (int r : {4, 64, 1024}) b->Args({t, int(FalloffKind::step), r});
    for (int r : {4, 64, 1024}) b->Args({t, int(FalloffKind::smooth), r});
    b->Args({t, int(FalloffKind::rational), 16});
    b->Args({t, int(FalloffKind::none), 0});
  }
  b->Unit(benchmark::kMillisecond)->Iterations(1);
}
BENCHMARK(BM_LsaoTangent)->Apply(TangentArgs);

using ao_truth::Diff;
using ao_truth::diff;

void measure() {
  struct Field {
    const char* name;
    HeightField f;
  };
  const Field fields[] = {
      {"craters", field_of(ProceduralKind::craters, 96, 9, 4, 10)},
      {"sines", field_of(ProceduralKind::sines, 96, 1)},
      {"terraces", field_of(ProceduralKind::terraces, 96, 5, 8)},
      {"ridges", field_of(ProceduralKind::ridges, 96, 4, 10)},
      {"rough", field_of(ProceduralKind::rough, 96, 3)},
  };
  const Falloff falloffs[] = {{FalloffKind::smooth, 32}, {FalloffKind::step, 8}};
  std::printf("%-9s %-9s %8s | %-17s %-17s %-17s  (mean / rmse of lsao - hbao)\n", "field", "falloff", "hbao",
              "fixed -0.85", "receiver hull", "receiver brute");
  for (const Field& fd : fields)
    for (const Falloff& rho : falloffs) {
      HbaoSettings s;
      s.falloff = rho;
      s.directions = uniform_directions(16);
      s.reach = default_reach(fd.f, rho);
      s.bent = false;
      std::vector<float> ref(fd.f.texel_count());
      hbao_field(fd.f, compute_normals(fd.f), s, RunControl{}, ref.data(), nullptr);
      double ref_mean = 0;
      for (float v : ref) ref_mean += v;
      ref_mean /= double(ref.size());
      auto run = [&](LsaoTangent t, LsaoEstimator e) {
        LsaoOptions o;
        o.directions = 16;
        o.occlusion.rho = rho;
        o.tangent = t;
        o.estimator = e;
        return diff(lsao_obscurance(fd.f, o, RunControl{}), ref);
      };
      const Diff a = run(LsaoTangent::fixed, LsaoEstimator::hull);
      const Diff b = run(LsaoTangent::receiver, LsaoEstimator::hull);
      const Diff c = run(LsaoTangent::receiver, LsaoEstimator::brute_visible);
      std::printf("%-9s %-6s%3.0f %8.4f | %+.4f / %.4f  %+.4f / %.4f  %+.4f / %.4f\n", fd.name,
                  falloff_kind_name(rho.kind), rho.radius, ref_mean, a.mean, a.rmse, b.mean, b.rmse, c.mean,
                  c.rmse);
    }
}

}  // namespace
}  // namespace hfbake

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "--measure") == 0) {
    hfbake::measure();
    return 0;
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
