// Throughput of environment lookups and of the structures built from an environment.
#include <benchmark/benchmark.h>

#include <random>

#include "env/environment.hpp"

namespace hfbake {
namespace {

Environment random_env(int h) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::vector<Rgb> t(std::size_t(2 * h) * h);
  for (Rgb& x : t) x = {u(rng), u(rng), u(rng)};
  return make_latlong_environment(2 * h, h, std::move(t));
}

std::vector<Vec3> directions(int n) {
  std::mt19937 rng(2);
  std::normal_distribution<double> g;
  std::vector<Vec3> d(n);
  for (Vec3& v : d) v = normalize({g(rng), g(rng), g(rng)});
  return d;
}

void BM_Radiance(benchmark::State& state) {
  const Environment env = random_env(int(state.range(0)));
  const auto dirs = directions(4096);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(env.radiance(dirs[i++ & 4095]));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Radiance)->Arg(64)->Arg(512);

void BM_RadianceFiltered(benchmark::State& state) {
  const Environment env = random_env(512);
  const auto dirs = directions(4096);
  const double cone = 0.05;
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(env.radiance_filtered(dirs[i++ & 4095], cone));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RadianceFiltered);

void BM_BuildMips(benchmark::State& state) {
  const Environment src = random_env(int(state.range(0)));
  for (auto _ : state) {
    Environment env = src;
    build_mip_levels(env);
    benchmark::DoNotOptimize(env.levels.back().texels.data());
  }
  state.SetItemsProcessed(state.iterations() * 2 * state.range(0) * state.range(0));  // level-0 texels
}
BENCHMARK(BM_BuildMips)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);

void BM_CubeView(benchmark::State& state) {
  const Environment env = random_env(256);
  const int size = int(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(make_cube_view(env, size).faces[0].data());
  state.SetItemsProcessed(state.iterations() * 6 * size * size);  // cube texels
}
BENCHMARK(BM_CubeView)->Arg(16)->Arg(64)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hfbake

BENCHMARK_MAIN();
