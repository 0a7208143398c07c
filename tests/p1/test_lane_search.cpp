// The lane search (methods/p1/lane_horizons.hpp) on its own against the exact march (p1_truth.hpp), every
// texel of non-square rough, stepped and smooth fields, in directions of every octant; its kernels (SSE2,
// AVX2, AVX-512), with and without casters, against each other, bit for bit; and its pruning against none.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "methods/p1/lane_horizons.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

struct Case {
  const char* name;
  HeightField field;
};

HeightField tilted(HeightField f, double gx, double gy, double z0) {
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) f.z[f.index(i, j)] += float(z0 + gx * i + gy * j);
  return f;
}

// f raised by z0, every texel east of `east` (a fraction of the width) set to the height below which
// `below` (a fraction) of the texels lie, and every texel lower than that raised to it.
HeightField flattened(HeightField f, double z0, double east, double below) {
  for (float& z : f.z) z += float(z0);
  std::vector<float> sorted = f.z;
  std::sort(sorted.begin(), sorted.end());
  const float level = sorted[std::size_t(below * double(sorted.size() - 1))];
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      float& z = f.z[f.index(i, j)];
      if (double(i) > east * f.width || z < level) z = level;
    }
  return f;
}

std::vector<Case> cases() {
  std::vector<Case> c;
  c.push_back({"rough 70", truth::rough_field(97, 61, 70, 0.6, 3, 16)});
  c.push_back({"terraces", truth::step_field(64, 90, 12, 25, 3, 9)});
  c.push_back({"fractal", truth::procedural(ProceduralKind::fractal, 83, 70, Wrap::clamp)});
  // A regional slope (the strips' trends, lane_kernel.inc).
  c.push_back({"tilted rough", tilted(truth::rough_field(90, 77, 70, 0.6, 5, 16), 0.5, -0.3, 0.0)});
  // Flat ground at one height, where every crossing ties (the searches that end where nothing ahead is
  // higher than the texel, lane_kernel.inc): a sea beside rough land, and a lake (the rough field cut off
  // below one height) far from 0.
  c.push_back({"coast", flattened(truth::rough_field(96, 70, 70, 0.6, 7, 16), 0.0, 0.45, 0.0)});
  c.push_back({"lake far from 0", flattened(truth::rough_field(81, 92, 70, 0.6, 9, 16), 1500.0, 2.0, 0.35)});
  // A sea with pebbles one float step above it: a ray over the sea that passes one has a horizon above 0.
  HeightField pebbles = flattened(truth::rough_field(88, 75, 70, 0.6, 4, 16), 1500.0, 0.3, 0.0);
  for (int t = 0; t < 40; ++t) {
    const std::size_t at = pebbles.index(40 + (t * 37) % 47, (t * 53) % 75);
    pebbles.z[at] = std::nextafter(pebbles.z[at], 1e30f);
  }
  c.push_back({"sea with pebbles", pebbles});
  return c;
}

// sin of the elevation of slope m (-inf: nothing behind, -1).
double sin_of(float m) {
  return m == -std::numeric_limits<float>::infinity() ? -1.0 : std::sin(std::atan(double(m)));
}

void check(const HeightField& f, const char* name, float tolerance, double curvature = 0,
           std::vector<double> azimuths = {0.3, 1.2, 2.0, 2.9, 3.7, 4.4, 5.1, 5.9, 0.0, 3.14159265358979 / 4,
                                           3.14159265358979}) {
  SweepSpec spec;
  spec.directions = 24;
  spec.azimuths = std::move(azimuths);
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
    p1::lane_search(L, d, 0, strips, tolerance, scratch, slope.data(), which.data(), nullptr,
                    p1::LaneIsa::sse2);
    for (const p1::LaneIsa isa : {p1::LaneIsa::avx2, p1::LaneIsa::avx512}) {
      if (!p1::lane_isa_available(isa)) continue;
      p1::lane_search(L, d, 0, strips, tolerance, scratch, slope2.data(), which2.data(), nullptr, isa);
      EXPECT_EQ(std::memcmp(slope.data(), slope2.data(), N * sizeof(float)), 0) << name << " k " << k;
      EXPECT_EQ(which, which2) << name << " k " << k;
    }
    // Without casters (which null; its own hints, once a block): the same slopes, on every kernel.
    for (const p1::LaneIsa isa : {p1::LaneIsa::sse2, p1::LaneIsa::avx2, p1::LaneIsa::avx512}) {
      if (!p1::lane_isa_available(isa)) continue;
      std::fill(slope2.begin(), slope2.end(), 0.0f);
      p1::lane_search(L, d, 0, strips, tolerance, scratch, slope2.data(), nullptr, nullptr, isa);
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

// Rays a hair off an axis or a diagonal (a light's or the sun's exact azimuth: 270.003 degrees) cross the
// field's other lines only far beyond it; their crossings read inside the layout and give the exact march's
// slopes, on small fields (a strip wider than the field) and on the cases'.
TEST(LaneSearch, RaysAHairOffAnAxisEqualTheExactMarch) {
  const double pi = 3.14159265358979;
  std::vector<double> azimuths;
  for (const double axis : {0.0, pi / 4, pi / 2, pi, 1.5 * pi, 1.75 * pi})
    for (const double off : {1e-4, 5.2e-5, 1e-5, 1e-6, 1e-7})
      for (const double sign : {-1.0, 1.0}) azimuths.push_back(std::fmod(axis + sign * off + 2 * pi, 2 * pi));
  std::vector<Case> all = cases();
  all.push_back({"rough 8x8", truth::rough_field(8, 8, 70, 0.6, 3, 4)});
  all.push_back({"rough 5x13", truth::rough_field(5, 13, 70, 0.6, 3, 4)});
  HeightField flat;
  flat.width = 8, flat.height = 8, flat.z.assign(64, 0.0f);
  all.push_back({"flat 8x8", flat});
  for (const Case& c : all) check(c.field, c.name, 0.0f, 0.0, azimuths);
}

// A curvature large enough to change most horizons on fields this size (a point 40 texels away lowered by
// 3.2 units), exact and within a tolerance.
TEST(LaneSearch, CurvedEarthEqualsTheExactMarch) {
  for (const Case& c : cases()) {
    check(c.field, c.name, 0.0f, 0.002);
    check(c.field, c.name, 0.02f, 0.002);
  }
}

// The pruning keeps the steepest crossing, bit for bit: the same search with every bound on the field
// raised out of reach (so no block is skipped and every crossing up to the ray's end is evaluated) gives
// the same slope at every texel whose ray has a crossing on the field.
TEST(LaneSearch, PruningKeepsTheSteepestCrossingBitForBit) {
  std::vector<Case> all_cases = cases();
  // Bare planes far from height 0 (their float heights are too coarse for the exact march's 1e-5): every
  // crossing of a ray has nearly the same slope, and only the slanted bounds' margins stand between a
  // skipped block and a crossing one rounding above the best.
  const HeightField flat = truth::procedural(ProceduralKind::flat, 101, 66, Wrap::clamp);
  all_cases.push_back({"plane", tilted(flat, 0.37, 0.61, 1500.0)});
  all_cases.push_back({"steep plane", tilted(flat, -2.3, 0.2, -40.0)});
  all_cases.push_back(
      {"tilted rough far from 0", tilted(truth::rough_field(90, 77, 70, 0.6, 5, 16), 0.9, -0.4, 800.0)});
  for (const Case& c : all_cases) {
    const HeightField& f = c.field;
    SweepSpec spec;
    spec.directions = 16;
    p1::LaneLayout layouts[2], open[2];
    for (int a = 0; a < 2; ++a) {
      layouts[a].build(f, a == 0), open[a].build(f, a == 0);
      for (std::size_t t = 0; t < open[a].size; ++t)
        if (open[a].window[t] > p1::kOffField) open[a].window[t] = 1e30f;
    }
    const std::size_t N = f.texel_count();
    std::vector<float> pruned(N), all(N);
    p1::LaneScratch scratch;
    for (int k = 0; k < spec.directions; ++k) {
      const SweepDirection sd = plan_direction(f, spec, k);
      const int a = std::fabs(sd.dx) >= std::fabs(sd.dy) ? 0 : 1;
      p1::LaneDirection d;
      d.build(f, layouts[a], sd.dx, sd.dy);
      const int strips = p1::lane_strip_count(layouts[a], d);
      p1::lane_search(layouts[a], d, 0, strips, 0.0f, scratch, pruned.data(), nullptr);
      p1::LaneDirection every = d;
      every.end_below = false;  // nor ended where nothing ahead is higher
      p1::lane_search(open[a], every, 0, strips, 0.0f, scratch, all.data(), nullptr);
      long on_field = 0, differ = 0;
      for (std::size_t t = 0; t < N; ++t) {
        if (!(all[t] > -1e20f)) continue;  // no crossing on the field (-inf, or only the padding's)
        ++on_field;
        differ += std::memcmp(&pruned[t], &all[t], sizeof(float)) != 0;
      }
      EXPECT_EQ(differ, 0) << c.name << " k " << k;
      EXPECT_GT(on_field, long(N) / 2) << c.name << " k " << k;
    }
  }
}

// A layout built again into the buffers of an earlier one (the other axis, or another field's: LaneReuse
// keeps one layout across a bake's direction blocks) holds what a fresh build holds: every height, window
// value and plane, nothing left from the earlier build. Fields wider than tall and taller than wide, so the
// buffers are reused both when they are large enough and when they must grow.
TEST(LaneSearch, ALayoutBuiltAgainEqualsAFreshOne) {
  const HeightField wide = tilted(truth::rough_field(97, 61, 70, 0.6, 3, 16), 0.4, -0.2, 300.0);
  const HeightField tall = truth::rough_field(58, 93, 70, 0.6, 8, 16);
  const HeightField level = tilted(truth::procedural(ProceduralKind::flat, 40, 70, Wrap::clamp), 0, 0, 5);
  // Sizes (major x padded minor): 93 x 186, then 97 x 189 (the buffers grow), then smaller ones.
  const std::vector<std::pair<const HeightField*, bool>> order = {
      {&tall, false}, {&wide, true}, {&wide, false}, {&tall, true}, {&level, false}, {&wide, true}};
  p1::LaneLayout reused;
  for (const auto& [f, xm] : order) {
    reused.build(*f, xm);
    p1::LaneLayout fresh;
    fresh.build(*f, xm);
    ASSERT_EQ(reused.size, fresh.size);
    EXPECT_GE(reused.capacity, reused.size);
    EXPECT_EQ(std::memcmp(reused.z.get(), fresh.z.get(), fresh.size * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(reused.window.get(), fresh.window.get(), fresh.size * sizeof(float)), 0);
    EXPECT_EQ(reused.tilt0, fresh.tilt0);
    EXPECT_EQ(reused.tilt_major, fresh.tilt_major);
    EXPECT_EQ(reused.tilt_minor, fresh.tilt_minor);
    EXPECT_EQ(reused.zabs, fresh.zabs);
    EXPECT_EQ(reused.plane_abs, fresh.plane_abs);
    EXPECT_EQ(reused.stride, fresh.stride);
    EXPECT_EQ(reused.nmajor, fresh.nmajor);
  }
}

// A field past 46341^2 texels: a crossing's offset in the lane layout (major index times the padded stride)
// exceeds 2^31, and every crossing still reads the texel its corner names. The directions' crossings are
// built from the field's shape alone (no heights are held).
TEST(LaneSearch, CrossingOffsetsOfALargeFieldAreExact) {
  HeightField f;
  f.width = 50000, f.height = 47000;
  p1::LaneLayout L;  // its shape only: build would hold 19 GB
  L.x_major = true, L.nmajor = f.width, L.nminor = f.height, L.stride = f.height + 2 * p1::kLanePad;
  SweepSpec spec;
  spec.directions = 8;
  for (int k : {0, 1}) {
    const SweepDirection sd = plan_direction(f, spec, k);
    ASSERT_GE(std::fabs(sd.dx), std::fabs(sd.dy));
    p1::LaneDirection d;
    d.build(f, L, sd.dx, sd.dy);
    std::ptrdiff_t largest = 0;
    for (std::size_t c = 0; c < d.crossings.size(); ++c) {
      const p1::LaneCrossing& x = d.crossings[c];
      // The corner's major index (the offset over the stride, rounded) is a column next to the crossing's.
      for (const std::ptrdiff_t a : {x.a, x.b}) {
        const double maj = std::floor(double(a + L.stride / 2) / double(L.stride));
        EXPECT_LE(std::fabs(maj - double(d.su) * double(d.major[c])), 1.5) << "k " << k << " crossing " << c;
        largest = std::max(largest, a < 0 ? -a : a);
      }
    }
    EXPECT_GT(largest, std::ptrdiff_t(1) << 31) << "k " << k;
  }
}

}  // namespace
}  // namespace hfbake
