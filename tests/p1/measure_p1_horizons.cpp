// P1's horizons against the exact march over the reference's triangulated surface from every texel centre
// (truth::march_tri: every column, row and diagonal crossing), per direction class (multiples of 45
// degrees, where the sweep's lines pass through the texel centres, and the rest), and P1's ao against the
// ao of the exact horizons (same K, same Eq. 5 at the texel normal). A measurement program, not a test.
// Usage:
//   measure_p1_horizons <field> <size> <K> [near_radius] [stride] [time]
//     field: rough60, rough70, rough80 (truth::rough_field, gain 0.7; rough70g5: gain 0.5), step4
//            (a 4 m step at 20 degrees), step4x (along a column), terraces (five 4 m steps, 16 texels
//            apart, at 30 degrees), fractal (the smooth built-in fBm), sines
//     stride: every stride-th texel in both axes (default 1)
//     time: also times compute_p1 (horizons + ao only) on the field, best of 3
//   Prints p99 / max of |sin h - sin h_exact| and the share above 0.05 per class, ao bias / rms / max.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "methods/p1/p1.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

HeightField make_field(const std::string& name, int size, bool* ok) {
  *ok = true;
  if (name == "rough60") return truth::rough_field(size, size, 60, 0.7, 3);
  if (name == "rough70") return truth::rough_field(size, size, 70, 0.7, 4);
  if (name == "rough80") return truth::rough_field(size, size, 80, 0.7, 5);
  if (name == "rough70g5") return truth::rough_field(size, size, 70, 0.5, 6);
  if (name == "step4") return truth::step_field(size, size, 4, 20);
  if (name == "step4x") return truth::step_field(size, size, 4, 0);
  if (name == "terraces") return truth::step_field(size, size, 4, 30, 5, 16);
  if (name == "fractal") return truth::procedural(ProceduralKind::fractal, size, size, Wrap::clamp);
  if (name == "sines") return truth::procedural(ProceduralKind::sines, size, size, Wrap::clamp);
  *ok = false;
  return {};
}

double march_exact_sin(const HeightField& f, const SweepDirection& d, int i, int j) {
  return std::sin(truth::march_tri(f, i, j, d.dx, d.dy, 7));
}

double quantile(std::vector<float> v, double q) {
  if (v.empty()) return 0;
  const std::size_t at = std::min(v.size() - 1, std::size_t(q * double(v.size())));
  std::nth_element(v.begin(), v.begin() + at, v.end());
  return v[at];
}

}  // namespace
}  // namespace hfbake

int main(int argc, char** argv) {
  using namespace hfbake;
  if (argc < 4) {
    std::fprintf(stderr, "usage: measure_p1_horizons field size K [near_radius] [stride] [time]\n");
    return 2;
  }
  bool ok;
  Scene scene;
  scene.field = make_field(argv[1], std::atoi(argv[2]), &ok);
  if (!ok) {
    std::fprintf(stderr, "unknown field %s\n", argv[1]);
    return 2;
  }
  scene.normals = compute_normals(scene.field);
  scene.environment = make_uniform_environment({1, 1, 1});
  const HeightField& f = scene.field;
  const int K = std::atoi(argv[3]);
  const double near_radius = argc > 4 ? std::atof(argv[4]) : P1Params{}.near_radius;
  const int stride = argc > 5 ? std::atoi(argv[5]) : 1;
  const bool timed = argc > 6 && std::string(argv[6]) == "time";

  P1Params p;
  p.directions = K;
  p.near_radius = near_radius;
  p.vsky = p.direct = false;
  p.horizon = true;
  p.horizon_distance = std::getenv("MEASURE_WORST") != nullptr;
  const P1Result r = compute_p1(scene, p, RunControl{});

  SweepSpec spec;
  spec.directions = K;
  std::vector<SweepDirection> dirs;
  std::vector<char> diag(K);
  for (int k = 0; k < K; ++k) {
    dirs.push_back(plan_direction(f, spec, k));
    diag[k] = (8 * k) % K == 0;  // phi_k a multiple of 45 degrees
  }
  std::vector<std::pair<int, int>> texels;
  for (int j = stride / 2; j < f.height; j += stride)
    for (int i = stride / 2; i < f.width; i += stride) texels.push_back({i, j});
  const std::size_t T = texels.size();
  std::vector<float> err(T * K), ao_exact(T);
  tbb::parallel_for(std::size_t(0), T, [&](std::size_t t) {
    const auto [i, j] = texels[t];
    const std::size_t idx = f.index(i, j);
    std::vector<float> h(K);
    truth::exact_horizons(f, dirs, i, j, h.data());
    const Vec3f n = scene.normals[idx];
    double ao = 0;
    for (int k = 0; k < K; ++k) {
      err[t * K + k] = std::fabs(r.horizon[idx * K + k] - h[k]);
      ao += truth::ao_term(std::asin(std::clamp(double(h[k]), -1.0, 1.0)),
                           n.x * dirs[k].dx + n.y * dirs[k].dy, n.z);
    }
    ao_exact[t] = float(ao / K);
  });
  std::vector<float> cls[2];
  float inner[2] = {0, 0};  // max without the field's outermost texel ring
  for (std::size_t t = 0; t < T; ++t) {
    const auto [i, j] = texels[t];
    const bool in = i > 0 && j > 0 && i < f.width - 1 && j < f.height - 1;
    for (int k = 0; k < K; ++k) {
      cls[diag[k] ? 0 : 1].push_back(err[t * K + k]);
      if (in) inner[diag[k] ? 0 : 1] = std::max(inner[diag[k] ? 0 : 1], err[t * K + k]);
    }
  }
  truth::ErrorStats ao;
  double ao_max = 0, ao_mean = 0;
  for (std::size_t t = 0; t < T; ++t) {
    const double d = r.ao[f.index(texels[t].first, texels[t].second)] - ao_exact[t];
    ao.add(d), ao_max = std::max(ao_max, std::fabs(d)), ao_mean += ao_exact[t];
  }
  std::printf("%-9s %4d^2 K=%3d R=%g stride %d (%zu texels)", argv[1], f.width, K, near_radius, stride, T);
  for (int c = 0; c < 2; ++c) {
    const double above =
        double(std::count_if(cls[c].begin(), cls[c].end(), [](float e) { return e > 0.05f; }));
    std::printf(" | %s p99 %.2g max %.2g (inner %.2g) >.05 %.2f%%", c == 0 ? "45deg" : "other",
                quantile(cls[c], 0.99),
                cls[c].empty() ? 0.0 : double(*std::max_element(cls[c].begin(), cls[c].end())), inner[c],
                100 * above / std::max<double>(1, double(cls[c].size())));
  }
  std::printf(" | ao bias %+.5f rms %.5f max %.4f (mean %.4f)\n", ao.mean(), ao.rms(), ao_max,
              ao_mean / double(T));
  if (std::getenv("MEASURE_WORST")) {  // the worst texel-directions: where they are
    std::vector<std::size_t> order(T * K);
    for (std::size_t q = 0; q < order.size(); ++q) order[q] = q;
    const std::size_t n =
        std::min<std::size_t>(order.size(), std::size_t(std::atoi(std::getenv("MEASURE_WORST"))));
    std::partial_sort(order.begin(), order.begin() + n, order.end(),
                      [&](std::size_t a, std::size_t b) { return err[a] > err[b]; });
    for (std::size_t q = 0; q < n; ++q) {
      const auto [i, j] = texels[order[q] / K];
      const int k = int(order[q] % K);
      const double e = march_exact_sin(f, dirs[k], i, j);
      double dz, run;
      truth::march_from(f, i, j, dirs[k].dx, dirs[k].dy, 7, 0, &dz, &run);
      std::printf("  texel (%d, %d) k %d: p1 %.4f exact %.4f; caster at %.3f (p1 %.3f)\n", i, j, k,
                  r.horizon[f.index(i, j) * K + k], e, std::hypot(dz, run),
                  r.horizon_distance[f.index(i, j) * K + k]);
    }
  }
  if (timed) {
    P1Params q = p;
    q.horizon = false;
    double best = 1e30;
    for (int rep = 0; rep < 3; ++rep) {
      const auto t0 = std::chrono::steady_clock::now();
      const P1Result rr = compute_p1(scene, q, RunControl{});
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      if (rr.ao.empty()) return 3;
    }
    std::printf("  compute_p1 (ao only) %.3f s: %.2f ns per texel-direction, %.1f M texel-directions/s\n",
                best, best * 1e9 / (double(f.texel_count()) * K), double(f.texel_count()) * K / best * 1e-6);
  }
  return 0;
}
