// The point horizon (terrain/point_horizon) against an independent exact march over the triangulated
// surface (every column, row and diagonal crossing enumerated by brute force here, heights from
// tests/p1/p1_truth.hpp's own triangle rule, curved pieces maximised by ternary search), and against closed
// forms: a step, a conical pit (the quad split shows on one diagonal), a tower beyond the curved Earth, the
// dip of a flat Earth's horizon and a sphere's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "../p1/p1_truth.hpp"
#include "terrain/horizon_plot.hpp"
#include "terrain/point_horizon.hpp"

namespace hfbake {
namespace {

constexpr double kDeg = 180 / kPi;

HeightField flat_field(int w, int h, double z = 0) {
  HeightField f;
  f.width = w, f.height = h, f.wrap = Wrap::clamp;
  f.z.assign(f.texel_count(), float(z));
  return f;
}

// The exact horizon by brute force: every crossing of the ray (x0, y0) + d (vx, vy) with a column, a row
// or a diagonal of the field listed and sorted; each piece between two consecutive crossings maximised by
// its end points and, for a curved Earth, a ternary search (the slope is concave on a piece that can have an
// inner maximum) kept 1e-6 of the piece away from its ends: the truth is within 5e-6 degrees. Returns the
// elevation (degrees) and the caster's distance; -1e9 when there is none.
struct Truth {
  double elevation_deg = -1e9, distance = 0;
};
Truth brute_force(const HeightField& f, double x0, double y0, double vx, double vy, double z0, double c) {
  std::vector<double> ds;
  auto end = [&](double o, double v, int n) { return v > 0 ? (n - 1 - o) / v : v < 0 ? o / -v : 1e300; };
  const double d_end = std::min(end(x0, vx, f.width), end(y0, vy, f.height));
  auto add = [&](double o, double v, int lo, int hi) {
    if (std::fabs(v) < 1e-14) return;
    for (int n = lo; n <= hi; ++n) {
      const double d = (n - o) / v;
      if (d > 1e-12 && d < d_end) ds.push_back(d);
    }
  };
  add(x0, vx, 0, f.width - 1);
  add(y0, vy, 0, f.height - 1);
  add(x0 + y0, vx + vy, 0, f.width + f.height - 2);
  ds.push_back(d_end);
  std::sort(ds.begin(), ds.end());
  auto z_at = [&](double d) {
    const double x = std::clamp(x0 + d * vx, 0.0, f.width - 1.0),
                 y = std::clamp(y0 + d * vy, 0.0, f.height - 1.0);
    return truth::tri_height(f, x, y);
  };
  auto slope = [&](double d) { return (z_at(d) - c * d * d - z0) / d; };
  double best = -1e300, best_d = 0;
  auto take = [&](double d) {
    const double s = slope(d);
    if (s > best) best = s, best_d = d;
  };
  double prev = 0;
  for (const double d : ds) {
    take(d);
    if (c > 0) {  // ternary search on (prev, d), where the piece is a line of the surface
      double lo = prev + 1e-6 * (d - prev), hi = d - 1e-6 * (d - prev);  // (z - z0) / d rounds near 0
      for (int it = 0; it < 200 && hi - lo > 1e-12 * d; ++it) {
        const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
        if (slope(m1) < slope(m2))
          lo = m1;
        else
          hi = m2;
      }
      if (lo > 0) take(0.5 * (lo + hi));
    }
    prev = d;
  }
  Truth t;
  if (best > -1e300) t.elevation_deg = std::atan(best) * kDeg, t.distance = best_d;
  return t;
}

// Off-centre points on a rough field, square and non-square texels, an observer above the surface, flat
// and curved Earth (an exaggerated curvature so that it matters over 64 texels).
TEST(PointHorizon, EqualsAnIndependentExactMarch) {
  const HeightField f = truth::rough_field(64, 48, 60, 0.6, 11, 16);
  const double points[][2] = {{20.3, 17.8}, {31.0, 24.0}, {5.25, 40.5}, {60.9, 2.1}, {33.5, 0.0}};
  const GroundFrame frames[] = {{1, -1}, {2.5, -1.5}, {-0.7, 0.9}};
  int checked = 0;
  for (const auto& p : points)
    for (const GroundFrame& frame : frames)
      for (const double h : {0.0, 1.7})
        for (const double radius : {0.0, 40.0}) {
          PointHorizonQuery q;
          q.x = p[0], q.y = p[1], q.observer_height = h, q.directions = 37, q.frame = frame;
          if (radius > 0) q.curvature = EarthCurvature{radius, radius * 1.3, 0.13};
          const std::vector<HorizonRay> rays = point_horizon(f, q);
          ASSERT_EQ(rays.size(), 37u);
          const double z0 = truth::tri_height(f, p[0], p[1]) + h;
          for (const HorizonRay& r : rays) {
            const double a = r.azimuth_deg / kDeg;
            const double vx = std::sin(a) / frame.east_per_x, vy = std::cos(a) / frame.north_per_y;
            const double c = q.curvature ? q.curvature->coefficient(a) : 0;
            const Truth t = brute_force(f, p[0], p[1], vx, vy, z0, c);
            if (t.elevation_deg < -1e8) {
              EXPECT_FALSE(r.found);
              continue;
            }
            ASSERT_TRUE(r.found) << r.azimuth_deg;
            EXPECT_NEAR(r.elevation_deg, t.elevation_deg, 5e-6)
                << p[0] << "," << p[1] << " A " << r.azimuth_deg << " frame " << frame.east_per_x << " h "
                << h << " R " << radius;
            // The caster itself is only defined where the maximum is unique: check its elevation instead.
            const double zc = truth::tri_height(f, std::clamp(r.x, 0.0, 63.0), std::clamp(r.y, 0.0, 47.0));
            EXPECT_NEAR(zc, r.z, 1e-4);
            if (r.distance > 0)
              EXPECT_NEAR(std::atan((r.z - c * r.distance * r.distance - z0) / r.distance) * kDeg,
                          r.elevation_deg, 1e-9);
            else  // an eye on the surface, its own facet's slope (the limit d -> 0)
              EXPECT_TRUE(h == 0 && radius > 0 && r.x == p[0] && r.y == p[1]);
            ++checked;
          }
        }
  EXPECT_GT(checked, 1900);  // of 2220: the rays off the border row find nothing
}

// Square texels, flat Earth, on the surface: p1's exact march (tests/p1/p1_truth.hpp march_from).
TEST(PointHorizon, AgreesWithP1sTruthMarch) {
  const HeightField f = truth::random_field(40, 40, 5, 3, Wrap::clamp);
  PointHorizonQuery q;
  q.x = 17.37, q.y = 22.61, q.directions = 64;
  for (const HorizonRay& r : point_horizon(f, q)) {
    const double a = r.azimuth_deg / kDeg;
    double dz = 0, run = 0;
    ASSERT_TRUE(truth::march_from(f, q.x, q.y, std::sin(a), -std::cos(a), 7, 0, &dz, &run));
    EXPECT_NEAR(r.elevation_deg, std::atan2(dz, run) * kDeg, 1e-9) << r.azimuth_deg;
  }
}

// A step of height s along a column: looking east from the low side, the caster is the step's top edge, the
// first column at full height, d = i0 - x0 away: atan((s - H) / d).
TEST(PointHorizon, StepClosedForm) {
  HeightField f = flat_field(50, 20);
  for (int j = 0; j < 20; ++j)
    for (int i = 30; i < 50; ++i) f.z[f.index(i, j)] = 7;
  PointHorizonQuery q;
  q.x = 12.4, q.y = 9.3, q.directions = 4, q.frame = {2.0, -2.0}, q.observer_height = 1.5;
  const std::vector<HorizonRay> rays = point_horizon(f, q);
  const HorizonRay& east = rays[1];
  ASSERT_TRUE(east.found);
  EXPECT_NEAR(east.elevation_deg, std::atan((7 - 1.5) / ((30 - 12.4) * 2)) * kDeg, 1e-10);
  EXPECT_NEAR(east.distance, (30 - 12.4) * 2, 1e-9);
  EXPECT_NEAR(east.x, 30, 1e-9);
  // West and north and south: a flat surface 1.5 below the eye; the farthest point is the highest.
  EXPECT_NEAR(rays[3].elevation_deg, std::atan(-1.5 / (12.4 * 2)) * kDeg, 1e-10);
  EXPECT_NEAR(rays[0].elevation_deg, std::atan(-1.5 / (9.3 * 2)) * kDeg, 1e-10);
  EXPECT_NEAR(rays[2].elevation_deg, std::atan(-1.5 / ((19 - 9.3) * 2)) * kDeg, 1e-10);
}

// A conical pit z = g r around texel (20, 20), seen from its bottom. Along the axes and the diagonal that
// the quads are split along (north-east, south-west) every crossing is a vertex or on a triangulation edge
// between two: atan(g). Across the split (north-west, south-east) the first diagonal crossing lies between
// two texels r = 1 from the bottom, at height g, while it is sqrt(1/2) away: atan(g sqrt 2).
TEST(PointHorizon, PitClosedFormShowsTheQuadSplit) {
  HeightField f = flat_field(41, 41);
  const double g = 0.3;
  for (int j = 0; j < 41; ++j)
    for (int i = 0; i < 41; ++i) f.z[f.index(i, j)] = float(g * std::hypot(i - 20, j - 20));
  PointHorizonQuery q;
  q.x = 20, q.y = 20, q.directions = 8;
  const std::vector<HorizonRay> rays = point_horizon(f, q);
  for (const int k : {0, 1, 2, 4, 5, 6}) EXPECT_NEAR(rays[k].elevation_deg, std::atan(g) * kDeg, 1e-5) << k;
  for (const int k : {3, 7}) {  // 135° (south-east: +x +y) and 315°
    EXPECT_NEAR(rays[k].elevation_deg, std::atan(g * std::sqrt(2.0)) * kDeg, 1e-5) << k;
    EXPECT_NEAR(rays[k].distance, std::sqrt(0.5), 1e-9) << k;
  }
}

// Curvature, closed forms. A flat Earth of heights 0 seen from H above it: the point at distance d appears
// at slope (-H - c d^2) / d, steepest at d* = sqrt(H / c) (inside a piece: the in-piece maximum), where it is
// -2 sqrt(H c). A tower of height T at distance D east: atan((T - c D^2) / D) with c = (1 - k) / (2 N) east
// and (1 - k) / (2 M) north (Euler's radius).
TEST(PointHorizon, CurvatureClosedForms) {
  const double texel = 250, H = 120, k = 0.13;
  const Ellipsoid wgs84{6378137.0, 6356752.314245};
  const EarthCurvature earth = EarthCurvature::at(wgs84, 46 * kPi / 180, k);
  HeightField f = flat_field(401, 401);
  PointHorizonQuery q;
  q.x = 200, q.y = 200, q.directions = 4, q.frame = {texel, -texel}, q.observer_height = H,
  q.curvature = earth;
  std::vector<HorizonRay> rays = point_horizon(f, q);
  for (int a = 0; a < 4; ++a) {
    const double c = earth.coefficient(a * kPi / 2);
    EXPECT_NEAR(rays[a].elevation_deg, std::atan(-2 * std::sqrt(H * c)) * kDeg, 1e-9) << a;
    EXPECT_NEAR(rays[a].distance, std::sqrt(H / c), 1e-6) << a;
  }
  EXPECT_NEAR(earth.radius(0), wgs84.meridian_radius(46 * kPi / 180), 1e-6);
  EXPECT_NEAR(earth.radius(kPi / 2), wgs84.prime_vertical_radius(46 * kPi / 180), 1e-6);
  // The tower, 30 km east and 40 km north, 400 m: above the dip.
  f.z[f.index(320, 200)] = 400;
  f.z[f.index(200, 40)] = 400;
  q.observer_height = 0;
  rays = point_horizon(f, q);
  EXPECT_NEAR(rays[1].elevation_deg, std::atan((400 - earth.coefficient(kPi / 2) * 3e4 * 3e4) / 3e4) * kDeg,
              1e-9);
  EXPECT_NEAR(rays[0].elevation_deg, std::atan((400 - earth.coefficient(0) * 4e4 * 4e4) / 4e4) * kDeg, 1e-9);
  EXPECT_NEAR(rays[1].x, 320, 1e-9);
  // The drop itself: 30 km east lowers a point by 61.5 m (k = 0.13, N at 46°).
  EXPECT_NEAR(earth.coefficient(kPi / 2) * 3e4 * 3e4, 9e8 * 0.87 / (2 * 6388838.3), 0.05);
}

// A sphere-cap DEM, z = sqrt(R^2 - r^2) - R around the point (the Earth's surface in its tangent plane),
// on a flat Earth gives the horizon the curvature term gives a flat DEM (up to the cap's triangulation,
// chords t^2 / (8 R) below it), and both are the exact dip of a sphere seen from H, acos(R / (R + H)),
// within the parabolic approximation: the term d^2 / (2 R) against R - sqrt(R^2 - d^2) differs by
// d^4 / (8 R^3), here under 1e-4 degrees.
TEST(PointHorizon, SphereCapMatchesTheCurvatureTerm) {
  const double R = 6371008.8, texel = 100, H = 200;
  const int n = 1201;  // 120 km across: the dip is at sqrt(2 R H) = 50.5 km
  HeightField cap = flat_field(n, n), flat = flat_field(n, n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double r = texel * std::hypot(i - 600, j - 600);
      cap.z[cap.index(i, j)] = float(std::sqrt(R * R - r * r) - R);
    }
  PointHorizonQuery q;
  q.x = 600, q.y = 600, q.directions = 8, q.frame = {texel, -texel}, q.observer_height = H;
  const std::vector<HorizonRay> on_cap = point_horizon(cap, q);
  q.curvature = EarthCurvature{R, R, 0.0};
  const std::vector<HorizonRay> curved = point_horizon(flat, q);
  const double dip = -std::acos(R / (R + H)) * kDeg;
  for (int k = 0; k < 8; ++k) {
    EXPECT_NEAR(curved[k].elevation_deg, dip, 1e-4) << k;
    // float heights of the cap (200 m to ~0.01 m) and its chords: 2e-4 degrees
    EXPECT_NEAR(on_cap[k].elevation_deg, curved[k].elevation_deg, 2e-4) << k;
  }
}

TEST(PointHorizon, HolesCastNothingAndTheBorderLooksOut) {
  HeightField f = flat_field(30, 30);
  for (int j = 0; j < 30; ++j) f.z[f.index(25, j)] = 50;             // a wall east ...
  for (int j = 0; j < 30; ++j) f.z[f.index(24, j)] = std::nanf("");  // ... with a hole before it
  PointHorizonQuery q;
  q.x = 10, q.y = 0, q.directions = 4;
  const std::vector<HorizonRay> rays = point_horizon(f, q);
  EXPECT_FALSE(rays[0].found);  // north of row 0: off the surface
  ASSERT_TRUE(rays[1].found);
  EXPECT_NEAR(rays[1].elevation_deg, std::atan(50.0 / 15) * kDeg, 1e-10);  // the wall's column, past the hole
  EXPECT_FALSE(surface_height(f, 24.5, 3).has_value());
  EXPECT_FALSE(surface_height(f, 23.5, 3.2).has_value());  // a facet with a NoData corner
  EXPECT_EQ(surface_height(f, 23, 3.5).value_or(-1), 0);   // on the edge beside it: the surface is there
  EXPECT_EQ(surface_height(f, 25, 3).value_or(-1), 50);    // a vertex next to the hole
  EXPECT_FALSE(surface_height(f, -0.01, 3).has_value());
  EXPECT_TRUE(surface_height(f, 29, 29).has_value());
}

// An eye on a plane sees it rise at its own slope in every direction: atan(grad . u). Eyes at texel centres,
// on diagonals and a rounding error (1e-10 .. 1e-7 texel) off either, as a centre given in map coordinates
// lands: the first crossing, a hair from the eye, is the eye's own edge (its rise over that distance is
// rounding, which read 2 to 47 degrees). The heights are exact in float (a dyadic plane 500 up).
TEST(PointHorizon, AnEyeAHairOffAnEdgeSeesThePlanesOwnSlope) {
  HeightField f = flat_field(40, 40);
  const double a = 0.375, b = -0.25;  // height per column and per row
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) f.z[f.index(i, j)] = float(500 + a * i + b * j);
  PointHorizonQuery q;
  q.directions = 36, q.frame = {0.3, -0.3};
  double worst = 0;
  for (const double dx : {0.0, 1e-10, -1e-10, 3e-9, -1e-7})
    for (const double dy : {0.0, -1e-10, 2e-9})
      for (const bool diagonal : {false, true}) {
        q.x = 17 + dx, q.y = (diagonal ? 21.5 : 21) + dy;
        if (diagonal) q.x = 38.5 - q.y + dx;  // on x + y = 38, off it by dx
        for (const HorizonRay& r : point_horizon(f, q)) {
          ASSERT_TRUE(r.found);
          const double phi = r.azimuth_deg / kDeg;
          const double vx = std::sin(phi) / 0.3, vy = std::cos(phi) / -0.3;  // texels per world unit
          const double truth = std::atan(a * vx + b * vy) * kDeg;
          worst = std::max(worst, std::abs(r.elevation_deg - truth));
          EXPECT_NEAR(r.elevation_deg, truth, 1e-7) << q.x << ", " << q.y << " azimuth " << r.azimuth_deg;
        }
      }
  RecordProperty("worst_deg", std::to_string(worst));
}

// The last edge before NoData casts: rows 0-4 are holes and the rest a plane rising north, so from an eye
// 1 above it the farthest point of the surface along a ray is the highest, atan(s - 1 / d) with s the
// plane's slope along the ray and d the distance to row 5 (or to the field's side). Crossings of row 5
// computed a rounding error inside the holes' facets were dropped, and a nearer point was reported.
TEST(PointHorizon, TheLastEdgeBeforeAHoleCasts) {
  HeightField f = flat_field(30, 30);
  for (int j = 0; j < 30; ++j)
    for (int i = 0; i < 30; ++i) f.z[f.index(i, j)] = j < 5 ? std::nanf("") : float(0.5 * (29 - j));
  const double t = 0.7318;  // world units a texel
  PointHorizonQuery q;
  q.directions = 360, q.frame = {t, -t}, q.observer_height = 1;
  int north = 0;
  for (int k = 0; k < 8; ++k) {
    q.x = 11.3 + 1.2345678 * k, q.y = 20.7 - 0.9876543 * k;
    for (const HorizonRay& r : point_horizon(f, q)) {
      const double phi = r.azimuth_deg / kDeg;
      const double vx = std::sin(phi) / t, vy = std::cos(phi) / -t;  // texels per world unit
      auto exit = [](double origin, double rate, double lo, double hi) {
        return rate > 0 ? (hi - origin) / rate : rate < 0 ? (origin - lo) / -rate : 1e300;
      };
      const double d = std::min(exit(q.x, vx, 0, 29), exit(q.y, vy, 5, 29));
      const double s = -0.5 * vy;  // height per world unit along the ray
      ASSERT_TRUE(r.found);
      EXPECT_NEAR(r.elevation_deg, std::atan(s - 1 / d) * kDeg, 1e-9) << k << " azimuth " << r.azimuth_deg;
      EXPECT_NEAR(r.distance, d, 1e-9 * d) << k << " azimuth " << r.azimuth_deg;
      north += exit(q.y, vy, 5, 29) < exit(q.x, vx, 0, 29);
    }
  }
  EXPECT_GT(north, 800);  // rays that end at the holes' edge
}

// The polar plot of a profile: 45° east, -5° at the other three compass points, linear in between (cyclic).
// Terrain below the profile, sky above, white outside the -22.5° circle.
TEST(PointHorizon, PolarPlotShowsTheProfile) {
  std::vector<HorizonRay> rays(4);
  for (int k = 0; k < 4; ++k)
    rays[k].azimuth_deg = 90.0 * k, rays[k].found = true, rays[k].elevation_deg = -5;
  rays[1].elevation_deg = 45;
  EXPECT_DOUBLE_EQ(profile_elevation(rays, 45), 20);
  EXPECT_DOUBLE_EQ(profile_elevation(rays, 315), -5);
  EXPECT_DOUBLE_EQ(profile_elevation(rays, -45), -5);
  PolarPlotGeometry g;
  g.size = 200;
  const std::vector<std::uint8_t> px = horizon_polar_plot(rays, g);
  ASSERT_EQ(px.size(), 200u * 200u * 3u);
  auto pixel_at = [&](double azimuth_deg, double e) {  // the pixel where (A, e) is drawn
    const double r = (90 - e) / 90 * g.horizon_radius(), a = azimuth_deg / kDeg;
    const int x = int(std::floor(100 + r * std::sin(a) + 0.3)),
              y = int(std::floor(100 - r * std::cos(a) + 0.3));
    return &px[(std::size_t(y) * 200 + x) * 3];
  };
  auto is_sky = [](const std::uint8_t* p) { return p[2] == 240; };
  auto is_ground = [](const std::uint8_t* p) { return p[0] == 150 && p[2] == 80; };
  EXPECT_TRUE(is_ground(pixel_at(80, 35)));
  EXPECT_TRUE(is_sky(pixel_at(80, 44)));  // the profile is at 39.4° there
  EXPECT_TRUE(is_sky(pixel_at(350, 5)));
  EXPECT_TRUE(is_ground(pixel_at(340, -10)));
  EXPECT_TRUE(is_sky(pixel_at(200, -2)));
  EXPECT_EQ(px[0], 255);  // a corner: outside the -22.5° circle
}

}  // namespace
}  // namespace hfbake
