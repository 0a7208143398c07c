// nlp throughput: seconds and texels per second for a whole bake (pyramids, visibility, direct, bounces)
// on the fractal field under the sky and sun, 512^2 and 1024^2, m = 32, 1-3 bounces, 1 and 2 threads
// (tbb::global_control), 2x2 subsampling; m = 16, 64 at one bounce; `preset` 0 = the defaults, 1 = the
// previous defaults (texel senders, SH cosines, B-spline horizon, no near_spacing). Counters give the height
// pyramid's memory. Iterations(1) and real time: a bake is seconds long. BM_MarchRow: the row march alone
// (one azimuth, a row of receivers), texel-directions per second.
//   bench_nlp [--benchmark_filter=...]
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>
#include <string>
#include <vector>

#include "field/procedural.hpp"
#include "methods/nlp/bake_nlp.hpp"
#include "methods/nlp/horizon_march.hpp"
#include "methods/nlp/pyramid.hpp"

using namespace hfbake;

namespace {

Scene fractal_scene(int size) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = spec.height = size;
  spec.seed = 7;
  Scene s;
  s.field = make_procedural(spec, 1.0, Wrap::clamp);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
  const EnvironmentLighting sky = make_sky_environment(SkySpec{});
  s.environment = sky.environment;
  s.lights = sky.lights;
  s.bounces = 1;
  return s;
}

void BM_Bake(benchmark::State& state) {
  const int size = int(state.range(0)), m = int(state.range(1)), bounces = int(state.range(2)),
            sub = int(state.range(3)), threads = int(state.range(4)), preset = int(state.range(5));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  Scene s = fractal_scene(size);
  s.bounces = bounces;
  NlpOptions o;
  o.directions = m;
  o.subsample = sub;
  if (preset == 1) {
    o.facet_senders = o.exact_direct_cosine = o.exact_indirect_cosine = o.visibility_horizon_knots = false;
    o.near_spacing = 0;
  }
  o.layers = {"direct", "indirect", "total"};
  for (auto _ : state) {
    LayerSet ls = bake_nlp(s, o, RunControl{});
    benchmark::DoNotOptimize(ls.layers.front().data.data());
  }
  state.counters["texels/s"] =
      benchmark::Counter(double(s.field.texel_count()) * state.iterations(), benchmark::Counter::kIsRate);
  const nlp::MarchSetup ms = nlp::make_march_setup(size, size, 1.0, Wrap::clamp, o.levels_per_octave,
                                                   o.level_offset, o.radiance_level_offset);
  const nlp::Pyramid hp = nlp::build_pyramid(s.field.z.data(), 1, size, size, Wrap::clamp,
                                             o.levels_per_octave, nlp::height_levels(ms));
  state.counters["height_pyramid_MB"] = double(hp.bytes()) / 1e6;
  state.counters["height_levels"] = double(hp.levels.size());
  state.counters["full_res_stack_MB"] = double(hp.levels.size()) * size * size * 4 / 1e6;
}

// The row march of every row of a 512^2 fractal along one azimuth (near_spacing 0.5 or 0), and the angles.
void BM_MarchRow(benchmark::State& state) {
  const int size = 512;
  const float spacing = float(state.range(0)) / 10;
  const double phi = double(state.range(1)) * 3.14159265358979 / 180;
  const Scene s = fractal_scene(size);
  nlp::MarchSetup ms = nlp::make_march_setup(size, size, 1.0, Wrap::clamp, 4, 4, 4);
  ms.near_spacing = spacing;
  const nlp::Pyramid hp =
      nlp::build_pyramid(s.field.z.data(), 1, size, size, Wrap::clamp, 4, nlp::height_levels(ms));
  const int lv = int(hp.levels.size());
  std::vector<int> xs(static_cast<std::size_t>(size));
  for (int i = 0; i < size; ++i) xs[std::size_t(i)] = i;
  std::vector<std::vector<float>> recv(static_cast<std::size_t>(size));
  for (int j = 0; j < size; ++j) {
    recv[std::size_t(j)].resize(std::size_t(lv) * size);
    for (int l = 0; l < lv; ++l)
      for (int i = 0; i < size; ++i)
        recv[std::size_t(j)][std::size_t(l) * size + i] =
            nlp::sample_level1(hp, hp.levels[l], float(i), float(j));
  }
  nlp::RowMarch rm(ms.steps, size);
  const float cx = float(std::cos(phi)), cy = float(std::sin(phi));
  for (auto _ : state)
    for (int j = 0; j < size; ++j) {
      nlp::march_row(ms, hp, xs.data(), size, true, j, cx, cy, recv[std::size_t(j)].data(), size, rm);
      nlp::row_angles(rm, size);
      benchmark::DoNotOptimize(rm.omega.data());
    }
  state.counters["texel-directions/s"] =
      benchmark::Counter(double(size) * size * state.iterations(), benchmark::Counter::kIsRate);
}

}  // namespace

void bake_args(benchmark::internal::Benchmark* b) {
  for (int size : {512, 1024})
    for (int threads : {1, 2})
      for (int bounces : {1, 2, 3}) b->Args({size, 32, bounces, 1, threads, 0});
  for (int size : {512, 1024}) {
    b->Args({size, 32, 1, 1, 2, 1});
    b->Args({size, 32, 1, 2, 2, 0});
    b->Args({size, 16, 1, 1, 2, 0});
    b->Args({size, 64, 1, 1, 2, 0});
  }
}

BENCHMARK(BM_Bake)
    ->ArgNames({"size", "m", "bounces", "sub", "threads", "preset"})
    ->Apply(bake_args)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

BENCHMARK(BM_MarchRow)
    ->ArgNames({"near_spacing_x10", "azimuth_deg"})
    ->Args({5, 30})
    ->Args({0, 30})
    ->Args({5, 0});

BENCHMARK_MAIN();
