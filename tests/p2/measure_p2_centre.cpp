// P2 accuracy decomposition (a measurement program, not a test). For a job's scene and one bounce, on a
// strided subset of texels, compares
//   P2(K):  compute_p2's indirect_b1 (facet senders);
//   T_c(K): the same senders (every facet's exit radiance, its corners' mean, constant over the facet: the
//           exact near field's own rule, the light at the texel and along each facet, is test_p2_bake's
//           brute force) gathered from the
//           texel centre itself over the reference's triangulated surface: along each of the K azimuths the
//           profile is piecewise linear with kinks at every column, row and diagonal crossing, each piece
//           lies on one facet, and a piece is visible over the elevations above everything nearer;
//           weighted by the same wedge weights at the texel's normal (indirect_gather.hpp);
//   the reference (the job's cached reference EXR, indirect_b1 and its stderr).
// P2 - T_c is the sweep's part (line samples at column crossings, receivers blended to the texel);
// T_c - reference is what the sender model and K leave (excess = rms minus the reference's own standard
// errors, in quadrature).
// Usage: measure_p2_centre <job.json> <reference.exr|-> <stride> K [S] [near_radius]
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "../p1/p1_truth.hpp"
#include "cli/scene_loader.hpp"
#include "io/image_input.hpp"
#include "methods/p1/p1.hpp"
#include "methods/p2/bake_p2.hpp"
#include "methods/p2/indirect_gather.hpp"

using namespace hfbake;

namespace {

double tri_height(const HeightField& f, double x, double y) {
  return f.triangle_height(x, y);
}

// E/pi of bounce 1 at texel (i, j) from the facet exit radiance, K azimuths, marched from the centre.
double centre_gather(const HeightField& f, const std::vector<Vec3f>& normals, const std::vector<Rgb>& exit_f,
                     int i, int j, int K) {
  const Vec3 n = normals[f.index(i, j)].d();
  const double z0 = f.z[f.index(i, j)];
  double sum = 0;
  std::vector<double> s;
  for (int k = 0; k < K; ++k) {
    const double phi = 2 * kPi * k / K, dx = std::cos(phi), dy = std::sin(phi);
    const WedgeWeights w = WedgeWeights::make(n, dx, dy, 2 * kPi / K);
    // every crossing of a column, row or diagonal on the field, by distance
    s.clear();
    auto family = [&](double origin, double d) {
      if (std::fabs(d) < 1e-12) return;
      for (double c = d > 0 ? std::floor(origin) + 1 : std::ceil(origin) - 1;; c += d > 0 ? 1 : -1) {
        const double t = (c - origin) / d;
        const double x = i + t * dx, y = j + t * dy;
        if (x < -1e-9 || y < -1e-9 || x > f.width - 1 + 1e-9 || y > f.height - 1 + 1e-9) break;
        s.push_back(t);
      }
    };
    family(i, dx);
    family(j, dy);
    family(i + j, dx + dy);
    std::sort(s.begin(), s.end());
    double prev_t = 0, m = -1e300, acc = 0;
    for (double t : s) {
      if (t - prev_t < 1e-9) continue;
      const double x = std::clamp(i + t * dx, 0.0, double(f.width - 1)),
                   y = std::clamp(j + t * dy, 0.0, double(f.height - 1));
      const double slope = (tri_height(f, x, y) - z0) / (t * f.texel_size);
      // the facet under the piece (prev_t, t)
      const double u = 0.5 * (prev_t + t), mx = i + u * dx, my = j + u * dy;
      const int ci = int(std::floor(mx)), cj = int(std::floor(my));
      const bool lower = (mx - ci) + (my - cj) <= 1;
      const int ti = std::clamp(lower ? ci : ci + 1, 0, f.width - 1),
                tj = std::clamp(lower ? cj : cj + 1, 0, f.height - 1);
      const double L = exit_f[2 * f.index(ti, tj) + (lower ? 0 : 1)].g;
      const double lo = prev_t == 0 ? w.t_n : std::max(m, w.t_n);  // the first piece also fills the crease
      if (slope > lo) acc += L * (w.F(slope) - w.F(lo));
      m = std::max(m, slope);
      prev_t = t;
    }
    sum += acc;
  }
  return sum / kPi;
}

using Stats = truth::ErrorStats;

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: measure_p2_centre <job.json> <reference.exr|-> <stride> K [S]\n");
    return 2;
  }
  const JobLoad jl = load_job(argv[1], std::nullopt);
  if (!jl.job) {
    for (const std::string& e : jl.errors) std::fprintf(stderr, "%s\n", e.c_str());
    return 1;
  }
  Scene scene = load_scene(*jl.job);
  scene.bounces = 1;
  const HeightField& f = scene.field;
  const int stride = std::atoi(argv[3]), K = std::atoi(argv[4]), S = argc > 5 ? std::atoi(argv[5]) : 1;
  const double near_radius = argc > 6 ? std::atof(argv[6]) : P2Params{}.near_radius;

  P2Params p;
  p.directions = K;
  p.bounces = 1;
  p.supersampling = S;
  p.near_radius = near_radius;
  const std::size_t N = f.texel_count();
  // The facets' exit radiance as compute_p2 makes it (each facet's corner mean, P2State::facet_exit).
  const std::vector<Rgb> exit_f =
      p2_state_of_direct(scene, p, compute_p1(scene, p2_direct_params(p, false), RunControl{})).facet_exit;
  const P2Result r = compute_p2(scene, p, RunControl{});

  std::vector<float> ref, se;
  if (std::string(argv[2]) != "-") {
    const Image img = read_image(argv[2], {});
    int c = -1, cs = -1;
    for (int ch = 0; ch < img.info.channels; ++ch) {  // one bounce: indirect is indirect_b1
      const std::string& name = img.info.channel_names[ch];
      if (name == "indirect_b1.G" || (c < 0 && name == "indirect.G")) c = ch;
      if (name == "indirect_b1_stderr.G" || (cs < 0 && name == "indirect_stderr.G")) cs = ch;
    }
    if (c < 0 || cs < 0) {
      std::fprintf(stderr, "%s: no indirect_b1 (or indirect) layer with its stderr\n", argv[2]);
      return 1;
    }
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) ref.push_back(img.at(i, j, c)), se.push_back(img.at(i, j, cs));
  }
  std::vector<std::pair<int, int>> texels;
  for (int j = stride / 2; j < f.height; j += stride)
    for (int i = stride / 2; i < f.width; i += stride) texels.push_back({i, j});
  std::vector<double> tc(texels.size());
  tbb::parallel_for(std::size_t(0), texels.size(), [&](std::size_t t) {
    tc[t] = centre_gather(f, scene.normals, exit_f, texels[t].first, texels[t].second, K);
  });
  Stats p_t, t_ref, p_ref;
  double mean = 0;
  for (std::size_t t = 0; t < texels.size(); ++t) {
    const std::size_t idx = f.index(texels[t].first, texels[t].second);
    const double pv = r.indirect_b[0][idx].g;
    p_t.add(pv - tc[t]);
    mean += tc[t] / double(texels.size());
    if (!ref.empty()) {
      const double v = double(se[idx]) * se[idx];
      t_ref.add(tc[t] - ref[idx], v), p_ref.add(pv - ref[idx], v);
    }
  }
  std::printf("%s K=%d S=%d near %g, %zu texels: mean T_c %.5f | P2-T_c mean %+.5f rms %.5f", argv[1], K, S,
              near_radius, texels.size(), mean, p_t.mean(), p_t.rms());
  if (!ref.empty())
    std::printf(" | vs ref excess (bias): T_c %.5f (%+.5f) P2 %.5f (%+.5f)", t_ref.excess(), t_ref.mean(),
                p_ref.excess(), p_ref.mean());
  if (!ref.empty()) {  // P2 against the reference on every texel (what the job's report says)
    Stats all;
    for (std::size_t idx = 0; idx < N; ++idx)
      all.add(r.indirect_b[0][idx].g - ref[idx], double(se[idx]) * se[idx]);
    std::printf(" | all texels: P2 %.5f (%+.5f)", all.excess(), all.mean());
  }
  std::printf("\n");
  return 0;
}
