// The per-line gather against a brute-force ray march over the same polyline: for each elevation, find
// the first point the ray hits (linear interpolation between samples), take its exit radiance (linear
// along the line), and integrate (n . w) over the wedge numerically.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "methods/p2/hull_tree.hpp"
#include "methods/p2/indirect_gather.hpp"
#include "methods/p2/naive_visibility.hpp"

namespace hfbake {
namespace {

// Brute force: E/pi from direction k for receiver r (samples 0..r-1 terrain), radiance of sample j is
// L(j) (a smooth function of the position along the line), step = world distance between samples.
double brute_force(const std::vector<double>& h, const std::vector<double>& L, int r, double step,
                   const WedgeWeights& w) {
  // Global horizon slope (world), the top of the terrain part.
  double top = -1e300;
  for (int j = 0; j < r; ++j) top = std::max(top, (h[j] - h[r]) / ((r - j) * step));
  const double e0 = std::atan(w.t_n), e1 = std::atan(top);
  if (!(e1 > e0)) return 0;
  const int steps = 12000;
  double sum = 0;
  for (int q = 0; q < steps; ++q) {
    const double ea = e0 + (e1 - e0) * q / steps, eb = e0 + (e1 - e0) * (q + 1) / steps;
    const double sigma = std::tan(0.5 * (ea + eb)) * step;  // per-step slope of the ray
    // March away from R: g(j) = terrain height minus ray height at sample j; first j with g > 0 is hit.
    double g_prev = 0;  // at R itself
    double Lhit = 0;
    bool hit = false;
    for (int j = r - 1; j >= 0; --j) {
      const double g = h[j] - (h[r] + sigma * (r - j));
      if (g > 0) {
        const double f = -g_prev / (g - g_prev);  // from sample j+1 towards j
        const double Lj1 = L[j + 1];
        Lhit = Lj1 + f * (L[j] - Lj1);
        hit = true;
        break;
      }
      g_prev = g;
    }
    if (hit) sum += Lhit * (w.F(std::tan(eb)) - w.F(std::tan(ea)));
  }
  return sum / kPi;
}

std::uint64_t lcg(std::uint64_t& s) {
  s = s * 6364136223846793005ull + 1442695040888963407ull;
  return s >> 33;
}

Rgb gather(const std::vector<double>& h, const std::vector<Rgb>& L, int r, double step,
           const WedgeWeights& w) {
  HullTree tree;
  tree.reset(r + 1);
  for (int j = 0; j <= r; ++j) tree.push(h[j]);
  std::vector<int> starts;
  run_starts(h.data(), r, tree.horizons(), starts);
  return gather_stretches(h.data(), L.data(), r, r, starts, 1 / step, w);
}

TEST(IndirectGather, UniformRadianceFillsExactlyTangentToHorizon) {
  std::uint64_t s = 5;
  for (int t = 0; t < 200; ++t) {
    const int n = 2 + int(lcg(s) % 80);
    std::vector<double> h(n);
    for (auto& x : h) x = double(lcg(s) % 1000) / 100.0;
    const std::vector<Rgb> L(n, Rgb{1, 1, 1});
    const Vec3 nrm = normalize({double(lcg(s) % 100) / 100 - 0.5, double(lcg(s) % 100) / 100 - 0.5, 1});
    const double phi = double(lcg(s) % 628) / 100;
    const WedgeWeights w = WedgeWeights::make(nrm, std::cos(phi), std::sin(phi), 2 * kPi / 16);
    const int r = n - 1;
    double top = -1e300;
    for (int j = 0; j < r; ++j) top = std::max(top, (h[j] - h[r]) / (r - j) / 0.7);
    const double expect = top > w.t_n ? (w.F(top) - w.F(w.t_n)) / kPi : 0.0;
    EXPECT_NEAR(gather(h, L, r, 0.7, w).g, expect, 1e-6) << "case " << t;
  }
}

TEST(IndirectGather, MatchesBruteForceRayMarch) {
  std::uint64_t s = 17;
  int cases = 0;
  for (int t = 0; t < 40; ++t) {
    const int n = 20 + int(lcg(s) % 60);
    std::vector<double> h(n);
    // Rough lines with ties and plateaus, and smooth radiance along the line.
    for (int i = 0; i < n; ++i)
      h[i] = (t % 2) ? double(lcg(s) % 7) : 3 * std::sin(0.4 * i) + double(lcg(s) % 100) / 60.0;
    std::vector<double> Ls(n);
    std::vector<Rgb> L(n);
    for (int i = 0; i < n; ++i) {
      Ls[i] = 1 + 0.3 * std::sin(0.05 * i + t);
      L[i] = {float(Ls[i]), float(Ls[i]), float(Ls[i])};
    }
    const Vec3 nrm = normalize({double(lcg(s) % 100) / 150 - 0.33, double(lcg(s) % 100) / 150 - 0.33, 1});
    const double phi = double(lcg(s) % 628) / 100;
    const WedgeWeights w = WedgeWeights::make(nrm, std::cos(phi), std::sin(phi), 2 * kPi / 32);
    for (int r = 1; r < n; r += 4) {
      const double bf = brute_force(h, Ls, r, 1.0, w);
      const double g = gather(h, L, r, 1.0, w).r;
      // The gather's segment means differ from the brute force's exact radiance at the hit by second
      // order in the radiance change per segment (0.015 here): well below 1e-4 of the weights.
      EXPECT_NEAR(g, bf, 2e-4 + 1e-3 * bf) << "case " << t << " r " << r;
      ++cases;
    }
  }
  EXPECT_GT(cases, 200);
}

TEST(IndirectGather, NaiveRunStartsGiveTheSameBits) {
  std::uint64_t s = 23;
  for (int t = 0; t < 30; ++t) {
    const int n = 30 + int(lcg(s) % 100);
    std::vector<double> h(n);
    std::vector<Rgb> L(n);
    for (int i = 0; i < n; ++i) {
      h[i] = double(lcg(s) % 2000) / 100.0 - (i % 2) * double(t % 3);
      L[i] = {float(lcg(s) % 100) / 100, 0.5f, 1};
    }
    HullTree tree;
    tree.reset(n);
    std::vector<int> a, b, vis;
    const WedgeWeights w = WedgeWeights::make({0.1, -0.2, 0.97}, 0.6, 0.8, 2 * kPi / 8);
    for (int r = 0; r < n; ++r) {
      tree.push(h[r]);
      run_starts(h.data(), r, tree.horizons(), a);
      naive_visible(h.data(), r, vis);
      run_starts_of_visible(vis, b);
      ASSERT_EQ(a, b) << "case " << t << " r " << r;
      if (r == 0) continue;
      const Rgb ga = gather_stretches(h.data(), L.data(), r, r, a, 1.0, w);
      const Rgb gb = gather_stretches(h.data(), L.data(), r, r, b, 1.0, w);
      EXPECT_EQ(ga.r, gb.r);
      EXPECT_EQ(ga.b, gb.b);
    }
  }
}

TEST(IndirectGather, WedgeWeightsSumToTheCosineLobe) {
  // Uniform L = 1 over the whole hemisphere above the tangent plane: sum over K wedges of
  // (F(+inf) - F(t_n)) / pi = 1: exactly for an upward normal, and spectrally fast in K for a tilted one
  // (the midpoint rule in azimuth on a smooth periodic integrand): 2e-2 at K = 4, 1e-7 at K = 16.
  for (int K : {4, 16, 64}) {
    for (double tilt : {0.0, 0.3, 0.8}) {
      const Vec3 n{std::sin(tilt), 0, std::cos(tilt)};
      double sum = 0;
      for (int k = 0; k < K; ++k) {
        const double phi = 2 * kPi * k / K;
        const WedgeWeights w = WedgeWeights::make(n, std::cos(phi), std::sin(phi), 2 * kPi / K);
        sum += (w.F(1e12) - w.F(w.t_n)) / kPi;
      }
      EXPECT_NEAR(sum, 1.0, tilt == 0 ? 1e-12 : (K == 4 ? 2e-2 : 1e-6)) << "K " << K << " tilt " << tilt;
    }
  }
}

}  // namespace
}  // namespace hfbake
