// The reference's sh_visibility against closed forms: the projection of a hemisphere of any tilt is the
// hemisphere's zonal coefficients rotated to its pole (independent of the horizons' quadrature), traced on a
// tilted plane and at a cone's apex through Embree, and added to a reference only for methods that bake it.
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "core/azimuth.hpp"
#include "field/procedural.hpp"
#include "reference/sh_environment.hpp"
#include "reference/sh_visibility_reference.hpp"

namespace hfbake {
namespace {

constexpr double kDeg = kPi / 180.0;

// V = [w . n > 0]: its zonal coefficients about n are z_l = 2 pi int_0^1 Y_l0(t) dt = sqrt(pi),
// sqrt(3 pi) / 2, 0, -sqrt(7 pi) / 8, and rotated to n, c_lm = sqrt(4 pi / (2l + 1)) z_l Y_lm(n).
std::array<double, 16> hemisphere_closed_form(Vec3 n) {
  const double z[4] = {std::sqrt(kPi), std::sqrt(3 * kPi) / 2, 0, -std::sqrt(7 * kPi) / 8};
  const auto y = reference::sh_basis(n);
  std::array<double, 16> c{};
  for (int l = 0; l < 4; ++l)
    for (int m = -l; m <= l; ++m)
      c[l * (l + 1) + m] = std::sqrt(4 * kPi / (2 * l + 1)) * z[l] * y[l * (l + 1) + m];
  return c;
}

// The horizon of the plane through the receiver with unit normal n: tan h = -(n_x cos phi + n_y sin phi) /
// n_z.
std::vector<double> plane_horizons(Vec3 n, int K) {
  std::vector<double> h(K);
  for (int k = 0; k < K; ++k) {
    const double phi = 2 * kPi * k / K;
    h[k] = std::atan(-(n.x * std::cos(phi) + n.y * std::sin(phi)) / n.z);
  }
  return h;
}

Vec3 plane_normal(double slope_deg, double aspect_deg) {
  const double s = slope_deg * kDeg, a = aspect_deg * kDeg;
  return {std::sin(s) * std::cos(a), std::sin(s) * std::sin(a), std::cos(s)};
}

TEST(ShVisibilityReference, HemisphereOfAnyTiltIsTheRotatedZonalClosedForm) {
  // The periodic trapezoid rule in azimuth converges fast where the horizon is smooth in phi; a near-vertical
  // plane's horizon jumps by almost pi within a few degrees of azimuth, so it needs many more azimuths.
  for (auto [slope, aspect, K, tol] :
       {std::tuple{0.0, 0.0, 16, 1e-12}, std::tuple{35.0, 40.0, 64, 1e-8}, std::tuple{70.0, 200.0, 128, 1e-8},
        std::tuple{89.0, 301.0, 256, 5e-3}, std::tuple{89.0, 301.0, 2048, 2e-5}}) {
    const Vec3 n = plane_normal(slope, aspect);
    const auto c = sh_visibility_of_horizons(plane_horizons(n, K));
    const auto truth = hemisphere_closed_form(n);
    for (int i = 0; i < 16; ++i)
      EXPECT_NEAR(c[i], truth[i], tol) << "slope " << slope << " K " << K << " coefficient " << i;
  }
  // A constant horizon h over every azimuth (a pit): c_0 = 2 pi Y_0 (1 - sin h), the rest of band 0.
  const auto pit = sh_visibility_of_horizons(std::vector<double>(48, 20 * kDeg));
  EXPECT_NEAR(pit[0], 2 * kPi * 0.28209479177387814 * (1 - std::sin(20 * kDeg)), 1e-12);
  EXPECT_NEAR(pit[1], 0, 1e-12);
  EXPECT_NEAR(pit[3], 0, 1e-12);
}

TEST(ShVisibilityReference, TracedOnATiltedPlaneAndAtAConesApex) {
  ProceduralSpec p;
  p.kind = ProceduralKind::slope;
  p.width = p.height = 41;
  p.angle_deg = 35;
  p.aspect_deg = 40;  // faces 40 degrees: rises towards 220
  const HeightField plane = make_procedural(p, 1.0, Wrap::clamp);
  const std::vector<float> c = trace_reference_sh_visibility(plane, 64, {});
  const auto truth = hemisphere_closed_form(plane_normal(35, 40));
  // Interior texels: at the border the field ends and the outward horizon is the skirt's edge, not the plane.
  for (auto [i, j] : {std::pair{20, 20}, std::pair{5, 30}, std::pair{35, 8}})
    for (int n = 0; n < 16; ++n)
      EXPECT_NEAR(c[plane.index(i, j) * 16 + n], truth[n], 1e-5) << i << "," << j << " coefficient " << n;

  p.kind = ProceduralKind::cone;
  p.width = p.height = 9;
  p.angle_deg = 30;
  const HeightField cone = make_procedural(p, 1.0, Wrap::clamp);
  const std::vector<float> a = trace_reference_sh_visibility(cone, 64, {});
  // The apex sees its flanks fall at 30 degrees all around (the triangulated flanks sag by up to 1e-3 in
  // sin).
  const float* apex = a.data() + cone.index(4, 4) * 16;
  EXPECT_NEAR(apex[0], 2 * kPi * 0.28209479177387814 * 1.5, 2e-3);
  EXPECT_NEAR(apex[2], 0.4886025119029199 * kPi * (1 - 0.25),
              2e-3);  // int z over e > -30 deg: pi (1 - sin^2 h)
}

TEST(ShVisibilityReference, AddedForTheMethodsThatBakeIt) {
  ProceduralSpec p;
  p.kind = ProceduralKind::cone;
  p.width = p.height = 9;
  const HeightField f = make_procedural(p, 1.0, Wrap::clamp);
  LayerSet method;
  method.width = method.height = 9;
  method.add("ao", {"Y"});
  LayerSet reference;
  reference.width = reference.height = 9;
  add_reference_sh_visibility(f, {&method}, reference, {}, 16);
  EXPECT_FALSE(reference.find("sh_visibility"));  // nobody baked it
  std::vector<std::string> names;
  for (int i = 0; i < 16; ++i) {
    // Appended, not "c" + to_string(i): GCC 12's -Wrestrict misfires on that operator+ (GCC bug 105329).
    std::string name = "c";
    name += std::to_string(i);
    names.push_back(name);
  }
  method.add("sh_visibility", names);
  add_reference_sh_visibility(f, {&method}, reference, {}, 16);
  ASSERT_TRUE(reference.find("sh_visibility"));
  EXPECT_EQ(reference.find("sh_visibility")->channels, names);
  EXPECT_EQ(reference.find("sh_visibility")->data.size(), f.texel_count() * 16);
}

}  // namespace
}  // namespace hfbake
