// The lane search alone (methods/p1/lane_horizons.hpp): usage measure_lanes
// [fractal|rough|step|tilted|<procedural kind>] [size] [K] [tolerance] [checks]. Prints CPU per
// texel-direction (AVX2 with and without casters, AVX-512 without, and SSE2, all checked to give the same
// bits), groups evaluated, and the largest difference in sin h from the exact march at sampled texels.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

#include "methods/p1/lane_horizons.hpp"
#include "p1_truth.hpp"

using namespace hfbake;
static double cpu_now() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

int main(int argc, char** argv) {
  const std::string kind = argc > 1 ? argv[1] : "fractal";
  const int n = argc > 2 ? std::atoi(argv[2]) : 1024;
  const int K = argc > 3 ? std::atoi(argv[3]) : 64;
  const float tol = argc > 4 ? float(std::atof(argv[4])) : 0.0f;
  const int checks = argc > 5 ? std::atoi(argv[5]) : 2000;
  HeightField f;
  if (kind == "rough")
    f = truth::rough_field(n, n, 70, 0.6, 11);
  else if (kind == "step")
    f = truth::step_field(n, n, 20, 30, 3, 16);
  else if (kind == "tilted") {  // rough terrain at a tenth of its relief on a 30 degree tilt along x
    f = truth::rough_field(n, n, 70, 0.6, 11);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) f.z[f.index(i, j)] = 0.1f * f.z[f.index(i, j)] + 0.57735f * float(i);
  } else {
    ProceduralKind pk;
    parse_procedural_kind(kind, pk);
    ProceduralSpec s;
    s.kind = pk, s.width = n, s.height = n, s.seed = 7;
    f = make_procedural(s, 1.0, Wrap::clamp);
  }
  SweepSpec spec;
  spec.directions = K;
  p1::LaneLayout L[2];
  auto t0 = std::chrono::steady_clock::now();
  L[0].build(f, true), L[1].build(f, false);
  auto t1 = std::chrono::steady_clock::now();
  std::vector<float> slope(f.texel_count());
  std::vector<std::int32_t> which(f.texel_count());
  p1::LaneScratch S;
  p1::LaneStats st;
  double search_s = 0, sse_s = 0, bare_s = 0, avx512_s = 0, maxerr = 0;
  std::uint64_t hash = 1469598103934665603ull, slope_hash = 1469598103934665603ull;
  std::uint64_t seed = 99;
  for (int k = 0; k < K; ++k) {
    const SweepDirection sd = plan_direction(f, spec, k);
    const bool xm = std::fabs(sd.dx) >= std::fabs(sd.dy);
    p1::LaneDirection d;
    const double a = cpu_now();
    d.build(f, L[xm ? 0 : 1], sd.dx, sd.dy);
    p1::lane_search(L[xm ? 0 : 1], d, 0, p1::lane_strip_count(L[xm ? 0 : 1], d), tol, S, slope.data(),
                    which.data(), &st, p1::LaneIsa::avx2);
    const double b = cpu_now();
    search_s += b - a;
    for (std::size_t t = 0; t < slope.size(); ++t) {
      std::uint32_t bits;
      std::memcpy(&bits, &slope[t], 4);
      hash = (hash ^ bits ^ (std::uint64_t(std::uint32_t(which[t])) << 32)) * 1099511628211ull;
      slope_hash = (slope_hash ^ bits) * 1099511628211ull;
    }
    std::vector<float> slope0(slope.size());
    const double c0 = cpu_now();
    p1::lane_search(L[xm ? 0 : 1], d, 0, p1::lane_strip_count(L[xm ? 0 : 1], d), tol, S, slope0.data(),
                    nullptr, nullptr, p1::LaneIsa::avx2);
    bare_s += cpu_now() - c0;
    if (p1::lane_isa_available(p1::LaneIsa::avx512)) {
      std::vector<float> slope5(slope.size());
      std::vector<std::int32_t> which5(slope.size());
      const double e0 = cpu_now();
      p1::lane_search(L[xm ? 0 : 1], d, 0, p1::lane_strip_count(L[xm ? 0 : 1], d), tol, S, slope5.data(),
                      nullptr, nullptr, p1::LaneIsa::avx512);
      avx512_s += cpu_now() - e0;
      p1::lane_search(L[xm ? 0 : 1], d, 0, p1::lane_strip_count(L[xm ? 0 : 1], d), tol, S, slope5.data(),
                      which5.data(), nullptr, p1::LaneIsa::avx512);
      if (std::memcmp(slope.data(), slope5.data(), slope.size() * 4) != 0 || which != which5)
        std::printf("direction %d: AVX2 and AVX-512 differ\n", k);
    }
    if (std::memcmp(slope.data(), slope0.data(), slope.size() * 4) != 0)
      std::printf("direction %d: the slopes without casters differ\n", k);
    std::vector<float> slope2(slope.size());
    std::vector<std::int32_t> which2(slope.size());
    const double b1 = cpu_now();
    p1::lane_search(L[xm ? 0 : 1], d, 0, p1::lane_strip_count(L[xm ? 0 : 1], d), tol, S, slope2.data(),
                    which2.data(), nullptr, p1::LaneIsa::sse2);
    const double b2 = cpu_now();
    sse_s += b2 - b1;
    if (std::memcmp(slope.data(), slope2.data(), slope.size() * 4) != 0 || which != which2)
      std::printf("direction %d: AVX2 and SSE2 differ\n", k);
    for (int c = 0; c < checks / K + 1; ++c) {
      seed = seed * 6364136223846793005ull + 1442695040888963407ull;
      const int i = int((seed >> 33) % n);
      const int j = int((seed >> 13) % n);
      const double e = truth::march_tri(f, i, j, sd.dx, sd.dy, 7);
      const float m = slope[f.index(i, j)];
      const double got = m == -std::numeric_limits<float>::infinity() ? truth::kNone : std::atan(double(m));
      const double err = std::fabs(std::sin(got) - std::sin(e));
      if (err > maxerr) maxerr = err;
      if (err > 1e-5 + tol)
        std::printf("k %d texel %d %d: got %.7f exact %.7f\n", k, i, j, std::sin(got), std::sin(e));
    }
  }
  const double td = double(f.texel_count()) * K;
  std::printf("%s %d K=%d tol=%g: layouts %.3f s, search %.3f s = %.1f ns/texdir = %.1f M/s; max err %.2e\n",
              kind.c_str(), n, K, tol, std::chrono::duration<double>(t1 - t0).count(), search_s,
              search_s / td * 1e9, td / search_s * 1e-6, maxerr);
  std::printf("hash of every slope and caster: %016llx; of every slope: %016llx\n", (unsigned long long)hash,
              (unsigned long long)slope_hash);
  std::printf("without casters: %.1f ns/texdir = %.1f M/s\n", bare_s / td * 1e9, td / bare_s * 1e-6);
  std::printf("avx-512 without casters: %.1f ns/texdir\n", avx512_s / td * 1e9);
  std::printf("sse2: %.1f ns/texdir (avx2/sse2 %.3f)\n", sse_s / td * 1e9, search_s / sse_s);
  std::printf("per group of %d: blocks %.2f crossings %.1f\n", p1::kLanes, double(st.blocks) / st.groups,
              double(st.crossings) / st.groups);
}
