// Reference throughput: ao occlusion rays per second on a 1024^2 fractal field with 2 threads (grid vs
// triangle mesh vs quads, ray streams vs single rays; and Embree's calls alone), and the time to a per-texel
// ao standard error of 0.005 at 512^2. Run: build/tests/reference/bench_reference [--benchmark_filter=...]
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <sys/resource.h>

#include <chrono>
#include <limits>

#include "field/procedural.hpp"
#include "reference/bake_reference.hpp"
#include "reference/embree_field.hpp"
#include "reference/sampling.hpp"

namespace hfbake {
namespace {

Scene fractal_scene(int size) {
  ProceduralSpec p;
  p.kind = ProceduralKind::fractal;
  p.width = p.height = size;
  p.seed = 7;
  Scene s;
  s.field = make_procedural(p, 1.0, Wrap::clamp);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
  s.environment = make_uniform_environment({1, 1, 1});
  s.bounces = 0;
  return s;
}

// Process CPU seconds (all threads): the machine is shared, so wall time alone says little; with 2 threads
// and no competition, rays per wall second = 2 x rays per CPU second.
double cpu_seconds() {
  rusage u;
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

const Scene& scene1024() {
  static const Scene s = fractal_scene(1024);
  return s;
}

// ao only: one occlusion ray per sample, 256 samples a texel (32 per replicate: the default), on the rows
// 448..575 of the 1024^2 field (traced against the whole field). Rays = texels x samples. Arg 0: geometry
// (grid, triangles, quads), arg 1: rtcOccluded1M streams instead of single rays.
void BM_AoRays1024(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  const Scene& s = scene1024();
  ReferenceOptions o;
  o.layers = {"ao"};
  o.samples = 256;
  o.row_begin = 448;
  o.row_end = 576;
  const reference::GeometryKind kinds[] = {reference::GeometryKind::grid, reference::GeometryKind::triangles,
                                           reference::GeometryKind::quads};
  o.geometry = kinds[state.range(0)];
  o.ray_streams = state.range(1) != 0;
  double rays = 0, trace_cpu = 0, build_cpu = 0;
  for (auto _ : state) {
    const double c0 = cpu_seconds();
    { const reference::EmbreeField g(s.field, o.geometry, 1); }
    const double c1 = cpu_seconds();
    const LayerSet r = bake_reference(s, o, {});
    const double c2 = cpu_seconds();
    benchmark::DoNotOptimize(r.layers[0].data.data());
    rays += double(s.field.width) * (o.row_end - o.row_begin) * o.samples;
    build_cpu += c1 - c0;
    trace_cpu += (c2 - c1) - (c1 - c0);  // the bake builds the same scene once
  }
  state.counters["rays_per_cpu_second"] = rays / trace_cpu;
  state.counters["rays_per_second_2_threads"] = 2 * rays / trace_cpu;
  state.counters["build_cpu_seconds"] = build_cpu / double(state.iterations());
  const char* geometries[] = {"grid", "triangles", "quads"};
  state.SetLabel(std::string(geometries[state.range(0)]) +
                 (state.range(1) ? ", 1M streams" : ", single rays"));
}
BENCHMARK(BM_AoRays1024)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

// Embree's occlusion calls side by side on the same rays: 64 cosine-distributed rays from each of 64k texels
// of the 1024^2 field (every 4th texel of every 4th row), traced one by one (rtcOccluded1), as packets of
// 4, 8, 16 rays of one texel (rtcOccluded4/8/16), or as one stream (rtcOccluded1M); kernel 0 only makes the
// rays (the cost of the sample generation). Arg 0: kernel, arg 1: triangles instead of the grid.
template <int N, typename Packet, typename Call>
void trace_packets(RTCScene scene, const std::vector<RTCRay>& rays, int n, Call call, int& free_rays) {
  RTCIntersectContext c;
  rtcInitIntersectContext(&c);
  alignas(64) Packet p;
  alignas(64) int valid[N];
  for (int k0 = 0; k0 < n; k0 += N) {
    for (int q = 0; q < N; ++q) {
      const RTCRay& r = rays[std::size_t(k0 + q)];
      valid[q] = -1;
      p.org_x[q] = r.org_x, p.org_y[q] = r.org_y, p.org_z[q] = r.org_z;
      p.dir_x[q] = r.dir_x, p.dir_y[q] = r.dir_y, p.dir_z[q] = r.dir_z;
      p.tnear[q] = 0, p.tfar[q] = r.tfar, p.time[q] = 0, p.mask[q] = ~0u, p.id[q] = 0, p.flags[q] = 0;
    }
    call(valid, scene, &c, &p);
    for (int q = 0; q < N; ++q) free_rays += p.tfar[q] >= 0;
  }
}

void BM_OcclusionKernels(benchmark::State& state) {
  const Scene& s = scene1024();
  const int kernel = int(state.range(0));
  const reference::GeometryKind kinds[] = {reference::GeometryKind::grid, reference::GeometryKind::triangles,
                                           reference::GeometryKind::quads};
  const reference::EmbreeField g(s.field, kinds[state.range(1)], 1);
  constexpr int kRays = 64;
  std::vector<RTCRay> rays(kRays);
  double traced = 0, cpu = 0;
  int free_rays = 0;
  for (auto _ : state) {
    const double c0 = cpu_seconds();
    for (int j = 0; j < s.field.height; j += 4)
      for (int i = 0; i < s.field.width; i += 4) {
        const Vec3 n = s.normals[s.field.index(i, j)].d();
        const Vec3 o = s.field.position(i, j) + Vec3{0, 0, g.epsilon()};
        const reference::Sequence2 seq = reference::Sequence2::make(std::uint64_t(s.field.index(i, j)));
        for (int k = 0; k < kRays; ++k) {
          const Vec3 d = reference::cosine_hemisphere(n, seq(std::uint32_t(k)));
          RTCRay& r = rays[std::size_t(k)];
          r.org_x = float(o.x), r.org_y = float(o.y), r.org_z = float(o.z), r.tnear = 0;
          r.dir_x = float(d.x), r.dir_y = float(d.y), r.dir_z = float(d.z), r.time = 0;
          r.tfar = std::numeric_limits<float>::infinity(), r.mask = ~0u, r.id = 0, r.flags = 0;
        }
        RTCIntersectContext c;
        rtcInitIntersectContext(&c);
        switch (kernel) {
          case 1:
            for (RTCRay& r : rays) rtcOccluded1(g.scene(), &c, &r);
            for (const RTCRay& r : rays) free_rays += r.tfar >= 0;
            break;
          case 2:
            trace_packets<4, RTCRay4>(g.scene(), rays, kRays, rtcOccluded4, free_rays);
            break;
          case 3:
            trace_packets<8, RTCRay8>(g.scene(), rays, kRays, rtcOccluded8, free_rays);
            break;
          case 4:
            trace_packets<16, RTCRay16>(g.scene(), rays, kRays, rtcOccluded16, free_rays);
            break;
          case 5:
            rtcOccluded1M(g.scene(), &c, rays.data(), kRays, sizeof(RTCRay));
            for (const RTCRay& r : rays) free_rays += r.tfar >= 0;
            break;
          default:
            break;
        }
        traced += kRays;
      }
    cpu += cpu_seconds() - c0;
  }
  benchmark::DoNotOptimize(free_rays);  // (a count of escaped rays: keeps the traces from being dropped)
  state.counters["rays_per_cpu_second"] = traced / cpu;
  const char* names[] = {"make rays only", "rtcOccluded1",  "rtcOccluded4",
                         "rtcOccluded8",   "rtcOccluded16", "rtcOccluded1M"};
  const char* geometries[] = {", grid", ", triangles", ", quads"};
  state.SetLabel(std::string(names[kernel]) + geometries[state.range(1)]);
}
BENCHMARK(BM_OcclusionKernels)
    ->ArgsProduct({{0, 1, 2, 3, 4, 5}, {0, 1, 2}})
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

// Time to a per-texel ao standard error of 0.005 at 512^2 (target_stderr, samples capped at 16384).
void BM_AoToStderr512(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  const Scene s = fractal_scene(512);
  ReferenceOptions o;
  o.layers = {"ao"};
  o.samples = 16384;
  o.target_stderr = 0.005;
  double mean_samples = 0, max_se = 0, cpu = 0;
  for (auto _ : state) {
    const double c0 = cpu_seconds();
    const LayerSet r = bake_reference(s, o, {});
    cpu = cpu_seconds() - c0;
    const Layer& n = *r.find("samples");
    const Layer& se = *r.find("ao_stderr");
    mean_samples = 0, max_se = 0;
    for (float v : n.data) mean_samples += v / double(n.data.size());
    for (float v : se.data) max_se = std::max(max_se, double(v));
  }
  state.counters["mean_samples_per_texel"] = mean_samples;
  state.counters["max_stderr"] = max_se;
  state.counters["cpu_seconds"] = cpu;
  state.counters["seconds_2_threads_unloaded"] = cpu / 2;
}
BENCHMARK(BM_AoToStderr512)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// Everything at once on a 256^2 field (ao, vsky, direct, indirect with 2 bounces under the built-in sky).
void BM_AllLayers256(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  Scene s = fractal_scene(256);
  SkySpec spec;
  const EnvironmentLighting sky = make_sky_environment(spec);
  s.environment = sky.environment;
  s.lights = sky.lights;
  s.bounces = 2;
  ReferenceOptions o;
  o.layers = {"ao", "vsky", "direct", "indirect", "total"};
  o.samples = 64;
  o.ray_streams = state.range(0) != 0;
  double cpu = 0;
  for (auto _ : state) {
    const double c0 = cpu_seconds();
    benchmark::DoNotOptimize(bake_reference(s, o, {}).layers[0].data.data());
    cpu += cpu_seconds() - c0;
  }
  state.counters["cpu_seconds"] = cpu / double(state.iterations());
  state.SetLabel(state.range(0) ? "1M streams" : "single rays");
}
BENCHMARK(BM_AllLayers256)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// Is the reported stderr honest? A 48^2 tiling fractal against a 16384-sample truth: rms error vs rms
// stderr for ao, vsky and indirect (3 bounces) at 1024 samples, and for ao with target_stderr 0.01.
void BM_StderrCalibration(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  ProceduralSpec p;
  p.kind = ProceduralKind::fractal;
  p.width = p.height = 48;
  p.amplitude = 10;
  p.feature_size = 24;
  Scene s;
  s.field = make_procedural(p, 1.0, Wrap::repeat);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{0.6f, 0.6f, 0.6f});
  s.environment = make_uniform_environment({1, 1, 1});
  s.bounces = 3;
  for (auto _ : state) {
    ReferenceOptions o;
    o.layers = {"ao", "vsky", "indirect"};
    o.samples = 16384;
    const LayerSet truth = bake_reference(s, o, {});
    o.samples = 1024;
    o.seed = 7;
    const LayerSet r = bake_reference(s, o, {});
    ReferenceOptions a;
    a.layers = {"ao"};
    a.samples = 16384;
    a.target_stderr = 0.01;
    a.seed = 9;
    const LayerSet ad = bake_reference(s, a, {});
    auto stats = [&](const LayerSet& l, const std::string& name, const std::string& label) {
      const Layer &v = *l.find(name), &se = *l.find(name + "_stderr"), &t = *truth.find(name);
      double e2 = 0, s2 = 0;
      for (std::size_t k = 0; k < v.data.size(); ++k) {
        const double d = v.data[k] - t.data[k];
        e2 += d * d, s2 += double(se.data[k]) * se.data[k];
      }
      state.counters[label + "_rms_error"] = std::sqrt(e2 / double(v.data.size()));
      state.counters[label + "_rms_stderr"] = std::sqrt(s2 / double(v.data.size()));
    };
    stats(r, "ao", "ao");
    stats(r, "vsky", "vsky");
    stats(r, "indirect", "indirect");
    stats(ad, "ao", "ao_target0.01");
  }
}
BENCHMARK(BM_StderrCalibration)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
}  // namespace hfbake

BENCHMARK_MAIN();
