// field/subdivide.hpp against the triangulated surface computed here from first principles: each fine
// texel's height is the height of the plane through the three corners of the coarse triangle under it (the
// split from (i+1, j) to (i, j+1), docs/contract.md), on a plane and on random fields, clamp and repeat.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "field/subdivide.hpp"

namespace hfbake {
namespace {

HeightField random_field(int w, int h, Wrap wrap, double dx, unsigned seed) {
  HeightField f;
  f.width = w, f.height = h, f.wrap = wrap, f.texel_size = dx;
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 2.0f);
  f.z.resize(f.texel_count());
  for (float& z : f.z) z = noise(rng);
  return f;
}

// The height at world (x, y) of the plane through three world points.
double plane_through(const Vec3& a, const Vec3& b, const Vec3& c, double x, double y) {
  const Vec3 n = cross(b - a, c - a);
  return a.z - (n.x * (x - a.x) + n.y * (y - a.y)) / n.z;
}

// The coarse triangulated surface at world (x, y): the quad's corners as world points (wrapped heights on a
// repeat field), the triangle under the point by which side of the line from (i+1, j) to (i, j+1) it is on.
double surface_at(const HeightField& f, double x, double y) {
  int i = int(std::floor(x / f.dx() + 1e-9)), j = int(std::floor(y / f.dy() + 1e-9));
  if (f.wrap == Wrap::clamp) i = std::min(i, f.width - 2), j = std::min(j, f.height - 2);
  auto P = [&](int a, int b) { return Vec3{a * f.dx(), b * f.dy(), double(f.at(a, b))}; };
  const double u = x / f.dx() - i, v = y / f.dy() - j;
  if (u + v <= 1 + 1e-12) return plane_through(P(i, j), P(i + 1, j), P(i, j + 1), x, y);
  return plane_through(P(i + 1, j + 1), P(i, j + 1), P(i + 1, j), x, y);
}

void expect_on_the_surface(const HeightField& coarse, int s) {
  const HeightField fine = subdivided_field(coarse, s);
  const bool repeat = coarse.wrap == Wrap::repeat;
  ASSERT_EQ(fine.width, repeat ? coarse.width * s : (coarse.width - 1) * s + 1);
  ASSERT_EQ(fine.height, repeat ? coarse.height * s : (coarse.height - 1) * s + 1);
  EXPECT_DOUBLE_EQ(fine.dx(), coarse.dx() / s);
  EXPECT_DOUBLE_EQ(fine.dy(), coarse.dy() / s);
  EXPECT_EQ(fine.wrap, coarse.wrap);
  for (int J = 0; J < fine.height; ++J)
    for (int I = 0; I < fine.width; ++I) {
      const double want = surface_at(coarse, I * fine.dx(), J * fine.dy());
      ASSERT_NEAR(fine.z[fine.index(I, J)], want, 2e-6 * (1 + std::fabs(want)))
          << "fine texel " << I << ", " << J << " of s = " << s;
    }
  for (int j = 0; j < coarse.height; ++j)  // the original texels exactly
    for (int i = 0; i < coarse.width; ++i)
      ASSERT_EQ(fine.z[fine_index_of(fine, s, i, j)], coarse.z[coarse.index(i, j)]);
}

TEST(Subdivide, APlaneStaysThePlane) {
  HeightField f;
  f.width = 9, f.height = 6, f.texel_size = 0.5;
  f.z.resize(f.texel_count());
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) f.z[f.index(i, j)] = float(3 + 0.7 * i * 0.5 - 1.3 * j * 0.5);
  for (int s : {2, 4}) {
    const HeightField fine = subdivided_field(f, s);
    for (int J = 0; J < fine.height; ++J)
      for (int I = 0; I < fine.width; ++I)
        ASSERT_NEAR(fine.z[fine.index(I, J)], 3 + 0.7 * I * fine.dx() - 1.3 * J * fine.dy(), 1e-5);
    expect_on_the_surface(f, s);
  }
}

TEST(Subdivide, RandomFieldsAreTheirTriangulatedSurface) {
  for (int s : {2, 4}) {
    expect_on_the_surface(random_field(7, 5, Wrap::clamp, 1.0, 1), s);
    expect_on_the_surface(random_field(6, 8, Wrap::clamp, 2.5, 2), s);
    expect_on_the_surface(random_field(5, 4, Wrap::repeat, 1.0, 3), s);  // across the period's seam too
  }
}

// The fine triangulation (the same split) lies on the coarse facets: at any point the two surfaces agree.
TEST(Subdivide, TheFineTriangulationIsTheCoarseSurface) {
  const HeightField coarse = random_field(9, 7, Wrap::clamp, 1.0, 4);
  for (int s : {2, 4}) {
    const HeightField fine = subdivided_field(coarse, s);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> x(0, coarse.width - 1), y(0, coarse.height - 1);
    for (int n = 0; n < 2000; ++n) {
      const double px = x(rng), py = y(rng);
      ASSERT_NEAR(fine.triangle_height(px * s, py * s), surface_at(coarse, px, py), 1e-5)
          << "at " << px << ", " << py << ", s = " << s;
    }
  }
}

// Albedo and emission: interpolated with the same weights, so each fine value is the coarse facet's.
TEST(Subdivide, ValuesAreInterpolatedOverTheCoarseFacets) {
  const HeightField coarse = random_field(6, 5, Wrap::clamp, 1.0, 6);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<Rgb> values(coarse.texel_count());
  for (Rgb& v : values) v = {u(rng), u(rng), u(rng)};
  // The green channel as heights: the same surface construction as above.
  HeightField g = coarse;
  for (std::size_t t = 0; t < values.size(); ++t) g.z[t] = values[t].g;
  for (int s : {2, 4}) {
    const std::vector<Rgb> fine = subdivided_values(coarse, s, values);
    const FieldShape shape = subdivided_shape(coarse, s);
    ASSERT_EQ(fine.size(), std::size_t(shape.width) * std::size_t(shape.height));
    for (int J = 0; J < shape.height; ++J)
      for (int I = 0; I < shape.width; ++I)
        ASSERT_NEAR(fine[std::size_t(J) * std::size_t(shape.width) + std::size_t(I)].g,
                    surface_at(g, double(I) / s, double(J) / s), 1e-6);
  }
}

}  // namespace
}  // namespace hfbake
