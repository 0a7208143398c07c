// Independent truth for the obscurance family on the reference's triangulated surface (two triangles per
// quad, split along (i+1, j)-(i, j+1)): the profile along each direction rebuilt by sorting every column, row
// and diagonal crossing and interpolating inside the containing triangle (truth::tri_height), then
//   step falloff: the occluded elevations (a ray at elevation e is occluded iff the profile rises above it
//                 within horizontal distance R cos e), their edges found by bisection;
//   other falloffs: a dense midpoint rule over elevation, each ray's first hit found against every segment.
// No code of the methods is used.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "../p1/p1_truth.hpp"
#include "field/height_field.hpp"
#include "methods/ao/falloff.hpp"

namespace hfbake::ao_truth {

struct Profile {
  std::vector<double> t, z;  // horizontal distance (texels; t[0] = 0 the receiver) and height
};

inline Profile profile(const HeightField& f, int i, int j, double dx, double dy, double reach) {
  Profile p;
  p.t = {0.0};
  auto crossings = [&](double start, double d) {
    if (std::abs(d) < 1e-12) return;
    for (int k = 1;; ++k) {
      const double tt = ((d > 0 ? std::floor(start) + k : std::ceil(start) - k) - start) / d;
      if (tt > reach) break;
      p.t.push_back(tt);
    }
  };
  crossings(i, dx);
  crossings(j, dy);
  crossings(i + j, dx + dy);
  p.t.push_back(reach);
  std::sort(p.t.begin(), p.t.end());
  p.t.erase(std::unique(p.t.begin(), p.t.end(), [](double a, double b) { return b - a < 1e-9; }), p.t.end());
  for (double t : p.t) p.z.push_back(truth::tri_height(f, i + t * dx, j + t * dy));
  p.z[0] = f.z[f.index(i, j)];
  return p;
}

// Cosine-weighted occluded measure of one slice (integral of rho w(e) over elevation), step falloff.
inline double exact_step(const Profile& p, double nt, double nz, double R) {
  auto H = [&](double S) {  // the highest slope of the profile within horizontal distance S
    double h = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 1; k < p.t.size(); ++k) {
      if (p.t[k] <= S) {
        h = std::max(h, (p.z[k] - p.z[0]) / p.t[k]);
      } else {
        const double a = (S - p.t[k - 1]) / (p.t[k] - p.t[k - 1]);
        if (S > 0) h = std::max(h, (p.z[k - 1] + a * (p.z[k] - p.z[k - 1]) - p.z[0]) / S);
        break;
      }
    }
    return h;
  };
  // Ray e is occluded iff H(R cos e) >= tan e. Above the horizontal the occluded elevations are one interval
  // from the tangent up (the reach R cos e shrinks as e rises), but below it the reach grows with e, so on
  // steep downhill tangents (rough ground) the set can have gaps: its edges are found by scanning 4096
  // elevations and bisecting each change of the predicate, then integrated in closed form.
  auto occluded = [&](double e) { return H(R * std::cos(e)) >= std::tan(e); };
  auto P = [&](double e) { return nt * (e / 2 + std::sin(2 * e) / 4) + nz * std::sin(e) * std::sin(e) / 2; };
  const double tangent = std::atan2(-nt, nz), top = kPi / 2 - 1e-12;
  const int n = 4096;
  double sum = 0, start = tangent;  // start: where the current occluded run began (if `inside`)
  bool inside = occluded(tangent);
  double prev = tangent;
  for (int q = 1; q <= n; ++q) {
    const double e = tangent + (top - tangent) * q / n;
    const bool now = occluded(e);
    if (now != inside) {
      double lo = prev, hi = e;  // the predicate is `inside` at lo, `now` at hi
      for (int it = 0; it < 100 && hi - lo > 1e-13; ++it) {
        const double mid = 0.5 * (lo + hi);
        (occluded(mid) == inside ? lo : hi) = mid;
      }
      if (inside) sum += P(lo) - P(start);
      start = lo;
      inside = now;
    }
    prev = e;
  }
  if (inside) sum += P(top) - P(start);
  return sum;
}

// Any falloff: midpoint rule over elevation, the first hit of each ray against every segment.
inline double dense(const Profile& p, double nt, double nz, const Falloff& rho, int n) {
  const double tangent = std::atan2(-nt, nz), h = (kPi / 2 - tangent) / n;
  double sum = 0;
  for (int q = 0; q < n; ++q) {
    const double e = tangent + (q + 0.5) * h, c = std::cos(e), s = std::sin(e);
    double d = INFINITY;
    for (std::size_t k = 1; k < p.t.size() && !std::isfinite(d); ++k) {
      // Ray (c, s) u against the segment from (t[k-1], dz[k-1]) to (t[k], dz[k]).
      const double ah = p.t[k - 1], av = p.z[k - 1] - p.z[0], bh = p.t[k], bv = p.z[k] - p.z[0];
      const double fa = av * c - ah * s, fb = bv * c - bh * s;  // > 0: above the ray
      if (fb >= 0 && fa <= 0) {
        const double w = fa == fb ? 0.0 : -fa / (fb - fa);
        d = std::hypot(ah + w * (bh - ah), av + w * (bv - av));
      }
    }
    if (std::isfinite(d)) sum += rho(d) * std::max(0.0, nt * c + nz * s) * c;
  }
  return sum * h;
}

// The occluded measure (cosine, doubled: 1 - obscurance) of texel (i, j) with normal n over K vertical slices
// at phi_k = 2 pi k / K, each profile marched to `reach` texels (clamp fields: the border's ends are the
// caller's to avoid); step: exact_step, else dense with 20000 elevations.
inline double occluded(const HeightField& f, Vec3 n, int i, int j, int K, const Falloff& rho, double reach,
                       bool step) {
  double sum = 0;
  for (int k = 0; k < K; ++k) {
    const double phi = 2 * kPi * k / K, dx = std::cos(phi), dy = std::sin(phi);
    const Profile p = profile(f, i, j, dx, dy, reach);
    const double nt = n.x * dx + n.y * dy;
    sum += step ? exact_step(p, nt, n.z, rho.radius) : dense(p, nt, n.z, rho, 20000);
  }
  return 2 * sum / K;
}

// Mean and rms of a - b over all entries (the benches' tables).
struct Diff {
  double mean = 0, rmse = 0;
};
inline Diff diff(const std::vector<float>& a, const std::vector<float>& b) {
  Diff d;
  for (std::size_t t = 0; t < a.size(); ++t) {
    const double e = double(a[t]) - double(b[t]);
    d.mean += e;
    d.rmse += e * e;
  }
  d.mean /= double(a.size());
  d.rmse = std::sqrt(d.rmse / double(a.size()));
  return d;
}

}  // namespace hfbake::ao_truth
