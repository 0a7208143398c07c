// Where does the horizon methods' openness bias against the reference come from?
//
//   build-ao/tests/ao/ao_bench_obscurance_bias [crop interior] [samples] [K]
//
// On a crop of the frontier job's field (1024^2 fractal, seed 7, texel 1, clamp; step falloff R = 16), the
// reference (Embree, the same code as `hfbake bake`) is run with many samples on the crop, and each receiver
// at least R + 1 texels inside the crop is compared with per-slice estimators that differ in ONE factor:
//   surface  bilinear (what the methods march) or the reference's triangles (two per quad, split along
//            (i+1, j)-(i, j+1)): the exact profile of the triangulated surface along the slice, a polyline
//            with a vertex at every column, row and diagonal crossing;
//   sampling one texel steps (the methods) or 1/8 texel steps (bilinear), every vertex (triangles);
//   estimator "slab" (every sample above the running horizon is a vertical slab at its distance: what
//            hbao, farfield and hsao integrate) or "exact" (step falloff: the ray at elevation e is occluded
//            iff the profile rises above it within horizontal distance R cos e; the largest such e is
//            found by bisection, so the slice integral is exact for the polyline profile).
// The azimuths are the contract's phi_k = 2 pi k / K. Printed: mean(method - reference) of the obscurance
// (positive = too open) with the reference's standard error of that mean, and the rmse.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "../p1/p1_truth.hpp"
#include "env/environment.hpp"
#include "field/procedural.hpp"
#include "field/scene.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/slice_integral.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake {
namespace {

constexpr double kRadius = 16;

struct Profile {
  std::vector<double> t, z;  // horizontal distance (t[0] = 0: the receiver) and height
};

// The reference's surface (two triangles per quad): truth::tri_height (tests/p1/p1_truth.hpp).
using truth::tri_height;

void triangle_profile(const HeightField& f, int i, int j, double dx, double dy, double reach, Profile& p) {
  std::vector<double>& t = p.t;
  t.assign(1, 0.0);
  auto crossings = [&](double start, double d) {  // t where start + t d is an integer, 0 < t <= reach
    if (std::abs(d) < 1e-12) return;
    for (int k = 1;; ++k) {
      const double target = d > 0 ? std::floor(start) + k : std::ceil(start) - k;
      const double tt = (target - start) / d;
      if (tt > reach) break;
      if (tt > 1e-12) t.push_back(tt);
    }
  };
  crossings(i, dx);
  crossings(j, dy);
  crossings(i + j, dx + dy);
  t.push_back(reach);
  std::sort(t.begin(), t.end());
  t.erase(std::unique(t.begin(), t.end(), [](double a, double b) { return b - a < 1e-9; }), t.end());
  p.z.resize(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) p.z[k] = tri_height(f, i + t[k] * dx, j + t[k] * dy);
  p.z[0] = f.z[f.index(i, j)];
}

void bilinear_profile(const HeightField& f, int i, int j, double dx, double dy, double reach, double step,
                      Profile& p) {
  const int n = int(std::floor(reach / step + 1e-9));
  p.t.resize(n + 1);
  p.z.resize(n + 1);
  p.t[0] = 0, p.z[0] = f.z[f.index(i, j)];
  for (int m = 1; m <= n; ++m) {
    p.t[m] = m * step;
    p.z[m] = f.bilinear(i + m * step * dx, j + m * step * dy);
  }
}

// hbao's slab estimator over the profile's samples (cosine measure of the slice, not yet doubled).
double slab_occlusion(const Profile& p, const SliceFrame& frame, const Falloff& rho) {
  double max_slope = -std::numeric_limits<double>::infinity(), max_elev = -kPi / 2, occl = 0;
  for (std::size_t k = 1; k < p.t.size(); ++k) {
    const double slope = (p.z[k] - p.z[0]) / p.t[k];
    if (slope > max_slope) {
      max_slope = slope;
      const double e = std::atan(slope);
      occl += band_occlusion(rho, Weighting::cosine, frame, max_elev, e, p.t[k]);
      max_elev = e;
    }
  }
  return occl;
}

// Exact slice integral of the polyline profile for the step falloff (rays end at 3D distance R).
double exact_step_occlusion(const Profile& p, const SliceFrame& frame, double R, std::vector<double>& pm) {
  const std::size_t n = p.t.size();
  pm.resize(n);
  pm[0] = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k < n; ++k) pm[k] = std::max(pm[k - 1], (p.z[k] - p.z[0]) / p.t[k]);
  // Highest slope of the profile within horizontal distance S (S <= reach).
  auto H = [&](double S) {
    const std::size_t k = std::size_t(std::upper_bound(p.t.begin(), p.t.end(), S) - p.t.begin()) - 1;
    double h = pm[k];
    if (k + 1 < n && S > p.t[k]) {
      const double a = (S - p.t[k]) / (p.t[k + 1] - p.t[k]);
      const double z = p.z[k] + a * (p.z[k + 1] - p.z[k]);
      h = std::max(h, (z - p.z[0]) / S);
    }
    return h;
  };
  double lo = frame.tangent, hi = kPi / 2 - 1e-12;
  if (H(R * std::cos(lo)) < std::tan(lo)) return 0.0;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (H(R * std::cos(mid)) >= std::tan(mid) ? lo : hi) = mid;
  }
  Falloff none;
  return band_occlusion(none, Weighting::cosine, frame, -kPi / 2, lo, 1.0);
}

struct Stats {
  double sum = 0, sq = 0;
  std::size_t n = 0;
  void add(double e) { sum += e, sq += e * e, ++n; }
};

int run(int argc, char** argv) {
  const int interior = argc > 1 ? std::atoi(argv[1]) : 128;
  const int samples = argc > 2 ? std::atoi(argv[2]) : 2048;
  const int K = argc > 3 ? std::atoi(argv[3]) : 64;
  const int margin = int(kRadius) + 2;
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = spec.height = 1024;
  spec.seed = 7;
  const HeightField full = make_procedural(spec, 1.0, Wrap::clamp);
  const int crop = interior + 2 * margin, x0 = 512 - crop / 2, y0 = 512 - crop / 2;
  Scene scene;
  scene.field.width = scene.field.height = crop;
  scene.field.z.resize(std::size_t(crop) * crop);
  for (int j = 0; j < crop; ++j)
    for (int i = 0; i < crop; ++i)
      scene.field.z[scene.field.index(i, j)] = full.z[full.index(x0 + i, y0 + j)];
  scene.normals = compute_normals(scene.field);
  scene.surface.albedo.assign(scene.field.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
  scene.environment = make_uniform_environment(Rgb{1, 1, 1});
  scene.bounces = 0;

  ReferenceOptions ro;
  ro.layers = {"obscurance"};
  ro.samples = samples;
  ro.falloff.kind = FalloffKind::step;
  ro.falloff.radius = kRadius;
  const auto t0 = std::chrono::steady_clock::now();
  const LayerSet ref = bake_reference(scene, ro, RunControl{});
  const double ref_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::vector<float>& rv = ref.find("obscurance")->data;
  const std::vector<float>& rse = ref.find("obscurance_stderr")->data;
  std::printf(
      "crop %d^2 at (%d, %d) of the 1024^2 fractal (seed 7), receivers %d^2, reference %d samples "
      "in %.1f s, K = %d, step falloff R = %g\n",
      crop, x0, y0, interior, samples, ref_s, K, kRadius);

  Falloff rho;
  rho.kind = FalloffKind::step;
  rho.radius = kRadius;
  const std::vector<MarchDirection> dirs = uniform_directions(K);
  HbaoSettings hs;
  hs.falloff = rho;
  hs.directions = dirs;
  hs.reach = kRadius;
  hs.bent = false;

  const char* names[] = {"hbao_texel (shipped: bilinear, 1 texel steps, slab)",
                         "bilinear, 1 texel steps, slab",
                         "bilinear, 1/8 texel steps, slab",
                         "bilinear, 1/8 texel steps, exact",
                         "triangles, every vertex, slab",
                         "triangles, every vertex, exact",
                         "bilinear, 1 texel steps, exact",
                         "hbao_texel surface triangles (segment estimator)",
                         "hbao_texel bilinear, 1 texel steps, segment"};
  constexpr int kVariants = 9;
  HbaoSettings htri = hs, hseg = hs;
  htri.surface = MarchSurface::triangles;
  htri.estimator = HorizonEstimator::segment;
  hseg.estimator = HorizonEstimator::segment;
  Stats st[kVariants];
  double ref_sum = 0, se_sq = 0;
  Profile pb1, pb8, pt;
  std::vector<double> pm;
  for (int j = margin; j < margin + interior; ++j)
    for (int i = margin; i < margin + interior; ++i) {
      const std::size_t idx = scene.field.index(i, j);
      const Vec3 n = scene.normals[idx].d();
      double occ[kVariants] = {};
      occ[0] = hbao_texel(scene.field, n, i, j, hs).occluded;
      occ[7] = hbao_texel(scene.field, n, i, j, htri).occluded;
      occ[8] = hbao_texel(scene.field, n, i, j, hseg).occluded;
      for (const MarchDirection& d : dirs) {
        const SliceFrame frame = slice_frame(n.x * d.dx + n.y * d.dy, n.z);
        bilinear_profile(scene.field, i, j, d.dx, d.dy, kRadius, 1.0, pb1);
        bilinear_profile(scene.field, i, j, d.dx, d.dy, kRadius, 0.125, pb8);
        triangle_profile(scene.field, i, j, d.dx, d.dy, kRadius, pt);
        occ[1] += slab_occlusion(pb1, frame, rho);
        occ[2] += slab_occlusion(pb8, frame, rho);
        occ[3] += exact_step_occlusion(pb8, frame, kRadius, pm);
        occ[4] += slab_occlusion(pt, frame, rho);
        occ[5] += exact_step_occlusion(pt, frame, kRadius, pm);
        occ[6] += exact_step_occlusion(pb1, frame, kRadius, pm);
      }
      for (int v = 1; v < 7; ++v) occ[v] *= 2.0 / K;
      for (int v = 0; v < kVariants; ++v) st[v].add((1 - occ[v]) - rv[idx]);
      ref_sum += rv[idx];
      se_sq += double(rse[idx]) * rse[idx];
    }
  const double N = double(interior) * interior;
  std::printf("reference mean obscurance %.5f, standard error of the mean %.6f (rms texel stderr %.5f)\n",
              ref_sum / N, std::sqrt(se_sq) / N, std::sqrt(se_sq / N));
  std::printf("%-55s %10s %10s\n", "estimator", "bias", "rmse");
  for (int v = 0; v < kVariants; ++v)
    std::printf("%-55s %+10.5f %10.5f\n", names[v], st[v].sum / st[v].n, std::sqrt(st[v].sq / st[v].n));
  return 0;
}

}  // namespace
}  // namespace hfbake

int main(int argc, char** argv) {
  return hfbake::run(argc, argv);
}
