#include <gtest/gtest.h>

#include <cmath>

#include "field/procedural.hpp"

namespace hfbake {
namespace {

HeightField make(ProceduralKind kind, int w, int h, std::uint64_t seed = 1) {
  ProceduralSpec s;
  s.kind = kind;
  s.width = w;
  s.height = h;
  s.seed = seed;
  return make_procedural(s, 1.0, Wrap::clamp);
}

TEST(Procedural, KindsRoundTripByName) {
  for (int k = 0; k <= int(ProceduralKind::cone); ++k) {
    ProceduralKind parsed;
    ASSERT_TRUE(parse_procedural_kind(procedural_kind_name(ProceduralKind(k)), parsed));
    EXPECT_EQ(int(parsed), k);
  }
  ProceduralKind unused;
  EXPECT_FALSE(parse_procedural_kind("fractall", unused));
}

TEST(Procedural, DeterministicBySeedAndSeedMatters) {
  for (auto kind : {ProceduralKind::fractal, ProceduralKind::bricks, ProceduralKind::blocks}) {
    const HeightField a = make(kind, 96, 80, 7), b = make(kind, 96, 80, 7), c = make(kind, 96, 80, 8);
    EXPECT_EQ(a.z, b.z) << procedural_kind_name(kind);
    EXPECT_NE(a.z, c.z) << procedural_kind_name(kind);
  }
}

TEST(Procedural, FieldsHaveReliefAndFiniteHeights) {
  for (auto kind :
       {ProceduralKind::fractal, ProceduralKind::bricks, ProceduralKind::sines, ProceduralKind::blocks}) {
    const HeightField f = make(kind, 128, 128);
    float lo = INFINITY, hi = -INFINITY;
    for (float z : f.z) {
      ASSERT_TRUE(std::isfinite(z));
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
    EXPECT_GT(hi - lo, 2.0f) << procedural_kind_name(kind);
  }
}

TEST(Procedural, FractalTilesSeamlessly) {
  // The fBm lattice is periodic over the field: the step across the wrap seam must look like an
  // interior step, not a cliff.
  const HeightField f = make(ProceduralKind::fractal, 128, 128, 3);
  double seam = 0, interior = 0;
  for (int j = 0; j < 128; ++j) {
    seam = std::max(seam, double(std::abs(f.z[f.index(127, j)] - f.z[f.index(0, j)])));
    for (int i = 0; i + 1 < 128; ++i)
      interior = std::max(interior, double(std::abs(f.z[f.index(i + 1, j)] - f.z[f.index(i, j)])));
  }
  EXPECT_LE(seam, interior);
}

TEST(Procedural, AnalyticShapes) {
  ProceduralSpec s;
  s.width = s.height = 33;
  s.kind = ProceduralKind::trench;
  s.angle_deg = 45;
  HeightField t = make_procedural(s, 2.0, Wrap::clamp);
  EXPECT_FLOAT_EQ(t.z[t.index(16, 5)], 0.0f);      // floor at the center column
  EXPECT_FLOAT_EQ(t.z[t.index(20, 5)], 4 * 2.0f);  // tan 45 * 4 texels * texel size 2
  s.kind = ProceduralKind::pit;
  s.radius = 8;
  s.depth = 4;
  HeightField p = make_procedural(s, 1.0, Wrap::clamp);
  EXPECT_FLOAT_EQ(p.z[p.index(16, 16)], -4.0f);
  EXPECT_FLOAT_EQ(p.z[p.index(16, 25)], 0.0f);
  s.kind = ProceduralKind::cone;
  s.angle_deg = 30;
  HeightField c = make_procedural(s, 1.0, Wrap::clamp);
  EXPECT_FLOAT_EQ(c.z[c.index(16, 16)], 0.0f);
  EXPECT_NEAR(c.z[c.index(26, 16)], -10 * std::tan(kPi / 6), 1e-5);
}

}  // namespace
}  // namespace hfbake
