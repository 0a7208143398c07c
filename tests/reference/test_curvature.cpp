// The Earth's curvature in relief's march and in the reference's curved rays, against closed forms and
// against each other:
// - a bowl z = r^2 / (2 R) (a sphere's heights seen from its tangent plane, turned up) baked with c = 1 /
//   (2 R): the lowering cancels the bowl, and from a receiver p0 every point is on the plane of gradient
//   p0 / R, so every horizon, up and down, is atan(p0 . u / R) (within the triangulation's chord error);
// - a wall of height H at distance D: the horizon is atan((H - c D^2) / D);
// - relief and the reference agree on rough fields, square and rectangular texels, curved;
// each also fails with the curvature left out.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/azimuth.hpp"
#include "field/procedural.hpp"
#include "methods/relief/radius_horizon.hpp"
#include "methods/relief/relief.hpp"
#include "reference/embree_field.hpp"
#include "reference/horizon_reference.hpp"
#include "reference/relief_reference.hpp"

namespace hfbake {
namespace {

// The bowl z = ((x - xc)^2 + (y - yc)^2) / (2 R) around the field's centre, texels dx x dy.
HeightField bowl(int n, double R, double dx, double dy) {
  HeightField f;
  f.width = f.height = n;
  f.texel_size = dx;
  if (dy != dx) f.texel_size_y = dy;
  f.z.resize(f.texel_count());
  const double c = 0.5 * (n - 1);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = (i - c) * dx, y = (j - c) * dy;
      f.z[f.index(i, j)] = float((x * x + y * y) / (2 * R));
    }
  return f;
}

// A flat field, 3 rows high, with a wall of height H from column `wall` on (texel 1).
HeightField wall(int width, int wall_at, double H) {
  HeightField f;
  f.width = width;
  f.height = 3;
  f.z.assign(f.texel_count(), 0.0f);
  for (int j = 0; j < 3; ++j)
    for (int i = wall_at; i < width; ++i) f.z[f.index(i, j)] = float(H);
  return f;
}

// The tangent of the bowl's lowered plane from texel (i, j) along the world direction (ux, uy).
double bowl_slope(const HeightField& f, int i, int j, double ux, double uy, double R) {
  const double c = 0.5 * (f.width - 1);
  return ((i - c) * f.dx() * ux + (j - c) * f.dy() * uy) / R;
}

TEST(Curvature, ReliefOnABowlSeesAPlane) {
  const double R = 4000;  // texel units; the bowl rises 0.24 over the 44-texel search radius
  for (auto [dx, dy] : {std::pair{1.0, 1.0}, std::pair{0.7, 1.1}}) {
    const HeightField f = bowl(81, R, dx, dy);
    const double radius = 30, c = 1 / (2 * R);
    double worst = 0, worst_flat = 0;
    for (int j : {20, 40, 57})
      for (int i : {25, 40, 61})
        for (int k = 0; k < 16; ++k) {
          double ux, uy;
          relief_direction(k, 16, false, {}, ux, uy);
          const double truth = std::atan(bowl_slope(f, i, j, ux, uy, R));
          const HorizonPair h = radius_horizon(f, i, j, ux, uy, radius, c);
          worst = std::max({worst, std::abs(std::atan(h.up) - truth), std::abs(std::atan(h.down) - truth)});
          const HorizonPair flat = radius_horizon(f, i, j, ux, uy, radius, 0);
          worst_flat = std::max(worst_flat, std::abs(std::atan(flat.up) - truth));
        }
    // The chords of the triangulation lie above the bowl by at most s^2 / (8 R) over a side s (the
    // diagonal's 2.6 texels here): 2.1e-4 texels, seen from at least half a texel: 4.2e-4 rad.
    EXPECT_LT(worst, 4.2e-4) << dx << " x " << dy;
    EXPECT_GT(worst_flat, 2e-3) << "the bowl without the curvature is no plane";
  }
}

TEST(Curvature, ReferenceOnABowlSeesAPlane) {
  const double R = 4000, c = 1 / (2 * R);
  for (auto [dx, dy] : {std::pair{1.0, 1.0}, std::pair{0.7, 1.1}}) {
    const HeightField f = bowl(61, R, dx, dy);
    const reference::EmbreeField geometry(f, reference::GeometryKind::grid, 1);
    const CurvedRays curved = curved_rays(f, c);
    const double lift = horizon_receiver_lift(f, geometry);
    double worst = 0;
    for (int j : {18, 30, 44})
      for (int i : {20, 30, 41})
        for (int k = 0; k < 8; ++k) {
          double ux, uy;
          relief_direction(k, 8, false, {}, ux, uy);
          const double truth = std::atan(bowl_slope(f, i, j, ux, uy, R));
          const Vec3 o = f.position(i, j) + Vec3{0, 0, lift};
          const double e = bisect_horizon(geometry, o, ux, uy, 30, 20.0, curved).elevation;
          worst = std::max(worst, std::abs(e - truth));
        }
    // relief's chord bound plus the chain's sagitta (1e-4 texel) seen from half a texel.
    EXPECT_LT(worst, 4.2e-4 + 2e-4 * std::min(dx, dy)) << dx << " x " << dy;
  }
}

TEST(Curvature, AWallBeyondTheCurve) {
  const double H = 20, c = 1e-4;
  const int D = 300;
  const HeightField f = wall(400, 50 + D, H);
  const double truth = std::atan((H - c * D * D) / D), flat = std::atan(H / D);
  ASSERT_GT(flat - truth, 0.02);
  const HorizonPair h = radius_horizon(f, 50, 1, 1, 0, 1000, c);
  EXPECT_NEAR(std::atan(h.up), truth, 1e-9);
  const reference::EmbreeField geometry(f, reference::GeometryKind::grid, 1);
  const CurvedRays curved = curved_rays(f, c);
  const Vec3 o = f.position(50, 1) + Vec3{0, 0, horizon_receiver_lift(f, geometry)};
  const TexelHorizon r =
      bisect_horizon(geometry, o, 1, 0, 40, std::numeric_limits<double>::infinity(), curved);
  // The chain's sagitta (1e-4 texel) and the receiver's lift over D.
  EXPECT_NEAR(r.elevation, truth, (1e-4 + horizon_receiver_lift(f, geometry)) / D);
  // The highest occluded ray grazes the wall's top beyond its edge.
  EXPECT_NEAR(r.distance, std::hypot(double(D), H - c * D * D), 1.0);
}

// relief and the reference on rough fields, curved strongly enough to move horizons by degrees.
TEST(Curvature, ReliefAndReferenceAgreeOnRoughFields) {
  ProceduralSpec p;
  p.kind = ProceduralKind::fractal;
  p.width = p.height = 32;
  p.seed = 11;
  for (auto [dy, c] :
       {std::pair{1.0, 2e-3}, std::pair{1.45, 2e-3}, std::pair{0.8, 0.0}, std::pair{1.0, 0.0}}) {
    HeightField f = make_procedural(p, 1.0, Wrap::clamp);
    if (dy != 1.0) f.texel_size_y = dy;
    ReliefReferenceSettings s;
    s.directions = 8;
    s.search_radius = 15;
    const ReliefHorizons ref = trace_relief_horizons(f, s, true, {}, 30, c);
    ReliefSettings rs;
    rs.directions = 8;
    rs.search_radius = 15;
    rs.layers = {"horizon_deg", "openness_negative"};
    double worst_up = 0, worst_down = 0, moved = 0;
    // Receivers off the border (along a clamp border the reference's rays graze its skirt).
    for (int j = 1; j + 1 < f.height; ++j)
      for (int i = 1; i + 1 < f.width; ++i)
        for (int k = 0; k < 8; ++k) {
          double ux, uy;
          relief_direction(k, 8, false, {}, ux, uy);
          const HorizonPair h = radius_horizon(f, i, j, ux, uy, s.search_radius, c);
          const std::size_t t = f.index(i, j) * 8 + std::size_t(k);
          if (!h.any) continue;
          worst_up = std::max(worst_up, std::abs(std::atan(h.up) - ref.up[t]));
          worst_down = std::max(worst_down, std::abs(std::atan(h.down) - ref.down[t]));
          const HorizonPair flat = radius_horizon(f, i, j, ux, uy, s.search_radius, 0);
          moved = std::max(moved, std::abs(std::atan(flat.up) - ref.up[t]));
        }
    // The reference's receiver is lifted by h (its float floor, 6e-5 here): a caster at distance d looks
    // h / d lower (d >= half a texel), and a facet rising from the receiver looks 2 sqrt(h c) lower (the
    // dip of a horizon seen from h); the chain's chords lie within c L (L their length) of the curved
    // ray's elevation (horizon_reference.hpp).
    const reference::EmbreeField geometry(f, reference::GeometryKind::grid, 1);
    const double h = horizon_receiver_lift(f, geometry), side = std::min(f.dx(), f.dy());
    const double tolerance = 2 * h / side + 2 * std::sqrt(h * c) + c * curved_rays(f, c).step + 1e-5;
    EXPECT_LT(worst_up, tolerance) << "dy " << dy << " c " << c;
    EXPECT_LT(worst_down, tolerance) << "dy " << dy << " c " << c;
    if (c > 0) {
      EXPECT_GT(moved, 5e-3) << "the curvature moves the reference's horizons";
    }
  }
}

}  // namespace
}  // namespace hfbake
