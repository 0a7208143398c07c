// P1 accuracy decomposition (a measurement program, not a test): on a strided subset of texels of a field,
// compares P1's horizons and ao with
//   T_tri(K): exact horizons marched from the texel centers themselves on the reference's surface (two
//             triangles per quad split along (i+1, j)-(i, j+1)): the profile along a ray is piecewise linear
//             with kinks only where it crosses a column, a row or a diagonal, so the steepest of those
//             crossings is the exact horizon; same K azimuths as P1, same Eq. 5 ao at the texel normal;
//   T_col(K): the same march from the texel center, but sampling only the major-axis crossings (the points
//             the sweep used to sample): T_col - T_tri is the surface-model part, P1 - T_col the mapping;
//   the reference (an hfbake reference EXR with ao.Y and ao_stderr.Y): T_tri(K) - ref tells whether
//             anything else (normals, reference) is left once the horizons are exact (excess = rms minus
//             the reference's own per-texel standard errors, in quadrature).
// Usage:
//   measure_p1 <kind> <size> <reference.exr|-> <stride> K...      the table above (texels every `stride`)
//   measure_p1 <kind> <size> - <stride> sim K...                   transfer candidates: taps marched exactly
//   on
//       the triangulation (or on columns only), each transfer to the texel center, ao - T_tri(K); the
//       experiment that chose P1's near/far split (the first row is the transfer P1 had before it)
//   measure_p1 <kind> <size> debug i j K angle_deg [depth radius]  per-direction horizons of one texel of an
//       analytic field against T_tri (e.g. `pit 65 debug 48 32 64 30 10 16`: the pit rim)
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "field/procedural.hpp"
#include "io/image_input.hpp"
#include "methods/p1/p1.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

using truth::march_from;
using truth::march_tri;
using truth::tri_height;

using truth::ao_term;

using Stats = truth::ErrorStats;

// Simulates the sweep's two-tap transfer with exact triangle-surface taps (what a sweep that samples every
// column, row and diagonal crossing computes) and candidate transfers to the texel center, against T_tri.
void simulate(const Scene& scene, const std::vector<std::pair<int, int>>& texels, int K) {
  const HeightField& f = scene.field;
  constexpr int V = 13;
  const char* names[V] = {"before: two taps, normal-gradient lift",
                          "own angles",
                          "seen from texel height, run+off*dmin",
                          "actual lift, near weight",
                          "near exact R=2 + far taps seen from texel",
                          "near exact R=4 + far taps",
                          "near R=2 + overall tap caster if run>=R",
                          "near R=2 + far taps (columns only)",
                          "near R=4 + far taps (columns only)",
                          "R=2 cols, q-lift (parallel shift)",
                          "R=2 cols, tangent-plane lift, run unshifted",
                          "R=2 cols, own far angle",
                          "R=2 cols, minmod-gradient lift"};
  std::vector<std::array<double, V + 1>> res(texels.size());
  SweepSpec spec;
  spec.directions = K;
  std::vector<SweepDirection> dirs;
  for (int k = 0; k < K; ++k) dirs.push_back(plan_direction(f, spec, k));
  tbb::parallel_for(std::size_t(0), texels.size(), [&](std::size_t t) {
    const auto [i, j] = texels[t];
    const std::size_t idx = f.index(i, j);
    const Vec3f n = scene.normals[idx];
    const double Z = f.z[idx];
    std::array<double, V + 1> acc{};
    for (const SweepDirection& d : dirs) {
      const double np = n.x * d.dx + n.y * d.dy;
      acc[V] += ao_term(march_tri(f, i, j, d.dx, d.dy, 7), np, n.z);
      const int u = d.x_major ? i : j, v0 = d.x_major ? j : i;
      const double g = double(v0) - double(u) * d.slope, frac = g - std::floor(g);
      double off[2] = {-frac, 1 - frac}, w_hi = frac;
      if (frac > 0 && v0 == 0) off[0] = off[1], w_hi = 0;
      if (frac > 0 && v0 == d.n_minor - 1) w_hi = 0;
      if (frac == 0) w_hi = 0;
      const double dmin = d.x_major ? d.dy : d.dx;
      const double G = (d.x_major ? -n.y / n.z : -n.x / n.z) * f.texel_size;
      double e[V][2];
      double near[2] = {truth::kNone, truth::kNone};
      for (int r = 0; r < 2; ++r) {
        double ndz, nrun;
        const double R = r == 0 ? 2 : 4;
        if (march_from(f, i, j, d.dx, d.dy, 7, 0, &ndz, &nrun, R)) near[r] = std::atan2(ndz, nrun);
      }
      for (int tp = 0; tp < 2; ++tp) {
        const double x = d.x_major ? u : v0 + off[tp], y = d.x_major ? v0 + off[tp] : u;
        const double zt =
            tri_height(f, std::clamp(x, 0.0, double(f.width - 1)), std::clamp(y, 0.0, double(f.height - 1)));
        double dz, run;
        const bool any = march_from(f, x, y, d.dx, d.dy, 7, 0, &dz, &run);
        const double none = truth::kNone;
        const double lift_n = zt - Z - G * off[tp], lift_a = zt - Z;
        double w = (run / d.step - 1) / 3;
        w = std::clamp(w, 0.0, 1.0);
        const double own = any ? std::atan2(dz, run) : none;
        e[0][tp] = any ? own + (std::atan2(dz + lift_n, run) - own) * w : none;
        e[1][tp] = own;
        const double run2 = std::max(run + off[tp] * dmin * f.texel_size, 1e-3);
        e[2][tp] = any ? std::atan2(dz + lift_a, run2) : none;
        e[3][tp] = any ? own + (std::atan2(dz + lift_a, run) - own) * w : none;
        for (int r = 0; r < 2; ++r) {
          const double R = r == 0 ? 2 : 4;
          double fdz, frun;
          const bool fany = march_from(f, x, y, d.dx, d.dy, 7, R, &fdz, &frun);
          const double frun2 = std::max(frun + off[tp] * dmin * f.texel_size, 1e-3);
          e[4 + r][tp] = std::max(near[r], fany ? std::atan2(fdz + lift_a, frun2) : none);
          const bool cany = march_from(f, x, y, d.dx, d.dy, d.x_major ? 1 : 2, R, &fdz, &frun);
          const double crun2 = std::max(frun + off[tp] * dmin * f.texel_size, 1e-3);
          e[7 + r][tp] = std::max(near[r], cany ? std::atan2(fdz + lift_a, crun2) : none);
        }
        e[6][tp] = std::max(near[0], any && run >= 2 ? std::atan2(dz + lift_a, run2) : none);
        {
          double fdz, frun;
          const bool cany = march_from(f, x, y, d.dx, d.dy, d.x_major ? 1 : 2, 2, &fdz, &frun);
          const double sq = off[tp] * dmin;  // texels along the texel's own ray
          const double zq = tri_height(f, std::clamp(i + sq * d.dx, 0.0, double(f.width - 1)),
                                       std::clamp(j + sq * d.dy, 0.0, double(f.height - 1)));
          e[9][tp] = std::max(
              near[0], cany ? std::atan2(fdz + zq - Z, std::max(frun + sq * f.texel_size, 1e-3)) : none);
          e[10][tp] = std::max(near[0], cany ? std::atan2(fdz + lift_n, frun) : none);
          e[11][tp] = std::max(near[0], cany ? std::atan2(fdz, frun) : none);
          const double zm = d.x_major ? f.at(i, j - 1) : f.at(i - 1, j),
                       zp = d.x_major ? f.at(i, j + 1) : f.at(i + 1, j);
          const double gl = Z - zm, gr = zp - Z;
          const double gmm = gl * gr <= 0 ? 0.0 : (std::fabs(gl) < std::fabs(gr) ? gl : gr);
          e[12][tp] = std::max(near[0], cany ? std::atan2(fdz + zt - Z - gmm * off[tp], frun) : none);
        }
      }
      for (int v = 0; v < V; ++v) acc[v] += ao_term(e[v][0] + (e[v][1] - e[v][0]) * w_hi, np, n.z);
    }
    for (double& a : acc) a /= K;
    res[t] = acc;
  });
  std::printf("K = %d, transfer variants: ao - T_tri(K) over %zu texels\n", K, texels.size());
  for (int v = 0; v < V; ++v) {
    Stats s;
    double mx = 0;
    for (const auto& r : res) s.add(r[v] - r[V]), mx = std::max(mx, std::fabs(r[v] - r[V]));
    std::printf("  %-45s mean %+8.5f rms %8.5f max %8.5f\n", names[v], s.mean(), s.rms(), mx);
  }
}

}  // namespace
}  // namespace hfbake

int main(int argc, char** argv) {
  using namespace hfbake;
  if (argc < 6) {
    std::fprintf(stderr, "usage: measure_p1 kind size reference.exr|- stride K...\n");
    return 2;
  }
  ProceduralKind kind;
  if (!parse_procedural_kind(argv[1], kind)) return 2;
  if (std::string(argv[3]) == "debug") {  // measure_p1 kind size debug i j K angle: per-direction horizons
    ProceduralSpec ps;
    ps.kind = kind, ps.width = ps.height = std::atoi(argv[2]), ps.angle_deg = std::atof(argv[7]);
    if (argc > 8) ps.depth = std::atof(argv[8]);
    if (argc > 9) ps.radius = std::atof(argv[9]);
    Scene sc;
    sc.field = make_procedural(ps, 1.0, Wrap::clamp);
    sc.normals = compute_normals(sc.field);
    const int i = std::atoi(argv[4]), j = std::atoi(argv[5]), K = std::atoi(argv[6]);
    P1Params p;
    p.directions = K, p.horizon = true;
    const P1Result r = compute_p1(sc, p, RunControl{});
    double vsky_tri = 1;
    for (int k = 0; k < K; ++k) {
      const double phi = 2 * kPi * k / K;
      const double et = march_tri(sc.field, i, j, std::cos(phi), std::sin(phi), 7);
      vsky_tri -= std::max(std::sin(et), 0.0) / K;
      const double ep = std::asin(r.horizon[sc.field.index(i, j) * K + k]);
      std::printf("k %3d  p1 %8.4f  tri %8.4f  diff %+8.4f deg\n", k, ep * 180 / kPi, et * 180 / kPi,
                  (ep - et) * 180 / kPi);
    }
    std::printf("ao %.6f vsky %.6f (exact triangle-surface horizons: vsky %.6f)\n",
                r.ao[sc.field.index(i, j)], r.vsky[sc.field.index(i, j)], vsky_tri);
    return 0;
  }
  const int size = std::atoi(argv[2]), stride = std::atoi(argv[4]);
  const std::string ref_file = argv[3];
  Scene scene;
  scene.field = truth::procedural(kind, size, size, Wrap::clamp);
  scene.normals = compute_normals(scene.field);
  const HeightField& f = scene.field;
  std::vector<float> ref_ao, ref_se;
  if (ref_file != "-") {
    const Image img = read_image(ref_file, {});
    int c_ao = -1, c_se = -1;
    for (int c = 0; c < img.info.channels; ++c) {
      if (img.info.channel_names[c] == "ao.Y") c_ao = c;
      if (img.info.channel_names[c] == "ao_stderr.Y") c_se = c;
    }
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) {
        ref_ao.push_back(img.at(i, j, c_ao));
        ref_se.push_back(c_se >= 0 ? img.at(i, j, c_se) : 0.0f);
      }
  }
  std::vector<std::pair<int, int>> texels;
  for (int j = stride / 2; j < f.height; j += stride)
    for (int i = stride / 2; i < f.width; i += stride) texels.push_back({i, j});
  std::printf("%s %d^2, %zu texels (stride %d)\n", argv[1], size, texels.size(), stride);
  std::printf("%5s | %-27s | %-27s | %-20s | %-34s\n", "K", "p1-Ttri ao mean/rms/max",
              "Tcol-Ttri ao mean/rms", "p1-Tcol ao mean/rms", "vs ref excess: p1 Ttri Tcol (bias)");
  if (std::string(argv[5]) == "sim") {
    for (int a = 6; a < argc; ++a) simulate(scene, texels, std::atoi(argv[a]));
    return 0;
  }
  for (int a = 5; a < argc; ++a) {
    const int K = std::atoi(argv[a]);
    P1Params p;
    p.directions = K;
    p.vsky = p.direct = false;
    p.horizon = true;
    const P1Result r = compute_p1(scene, p, RunControl{});
    const std::size_t T = texels.size();
    std::vector<double> tri(T), col(T), eh_tri(T), eh_col(T);
    tbb::parallel_for(std::size_t(0), T, [&](std::size_t t) {
      const auto [i, j] = texels[t];
      const Vec3f n = scene.normals[f.index(i, j)];
      double at = 0, ac = 0, ht = 0, hc = 0;
      for (int k = 0; k < K; ++k) {
        SweepSpec s;
        s.directions = K;
        const double phi = 2 * kPi * k / K, dx = std::cos(phi), dy = std::sin(phi);
        const bool x_major = std::fabs(dx) >= std::fabs(dy) - 1e-12;
        const double et = march_tri(f, i, j, dx, dy, 7), ec = march_tri(f, i, j, dx, dy, x_major ? 1 : 2);
        const double np = n.x * dx + n.y * dy;
        at += ao_term(et, np, n.z), ac += ao_term(ec, np, n.z);
        const double ep = std::asin(std::clamp(double(r.horizon[f.index(i, j) * K + k]), -1.0, 1.0));
        ht += std::fabs(ep - et), hc += std::fabs(ep - ec);
      }
      tri[t] = at / K, col[t] = ac / K, eh_tri[t] = ht / K, eh_col[t] = hc / K;
    });
    Stats p_t, c_t, p_c, p_ref, t_ref, c_ref, h_t, h_c;
    double maxd = 0, ref_mean = 0;
    for (std::size_t t = 0; t < T; ++t) {
      const std::size_t idx = f.index(texels[t].first, texels[t].second);
      const double pa = r.ao[idx];
      p_t.add(pa - tri[t]), c_t.add(col[t] - tri[t]), p_c.add(pa - col[t]);
      maxd = std::max(maxd, std::fabs(pa - tri[t]));
      h_t.add(eh_tri[t]), h_c.add(eh_col[t]);
      if (!ref_ao.empty()) {
        const double v = double(ref_se[idx]) * ref_se[idx];
        p_ref.add(pa - ref_ao[idx], v), t_ref.add(tri[t] - ref_ao[idx], v),
            c_ref.add(col[t] - ref_ao[idx], v);
        ref_mean += ref_ao[idx];
      }
    }
    ref_mean /= double(T);
    std::printf("%5d | %+8.5f %8.5f %8.5f | %+8.5f %8.5f | %+8.5f %8.5f", K, p_t.mean(), p_t.rms(), maxd,
                c_t.mean(), c_t.rms(), p_c.mean(), p_c.rms());
    if (!ref_ao.empty())
      std::printf(" | %.5f %.5f %.5f (%+.5f %+.5f), mean %.4f", p_ref.excess(), t_ref.excess(),
                  c_ref.excess(), p_ref.mean(), t_ref.mean(), ref_mean);
    std::printf(" | |de| deg vs tri %.3f vs col %.3f\n", h_t.mean() * 180 / kPi, h_c.mean() * 180 / kPi);
    std::fflush(stdout);
  }
  return 0;
}
