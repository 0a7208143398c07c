// Measurement (not a test): nlp against an independent brute-force horizon integration on the four P2
// fields, as the parameters vary (NS09 Figure 10's convergence study). Brute force: K azimuths, a march of
// the bilinear surface in 1/4-texel steps to the border, the exact casting set (every running maximum above
// the tangent plane) and exact cosine integrals per elevation band; one diffuse bounce from the brute-force
// direct light. Uniform white environment (so SH order 4 represents the lighting exactly), albedo 0.5.
//   measure_nlp [size=128] [brute_azimuths=256] [oracle: only the oracle rows]
//   measure_nlp hash: bit hashes of a few bakes (speed work must not change them)
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "field/procedural.hpp"
#include "methods/nlp/bake_nlp.hpp"
#include "methods/nlp/nlp_basis.hpp"
#include "methods/nlp/sh.hpp"
#include "methods/nlp/wedge_matrices.hpp"

using namespace hfbake;

namespace {

// integral over e in [a, b] of (nh cos e + nz sin e) cos e de
// How far (texels) a march from texel (i, j) along (cx, cy) runs: to the clamp border, or one field size
// on a repeating field.
double exit_distance(const HeightField& f, int i, int j, double cx, double cy) {
  const int W = f.width, H = f.height;
  if (f.wrap != Wrap::clamp) return std::max(W, H);
  double t = 1e30;
  if (cx > 1e-9) t = std::min(t, (W - 1 - i) / cx);
  if (cx < -1e-9) t = std::min(t, -i / cx);
  if (cy > 1e-9) t = std::min(t, (H - 1 - j) / cy);
  if (cy < -1e-9) t = std::min(t, -j / cy);
  return t;
}

double band_cos(double nh, double nz, double a, double b) {
  auto F = [&](double e) {
    return nh * (e / 2 + std::sin(2 * e) / 4) + nz * (std::sin(e) * std::sin(e) / 2);
  };
  return F(b) - F(a);
}

struct Brute {
  std::vector<float> direct, indirect;
};

// E/pi for a uniform unit environment and one bounce of albedo rho.
Brute brute_force(const Scene& s, int K, float rho) {
  const HeightField& f = s.field;
  const int W = f.width, H = f.height;
  const double step = 0.25;
  Brute out;
  out.direct.assign(f.texel_count(), 0);
  out.indirect.assign(f.texel_count(), 0);
  // Per texel, per azimuth: casting set (distance, e) for the indirect pass.
  struct Hit {
    float x, y, e0, e1;  // point and its elevation band
    int az;
  };
  std::vector<std::vector<Hit>> hits(f.texel_count());
  tbb::parallel_for(0, H, [&](int j) {
    for (int i = 0; i < W; ++i) {
      const Vec3 n = s.normals[f.index(i, j)].d();
      const double h0 = f.at(i, j);
      double acc = 0;
      std::vector<Hit>& hv = hits[f.index(i, j)];
      for (int a = 0; a < K; ++a) {
        const double phi = 2 * kPi * (a + 0.5) / K, cx = std::cos(phi), cy = std::sin(phi);
        const double nh = n.x * cx + n.y * cy, nz = n.z;
        const double emin = std::atan2(-nh, nz);
        double run = emin;
        const double t_exit = exit_distance(f, i, j, cx, cy);
        for (double t = step; t_exit > 0; t += step) {
          const bool last = t >= t_exit;
          if (last) t = t_exit;
          const double x = i + t * cx, y = j + t * cy;
          const double e = std::atan2(f.bilinear(x, y) - h0, t * f.texel_size);
          if (e > run) {
            hv.push_back({float(x), float(y), float(run), float(e), a});
            run = e;
          }
          if (last) break;
        }
        acc += band_cos(nh, nz, std::max(run, emin), kPi / 2);
      }
      out.direct[f.index(i, j)] = float(acc * (2 * kPi / K) / kPi);
    }
  });
  std::vector<float> B(f.texel_count());
  for (std::size_t t = 0; t < B.size(); ++t) B[t] = rho * out.direct[t];
  HeightField bf = f;
  bf.z = B;
  tbb::parallel_for(0, H, [&](int j) {
    for (int i = 0; i < W; ++i) {
      const Vec3 n = s.normals[f.index(i, j)].d();
      double acc = 0;
      for (const Hit& h : hits[f.index(i, j)]) {
        const double phi = 2 * kPi * (h.az + 0.5) / K;
        const double nh = n.x * std::cos(phi) + n.y * std::sin(phi);
        acc += bf.bilinear(h.x, h.y) * band_cos(nh, n.z, h.e0, h.e1);
      }
      out.indirect[f.index(i, j)] = float(acc * (2 * kPi / K) / kPi);
    }
  });
  return out;
}

// The NLP/SH pipeline fed with exact geometry (the "oracle"): at nlp's own m azimuths phi_a = 2 pi a / m, the
// exact horizon and casting set of the bilinear surface (1/4-texel march to the border, as the brute force)
// and the brute-force radiance replace the pyramid march; the NLP vectors, wedge matrices, SH product and
// clamped-cosine shading are nlp's. Its error against the brute force is what remains of NLP/SH when the
// radial sampling is perfect: the azimuthal interpolation (falls with m) and the order-4 NLP / SH truncation
// (does not).
Brute oracle(const Scene& s, int m, float rho, const std::vector<float>& radiance_direct) {
  const HeightField& f = s.field;
  const int W = f.width, H = f.height;
  const double step = 0.25;
  const auto A = nlp::sample_matrices(nlp::AzimuthInterpolation::linear, m);
  const float conv[9] = {3.14159265f, 2.0943951f,  2.0943951f,  2.0943951f, 0.78539816f,
                         0.78539816f, 0.78539816f, 0.78539816f, 0.78539816f};
  HeightField bf = f;
  for (std::size_t t = 0; t < bf.z.size(); ++t) bf.z[t] = rho * radiance_direct[t];
  Brute out;
  out.direct.assign(f.texel_count(), 0);
  out.indirect.assign(f.texel_count(), 0);
  tbb::parallel_for(0, H, [&](int j) {
    for (int i = 0; i < W; ++i) {
      const Vec3 n = s.normals[f.index(i, j)].d();
      const double h0 = f.at(i, j);
      float V[16] = {}, U[16] = {};
      for (int a = 0; a < m; ++a) {
        const double phi = 2 * kPi * a / m, cx = std::cos(phi), cy = std::sin(phi);
        const float emin = float(std::atan2(-(n.x * cx + n.y * cy), n.z));
        const double t_exit = exit_distance(f, i, j, cx, cy);
        float wmax = -1.5707963f, run = emin, u[4] = {}, prev[4];
        nlp::occlusion4(std::sin(emin), prev);
        for (double t = step; t_exit > 0; t += step) {
          const bool last = t >= t_exit;
          if (last) t = t_exit;
          const double x = i + t * cx, y = j + t * cy;
          const float e = float(std::atan2(f.bilinear(x, y) - h0, t * f.texel_size));
          wmax = std::max(wmax, e);
          if (e > run) {
            float nu[4];
            nlp::occlusion4(std::sin(e), nu);
            const float r = bf.bilinear(x, y);
            for (int l = 0; l < 4; ++l) u[l] += r * (nu[l] - prev[l]), prev[l] = nu[l];
            run = e;
          }
          if (last) break;
        }
        if (t_exit <= 0) wmax = emin;
        float v[4];
        nlp::band4(std::sin(wmax), 1.0f, v);
        for (int r = 0; r < 16; ++r)
          for (int c = 0; c < 4; ++c) V[r] += A[a][r * 4 + c] * v[c], U[r] += A[a][r * 4 + c] * u[c];
      }
      float y[16];
      sh::eval(float(n.x), float(n.y), float(n.z), y);
      double d = 0, ind = 0;
      for (int k = 0; k < 9; ++k) d += conv[k] * y[k] * V[k], ind += conv[k] * y[k] * U[k];
      out.direct[f.index(i, j)] = float(d / kPi);
      out.indirect[f.index(i, j)] = float(ind / kPi);
    }
  });
  return out;
}

struct Err {
  double rmse = 0, bias = 0, mean = 0;
};
// got: `stride` floats per texel (3 for an RGB layer, 1 for a plain buffer), channel 0 compared.
Err error(const std::vector<float>& got, int stride, const std::vector<float>& truth, int W, int H,
          int margin) {
  Err e;
  int n = 0;
  for (int j = margin; j < H - margin; ++j)
    for (int i = margin; i < W - margin; ++i) {
      const std::size_t t = std::size_t(j) * W + i;
      const double d = got[t * stride] - truth[t];
      e.rmse += d * d;
      e.bias += d;
      e.mean += truth[t];
      ++n;
    }
  e.rmse = std::sqrt(e.rmse / n);
  e.bias /= n;
  e.mean /= n;
  return e;
}

}  // namespace

// FNV-1a over the bits of every layer of a few bakes (clamp and repeat, sun, 2 bounces, subsampling,
// B-spline wedges): speed work must leave these unchanged.
int print_hashes() {
  for (int c = 0; c < 5; ++c) {
    ProceduralSpec spec;
    spec.kind = c % 2 ? ProceduralKind::blocks : ProceduralKind::fractal;
    spec.width = 96;
    spec.height = 80;
    spec.seed = 3;
    Scene s;
    s.field = make_procedural(spec, 1.0, c == 2 ? Wrap::repeat : Wrap::clamp);
    s.normals = compute_normals(s.field);
    s.surface.albedo.assign(s.field.texel_count(), Rgb{0.5f, 0.6f, 0.7f});
    const EnvironmentLighting sky = make_sky_environment(SkySpec{});
    s.environment = sky.environment;
    s.lights = sky.lights;
    s.bounces = c == 3 ? 2 : 1;
    NlpOptions o;
    o.directions = c == 4 ? 17 : 32;
    o.subsample = c == 1 ? 2 : 1;
    if (c == 4) o.interpolation = nlp::AzimuthInterpolation::bspline;
    const LayerSet ls = bake_nlp(s, o, RunControl{});
    std::uint64_t h = 1469598103934665603ull;
    for (const Layer& l : ls.layers)
      for (float v : l.data) {
        std::uint32_t b;
        std::memcpy(&b, &v, 4);
        for (int k = 0; k < 4; ++k) h = (h ^ ((b >> (8 * k)) & 255)) * 1099511628211ull;
      }
    std::printf("case %d: %016llx\n", c, (unsigned long long)h);
  }
  return 0;
}

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "hash") return print_hashes();
  const int size = argc > 1 ? std::atoi(argv[1]) : 128;
  const int K = argc > 2 ? std::atoi(argv[2]) : 256;
  const bool oracle_only = argc > 3 && std::string(argv[3]) == "oracle";
  const float rho = 0.5f;
  std::printf("field   | m   | k | o_v o_u | interp  | direct rmse  bias   | indirect rmse  bias  | ms\n");
  for (ProceduralKind kind :
       {ProceduralKind::fractal, ProceduralKind::bricks, ProceduralKind::sines, ProceduralKind::blocks}) {
    ProceduralSpec spec;
    spec.kind = kind;
    spec.width = spec.height = size;
    spec.seed = 7;
    Scene s;
    s.field = make_procedural(spec, 1.0, Wrap::clamp);
    s.normals = compute_normals(s.field);
    s.surface.albedo.assign(s.field.texel_count(), Rgb{rho, rho, rho});
    s.environment = make_uniform_environment(Rgb{1, 1, 1});
    s.bounces = 1;
    const Brute bf = brute_force(s, K, rho);
    double md = 0, mi = 0;
    for (std::size_t t = 0; t < bf.direct.size(); ++t) md += bf.direct[t], mi += bf.indirect[t];
    std::printf("%-7s | brute force K=%d: mean direct %.4f, mean indirect %.4f\n", procedural_kind_name(kind),
                K, md / bf.direct.size(), mi / bf.direct.size());
    for (int m : {8, 16, 32, 64, 100}) {
      const Brute orc = oracle(s, m, rho, bf.direct);
      const Err d = error(orc.direct, 1, bf.direct, size, size, 2);
      const Err ind = error(orc.indirect, 1, bf.indirect, size, size, 2);
      std::printf(
          "%-7s | %3d | oracle: exact horizons, casting sets, radiance | %.4f  %+.4f | %.4f  %+.4f |\n",
          procedural_kind_name(kind), m, d.rmse, d.bias, ind.rmse, ind.bias);
    }
    if (oracle_only) continue;
    struct Cfg {
      int m, k, ov, ou;
      nlp::AzimuthInterpolation in;
    };
    const auto lin = nlp::AzimuthInterpolation::linear, bsp = nlp::AzimuthInterpolation::bspline;
    for (Cfg c :
         {Cfg{8, 4, 2, 2, lin}, Cfg{16, 4, 2, 2, lin}, Cfg{32, 4, 2, 2, lin}, Cfg{64, 4, 2, 2, lin},
          Cfg{100, 4, 2, 2, lin}, Cfg{32, 4, 2, 2, bsp}, Cfg{100, 2, 1, 1, lin}, Cfg{100, 8, 2, 2, lin},
          Cfg{100, 8, 4, 4, lin}, Cfg{100, 16, 6, 6, lin}, Cfg{32, 4, 3, 3, lin}, Cfg{32, 4, 4, 4, lin},
          Cfg{32, 8, 4, 4, lin}, Cfg{32, 4, 8, 8, lin}}) {
      NlpOptions o;
      o.directions = c.m;
      o.levels_per_octave = c.k;
      o.level_offset = c.ov;
      o.radiance_level_offset = c.ou;
      o.interpolation = c.in;
      o.layers = {"direct", "indirect"};
      const auto t0 = std::chrono::steady_clock::now();
      const LayerSet ls = bake_nlp(s, o, RunControl{});
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      const Err d = error(ls.find("direct")->data, 3, bf.direct, size, size, 2);
      const Err ind = error(ls.find("indirect")->data, 3, bf.indirect, size, size, 2);
      std::printf("%-7s | %3d | %d | %d   %d   | %-7s | %.4f  %+.4f | %.4f  %+.4f | %.0f\n",
                  procedural_kind_name(kind), c.m, c.k, c.ov, c.ou, c.in == lin ? "linear" : "bspline",
                  d.rmse, d.bias, ind.rmse, ind.bias, ms);
    }
  }
  return 0;
}
