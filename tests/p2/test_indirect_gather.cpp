// The per-line gather against a brute-force ray march over the same polyline: for each elevation, find
// the first point the ray hits (linear interpolation between samples), take its exit radiance (linear
// along the line), and integrate (n . w) over the wedge numerically.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "field/height_field.hpp"
#include "methods/p2/hull_tree.hpp"
#include "methods/p2/indirect_gather.hpp"
#include "methods/p2/indirect_sweep.hpp"
#include "methods/p2/naive_visibility.hpp"

namespace hfbake {
namespace {

// Brute force: E/pi from direction k for receiver r (samples 0..r-1 terrain; step = world distance
// between samples): for each of many elevations, march away from R to the first segment the ray meets and
// take its radiance there. Segment j (samples j -> j+1) radiates mean[j] + slope[j] * (u - 1/2) at its
// parameter u (0 at sample j).
double brute_force_segments(const std::vector<double>& h, const std::vector<double>& mean,
                            const std::vector<double>& slope, int r, double step, const WedgeWeights& w) {
  double top = -1e300;
  for (int j = 0; j < r; ++j) top = std::max(top, (h[j] - h[r]) / ((r - j) * step));
  const double e0 = std::atan(w.t_n), e1 = std::atan(top);
  if (!(e1 > e0)) return 0;
  const int steps = 12000;
  double sum = 0;
  for (int q = 0; q < steps; ++q) {
    const double ea = e0 + (e1 - e0) * q / steps, eb = e0 + (e1 - e0) * (q + 1) / steps;
    const double sigma = std::tan(0.5 * (ea + eb)) * step;
    double g_prev = 0;
    for (int j = r - 1; j >= 0; --j) {
      const double g = h[j] - (h[r] + sigma * (r - j));
      if (g > 0) {
        const double u = 1 + g_prev / (g - g_prev);  // the crossing on segment j, from sample j
        sum += (mean[j] + slope[j] * (u - 0.5)) * (w.F(std::tan(eb)) - w.F(std::tan(ea)));
        break;
      }
      g_prev = g;
    }
  }
  return sum / kPi;
}

// The same with the radiance given per sample, linear along each segment.
double brute_force(const std::vector<double>& h, const std::vector<double>& L, int r, double step,
                   const WedgeWeights& w) {
  std::vector<double> mean(L.size()), slope(L.size());
  for (std::size_t j = 0; j + 1 < L.size(); ++j)
    mean[j] = 0.5 * (L[j] + L[j + 1]), slope[j] = L[j + 1] - L[j];
  return brute_force_segments(h, mean, slope, r, step, w);
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

// Radiance given per segment (facet senders), constant per segment (the segment lies on one facet):
// the gather is exact up to its elevation integration, as with per-sample radiance. Rough lines.
TEST(IndirectGather, SegmentRadianceMatchesBruteForce) {
  std::uint64_t s = 29;
  int cases = 0;
  for (int t = 0; t < 30; ++t) {
    const int n = 20 + int(lcg(s) % 60);
    std::vector<double> h(n), mean(n), zero(n, 0.0);
    for (int i = 0; i < n; ++i) {
      h[i] = (t % 2) ? double(lcg(s) % 7) : 3 * std::sin(0.4 * i) + double(lcg(s) % 100) / 60.0;
      mean[i] = 0.5 + double(lcg(s) % 100) / 100;
    }
    std::vector<Rgb> M(n), D(n);
    for (int i = 0; i < n; ++i) M[i] = Rgb{float(mean[i]), 0, 0};
    const Vec3 nrm = normalize({double(lcg(s) % 100) / 150 - 0.33, double(lcg(s) % 100) / 150 - 0.33, 1});
    const double phi = double(lcg(s) % 628) / 100;
    const WedgeWeights w = WedgeWeights::make(nrm, std::cos(phi), std::sin(phi), 2 * kPi / 32);
    for (int r = 1; r < n; r += 3) {
      HullTree tree;
      tree.reset(r + 1);
      for (int j = 0; j <= r; ++j) tree.push(h[j]);
      std::vector<int> starts;
      run_starts(h.data(), r, tree.horizons(), starts);
      SegmentRadiance seg;
      seg.mean = M.data();
      seg.slope = D.data();
      seg.crease = M[r - 1];  // the brute force meets segment r - 1 at R
      const double g = gather_segments(h.data(), seg, r, r, starts, 1.0, w).r;
      const double bf = brute_force_segments(h, mean, zero, r, 1.0, w);
      EXPECT_NEAR(g, bf, 2e-4 + 1e-3 * bf) << "case " << t << " r " << r;
      ++cases;
    }
  }
  EXPECT_GT(cases, 150);
}

// A partly visible segment takes the mean of its linear trend over its visible part. Line (3, 0, 0.8, 0),
// receiver 3: segment 0 -> 1 is visible from sample 0 (slope 1) down to the line of sight to sample 2
// (slope 0.8), which it crosses at u = 0.6 / 2.2; below that the receiver's crease (radiance 0 here).
TEST(IndirectGather, PartlyVisibleSegmentTakesTheMeanOfItsVisiblePart) {
  const std::vector<double> h = {3, 0, 0.8, 0};
  const std::vector<Rgb> M = {{1, 1, 1}, {0, 0, 0}, {0, 0, 0}}, D = {{0.6f, -0.6f, 0}, {0, 0, 0}, {0, 0, 0}};
  const WedgeWeights w = WedgeWeights::make({0, 0, 1}, 1, 0, 2 * kPi / 16);
  std::vector<int> starts;
  run_starts_of_visible(std::vector<int>{0, 2}, starts);
  SegmentRadiance seg;
  seg.mean = M.data();
  seg.slope = D.data();
  const Rgb g = gather_segments(h.data(), seg, 3, 3, starts, 1.0, w);
  const double u = 0.6 / 2.2, W = (w.F(1.0) - w.F(0.8)) / kPi;
  EXPECT_NEAR(g.r, (1 + 0.6 * (u - 1) / 2) * W, 1e-6 * W);
  EXPECT_NEAR(g.g, (1 - 0.6 * (u - 1) / 2) * W, 1e-6 * W);
  EXPECT_NEAR(g.b, W, 1e-6 * W);  // no trend
}

// facet_segment_radiance against dense sampling of the segment: every sample point finds its triangle
// by its barycentric coordinates (the reference's split) and takes that facet's radiance.
TEST(IndirectGather, FacetSegmentRadianceIsTheLengthWeightedFacetMean) {
  HeightField f;
  f.width = f.height = 8;
  f.wrap = Wrap::repeat;
  f.z.assign(64, 0.0f);
  std::uint64_t s = 5;
  std::vector<Rgb> facet(2 * 64);
  for (Rgb& v : facet) v = Rgb{float(lcg(s) % 1000) / 1000, 0, 0};
  auto facet_at = [&](double x, double y) {
    const int i = int(std::floor(x)), j = int(std::floor(y));
    const double a = x - i, b = y - j;  // the lower triangle has barycentric weight 1 - a - b >= 0 at (i, j)
    if (1 - a - b >= 0) return double(facet[2 * f.index(f.wrap_i(i), f.wrap_j(j))].r);
    return double(facet[2 * f.index(f.wrap_i(i + 1), f.wrap_j(j + 1)) + 1].r);
  };
  for (int t = 0; t < 200; ++t) {
    // Segments as the sweep makes them: along x (or y) by 1 / S texel, the other coordinate by a slope.
    const int S = 1 + int(lcg(s) % 3);
    const double slope = double(lcg(s) % 2001) / 1000 - 1, len = 1.0 / S;
    double x0 = double(lcg(s) % 8) + double(lcg(s) % S) / S, y0 = double(lcg(s) % 8000) / 1000;
    double x1 = x0 + ((t & 1) ? len : -len), y1 = y0 + slope * len;
    if (t & 2) std::swap(x0, y0), std::swap(x1, y1);
    Rgb mean, trend;
    facet_segment_radiance(f, facet.data(), x0, y0, x1, y1, &mean, &trend);
    const int N = 200000;
    double m = 0, m1 = 0;
    for (int k = 0; k < N; ++k) {
      const double u = (k + 0.5) / N;
      const double v = facet_at(x0 + u * (x1 - x0), y0 + u * (y1 - y0));
      m += v / N;
      m1 += v * (u - 0.5) / N;
    }
    EXPECT_NEAR(mean.r, m, 2e-5) << "segment " << t;
    EXPECT_NEAR(trend.r, 12 * m1, 2e-4) << "segment " << t;
  }
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
