// Throughput of the EXR writer (half/float, zip/piz/none) and of environment loading (resampling).
#include <benchmark/benchmark.h>

#include <nlohmann/json.hpp>

#include "image_fixtures.hpp"
#include "io/exr_output.hpp"
#include "io/load_environment.hpp"
#include "temp_folder.hpp"

namespace hfbake {
namespace {

LayerSet layers(int n) {
  LayerSet set;
  set.width = set.height = n;
  for (const char* name : {"ao", "vsky"}) {
    Layer& l = set.add(name, mono_channels());
    for (std::size_t i = 0; i < l.data.size(); ++i) l.data[i] = float((i * 2654435761u) % 1000) / 1000.f;
  }
  for (const char* name : {"direct", "indirect", "total"}) {
    Layer& l = set.add(name, rgb_channels());
    for (std::size_t i = 0; i < l.data.size(); ++i) l.data[i] = 0.5f + 0.3f * std::sin(float(i) * 1e-3f);
  }
  return set;  // 11 channels
}

// Args: field size, float (0/1), compression (0 zip, 1 piz, 2 none).
void BM_WriteExr(benchmark::State& state) {
  test::TempFolder dir;
  const LayerSet set = layers(int(state.range(0)));
  ExrOptions o;
  o.float_pixels = state.range(1) != 0;
  o.compression = state.range(2) == 0 ? "zip" : state.range(2) == 1 ? "piz" : "none";
  for (auto _ : state) write_exr(dir / "bench.exr", set, o);
  state.SetItemsProcessed(state.iterations() * state.range(0) * state.range(0));  // texels
  state.counters["file_MB"] = double(std::filesystem::file_size(dir / "bench.exr")) / 1e6;
}
BENCHMARK(BM_WriteExr)
    ->Args({1024, 0, 0})
    ->Args({1024, 0, 1})
    ->Args({1024, 0, 2})
    ->Args({1024, 1, 0})
    ->Unit(benchmark::kMillisecond);

// A W x W/2 float lat-long resampled into the world frame (rows: the next power of two, capped at 1024).
void BM_LoadLatLong(benchmark::State& state) {
  test::TempFolder dir;
  const int w = int(state.range(0)), h = w / 2;
  std::vector<float> px(std::size_t(w) * h * 3);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = float(i % 97) / 97.f;
  test::write_test_image(dir / "env.exr", w, h, 3, px, OIIO::TypeDesc::HALF);
  const nlohmann::json j = {{"latlong", "env.exr"}};
  for (auto _ : state) benchmark::DoNotOptimize(load_environment(j, dir.path()).environment.levels.size());
  state.SetItemsProcessed(state.iterations() * w * h);  // input pixels
}
BENCHMARK(BM_LoadLatLong)->Arg(1024)->Arg(4096)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hfbake

BENCHMARK_MAIN();
