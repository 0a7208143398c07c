// LSAO (P3) and farfield (P4): throughput and accuracy measurements.
//
//   build/tests/ao/ao_bench_lsao [google-benchmark flags]   throughput: texel-directions per CPU-second
//       (items_per_second = texels x K / CPU time, one thread, so it holds on a loaded machine; the methods
//       parallelise over lines / rows) at 512^2, 1024^2, 2048^2 and K = 8..64, and cost against the radius
//       (1024^2, K = 16, step falloff): LSAO (its default, the receiver tangent; P3's fixed tangent beside it
//       in ao_bench_lsao_tangent), farfield and hbao in one run.
//   build/tests/ao/ao_bench_lsao --measure [fractal|bricks|sines|blocks|dem]   accuracy tables (printed):
//       LSAO's hull against the brute-force largest visible occluder over the same line samples (P3's
//       reference; and against hbao's largest_occluder march, which samples its own rays), and farfield
//       against its exact march and hbao's slab march, on the four P2 surfaces and on the real DEM
//       ../shared/data/TM1_564_146.tif (skipped when absent or when hfbake_io is not linked).
#include <benchmark/benchmark.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>

#include "field/procedural.hpp"
#include "io/image_input.hpp"
#include "methods/ao/farfield.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/lsao.hpp"

namespace hfbake {
namespace {

const HeightField& fractal(int n) {
  static std::map<int, HeightField> cache;
  auto it = cache.find(n);
  if (it == cache.end()) {
    ProceduralSpec spec;
    spec.kind = ProceduralKind::fractal;
    spec.width = spec.height = n;
    spec.seed = 7;
    it = cache.emplace(n, make_procedural(spec, 1.0, Wrap::clamp)).first;
  }
  return it->second;
}
const std::vector<Vec3f>& fractal_normals(int n) {
  static std::map<int, std::vector<Vec3f>> cache;
  auto it = cache.find(n);
  if (it == cache.end()) it = cache.emplace(n, compute_normals(fractal(n))).first;
  return it->second;
}

// Args: {size, K, radius}. Rational falloff (never ends: the hardest case for radius-bounded methods).
void BM_Lsao(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int n = int(state.range(0)), K = int(state.range(1));
  LsaoOptions o;
  o.directions = K;
  o.occlusion.rho = {FalloffKind::rational, double(state.range(2))};
  const HeightField& f = fractal(n);
  for (auto _ : state) benchmark::DoNotOptimize(lsao_obscurance(f, o, RunControl{}));
  state.SetItemsProcessed(state.iterations() * std::int64_t(n) * n * K);
}
void BM_Farfield(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int n = int(state.range(0)), K = int(state.range(1));
  FarfieldOptions o;
  o.directions = K;
  o.rho = {FalloffKind::rational, double(state.range(2))};
  const HeightField& f = fractal(n);
  const auto& normals = fractal_normals(n);
  for (auto _ : state) benchmark::DoNotOptimize(farfield_obscurance(f, normals, o, RunControl{}));
  state.SetItemsProcessed(state.iterations() * std::int64_t(n) * n * K);
}
// Cost against the radius: step falloff (hbao marches exactly R texels; LSAO and farfield do not care).
void BM_LsaoStepRadius(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int n = int(state.range(0)), K = int(state.range(1));
  LsaoOptions o;
  o.directions = K;
  o.occlusion.rho = {FalloffKind::step, double(state.range(2))};
  for (auto _ : state) benchmark::DoNotOptimize(lsao_obscurance(fractal(n), o, RunControl{}));
  state.SetItemsProcessed(state.iterations() * std::int64_t(n) * n * K);
}
void BM_FarfieldStepRadius(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int n = int(state.range(0)), K = int(state.range(1));
  FarfieldOptions o;
  o.directions = K;
  o.rho = {FalloffKind::step, double(state.range(2))};
  for (auto _ : state)
    benchmark::DoNotOptimize(farfield_obscurance(fractal(n), fractal_normals(n), o, RunControl{}));
  state.SetItemsProcessed(state.iterations() * std::int64_t(n) * n * K);
}
void BM_HbaoStepRadius(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int n = int(state.range(0)), K = int(state.range(1));
  HbaoSettings s;
  s.falloff = {FalloffKind::step, double(state.range(2))};
  s.directions = uniform_directions(K);
  s.reach = default_reach(fractal(n), s.falloff);
  s.bent = false;
  std::vector<float> out(fractal(n).texel_count());
  for (auto _ : state) hbao_field(fractal(n), fractal_normals(n), s, RunControl{}, out.data(), nullptr);
  state.SetItemsProcessed(state.iterations() * std::int64_t(n) * n * K);
}

void LsaoSizes(benchmark::internal::Benchmark* b) {
  for (int n : {512, 1024, 2048})
    for (int K : {8, 16, 64}) b->Args({n, K, 16});
  b->Unit(benchmark::kMillisecond)->Iterations(1);
}
void FarfieldSizes(benchmark::internal::Benchmark* b) {
  for (int n : {512, 1024})
    for (int K : {8, 16, 64}) b->Args({n, K, 16});
  b->Args({2048, 8, 16});
  b->Unit(benchmark::kMillisecond)->Iterations(1);
}
void Radii(benchmark::internal::Benchmark* b) {
  for (int r : {4, 64, 1024}) b->Args({1024, 16, r});
  b->Unit(benchmark::kMillisecond)->Iterations(1);
}
BENCHMARK(BM_Lsao)->Apply(LsaoSizes);
BENCHMARK(BM_Farfield)->Apply(FarfieldSizes);
BENCHMARK(BM_LsaoStepRadius)->Apply(Radii);
BENCHMARK(BM_FarfieldStepRadius)->Apply(Radii);
void HbaoRadii(benchmark::internal::Benchmark* b) {  // R texels of march per direction: stop at 64
  for (int r : {4, 16, 64}) b->Args({1024, 16, r});
  b->Unit(benchmark::kMillisecond)->Iterations(1);
}
BENCHMARK(BM_HbaoStepRadius)->Apply(HbaoRadii);

// ---- accuracy measurements -------------------------------------------------------------------------------

struct Errors {
  double mean = 0, worst = 0, differ = 0;
};
template <class A, class B>
Errors compare(const A& a, const B& b, bool clamp_both) {
  Errors e;
  for (std::size_t t = 0; t < a.size(); ++t) {
    double x = a[t], y = b[t];
    if (clamp_both) x = std::clamp(x, 0.0, 1.0), y = std::clamp(y, 0.0, 1.0);
    const double d = std::fabs(x - y);
    e.mean += d;
    e.worst = std::max(e.worst, d);
    e.differ += d > 1e-6;
  }
  e.mean /= a.size();
  e.differ /= a.size();
  return e;
}

void measure_field(const char* name, const HeightField& f) {
  const auto normals = compute_normals(f);
  struct Case {
    FalloffKind kind;
    double radius;
    const char* label;
  };
  const Case cases[] = {{FalloffKind::rational, 8, "rational R=8"},
                        {FalloffKind::rational, 64, "rational R=64"},
                        {FalloffKind::smooth, 32, "smooth R=32"},
                        {FalloffKind::exponential, 16, "exponential R=16"},
                        {FalloffKind::step, 32, "step R=32"}};
  const int K = 16;
  for (const Case& c : cases) {
    for (auto w : {ObscuranceWeighting::uniform, ObscuranceWeighting::cosine}) {
      LsaoOptions o;
      o.directions = K;
      o.occlusion = {{c.kind, c.radius}, -0.85, w};
      auto t0 = std::chrono::steady_clock::now();
      const auto hull = lsao_mean_occlusion(f, o, RunControl{});
      auto t1 = std::chrono::steady_clock::now();
      o.estimator = LsaoEstimator::brute_visible;
      const auto brute = lsao_mean_occlusion(f, o, RunControl{});
      auto t2 = std::chrono::steady_clock::now();
      const Errors e = compare(hull, brute, true);
      std::printf(
          "%-9s lsao %-7s %-17s K=%d  vs brute(same samples): mean %.4f %%  worst %.4f  differ %5.1f %%"
          "   time hull %.2f s brute %.2f s\n",
          name, w == ObscuranceWeighting::uniform ? "uniform" : "cosine", c.label, K, 100 * e.mean, e.worst,
          100 * e.differ, std::chrono::duration<double>(t1 - t0).count(),
          std::chrono::duration<double>(t2 - t1).count());
      if (w == ObscuranceWeighting::uniform) {
        HbaoSettings s;
        s.falloff = {c.kind, c.radius};
        s.weighting = Weighting::uniform;
        s.estimator = HorizonEstimator::largest_occluder;
        s.directions = uniform_directions(K);
        s.reach = default_reach(f, s.falloff);
        s.bent = false;
        std::vector<float> light(f.texel_count());
        hbao_field(f, normals, s, RunControl{}, light.data(), nullptr);
        std::vector<double> occ(light.size());
        for (std::size_t t = 0; t < occ.size(); ++t) occ[t] = 1.0 - light[t];
        const Errors h = compare(hull, occ, true);
        LsaoOptions os = o;
        os.estimator = LsaoEstimator::hull;
        os.texel_receivers = false;
        const Errors hs = compare(lsao_mean_occlusion(f, os, RunControl{}), occ, true);
        std::printf(
            "%-9s lsao %-7s %-17s K=%d  vs hbao largest_occluder (texel-centred rays): mean %.4f %%  worst "
            "%.4f   (line-sample receivers: mean %.4f %%  worst %.4f)\n",
            name, "uniform", c.label, K, 100 * h.mean, h.worst, 100 * hs.mean, hs.worst);
      }
    }
    FarfieldOptions fo;
    fo.directions = K;
    fo.rho = {c.kind, c.radius};
    fo.near_field = 1e6;
    const auto exact = farfield_obscurance(f, normals, fo, RunControl{});
    for (bool average : {false, true}) {
      fo.near_field = -1;
      fo.sector_average = average;
      FarfieldStats st;
      auto t0 = std::chrono::steady_clock::now();
      const auto far = farfield_obscurance(f, normals, fo, RunControl{}, &st);
      auto t1 = std::chrono::steady_clock::now();
      const Errors e = compare(far, exact, false);
      std::printf(
          "%-9s farfield %-17s K=%d%s vs exact march: mean %.4f %%  worst %.4f  virtual points/sector %.2f  "
          "time %.2f s\n",
          name, c.label, K, average ? "x2 (averaged)" : " (centre line)", 100 * e.mean, e.worst,
          double(st.virtual_points) / double(st.texel_directions) / (average ? 2.0 : 1.0),
          std::chrono::duration<double>(t1 - t0).count());
      if (!average) {
        HbaoSettings s;
        s.falloff = {c.kind, c.radius};
        s.directions = uniform_directions(K);
        s.reach = default_reach(f, s.falloff);
        s.bent = false;
        std::vector<float> light(f.texel_count());
        hbao_field(f, normals, s, RunControl{}, light.data(), nullptr);
        const Errors h = compare(far, light, false);
        const Errors x = compare(exact, light, false);
        std::printf(
            "%-9s farfield %-17s K=%d  vs hbao slab march: mean %.4f %%  worst %.4f   (exact march vs hbao: "
            "mean %.4f %%)\n",
            name, c.label, K, 100 * h.mean, h.worst, 100 * x.mean);
      }
    }
  }
}

int measure(const char* only) {
  for (ProceduralKind kind :
       {ProceduralKind::fractal, ProceduralKind::bricks, ProceduralKind::sines, ProceduralKind::blocks}) {
    ProceduralSpec s;
    s.kind = kind;
    s.width = s.height = 256;
    s.seed = 5;
    if (only && std::strcmp(only, procedural_kind_name(kind)) != 0) continue;
    measure_field(procedural_kind_name(kind), make_procedural(s, 1.0, Wrap::clamp));
  }
  if (only && std::strcmp(only, "dem") != 0) return 0;
  const std::filesystem::path dem = std::filesystem::path(HFBAKE_SHARED_DATA_DIR) / "TM1_564_146.tif";
  if (!std::filesystem::exists(dem)) {
    std::printf("DEM %s absent: skipped\n", dem.string().c_str());
    return 0;
  }
  const Plane p = read_image_channel(dem, 0, {}, {});
  // A 500 x 500 crop (the brute force is O(M^2) per line): metres, 1 m texels.
  HeightField f;
  f.width = f.height = 500;
  f.texel_size = 1.0;
  f.z.resize(f.texel_count());
  for (int j = 0; j < 500; ++j)
    for (int i = 0; i < 500; ++i) f.z[f.index(i, j)] = p.values[std::size_t(j + 250) * p.width + (i + 250)];
  measure_field("DEM500", f);
  return 0;
}

}  // namespace
}  // namespace hfbake

int main(int argc, char** argv) {
  for (int a = 1; a < argc; ++a)
    if (std::strcmp(argv[a], "--measure") == 0) return hfbake::measure(a + 1 < argc ? argv[a + 1] : nullptr);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
