// hbao on the reference's triangulated surface (surface "triangles", segment estimator) against independent
// slice integrals of the same surface (ao_truth.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "ao_scenes.hpp"
#include "ao_truth.hpp"
#include "field/procedural.hpp"
#include "methods/ao/farfield.hpp"
#include "methods/ao/hbao.hpp"

namespace hfbake {
namespace {

struct Case {
  HeightField field;
  std::vector<Vec3f> normals;
};

Case fractal_case() {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = spec.height = 40;
  spec.seed = 3;
  Case c;
  c.field = make_procedural(spec, 1.0, Wrap::clamp);
  c.normals = compute_normals(c.field);
  return c;
}

double independent(const Case& c, int i, int j, int K, const Falloff& rho, double reach, bool step) {
  return ao_truth::occluded(c.field, c.normals[c.field.index(i, j)].d(), i, j, K, rho, reach, step);
}

HbaoSettings triangles(int K, const Falloff& rho, double reach) {
  HbaoSettings s;
  s.falloff = rho;
  s.directions = uniform_directions(K);
  s.reach = reach;
  s.surface = MarchSurface::triangles;
  s.estimator = HorizonEstimator::segment;
  return s;
}

TEST(HbaoTriangles, StepFalloffIsTheExactSliceIntegral) {
  const Case c = fractal_case();
  Falloff rho;
  rho.kind = FalloffKind::step;
  rho.radius = 8;
  const HbaoSettings s = triangles(16, rho, 8);
  double worst = 0, mean = 0;
  int count = 0;
  for (int j = 10; j < 30; j += 3)
    for (int i = 10; i < 30; i += 3) {
      const double got = hbao_texel(c.field, c.normals[c.field.index(i, j)].d(), i, j, s).occluded;
      const double want = independent(c, i, j, 16, rho, 8, true);
      worst = std::max(worst, std::abs(got - want));
      mean += want, ++count;
    }
  EXPECT_GT(mean / count, 0.02);  // the field occludes: the comparison is not 0 = 0
  EXPECT_LT(worst, 1e-7);
}

TEST(HbaoTriangles, SmoothFalloffsAgainstDenseRays) {
  const Case c = fractal_case();
  for (FalloffKind kind : {FalloffKind::linear, FalloffKind::exponential}) {
    Falloff rho;
    rho.kind = kind;
    rho.radius = 4;
    const double reach = 10;  // exponential: the slice integrals of both sides end here
    const HbaoSettings s = triangles(8, rho, reach);
    for (int j = 14; j < 26; j += 5)
      for (int i = 14; i < 26; i += 5) {
        const double got = hbao_texel(c.field, c.normals[c.field.index(i, j)].d(), i, j, s).occluded;
        const double want = independent(c, i, j, 8, rho, reach, false);
        EXPECT_NEAR(got, want, 2e-4) << "falloff " << int(kind) << " texel " << i << ", " << j;
      }
  }
}

TEST(HbaoTriangles, PlanesAreOpenAndTheStepOptionMoves) {
  // A tilted plane is its own triangulation: nothing above the tangent plane.
  const HeightField plane = test::make_plane(33, 0.4, -0.7);
  const std::vector<Vec3f> nrm = compute_normals(plane);
  Falloff rho;
  rho.kind = FalloffKind::step;
  rho.radius = 10;
  const HbaoSettings s = triangles(16, rho, 10);
  EXPECT_NEAR(hbao_texel(plane, nrm[plane.index(16, 16)].d(), 16, 16, s).occluded, 0.0, 1e-9);
  // On the fractal, one-texel bilinear steps miss peaks between samples: less occluded than the exact
  // triangulated profile on average.
  const Case c = fractal_case();
  HbaoSettings bil = s;
  bil.surface = MarchSurface::bilinear;
  bil.estimator = HorizonEstimator::slab;
  double exact = 0, coarse = 0;
  for (int j = 10; j < 30; ++j)
    for (int i = 10; i < 30; ++i) {
      const Vec3 n = c.normals[c.field.index(i, j)].d();
      exact += hbao_texel(c.field, n, i, j, s).occluded;
      coarse += hbao_texel(c.field, n, i, j, bil).occluded;
    }
  EXPECT_LT(coarse, exact);
}

// farfield's near field on the triangles: with R = 8 inside the near field (1.5 B0 = 12 texels) it is the
// same exact slice integral as hbao's.
TEST(HbaoTriangles, FarfieldNearFieldIsTheSameIntegral) {
  const Case c = fractal_case();
  Falloff rho;
  rho.kind = FalloffKind::step;
  rho.radius = 8;
  FarfieldOptions o;
  o.directions = 16;
  o.rho = rho;
  o.triangles = true;
  std::vector<std::size_t> texels;
  for (int j = 10; j < 30; j += 4)
    for (int i = 10; i < 30; i += 4) texels.push_back(c.field.index(i, j));
  const std::vector<double> ff = farfield_occlusion_at(c.field, c.normals, o, texels);
  const HbaoSettings s = triangles(16, rho, 8);
  for (std::size_t t = 0; t < texels.size(); ++t) {
    const int i = int(texels[t] % 40), j = int(texels[t] / 40);
    EXPECT_NEAR(ff[t], hbao_texel(c.field, c.normals[texels[t]].d(), i, j, s).occluded, 1e-9);
  }
}

}  // namespace
}  // namespace hfbake
