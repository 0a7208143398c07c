// hbao on the reference's triangulated surface (surface "triangles", segment estimator) against independent
// slice integrals of the same surface: the profile along each direction rebuilt here by sorting every
// column, row and diagonal crossing and interpolating inside the containing triangle, then
//   step falloff: the largest occluded elevation found by bisection (a ray at elevation e is occluded iff the
//                 profile rises above it within horizontal distance R cos e);
//   other falloffs: a dense midpoint rule over elevation, each ray's first hit found against every segment.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "../p1/p1_truth.hpp"
#include "ao_scenes.hpp"
#include "field/procedural.hpp"
#include "methods/ao/farfield.hpp"
#include "methods/ao/hbao.hpp"

namespace hfbake {
namespace {

struct Profile {
  std::vector<double> t, z;  // horizontal distance (texels; t[0] = 0 the receiver) and height
};

// The reference's surface (two triangles per quad): truth::tri_height (tests/p1/p1_truth.hpp).
using truth::tri_height;

Profile profile(const HeightField& f, int i, int j, double dx, double dy, double reach) {
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
  for (double t : p.t) p.z.push_back(tri_height(f, i + t * dx, j + t * dy));
  p.z[0] = f.z[f.index(i, j)];
  return p;
}

// Cosine-weighted occluded measure of one slice (integral of rho w(e) over elevation), step falloff.
double exact_step(const Profile& p, double nt, double nz, double R) {
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
  double lo = std::atan2(-nt, nz), hi = kPi / 2 - 1e-12;
  const double tangent = lo;
  if (H(R * std::cos(lo)) < std::tan(lo)) return 0.0;
  for (int it = 0; it < 200 && hi - lo > 1e-13; ++it) {
    const double mid = 0.5 * (lo + hi);
    (H(R * std::cos(mid)) >= std::tan(mid) ? lo : hi) = mid;
  }
  // integral over [tangent, lo] of (nt cos e + nz sin e) cos e
  auto P = [&](double e) { return nt * (e / 2 + std::sin(2 * e) / 4) + nz * std::sin(e) * std::sin(e) / 2; };
  return P(lo) - P(tangent);
}

// Any falloff: midpoint rule over elevation, the first hit of each ray against every segment.
double dense(const Profile& p, double nt, double nz, const Falloff& rho, int n) {
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

struct Case {
  HeightField field;
  std::vector<Vec3f> normals;
};

Case fractal_case() {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = spec.height = 40;
  spec.seed = 3;
  Case c;
  c.field = make_procedural(spec, 1.0, Wrap::clamp);
  c.normals = compute_normals(c.field);
  return c;
}

double independent(const Case& c, int i, int j, int K, const Falloff& rho, double reach, bool step) {
  const Vec3 n = c.normals[c.field.index(i, j)].d();
  double sum = 0;
  for (int k = 0; k < K; ++k) {
    const double phi = 2 * kPi * k / K, dx = std::cos(phi), dy = std::sin(phi);
    const Profile p = profile(c.field, i, j, dx, dy, reach);
    const double nt = n.x * dx + n.y * dy;
    sum += step ? exact_step(p, nt, n.z, rho.radius) : dense(p, nt, n.z, rho, 20000);
  }
  return 2 * sum / K;
}

HbaoSettings triangles(int K, const Falloff& rho, double reach) {
  HbaoSettings s;
  s.falloff = rho;
  s.directions = uniform_directions(K);
  s.reach = reach;
  s.surface = MarchSurface::triangles;
  s.estimator = HorizonEstimator::segment;
  return s;
}

TEST(HbaoTriangles, StepFalloffIsTheExactSliceIntegral) {
  const Case c = fractal_case();
  Falloff rho;
  rho.kind = FalloffKind::step;
  rho.radius = 8;
  const HbaoSettings s = triangles(16, rho, 8);
  double worst = 0, mean = 0;
  int count = 0;
  for (int j = 10; j < 30; j += 3)
    for (int i = 10; i < 30; i += 3) {
      const double got = hbao_texel(c.field, c.normals[c.field.index(i, j)].d(), i, j, s).occluded;
      const double want = independent(c, i, j, 16, rho, 8, true);
      worst = std::max(worst, std::abs(got - want));
      mean += want, ++count;
    }
  EXPECT_GT(mean / count, 0.02);  // the field occludes: the comparison is not 0 = 0
  EXPECT_LT(worst, 1e-7);
}

TEST(HbaoTriangles, SmoothFalloffsAgainstDenseRays) {
  const Case c = fractal_case();
  for (FalloffKind kind : {FalloffKind::linear, FalloffKind::exponential}) {
    Falloff rho;
    rho.kind = kind;
    rho.radius = 4;
    const double reach = 10;  // exponential: the slice integrals of both sides end here
    const HbaoSettings s = triangles(8, rho, reach);
    for (int j = 14; j < 26; j += 5)
      for (int i = 14; i < 26; i += 5) {
        const double got = hbao_texel(c.field, c.normals[c.field.index(i, j)].d(), i, j, s).occluded;
        const double want = independent(c, i, j, 8, rho, reach, false);
        EXPECT_NEAR(got, want, 2e-4) << "falloff " << int(kind) << " texel " << i << ", " << j;
      }
  }
}

TEST(HbaoTriangles, PlanesAreOpenAndTheStepOptionMoves) {
  // A tilted plane is its own triangulation: nothing above the tangent plane.
  const HeightField plane = test::make_plane(33, 0.4, -0.7);
  const std::vector<Vec3f> nrm = compute_normals(plane);
  Falloff rho;
  rho.kind = FalloffKind::step;
  rho.radius = 10;
  const HbaoSettings s = triangles(16, rho, 10);
  EXPECT_NEAR(hbao_texel(plane, nrm[plane.index(16, 16)].d(), 16, 16, s).occluded, 0.0, 1e-9);
  // On the fractal, one-texel bilinear steps miss peaks between samples: less occluded than the exact
  // triangulated profile on average.
  const Case c = fractal_case();
  HbaoSettings bil = s;
  bil.surface = MarchSurface::bilinear;
  bil.estimator = HorizonEstimator::slab;
  double exact = 0, coarse = 0;
  for (int j = 10; j < 30; ++j)
    for (int i = 10; i < 30; ++i) {
      const Vec3 n = c.normals[c.field.index(i, j)].d();
      exact += hbao_texel(c.field, n, i, j, s).occluded;
      coarse += hbao_texel(c.field, n, i, j, bil).occluded;
    }
  EXPECT_LT(coarse, exact);
}

// farfield's near field on the triangles: with R = 8 inside the near field (1.5 B0 = 12 texels) it is the
// same exact slice integral as hbao's.
TEST(HbaoTriangles, FarfieldNearFieldIsTheSameIntegral) {
  const Case c = fractal_case();
  Falloff rho;
  rho.kind = FalloffKind::step;
  rho.radius = 8;
  FarfieldOptions o;
  o.directions = 16;
  o.rho = rho;
  o.triangles = true;
  std::vector<std::size_t> texels;
  for (int j = 10; j < 30; j += 4)
    for (int i = 10; i < 30; i += 4) texels.push_back(c.field.index(i, j));
  const std::vector<double> ff = farfield_occlusion_at(c.field, c.normals, o, texels);
  const HbaoSettings s = triangles(16, rho, 8);
  for (std::size_t t = 0; t < texels.size(); ++t) {
    const int i = int(texels[t] % 40), j = int(texels[t] / 40);
    EXPECT_NEAR(ff[t], hbao_texel(c.field, c.normals[texels[t]].d(), i, j, s).occluded, 1e-9);
  }
}

}  // namespace
}  // namespace hfbake
