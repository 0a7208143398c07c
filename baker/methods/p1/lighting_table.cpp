#include "methods/p1/lighting_table.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/azimuth.hpp"

namespace hfbake::p1 {
namespace {

// Antiderivative of sin(t) cos(t - tn): [sin(2t - tn) + sin(tn)] / 2.
double G(double t, double tn) {
  return -std::cos(2 * t - tn) / 4 + t * std::sin(tn) / 2;
}

// (2 / K) * sum over rows of profile[r] * integral over [row start, min(row end, limit)].
Rgb integrate_rows(const std::vector<Rgb>& profile, int K, double tn, double limit) {
  const int R = int(profile.size());
  double r_ = 0, g_ = 0, b_ = 0;
  for (int r = 0; r < R; ++r) {
    const double t0 = kPi * r / R;
    if (t0 >= limit) break;
    const double t1 = std::min(kPi * (r + 1) / R, limit);
    const double w = G(t1, tn) - G(t0, tn);
    r_ += profile[r].r * w, g_ += profile[r].g * w, b_ += profile[r].b * w;
  }
  const double s = 2.0 / K;
  return {float(r_ * s), float(g_ * s), float(b_ * s)};
}

}  // namespace

LightingTables build_lighting_tables(const Environment& env, int K, int normal_bins, int horizon_bins) {
  LightingTables t;
  t.directions = K;
  t.normal_bins = normal_bins;
  t.horizon_bins = horizon_bins;
  const std::size_t row = std::size_t(horizon_bins) + 1;
  t.data.resize(std::size_t(K) * normal_bins * row);
  tbb::parallel_for(0, K, [&](int k) {
    const double phi = azimuth(k, K);
    const std::vector<Rgb> profile = azimuth_wedge_profile(env, phi - kPi / K, phi + kPi / K);
    const int R = int(profile.size());
    std::vector<double> prefix(std::size_t(R + 1) * 3);
    for (int i = 0; i < normal_bins; ++i) {
      const double tn = -kPi / 2 + kPi * i / (normal_bins - 1);
      // Prefix integrals at row edges, then each horizon sample adds its partial row.
      double acc[3] = {0, 0, 0};
      for (int r = 0; r <= R; ++r) {
        for (int c = 0; c < 3; ++c) prefix[std::size_t(r) * 3 + c] = acc[c];
        if (r == R) break;
        const double w = G(kPi * (r + 1) / R, tn) - G(kPi * r / R, tn);
        acc[0] += profile[r].r * w, acc[1] += profile[r].g * w, acc[2] += profile[r].b * w;
      }
      Rgb* out = t.data.data() + (std::size_t(k) * normal_bins + i) * row;
      for (int j = 0; j <= horizon_bins; ++j) {
        const double limit = std::min(kPi * j / horizon_bins, tn + kPi / 2);
        const double x = std::clamp(limit * R / kPi, 0.0, double(R));
        int r = std::min(int(x), R - 1);
        const double t0 = kPi * r / R;
        const double w = limit > t0 ? G(limit, tn) - G(t0, tn) : 0.0;
        const double s = 2.0 / K;
        out[j] = {float((prefix[std::size_t(r) * 3 + 0] + profile[r].r * w) * s),
                  float((prefix[std::size_t(r) * 3 + 1] + profile[r].g * w) * s),
                  float((prefix[std::size_t(r) * 3 + 2] + profile[r].b * w) * s)};
      }
    }
  });
  return t;
}

SwathProfiles build_swath_profiles(const Environment& env, int K) {
  SwathProfiles sp;
  sp.directions = K;
  sp.inv_k = 1.0f / float(K);
  const std::vector<Rgb> first = azimuth_wedge_profile(env, -kPi / K, kPi / K);
  const int R = int(first.size());
  sp.rows = R;
  sp.radiance.resize(std::size_t(K) * R);
  sp.pa.resize(std::size_t(K) * R);
  sp.pb.resize(std::size_t(K) * R);
  sp.sa.resize(R);
  sp.sb.resize(R);
  for (int r = 0; r < R; ++r) {
    const double t = kPi * r / R;
    sp.sa[r] = float(std::sin(t) * std::sin(t));
    sp.sb[r] = float(t - std::sin(t) * std::cos(t));
  }
  tbb::parallel_for(0, K, [&](int k) {
    const double phi = azimuth(k, K);
    const std::vector<Rgb> profile =
        k == 0 ? first : azimuth_wedge_profile(env, phi - kPi / K, phi + kPi / K);
    double a[3] = {0, 0, 0}, b[3] = {0, 0, 0};
    for (int r = 0; r < R; ++r) {
      const std::size_t i = std::size_t(k) * R + r;
      sp.radiance[i] = profile[r];
      sp.pa[i] = {float(a[0]), float(a[1]), float(a[2])};
      sp.pb[i] = {float(b[0]), float(b[1]), float(b[2])};
      const double t0 = kPi * r / R, t1 = kPi * (r + 1) / R;
      // (2/K) * integral of sin cos = (sin^2 t1 - sin^2 t0) / K; of sin^2 = ((t - sin t cos t) |) / K.
      const double wa = (std::sin(t1) * std::sin(t1) - std::sin(t0) * std::sin(t0)) / K;
      const double wb = ((t1 - std::sin(t1) * std::cos(t1)) - (t0 - std::sin(t0) * std::cos(t0))) / K;
      const float c[3] = {profile[r].r, profile[r].g, profile[r].b};
      for (int q = 0; q < 3; ++q) a[q] += c[q] * wa, b[q] += c[q] * wb;
    }
  });
  return sp;
}

Rgb lighting_table_exact(const Environment& env, int K, int k, double theta_n, double theta_h) {
  const double phi = azimuth(k, K);
  const std::vector<Rgb> profile = azimuth_wedge_profile(env, phi - kPi / K, phi + kPi / K);
  return integrate_rows(profile, K, theta_n, std::min(theta_h, theta_n + kPi / 2));
}

}  // namespace hfbake::p1
