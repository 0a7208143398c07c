#include "methods/ao/lsao.hpp"

#include <algorithm>
#include <atomic>

#include "methods/ao/bake_ao.hpp"
#include "methods/ao/obscurance_params.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake {
namespace {

struct LsaoWorker {
  const LsaoOptions* options = nullptr;
  std::atomic<std::uint64_t>* samples = nullptr;
  std::atomic<std::uint64_t>* iterations = nullptr;
  ObscuranceHull hull;
  std::vector<SlicePoint> terrain;  // brute force only: the terrain samples seen so far

  void operator()(const SweepLine& line, float* out) {
    const OcclusionFunction& f = options->occlusion;
    hull.clear();
    hull.reserve(std::size_t(line.count));
    terrain.clear();
    const bool brute = options->estimator != LsaoEstimator::hull;
    const bool visible_only = options->estimator == LsaoEstimator::brute_visible;
    if (brute) terrain.reserve(std::size_t(line.count));
    for (int n = 0; n < line.count; ++n) {
      const SlicePoint p{line.s(n), double(line.z[n])};
      if (n >= line.first_receiver) {
        double v;
        if (!brute) {
          v = hull.receive(p, f);
        } else {
          v = f.none();
          double max_sin = -2.0;
          for (std::size_t q = terrain.size(); q-- > 0;) {
            const double hs = p.s - terrain[q].s, hz = terrain[q].z - p.z;
            const double se = sine_elevation(hs, hz);
            if (visible_only) {
              if (se < max_sin) continue;
              max_sin = se;
            }
            v = std::max(v, f(hs, hz));
          }
        }
        out[n - line.first_receiver] = float(v);
      } else if (!brute) {
        hull.receive(p,
                     f);  // warm-up samples prune like receivers, so the hull is the one of an endless line
      }
      if (line.is_terrain(n)) {
        if (brute)
          terrain.push_back(p);
        else
          hull.push(p);
      }
    }
    *samples += std::uint64_t(line.count);
    *iterations += hull.iterations();
  }
};

}  // namespace

std::vector<double> lsao_mean_occlusion(const HeightField& field, const LsaoOptions& options,
                                        const RunControl& rc, LsaoStats* stats) {
  SweepSpec spec;
  spec.directions = std::max(options.directions, 1);
  spec.channels = 1;
  spec.wrap_periods = std::max(options.wrap_periods, 1);
  std::vector<double> sum(field.texel_count(), 0.0);
  std::atomic<std::uint64_t> samples{0}, iterations{0};
  sweep_lines(
      field, spec, rc,
      [&] {
        LsaoWorker w;
        w.options = &options;
        w.samples = &samples;
        w.iterations = &iterations;
        return w;
      },
      [&](int, int i, int j, const TexelTaps& t) { sum[field.index(i, j)] += t.value(0); });
  const double inv = 1.0 / spec.directions;
  for (double& v : sum) v *= inv;
  if (stats) {
    stats->samples = samples;
    stats->iterations = iterations;
  }
  return sum;
}

std::vector<float> lsao_obscurance(const HeightField& field, const LsaoOptions& options, const RunControl& rc,
                                   LsaoStats* stats) {
  const std::vector<double> mean = lsao_mean_occlusion(field, options, rc, stats);
  std::vector<float> out(mean.size());
  for (std::size_t t = 0; t < mean.size(); ++t) out[t] = float(1.0 - std::clamp(mean[t], 0.0, 1.0));
  return out;
}

LayerSet bake_lsao(const Scene& scene, const nlohmann::json& params, const RunControl& rc) {
  LsaoOptions o;
  o.occlusion.rho = parse_falloff(params);
  o.occlusion.weighting = parse_weighting(params, true) == Weighting::uniform ? ObscuranceWeighting::uniform
                                                                              : ObscuranceWeighting::cosine;
  o.occlusion.sin_t = number_param(params, "tangent", -0.85, -1.0, 0.0);
  o.directions = int_param(params, "directions", 16, 1, 4096);
  const auto layers = select_layers(params, {"obscurance"}, {"obscurance"});
  LayerSet out;
  out.width = scene.field.width;
  out.height = scene.field.height;
  std::vector<float> light = lsao_obscurance(scene.field, o, rc);
  if (wants(layers, "obscurance")) out.add("obscurance", mono_channels()).data = std::move(light);
  return out;
}

}  // namespace hfbake
