// The lane search (methods/p1/lane_horizons.hpp) on its own against the exact march (p1_truth.hpp), every
// texel of non-square rough, stepped and smooth fields, in directions of every octant; and its two kernels
// (SSE2, AVX2), with and without casters, against each other, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "methods/p1/lane_horizons.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

struct Case {
  const char* name;
  HeightField field;
};

std::vector<Case> cases() {
  std::vector<Case> c;
  c.push_back({"rough 70", truth::rough_field(97, 61, 70, 0.6, 3, 16)});
  c.push_back({"terraces", truth::step_field(64, 90, 12, 25, 3, 9)});
  c.push_back({"fractal", truth::procedural(ProceduralKind::fractal, 83, 70, Wrap::clamp)});
  return c;
}

// sin of the elevation of slope m (-inf: nothing behind, -1).
double sin_of(float m) {
  return m == -std::numeric_limits<float>::infinity() ? -1.0 : std::sin(std::atan(double(m)));
}

void check(const HeightField& f, const char* name, float tolerance, double curvature = 0) {
  SweepSpec spec;
  spec.directions = 24;
  spec.azimuths = {0.3, 1.2, 2.0, 2.9, 3.7, 4.4, 5.1, 5.9, 0.0, 3.14159265358979 / 4, 3.14159265358979};
  p1::LaneLayout layouts[2];
  layouts[0].build(f, true), layouts[1].build(f, false);
  const std::size_t N = f.texel_count();
  std::vector<float> slope(N), slope2(N);
  std::vector<std::int32_t> which(N), which2(N);
  p1::LaneScratch scratch;
  for (int k = 0; k < int(spec.azimuths.size()); ++k) {
    const SweepDirection sd = plan_direction(f, spec, k);
    const p1::LaneLayout& L = layouts[std::fabs(sd.dx) >= std::fabs(sd.dy) ? 0 : 1];
    p1::LaneDirection d;
    d.build(f, L, sd.dx, sd.dy, curvature);
    const int strips = p1::lane_strip_count(L, d);
    p1::lane_search(f, L, d, 0, strips, tolerance, scratch, slope.data(), which.data(), nullptr,
                    p1::LaneIsa::sse2);
    if (p1::lane_avx2_available()) {
      p1::lane_search(f, L, d, 0, strips, tolerance, scratch, slope2.data(), which2.data(), nullptr,
                      p1::LaneIsa::avx2);
      EXPECT_EQ(std::memcmp(slope.data(), slope2.data(), N * sizeof(float)), 0) << name << " k " << k;
      EXPECT_EQ(which, which2) << name << " k " << k;
    }
    // Without casters (which null; its own hints, once a block): the same slopes, on either kernel.
    for (const p1::LaneIsa isa : {p1::LaneIsa::sse2, p1::LaneIsa::avx2}) {
      if (isa == p1::LaneIsa::avx2 && !p1::lane_avx2_available()) continue;
      std::fill(slope2.begin(), slope2.end(), 0.0f);
      p1::lane_search(f, L, d, 0, strips, tolerance, scratch, slope2.data(), nullptr, nullptr, isa);
      EXPECT_EQ(std::memcmp(slope.data(), slope2.data(), N * sizeof(float)), 0)
          << name << " k " << k << " without casters";
    }
    double worst_below = 0, worst_above = 0;
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) {
        const double exact = std::sin(truth::march_tri(f, i, j, sd.dx, sd.dy, 7, curvature));
        const double got = sin_of(slope[f.index(i, j)]);
        worst_below = std::max(worst_below, exact - got);
        worst_above = std::max(worst_above, got - exact);
      }
    EXPECT_LE(worst_above, 1e-5) << name << " azimuth " << spec.azimuths[std::size_t(k)];
    EXPECT_LE(worst_below, 1e-5 + tolerance) << name << " azimuth " << spec.azimuths[std::size_t(k)];
  }
}

TEST(LaneSearch, EveryTexelEqualsTheExactMarch) {
  for (const Case& c : cases()) check(c.field, c.name, 0.0f);
}

TEST(LaneSearch, WithinTheToleranceOfTheExactMarch) {
  for (const Case& c : cases()) check(c.field, c.name, 0.02f);
}

// A curvature large enough to change most horizons on fields this size (a point 40 texels away lowered by
// 3.2 units), exact and within a tolerance.
TEST(LaneSearch, CurvedEarthEqualsTheExactMarch) {
  for (const Case& c : cases()) {
    check(c.field, c.name, 0.0f, 0.002);
    check(c.field, c.name, 0.02f, 0.002);
  }
}

}  // namespace
}  // namespace hfbake
