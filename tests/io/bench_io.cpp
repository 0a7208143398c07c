// Throughput of the EXR writer (half/float, zip/piz/none) and of environment loading (resampling).
#include <benchmark/benchmark.h>

#include <ImfThreading.h>
#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <map>

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

// A bake's own EXR (the file named by $HFBAKE_BENCH_EXR, e.g. a p1 bake with a 64-channel horizon layer),
// read back into layers and written again. Args: compression (0 zip, 1 piz, 2 dwaa, 3 dwab, 4 none), float
// (0/1), threads (OpenEXR's pool; 0 = none), tile size (0 = scanlines).
LayerSet baked_layers() {
  const char* file = std::getenv("HFBAKE_BENCH_EXR");
  LayerSet set;
  if (!file) return set;
  auto in = OIIO::ImageInput::open(file);
  if (!in) return set;
  const OIIO::ImageSpec spec = in->spec();
  std::vector<float> px(std::size_t(spec.width) * spec.height * spec.nchannels);
  in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data());
  set.width = spec.width;
  set.height = spec.height;
  std::map<std::string, std::vector<int>> by_layer;  // layer -> its channels in the file
  std::vector<std::string> order;
  for (int c = 0; c < spec.nchannels; ++c) {
    const std::string& n = spec.channelnames[c];
    const std::string layer = n.substr(0, n.rfind('.'));
    if (!by_layer.count(layer)) order.push_back(layer);
    by_layer[layer].push_back(c);
  }
  for (const std::string& name : order) {
    std::vector<std::string> suffixes;
    for (int c : by_layer[name]) suffixes.push_back(spec.channelnames[c].substr(name.size() + 1));
    Layer& l = set.add(name, suffixes);
    const std::size_t nc = suffixes.size(), texels = std::size_t(spec.width) * spec.height;
    for (std::size_t t = 0; t < texels; ++t)
      for (std::size_t k = 0; k < nc; ++k) l.data[t * nc + k] = px[t * spec.nchannels + by_layer[name][k]];
  }
  return set;
}

void BM_WriteBakedExr(benchmark::State& state) {
  static const LayerSet set = baked_layers();
  if (set.layers.empty()) {
    state.SkipWithError("set HFBAKE_BENCH_EXR to a baked EXR");
    return;
  }
  test::TempFolder dir;
  static const char* const names[] = {"zip", "piz", "dwaa", "dwab", "none"};
  ExrOptions o;
  o.compression = names[state.range(0)];
  o.float_pixels = state.range(1) != 0;
  Imf::setGlobalThreadCount(int(state.range(2)));
  o.threads = int(state.range(2));
  o.tile_size = int(state.range(3));
  for (auto _ : state) write_exr(dir / "bench.exr", set, o);
  Imf::setGlobalThreadCount(0);
  state.counters["file_MB"] = double(std::filesystem::file_size(dir / "bench.exr")) / 1e6;
}
BENCHMARK(BM_WriteBakedExr)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {0, 1}, {0, 2}, {0}})
    ->ArgsProduct({{0, 1}, {0}, {2}, {64, 256}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

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
