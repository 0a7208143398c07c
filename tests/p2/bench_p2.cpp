// Benchmarks of P2 (never run by CTest):
//   BM_LineTree / BM_LineNaive: visibility along 1024-sample lines of the four P2 fields, the convex hull
//     tree against the naive march (the paper's complexity claim); items = receivers.
//   BM_Bounce: one full indirect bounce (visibility + exact gathering), N^2 texels, K directions;
//     items = texel-directions.
//   BM_Visibility: the sweep with visibility only (tree or naive), N = 1024.
//   BM_P2HorizonsKeptOrRecomputed: compute_p2 (p1's direct light, then one bounce, facet senders) on a 512^2
//     fractal, K = 32, with p1's horizons kept from the direct-light sweep (1) or recomputed per direction
//     block in the bounce (0, p2_keeps_horizons); the same bits, the second pays p1's horizon sweep again.
//   BM_P2Bounce: one bounce of p2's defaults (facet senders, near_radius 4, exact line profiles, P1's
//     horizons kept), fractal (0) or terraces (9), N^2 texels, K directions, one thread; stage 0 (P1's
//     direct light) is made once outside the timing. items = texel-directions (counter texdir/s). The
//     fourth argument 0 skips the bounce: what the process spends besides it (for instruction counts,
//     valgrind --tool=cachegrind, which count the whole process).
// Run: build-p2/tests/p2/bench_p2 --benchmark_filter=Line
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <vector>

#include "env/environment.hpp"
#include "field/procedural.hpp"
#include "field/scene.hpp"
#include "methods/p2/bake_p2.hpp"
#include "methods/p2/hull_tree.hpp"
#include "methods/p2/indirect_sweep.hpp"
#include "methods/p2/naive_visibility.hpp"

namespace hfbake {
namespace {

HeightField field(int kind, int n) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind(kind);
  spec.width = spec.height = n;
  spec.seed = 1;
  return make_procedural(spec, 1.0, Wrap::clamp);
}

std::vector<std::vector<double>> rows(int kind, int n, int count) {
  const HeightField f = field(kind, n);
  std::vector<std::vector<double>> out;
  for (int j = 0; j < count; ++j) {
    std::vector<double> h(n);
    for (int i = 0; i < n; ++i) h[i] = f.at(i, (j * 37) % n);
    out.push_back(std::move(h));
  }
  return out;
}

void BM_LineTree(benchmark::State& state) {
  const auto lines = rows(int(state.range(0)), 1024, 32);
  HullTree tree;
  std::uint64_t receivers = 0, horizons = 0;
  for (auto _ : state) {
    for (const auto& h : lines) {
      tree.reset(int(h.size()));
      for (double x : h) {
        tree.push(x);
        horizons += tree.horizons().size();
      }
      receivers += h.size();
    }
  }
  benchmark::DoNotOptimize(horizons);
  state.SetItemsProcessed(std::int64_t(receivers));
  state.SetLabel(procedural_kind_name(ProceduralKind(state.range(0))));
}

void BM_LineNaive(benchmark::State& state) {
  const auto lines = rows(int(state.range(0)), 1024, 32);
  std::vector<int> visible;
  std::uint64_t receivers = 0, count = 0;
  for (auto _ : state) {
    for (const auto& h : lines) {
      for (int r = 0; r < int(h.size()); ++r) {
        naive_visible(h.data(), r, visible);
        count += visible.size();
      }
      receivers += h.size();
    }
  }
  benchmark::DoNotOptimize(count);
  state.SetItemsProcessed(std::int64_t(receivers));
  state.SetLabel(procedural_kind_name(ProceduralKind(state.range(0))));
}

void run_sweep(benchmark::State& state, int kind, int N, int K, bool gather, P2Visibility vis) {
  const HeightField f = field(kind, N);
  const std::vector<Vec3f> normals = compute_normals(f);
  const std::vector<Rgb> exit(f.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
  IndirectSweepSpec spec;
  spec.directions = K;
  spec.gather = gather;
  spec.visibility = vis;
  for (auto _ : state) benchmark::DoNotOptimize(sweep_indirect(f, normals, exit, spec, RunControl{}));
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(f.texel_count()) * K);
  state.SetLabel(procedural_kind_name(ProceduralKind(kind)));
}

// args: kind, N, K
void BM_Bounce(benchmark::State& state) {
  run_sweep(state, int(state.range(0)), int(state.range(1)), int(state.range(2)), true, P2Visibility::tree);
}
// args: kind, tree (1) or naive (0)
void BM_Visibility(benchmark::State& state) {
  run_sweep(state, int(state.range(0)), 1024, 8, false,
            state.range(1) ? P2Visibility::tree : P2Visibility::naive);
}

// args: keep (1) or recompute (0) p1's horizons
void BM_P2HorizonsKeptOrRecomputed(benchmark::State& state) {
  Scene s;
  s.field = field(0, 512);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
  s.environment = make_uniform_environment({1, 1, 1});
  s.bounces = 1;
  P2Params p;
  p.directions = 32;
  p.bounces = 1;
  p.keep_horizons = int(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(compute_p2(s, p, RunControl{}));
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(s.field.texel_count()) * 32);
  state.SetLabel(state.range(0) ? "kept" : "recomputed");
}

// args: kind (ProceduralKind), N, K, run the bounce (1) or not (0)
void BM_P2Bounce(benchmark::State& state) {
  const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  Scene s;
  s.field = field(int(state.range(0)), int(state.range(1)));
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
  s.environment = make_uniform_environment({1, 1, 1});
  s.bounces = 1;
  P2Params p;
  p.directions = int(state.range(2));
  p.bounces = 1;
  const P2State stage0 = p2_stage0(s, p, RunControl{});
  for (auto _ : state) {
    if (!state.range(3)) continue;
    P2State st = stage0;
    p2_bounce(s, p, 1, st, RunControl{});
    benchmark::DoNotOptimize(st.indirect.data());
  }
  const double td = double(state.iterations()) * double(s.field.texel_count()) * double(p.directions);
  state.counters["texdir/s"] = benchmark::Counter(td, benchmark::Counter::kIsRate);
  state.SetLabel(procedural_kind_name(ProceduralKind(state.range(0))));
}

BENCHMARK(BM_LineTree)->DenseRange(0, 3);
BENCHMARK(BM_P2Bounce)
    ->ArgsProduct({{0, 9}, {256, 512}, {16, 64}, {1}})
    ->ArgsProduct({{0, 9}, {256}, {16}, {0}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_P2HorizonsKeptOrRecomputed)
    ->DenseRange(0, 1)
    ->Iterations(1)
    ->Repetitions(5)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LineNaive)->DenseRange(0, 3);
BENCHMARK(BM_Bounce)
    ->ArgsProduct({{0, 1, 2, 3}, {512, 1024}, {16, 32, 64, 128}})
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Visibility)
    ->ArgsProduct({{0, 1, 2, 3}, {1, 0}})
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hfbake

BENCHMARK_MAIN();
