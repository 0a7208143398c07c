// p1's row-run lighting kernels (methods/p1/row_shading.hpp): SSE2, AVX2 and AVX-512F give the same bits
// for every sum and layer they write, on random runs of every width, with each kind of environment light.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "core/azimuth.hpp"
#include "env/environment.hpp"
#include "methods/p1/lighting_table.hpp"
#include "methods/p1/row_shading.hpp"

namespace hfbake {
namespace {

struct Sums {
  std::vector<float> ao, vsky, rgb, bent, fao, fdr, fdg, fdb, hz, hd;
  explicit Sums(std::size_t N, int nb)
      : ao(N),
        vsky(N),
        rgb(3 * N),
        bent(3 * N),
        fao(kCornerFacets * N),
        fdr(kCornerFacets * N),
        fdg(kCornerFacets * N),
        fdb(kCornerFacets * N),
        hz(N * std::size_t(nb)),
        hd(N * std::size_t(nb)) {}
  bool same_bits(const Sums& o) const {
    for (auto m : {&Sums::ao, &Sums::vsky, &Sums::rgb, &Sums::bent, &Sums::fao, &Sums::fdr, &Sums::fdg,
                   &Sums::fdb, &Sums::hz, &Sums::hd})
      if (std::memcmp((this->*m).data(), (o.*m).data(), (this->*m).size() * sizeof(float)) != 0) return false;
    return true;
  }
};

enum class Light { uniform, tables, profiles };

// Every run of a field of N texels, in random widths, through `kernel`; the same random draws each call.
Sums shade_all(p1::ShadeRowFn kernel, Light light, bool slopes, const p1::LightingTables& tables,
               const p1::SwathProfiles& profiles) {
  constexpr std::size_t N = 4096;
  constexpr int K = 16, k_begin = 4, k_end = 12;
  std::vector<float> cs, sn;
  azimuth_table(K, cs, sn);
  Sums s(N, k_end - k_begin);
  p1::ShadeRowTarget t;
  t.N = N, t.k_begin = k_begin, t.cs = cs.data(), t.sn = sn.data();
  t.uniform_env = light == Light::uniform;
  t.need_theta = true, t.facets = true;
  t.ao = s.ao.data(), t.vsky = s.vsky.data(), t.bent = s.bent.data(), t.hz = s.hz.data(), t.hd = s.hd.data();
  if (light == Light::uniform) {
    t.fao = s.fao.data();
  } else {
    t.rgb = s.rgb.data(), t.fdr = s.fdr.data(), t.fdg = s.fdg.data(), t.fdb = s.fdb.data();
    t.tables = light == Light::tables ? &tables : nullptr;
    t.profiles = light == Light::profiles ? &profiles : nullptr;
    t.need_theta = light == Light::profiles;
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1, 1), up(0.05f, 1), span(-1.5f, 1.5f), wide(-40, 40);
  std::uniform_int_distribution<int> width(1, p1::kShadeRun);
  std::vector<float> nx(N), ny(N), nz(N), fx(kCornerFacets * N), fy(kCornerFacets * N), fz(kCornerFacets * N),
      h(N), d(N);
  for (std::size_t i = 0; i < N; ++i) {
    nx[i] = u(rng), ny[i] = u(rng), nz[i] = up(rng);
    for (std::size_t q = 0; q < kCornerFacets; ++q)
      fx[q * N + i] = u(rng), fy[q * N + i] = u(rng), fz[q * N + i] = up(rng);
    // Slopes over a wide range with no crossing at all (-inf) among them; elevations within (-pi/2, pi/2).
    h[i] = slopes ? (i % 97 == 0 ? -std::numeric_limits<float>::infinity() : wide(rng)) : span(rng);
    d[i] = i % 89 == 0 ? std::numeric_limits<float>::infinity() : up(rng) * 100;
  }
  for (int k = k_begin; k < k_end; ++k)
    for (std::size_t base = 0; base < N;) {
      const int w = int(std::min<std::size_t>(std::size_t(width(rng)), N - base));
      p1::ShadeRowRun run;
      run.k = k, run.base = base, run.w = w;
      run.nx = nx.data() + base, run.ny = ny.data() + base, run.nz = nz.data() + base;
      for (int q = 0; q < kCornerFacets; ++q)
        run.fx[q] = fx.data() + q * N + base, run.fy[q] = fy.data() + q * N + base,
        run.fz[q] = fz.data() + q * N + base;
      run.horizon = h.data() + base, run.slopes = slopes, run.distance = d.data() + base;
      kernel(t, run);
      base += std::size_t(w);
    }
  return s;
}

TEST(RowShading, EveryInstructionSetGivesTheSameBits) {
  const EnvironmentLighting sky = make_sky_environment(SkySpec{});
  const p1::LightingTables tables = p1::build_lighting_tables(sky.environment, 16, 15, 64);
  const p1::SwathProfiles profiles = p1::build_swath_profiles(sky.environment, 16);
  int compared = 0;
  for (const Light light : {Light::uniform, Light::tables, Light::profiles})
    for (const bool slopes : {true, false}) {
      const Sums base = shade_all(p1::shade_row_sse2, light, slopes, tables, profiles);
      // The runs did write: the horizons, and the light's sums.
      EXPECT_NE(base.hz[17], 0.0f);
      EXPECT_NE(light == Light::uniform ? base.ao[17] : base.rgb[3 * 17], 0.0f);
      EXPECT_NE(light == Light::uniform ? base.fao[17] : base.fdr[17], 0.0f);
      for (const p1::LaneIsa isa : {p1::LaneIsa::avx2, p1::LaneIsa::avx512}) {
        if (!p1::lane_isa_available(isa)) continue;
        const Sums other = shade_all(p1::shade_row_kernel(isa), light, slopes, tables, profiles);
        EXPECT_TRUE(base.same_bits(other))
            << "light " << int(light) << " slopes " << slopes << " isa " << int(isa);
        ++compared;
      }
    }
  if (compared == 0) GTEST_SKIP() << "this processor runs only the SSE2 kernel";
}

}  // namespace
}  // namespace hfbake
