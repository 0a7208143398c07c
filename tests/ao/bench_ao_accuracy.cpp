// Accuracy against cost on a fractal field (128^2, texel 1, clamp), radius 16 with the step falloff: hbao and
// hsao at practical settings against hbao at K = 128, step 1/4 texel (the slab integral converged: the
// closed-form table shows hbao within the raster error), and vo against its own limit (box VO, brute force).
// Counters: mae, rmse, max of the occluded fraction; time per texel. One thread.
//   build-ao/tests/ao/ao_bench_ao_accuracy
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <time.h>

#include <cmath>

#include "field/procedural.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/hsao.hpp"
#include "methods/ao/vo.hpp"

namespace hfbake {
namespace {

constexpr int kSize = 128;
constexpr double kRadius = 16;

struct Fixture {
  HeightField field;
  std::vector<Vec3f> normals;
  std::vector<float> truth;  // hbao reference, obscurance
};

HbaoSettings hbao_settings(int K, double step) {
  HbaoSettings s;
  s.falloff.kind = FalloffKind::step;
  s.falloff.radius = kRadius;
  s.directions = uniform_directions(K);
  s.step = step;
  s.reach = kRadius;
  return s;
}

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture x;
    ProceduralSpec spec;
    spec.kind = ProceduralKind::fractal;
    spec.width = spec.height = kSize;
    spec.seed = 3;
    x.field = make_procedural(spec, 1.0, Wrap::clamp);
    x.normals = compute_normals(x.field);
    x.truth.resize(x.field.texel_count());
    hbao_field(x.field, x.normals, hbao_settings(128, 0.25), RunControl{}, x.truth.data(), nullptr);
    return x;
  }();
  return f;
}

// CPU seconds of this thread (the work runs on it: oneTBB is limited to one thread).
double cpu_seconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

void report(benchmark::State& state, const std::vector<float>& got, const std::vector<float>& truth,
            double cpu) {
  double sum = 0, sq = 0, worst = 0;
  for (std::size_t t = 0; t < got.size(); ++t) {
    const double e = std::abs(double(got[t]) - truth[t]);
    sum += e, sq += e * e, worst = std::max(worst, e);
  }
  state.counters["mae"] = sum / got.size();
  state.counters["rmse"] = std::sqrt(sq / got.size());
  state.counters["max"] = worst;
  state.counters["us_per_texel"] = 1e6 * cpu / (double(got.size()) * state.iterations());
}

void BM_Hbao(benchmark::State& state) {
  const Fixture& f = fixture();
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  std::vector<float> got(f.field.texel_count());
  const HbaoSettings s = hbao_settings(int(state.range(0)), 1.0 / state.range(1));
  const double t0 = cpu_seconds();
  for (auto _ : state) hbao_field(f.field, f.normals, s, RunControl{}, got.data(), nullptr);
  report(state, got, f.truth, cpu_seconds() - t0);
}
// Args: K, samples per texel of distance.
BENCHMARK(BM_Hbao)
    ->Args({8, 1})
    ->Args({16, 1})
    ->Args({32, 1})
    ->Args({16, 2})
    ->Args({16, 4})
    ->Args({64, 4})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

void BM_Hsao(benchmark::State& state) {
  const Fixture& f = fixture();
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  HsaoSettings s;
  s.falloff.kind = FalloffKind::step;
  s.falloff.radius = kRadius;
  s.directions = int(state.range(0));
  s.steps = int(state.range(1));
  s.normal_rays = int(state.range(2));
  std::vector<float> got(f.field.texel_count());
  const double t0 = cpu_seconds();
  for (auto _ : state) hsao_field(f.field, f.normals, s, RunControl{}, got.data(), nullptr);
  report(state, got, f.truth, cpu_seconds() - t0);
}
BENCHMARK(BM_Hsao)
    ->Args({8, 16, 0})
    ->Args({8, 16, 2})
    ->Args({16, 16, 2})
    ->Args({16, 32, 2})
    ->Args({32, 32, 2})
    ->Args({32, 64, 4})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

void BM_VoAgainstBoxVo(benchmark::State& state) {
  const Fixture& f = fixture();
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  VoSettings s;
  s.radius = 8, s.box_height = 8, s.fade = 8, s.levels = int(state.range(0));
  std::vector<float> got;
  const double t0 = cpu_seconds();
  for (auto _ : state) got = vo_occlusion(f.field, f.normals, s, RunControl{});
  const double cpu = cpu_seconds() - t0;
  std::vector<float> box(f.field.texel_count());
  for (int j = 0; j < kSize; ++j)
    for (int i = 0; i < kSize; ++i)
      box[f.field.index(i, j)] = float(vo_brute_force(f.field, f.normals[f.field.index(i, j)].d(), i, j, s));
  report(state, got, box, cpu);
}
BENCHMARK(BM_VoAgainstBoxVo)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hfbake

BENCHMARK_MAIN();
