#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <vector>

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
  for (int k = 0; k <= int(kLastProceduralKind); ++k) {
    ProceduralKind parsed;
    ASSERT_TRUE(parse_procedural_kind(procedural_kind_name(ProceduralKind(k)), parsed));
    EXPECT_EQ(int(parsed), k);
  }
  ProceduralKind unused;
  EXPECT_FALSE(parse_procedural_kind("fractall", unused));
}

TEST(Procedural, DeterministicBySeedAndSeedMatters) {
  for (auto kind :
       {ProceduralKind::fractal, ProceduralKind::bricks, ProceduralKind::blocks, ProceduralKind::terraces,
        ProceduralKind::craters, ProceduralKind::ridges, ProceduralKind::rough}) {
    const HeightField a = make(kind, 96, 80, 7), b = make(kind, 96, 80, 7), c = make(kind, 96, 80, 8);
    EXPECT_EQ(a.z, b.z) << procedural_kind_name(kind);
    EXPECT_NE(a.z, c.z) << procedural_kind_name(kind);
  }
}

TEST(Procedural, FieldsHaveReliefAndFiniteHeights) {
  for (auto kind :
       {ProceduralKind::fractal, ProceduralKind::bricks, ProceduralKind::sines, ProceduralKind::blocks,
        ProceduralKind::terraces, ProceduralKind::craters, ProceduralKind::ridges, ProceduralKind::rough}) {
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

TEST(Procedural, TerracesAreFlatStepsOfTheGivenHeight) {
  ProceduralSpec s;
  s.kind = ProceduralKind::terraces;
  s.width = s.height = 128;
  s.amplitude = 8;
  s.step = 3;
  const HeightField f = make_procedural(s, 2.0, Wrap::clamp);
  std::size_t flat = 0, steps = 0;
  for (int j = 0; j < 128; ++j)
    for (int i = 0; i + 1 < 128; ++i) {
      const double d = std::abs(double(f.z[f.index(i + 1, j)]) - f.z[f.index(i, j)]);
      if (d == 0) {
        ++flat;
        continue;
      }
      ++steps;
      // Every height is a whole number of steps (3 texels x texel size 2): so is every difference.
      EXPECT_NEAR(d / 6.0, std::round(d / 6.0), 1e-5);
    }
  EXPECT_GT(steps, 20u);        // there are cliffs ...
  EXPECT_GT(flat, 20 * steps);  // ... between wide flat treads
}

TEST(Procedural, CratersAreBowlsWithRaisedRims) {
  ProceduralSpec s;
  s.kind = ProceduralKind::craters;
  s.width = s.height = 200;
  s.feature_size = 12;
  s.amplitude = 5;
  const HeightField f = make_procedural(s, 1.0, Wrap::clamp);
  std::size_t below = 0, above = 0, ground = 0;
  float lo = INFINITY;
  for (float z : f.z) {
    below += z < -0.5f;
    above += z > 0.1f;
    ground += z == 0.0f;
    lo = std::min(lo, z);
  }
  // The deepest floor: d ((r/R)^2 - 1) + d/4 at the centre, d in [2.5, 5] for amplitude 5.
  EXPECT_LT(lo, -0.75f * 2.5f);
  EXPECT_GE(lo, -2 * 0.75f * 5.0f);  // at most two overlapping floors
  EXPECT_GT(below, f.z.size() / 20);
  EXPECT_GT(above, f.z.size() / 50);   // rims
  EXPECT_GT(ground, f.z.size() / 10);  // flat ground between craters
}

TEST(Procedural, RoughHasTheRequestedMedianSlopeAtAnySize) {
  for (int size : {96, 300}) {
    for (double angle : {60.0, 80.0}) {
      ProceduralSpec s;
      s.kind = ProceduralKind::rough;
      s.width = s.height = size;
      s.angle_deg = angle;
      s.seed = 11;
      const HeightField f = make_procedural(s, 1.0, Wrap::clamp);
      std::vector<double> d;
      for (int j = 0; j < size; ++j)
        for (int i = 0; i + 1 < size; ++i)
          d.push_back(std::abs(double(f.z[f.index(i + 1, j)]) - f.z[f.index(i, j)]));
      std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
      const double median_deg = std::atan(d[d.size() / 2]) * 180 / kPi;
      EXPECT_NEAR(median_deg, angle, 3.0) << size;
    }
  }
  ProceduralSpec s;
  s.kind = ProceduralKind::rough;
  s.width = s.height = 64;
  const HeightField a = make_procedural(s, 1.0, Wrap::clamp);
  s.angle_deg = 70;
  EXPECT_EQ(a.z, make_procedural(s, 1.0, Wrap::clamp).z);  // 70 degrees is rough's default
}

TEST(Procedural, RidgesHaveSharpCrests) {
  // (1 - |n|)^2 has a kink where the noise crosses zero: the largest second difference across a crest is
  // much larger than a smooth fractal's of the same amplitude.
  auto max_second_difference = [](const HeightField& f) {
    double m = 0;
    for (int j = 0; j < f.height; ++j)
      for (int i = 1; i + 1 < f.width; ++i)
        m = std::max(m, double(f.z[f.index(i - 1, j)] - 2 * f.z[f.index(i, j)] + f.z[f.index(i + 1, j)]));
    return m;
  };
  ProceduralSpec s;
  s.width = s.height = 128;
  s.kind = ProceduralKind::ridges;
  const HeightField r = make_procedural(s, 1.0, Wrap::clamp);
  s.kind = ProceduralKind::fractal;
  const HeightField f = make_procedural(s, 1.0, Wrap::clamp);
  // Crests are maxima: the most negative second difference (a crest's kink) dominates.
  auto min_second_difference = [](const HeightField& g) {
    double m = 0;
    for (int j = 0; j < g.height; ++j)
      for (int i = 1; i + 1 < g.width; ++i)
        m = std::min(m, double(g.z[g.index(i - 1, j)] - 2 * g.z[g.index(i, j)] + g.z[g.index(i + 1, j)]));
    return m;
  };
  EXPECT_LT(min_second_difference(r), 1.5 * min_second_difference(f));
  EXPECT_GT(max_second_difference(f), 0.0);
}

// The fBm kinds' definition, texel by texel, written out from procedural.cpp's header: splitmix64-hashed
// lattice values in [-1, 1), periodic in the octave's cell counts, quintic-weighted bilinear blend, octaves
// from width / feature cells doubling until a cell is below a texel, amplitudes halving. make_procedural
// walks rows and hashes each lattice value once per row; it must give these values to the bit.
namespace oracle {
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
double lattice(std::uint64_t seed, std::int64_t xi, std::int64_t yi, int octave, std::int64_t nx,
               std::int64_t ny) {
  xi = ((xi % nx) + nx) % nx;
  yi = ((yi % ny) + ny) % ny;
  const std::uint64_t h =
      mix(seed ^ mix(std::uint64_t(xi) ^ mix(std::uint64_t(yi) ^ mix(std::uint64_t(octave)))));
  return 2.0 * (double(h >> 11) * (1.0 / 9007199254740992.0)) - 1.0;
}
double quintic(double t) {
  return t * t * t * (t * (t * 6 - 15) + 10);
}
template <class Shape>
double fbm(const ProceduralSpec& s, double feature, double amp, int i, int j, int octaves, Shape shape) {
  const double u = double(i) / s.width, v = double(j) / s.height;
  std::int64_t nx = std::max<std::int64_t>(1, std::llround(s.width / feature));
  std::int64_t ny = std::max<std::int64_t>(1, std::llround(s.height / feature));
  double h = 0, a = amp;
  for (int o = 0; o < octaves && std::min(nx, ny) <= std::max(s.width, s.height); ++o) {
    const double x = u * double(nx), y = v * double(ny);
    const double fx = std::floor(x), fy = std::floor(y);
    const auto x0 = std::int64_t(fx), y0 = std::int64_t(fy);
    const double tx = quintic(x - fx), ty = quintic(y - fy);
    const double l00 = lattice(s.seed, x0, y0, o, nx, ny), l10 = lattice(s.seed, x0 + 1, y0, o, nx, ny);
    const double l01 = lattice(s.seed, x0, y0 + 1, o, nx, ny),
                 l11 = lattice(s.seed, x0 + 1, y0 + 1, o, nx, ny);
    h += a * shape((l00 + (l10 - l00) * tx) * (1 - ty) + (l01 + (l11 - l01) * tx) * ty);
    a *= 0.5;
    nx *= 2;
    ny *= 2;
  }
  return h;
}
// rough: bilinear (not periodic) lattice noise, cells of 64 texels down to 1, each octave 0.7 times the
// last, scaled so that the median forward difference over the 256x256 window at the origin is tan(angle).
double rough_noise(std::uint64_t seed, int i, int j) {
  double h = 0, a = 1;
  int o = 0;
  for (int cell = 64; cell >= 1; cell /= 2, a *= 0.7, ++o) {
    const double x = double(i) / cell, y = double(j) / cell;
    const auto x0 = std::int64_t(std::floor(x)), y0 = std::int64_t(std::floor(y));
    const double tx = x - double(x0), ty = y - double(y0);
    auto at = [&](std::int64_t p, std::int64_t q) {
      const std::uint64_t u =
          mix(seed ^ mix(std::uint64_t(p) ^ mix(std::uint64_t(q) ^ mix(std::uint64_t(100 + o)))));
      return 2.0 * (double(u >> 11) * (1.0 / 9007199254740992.0)) - 1.0;
    };
    const double l00 = at(x0, y0), l10 = at(x0 + 1, y0), l01 = at(x0, y0 + 1), l11 = at(x0 + 1, y0 + 1);
    h += a * ((l00 + (l10 - l00) * tx) * (1 - ty) + (l01 + (l11 - l01) * tx) * ty);
  }
  return h;
}
double rough_scale(std::uint64_t seed, double angle_deg) {
  std::vector<double> d;
  for (int j = 0; j < 256; ++j)
    for (int i = 0; i + 1 < 256; ++i)
      d.push_back(std::abs(rough_noise(seed, i + 1, j) - rough_noise(seed, i, j)));
  std::sort(d.begin(), d.end());
  return std::tan(angle_deg * 3.14159265358979323846 / 180) / d[d.size() / 2];
}
}  // namespace oracle

TEST(Procedural, RoughEqualsItsPerTexelDefinitionToTheBit) {
  for (const auto& [w, h, angle] : {std::tuple{120, 77, 70.0}, std::tuple{300, 5, 40.0}}) {
    ProceduralSpec s;
    s.kind = ProceduralKind::rough;
    s.width = w;
    s.height = h;
    s.seed = 3;
    s.angle_deg = angle;
    const HeightField f = make_procedural(s, 1.0, Wrap::clamp);
    const double scale = oracle::rough_scale(s.seed, angle);
    std::int64_t mismatches = 0;
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i)
        mismatches += f.z[f.index(i, j)] != float(scale * oracle::rough_noise(s.seed, i, j));
    EXPECT_EQ(mismatches, 0) << w << "x" << h;
  }
}

TEST(Procedural, FbmKindsEqualTheirPerTexelDefinitionToTheBit) {
  struct Case {
    ProceduralKind kind;
    int w, h;
    double feature, amplitude, step;
  };
  const Case cases[] = {
      {ProceduralKind::fractal, 97, 64, 0, 0, 0},    {ProceduralKind::fractal, 256, 256, 0, 0, 0},
      {ProceduralKind::fractal, 300, 7, 13.5, 4, 0}, {ProceduralKind::fractal, 3, 200, 0, 0, 0},
      {ProceduralKind::ridges, 130, 90, 0, 0, 0},    {ProceduralKind::ridges, 64, 64, 5, 2, 0},
      {ProceduralKind::terraces, 128, 100, 0, 0, 0}, {ProceduralKind::terraces, 80, 80, 30, 9, 1.5}};
  for (const Case& c : cases) {
    ProceduralSpec s;
    s.kind = c.kind;
    s.width = c.w;
    s.height = c.h;
    s.seed = 11;
    s.feature_size = c.feature;
    s.amplitude = c.amplitude;
    s.step = c.step;
    const double texel = 0.75;
    const HeightField f = make_procedural(s, texel, Wrap::clamp);
    const double size = std::min(c.w, c.h);
    double feature = c.feature > 0 ? c.feature : size / 2;
    double amp = c.amplitude > 0 ? c.amplitude : (c.kind == ProceduralKind::terraces ? size / 16 : size / 8);
    const double step = c.step > 0 ? c.step : amp / 3;
    std::int64_t mismatches = 0;
    for (int j = 0; j < c.h; ++j) {
      for (int i = 0; i < c.w; ++i) {
        double z = 0;
        if (c.kind == ProceduralKind::ridges)
          z = oracle::fbm(s, feature, amp, i, j, 16,
                          [](double n) { return (1 - std::abs(n)) * (1 - std::abs(n)); });
        else if (c.kind == ProceduralKind::terraces)
          z = step * std::floor(oracle::fbm(s, feature, amp, i, j, 3, [](double n) { return n; }) / step);
        else
          z = oracle::fbm(s, feature, amp, i, j, 16, [](double n) { return n; });
        mismatches += f.z[f.index(i, j)] != float(z * texel);
      }
    }
    EXPECT_EQ(mismatches, 0) << procedural_kind_name(c.kind) << " " << c.w << "x" << c.h;
  }
}

}  // namespace
}  // namespace hfbake
