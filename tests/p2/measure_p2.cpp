// Measurements for the P2 closing note (not a test): P2 Table 2 (horizons and iterations per point and
// direction), the scaling of iterations with line length (P2 Figure 8), and the speed table (ms per
// direction for visibility alone, with one bounce, and the naive method with identical output).
//   measure_p2 table2 [N=1024] [K=256]
//   measure_p2 scaling
//   measure_p2 speed [N=1024] [K=64] [naive_K=8]
//   measure_p2 kconv [N=256]
#include <tbb/global_control.h>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include <ctime>
#include <string>
#include <vector>

#include "env/environment.hpp"
#include "field/procedural.hpp"
#include "field/scene.hpp"
#include "methods/p1/p1.hpp"
#include "methods/p2/bake_p2.hpp"
#include "methods/p2/hull_tree.hpp"
#include "methods/p2/indirect_sweep.hpp"

using namespace hfbake;

namespace {

const ProceduralKind kKinds[] = {ProceduralKind::fractal, ProceduralKind::bricks, ProceduralKind::sines,
                                 ProceduralKind::blocks};

HeightField field(ProceduralKind kind, int n) {
  ProceduralSpec spec;
  spec.kind = kind;
  spec.width = spec.height = n;
  spec.seed = 1;
  return make_procedural(spec, 1.0, Wrap::clamp);
}

// CPU seconds of the process (all threads): on a shared, loaded machine wall time says little; on an
// idle machine with T cores the wall time is about this divided by T.
struct CpuClock {
  std::clock_t c0 = std::clock();
  double seconds() const { return double(std::clock() - c0) / CLOCKS_PER_SEC; }
};

void table2(int N, int K) {
  std::printf("P2 Table 2 on %dx%d (clamp), K = %d: per point and direction\n", N, N, K);
  std::printf("%-8s %8s %8s %10s %8s %12s %8s\n", "field", "m_a", "t_a", "naive", "t_a/nv", "run starts",
              "cpu s");
  for (ProceduralKind kind : kKinds) {
    const HeightField f = field(kind, N);
    const std::vector<Vec3f> normals = compute_normals(f);
    const std::vector<Rgb> exit(f.texel_count());
    IndirectSweepSpec spec;
    spec.directions = K;
    spec.gather = false;
    P2SweepStats st;
    const CpuClock t0;
    sweep_indirect(f, normals, exit, spec, RunControl{}, &st);
    const double sec = t0.seconds();
    const double pts = double(st.receivers);
    std::printf("%-8s %8.2f %8.2f %10.1f %7.2f%% %12.2f %8.1f\n", procedural_kind_name(kind),
                st.horizons / pts, st.iterations / pts, st.naive_iterations / pts,
                100.0 * st.iterations / st.naive_iterations, st.run_starts / pts, sec);
  }
}

std::uint64_t lcg(std::uint64_t& s) {
  s = s * 6364136223846793005ull + 1442695040888963407ull;
  return s >> 11;
}
double u01(std::uint64_t& s) {
  return double(lcg(s)) * (1.0 / 9007199254740992.0);
}

// P2 §6: "detail": every doubling of n adds points between the existing ones, uniform with half the
// range (midpoint displacement); "extent": random heights from a fixed range.
void scaling() {
  std::printf(
      "P2 Figure 8: iterations t per line of n samples (mean over lines), fit t ~ n^k for n >= 512\n");
  std::printf("%8s %14s %14s %14s\n", "n", "detail t", "extent t", "naive n(n-1)/2");
  const int lines = 16;
  std::vector<double> ln_n, ln_detail, ln_extent;
  for (int lev = 6; lev <= 14; ++lev) {
    const int n = 1 << lev;
    double td = 0, te = 0;
    for (int l = 0; l < lines; ++l) {
      std::uint64_t s = 1000 + l;
      std::vector<double> h(n + 1, 0.0);
      h[0] = u01(s);
      h[n] = u01(s);
      double range = 1.0;
      for (int step = n; step > 1; step /= 2, range *= 0.5)
        for (int i = step / 2; i < n; i += step)
          h[i] = 0.5 * (h[i - step / 2] + h[i + step / 2]) + (u01(s) - 0.5) * range;
      HullTree t;
      t.reset(n);
      for (int i = 0; i < n; ++i) t.push(h[i] * n);  // the detail's range grows with the line: fixed slopes
      td += double(t.iterations());
      HullTree e;
      e.reset(n);
      for (int i = 0; i < n; ++i) e.push(u01(s) * 16);
      te += double(e.iterations());
    }
    td /= lines;
    te /= lines;
    std::printf("%8d %14.0f %14.0f %14.0f\n", n, td, te, double(n) * (n - 1) / 2);
    if (n >= 512) {
      ln_n.push_back(std::log(double(n)));
      ln_detail.push_back(std::log(td));
      ln_extent.push_back(std::log(te));
    }
  }
  auto slope = [&](const std::vector<double>& y) {
    double mx = 0, my = 0;
    for (std::size_t i = 0; i < y.size(); ++i) mx += ln_n[i], my += y[i];
    mx /= y.size(), my /= y.size();
    double sxy = 0, sxx = 0;
    for (std::size_t i = 0; i < y.size(); ++i)
      sxy += (ln_n[i] - mx) * (y[i] - my), sxx += (ln_n[i] - mx) * (ln_n[i] - mx);
    return sxy / sxx;
  };
  std::printf("exponent k: detail %.2f (P2: 1.65), extent %.2f (P2: 1.01)\n", slope(ln_detail),
              slope(ln_extent));
}

void speed(int N, int K, int naive_K) {
  std::printf("Speed on %dx%d (clamp), CPU ms per direction, 1 thread; naive measured with K = %d\n", N, N,
              naive_K);
  std::printf("%-8s %10s %10s %10s %10s %10s %12s\n", "field", "vis tree", "vis naive", "speedup", "1 bounce",
              "naive 1b", "1b (facets)");
  for (ProceduralKind kind : kKinds) {
    const HeightField f = field(kind, N);
    const std::vector<Vec3f> normals = compute_normals(f);
    std::vector<Rgb> exit(f.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
    IndirectSweepSpec spec;
    spec.directions = K;
    spec.gather = false;
    CpuClock t0;
    sweep_indirect(f, normals, exit, spec, RunControl{});
    const double vis_tree = t0.seconds() * 1000 / K;
    spec.gather = true;
    t0 = CpuClock{};
    const std::vector<Rgb> a = sweep_indirect(f, normals, exit, spec, RunControl{});
    const double bounce_tree = t0.seconds() * 1000 / K;
    // The naive method on a subset of directions (same directions for both, identical output checked).
    IndirectSweepSpec ns = spec;
    ns.directions = naive_K;
    ns.gather = false;
    ns.visibility = P2Visibility::naive;
    t0 = CpuClock{};
    sweep_indirect(f, normals, exit, ns, RunControl{});
    const double vis_naive = t0.seconds() * 1000 / naive_K;
    ns.gather = true;
    t0 = CpuClock{};
    const std::vector<Rgb> b = sweep_indirect(f, normals, exit, ns, RunControl{});
    const double bounce_naive = t0.seconds() * 1000 / naive_K;
    IndirectSweepSpec ts = ns;
    ts.visibility = P2Visibility::tree;
    const std::vector<Rgb> c = sweep_indirect(f, normals, exit, ts, RunControl{});
    const bool same = std::memcmp(b.data(), c.data(), b.size() * sizeof(Rgb)) == 0;
    // The default sender model: per-facet radiance (two facets per texel, six corner values per texel) and
    // the corners' next-bounce light.
    std::vector<Rgb> exit_f(2 * f.texel_count(), Rgb{0.5f, 0.5f, 0.5f}),
        corner_f(kCornerFacets * f.texel_count(), Rgb{0.5f, 0.5f, 0.5f}), facet_e;
    IndirectSweepSpec fs = spec;
    fs.exit_facets = &exit_f;
    fs.corner_exit = &corner_f;
    t0 = CpuClock{};
    sweep_indirect(f, normals, exit, fs, RunControl{}, nullptr, &facet_e);
    const double bounce_facets = t0.seconds() * 1000 / K;
    std::printf("%-8s %10.1f %10.1f %9.1fx %10.1f %10.1f %12.1f  %s\n", procedural_kind_name(kind), vis_tree,
                vis_naive, vis_naive / vis_tree, bounce_tree, bounce_naive, bounce_facets,
                same ? "identical" : "DIFFERENT");
  }
}

// Azimuthal convergence alone: indirect bounce 1 for K against K = 512 of the same method (same line
// sampling, so the difference is the K error only), on 256^2 fields under a uniform sky, albedo 0.6.
void kconv(int N) {
  std::printf(
      "Azimuthal self-convergence of indirect bounce 1 (%dx%d, uniform sky 1, albedo 0.6): rms of\n"
      "(K) - (K = 512) over texels, and the mean of bounce 1\n",
      N, N);
  std::printf("%-8s %10s %10s %10s %10s %10s\n", "field", "mean", "K=16", "K=32", "K=64", "K=128");
  for (ProceduralKind kind : kKinds) {
    Scene s;
    s.field = field(kind, N);
    s.normals = compute_normals(s.field);
    s.surface.albedo.assign(s.field.texel_count(), Rgb{0.6f, 0.6f, 0.6f});
    s.environment = make_uniform_environment({1, 1, 1});
    auto run = [&](int K) {
      P2Params p;
      p.directions = K;
      p.bounces = 1;
      return compute_p2(s, p, RunControl{}).indirect;
    };
    const std::vector<Rgb> ref = run(512);
    double mean = 0;
    for (const Rgb& v : ref) mean += v.g / double(ref.size());
    std::printf("%-8s %10.5f", procedural_kind_name(kind), mean);
    for (int K : {16, 32, 64, 128}) {
      const std::vector<Rgb> a = run(K);
      double sq = 0;
      for (std::size_t i = 0; i < a.size(); ++i) sq += double(a[i].g - ref[i].g) * (a[i].g - ref[i].g);
      std::printf(" %10.5f", std::sqrt(sq / double(a.size())));
    }
    std::printf("\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "speed";
  // One thread: CPU time is then the work itself (no pool spinning); 2 cores take about half of it.
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  auto arg = [&](int i, int def) { return argc > i ? std::atoi(argv[i]) : def; };
  if (what == "table2")
    table2(arg(2, 1024), arg(3, 256));
  else if (what == "kconv")
    kconv(arg(2, 256));
  else if (what == "scaling")
    scaling();
  else
    speed(arg(2, 1024), arg(3, 64), arg(4, 8));
  return 0;
}
