// Where lsao's and hsao's excess over hbao comes from on the nightly fields: a
// decomposition against hbao on the reference's triangulated surface (surface "triangles", segment
// estimator: the exact slice integral of that surface at the same K), per field of tests/nightly/fields
// (96^2, K = 16, step falloff R = 8 as the nightly jobs bake them).
//
//   build/tests/ao/ao_bench_lsao_surface [--radius R] [--falloff step|smooth]
//
// Columns, each the mean / rmse of (variant - hbao triangles) in obscurance:
//   lsao        surface bilinear (the sweep lines'
//               column samples, chain hull, two taps)
//   lsao brute  the same line samples, every visible band (no hull merging)
//   own cols    each texel's own ray, the receiver-tangent band sum over the column crossings only (where
//               the sweep's line samples lie: the triangulated surface's heights on the column edges)
//   own tri     each texel's own ray over every crossing of the triangulated surface, slab estimator
//   hbao bil    hbao's former default (one-texel bilinear steps, slab)
//   hsao        hsao on the bilinear surface (its former default), N_s = R steps
//   hsao tri    hsao on the triangulated surface (every vertex under each ray)
//   lsao tri    lsao with surface triangles (the crossings between the samples in the lines' hulls);
//               "brute": every visible band of those points; "near N": with near_radius N texels
// lsao brute - own cols is the line offset (the sweep's lines pass up to one texel beside the texel, whose
// result is blended from two of them), own cols - own tri the profile's missed kinks (row and diagonal
// crossings), own tri the slab estimator's own error; "near R" must be 0 (the near field covers the radius:
// hbao's integral exactly).
// Measured (2026-12-02, rmse): rough lsao 0.061, brute 0.060, own cols 0.061, own tri 0.015 (so the kinks,
// not the offset nor the hull); terraces 0.016 / 0.015 / 0.017 / 0.0025; fractal 0.0075 / 0.0062 / 0.0068 /
// 0.0030. lsao tri near 4 (the default): rough 0.010, terraces 0.0062, fractal 0.0034, craters 0.0010; its
// brute force at near 2: rough 0.012, fractal 0.0011, craters 0.0002 (the rest on gentle fields is the
// hull's merging). hsao tri: rough 0.043 (bilinear 0.074), fractal 0.0026 (0.0088).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "ao_truth.hpp"
#include "field/procedural.hpp"
#include "field/triangulation.hpp"
#include "methods/ao/hbao.hpp"
#include "methods/ao/hsao.hpp"
#include "methods/ao/lsao.hpp"
#include "methods/ao/lsao_chain_hull.hpp"
#include "methods/ao/triangle_profile.hpp"

namespace hfbake {
namespace {

HeightField field_of(ProceduralKind kind, std::uint64_t seed, double amplitude = 0, double feature = 0,
                     double step = 0, double angle = NAN) {
  ProceduralSpec spec;
  spec.kind = kind;
  spec.width = spec.height = 96;
  spec.seed = seed;
  spec.amplitude = amplitude;
  spec.feature_size = feature;
  spec.step = step;
  spec.angle_deg = angle;
  return make_procedural(spec, 1.0, Wrap::clamp);
}

using ao_truth::Diff;
using ao_truth::diff;

// The receiver-tangent band sum (lsao's TangentChain, slab estimator) over each texel's own ray: every
// crossing of the triangulated surface, or (columns_only) only the column (x-major) / row (y-major) ones.
std::vector<float> own_ray(const HeightField& f, const Falloff& rho, int K, bool columns_only) {
  const std::vector<Vec3f> normals = compute_normals(f);
  const std::vector<MarchDirection> dirs = uniform_directions(K);
  std::vector<float> out(f.texel_count());
  const double reach = default_reach(f, rho);
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      const Vec3f n = normals[f.index(i, j)];
      const double z0 = f.z[f.index(i, j)];
      double total = 0;
      for (const MarchDirection& d : dirs) {
        const SliceFrame frame = slice_frame(n.x * d.dx + n.y * d.dy, n.z);
        TangentChain chain(rho, Weighting::cosine, frame);
        const bool x_major = std::abs(d.dx) >= std::abs(d.dy);
        const double major = std::abs(x_major ? d.dx : d.dy);
        const double t_end = profile_end(f, i, j, d.dx, d.dy, reach);
        if (t_end > 1e-9)
          triangle_profile(f, i, j, d.dx, d.dy, t_end, [&](double t, double z) {
            if (columns_only) {
              const double m = t * major;
              if (std::abs(m - std::round(m)) > 1e-9) return;
            }
            chain.add(t, z - z0, t);
          });
        total += chain.length * chain.sum;
      }
      out[f.index(i, j)] = float(1.0 - std::clamp(total / K, 0.0, 1.0));
    }
  return out;
}

void measure(const Falloff& rho) {
  struct Field {
    const char* name;
    HeightField f;
  };
  // The nightly fields (tests/nightly/fields/*.json).
  const Field fields[] = {
      {"fractal", field_of(ProceduralKind::fractal, 7)},
      {"blocks", field_of(ProceduralKind::blocks, 5)},
      {"terraces", field_of(ProceduralKind::terraces, 5, 8, 0, 2.5)},
      {"craters", field_of(ProceduralKind::craters, 9, 4, 10)},
      {"ridges", field_of(ProceduralKind::ridges, 4, 10)},
      {"rough", field_of(ProceduralKind::rough, 3, 0, 0, 0, 70)},
  };
  const int K = 16;
  std::printf("%s R = %g, K = %d: mean / rmse of (variant - hbao triangles)\n", falloff_kind_name(rho.kind),
              rho.radius, K);
  std::printf("%-9s %7s | %-16s %-16s %-16s %-16s %-16s %-16s %-16s %-16s %-16s %-16s %-16s %-16s %-16s\n",
              "field", "hbao", "lsao", "lsao brute", "own cols", "own tri", "hbao bil", "hsao", "hsao tri",
              "lsao tri", "lsao tri brute", "lsao tri near 2", "lsao tri near 4", "near 2 brute", "near R");
  for (const Field& fd : fields) {
    const std::vector<Vec3f> normals = compute_normals(fd.f);
    auto hbao = [&](MarchSurface surface) {
      HbaoSettings s;
      s.falloff = rho;
      s.directions = uniform_directions(K);
      s.reach = default_reach(fd.f, rho);
      s.surface = surface;
      s.estimator = surface == MarchSurface::triangles ? HorizonEstimator::segment : HorizonEstimator::slab;
      s.bent = false;
      std::vector<float> v(fd.f.texel_count());
      hbao_field(fd.f, normals, s, RunControl{}, v.data(), nullptr);
      return v;
    };
    const std::vector<float> ref = hbao(MarchSurface::triangles);
    double ref_mean = 0;
    for (float v : ref) ref_mean += v;
    ref_mean /= double(ref.size());
    auto lsao = [&](LsaoEstimator e, double near = 0, LsaoSurface surface = LsaoSurface::bilinear) {
      LsaoOptions o;
      o.directions = K;
      o.occlusion.rho = rho;
      o.estimator = e;
      o.near_radius = near;
      o.surface = surface;
      return diff(lsao_obscurance(fd.f, o, RunControl{}), ref);
    };
    HsaoSettings hs;
    hs.falloff = rho;
    hs.directions = K;
    hs.steps = int(std::ceil(rho.radius));
    std::vector<float> hsao(fd.f.texel_count()), hsao_tri(fd.f.texel_count());
    hsao_field(fd.f, normals, hs, RunControl{}, hsao.data(), nullptr);
    hs.surface = HsaoSurface::triangles;
    hsao_field(fd.f, normals, hs, RunControl{}, hsao_tri.data(), nullptr);
    const Diff cols[] = {lsao(LsaoEstimator::hull),
                         lsao(LsaoEstimator::brute_visible),
                         diff(own_ray(fd.f, rho, K, true), ref),
                         diff(own_ray(fd.f, rho, K, false), ref),
                         diff(hbao(MarchSurface::bilinear), ref),
                         diff(hsao, ref),
                         diff(hsao_tri, ref),
                         lsao(LsaoEstimator::hull, 0, LsaoSurface::triangles),
                         lsao(LsaoEstimator::brute_visible, 0, LsaoSurface::triangles),
                         lsao(LsaoEstimator::hull, 2, LsaoSurface::triangles),
                         lsao(LsaoEstimator::hull, 4, LsaoSurface::triangles),
                         lsao(LsaoEstimator::brute_visible, 2, LsaoSurface::triangles),
                         lsao(LsaoEstimator::hull, rho.radius, LsaoSurface::triangles)};
    std::printf("%-9s %7.4f |", fd.name, ref_mean);
    for (const Diff& d : cols) std::printf(" %+.4f / %.4f", d.mean, d.rmse);
    std::printf("\n");
  }
}

}  // namespace
}  // namespace hfbake

int main(int argc, char** argv) {
  hfbake::Falloff rho{hfbake::FalloffKind::step, 8};
  for (int a = 1; a + 1 < argc; a += 2) {
    if (std::strcmp(argv[a], "--radius") == 0) rho.radius = std::atof(argv[a + 1]);
    if (std::strcmp(argv[a], "--falloff") == 0)
      rho.kind =
          std::string(argv[a + 1]) == "smooth" ? hfbake::FalloffKind::smooth : hfbake::FalloffKind::step;
  }
  hfbake::measure(rho);
  return 0;
}
